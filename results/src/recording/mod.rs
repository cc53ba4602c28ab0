//! Episode recordings as MCAP (zstd chunks), readable by the `mcap` CLI and Foxglove.
//!
//! Channels (JSON messages with a JSON schema, or protobuf with its descriptor set, see
//! [`proto`]; log time = simulation time in ns):
//!
//! | topic | schema | rate | content |
//! |---|---|---|---|
//! | `/task` | `autobio.Task` | once | compiled task, scene instance, seed |
//! | `/robot/<name>/joint_state` | `autobio.JointState` | control (50 Hz) | one robot's `position` (its state layout: arm joints + gripper driver, rad) and `ctrl` |
//! | `/robot/<name>/action` | `autobio.Action` | control | that robot's part of the action applied for the next period |
//! | `/labware/state` | `autobio.LabwareState` | control | per labware: root pose, joints by role, loose parts' poses, logic state (latch flags), the robots touching it (`touched_by`, omitted when none) |
//! | `/physics/state` | `autobio.PhysicsState` (protobuf) | control | MuJoCo's state before the step's action (`mjSTATE_INTEGRATION`, [`proto::STATE_SPEC`]), and once more at the end: with `/labware/state`'s logic it is everything needed to re-simulate from any step or to redraw any frame |
//! | `/camera/<name>` | `foxglove.CompressedImage` (protobuf) | `image_every` control steps (default 10 Hz) | 224x224 PNG (lossless) |
//! | `/stage` | `autobio.StageEvent` | on event | expert motion / lab-step starts |
//! | `/verdict` | `autobio.Verdict` | once, at the end | success and every predicate's value, the error if any, the trajectory hash and control steps |
//! | `/liquid/<name>` | `autobio.Liquid` | physics or control | volume (µL), surface normal and offset (container frame), the surface disk's world pose and radius |
//!
//! A recording is written as `<path>.partial` and renamed to its path by [`Recorder::finish`]:
//! a file under a recording's name is whole, and an episode cut short (a killed process, a
//! failed write) leaves only the `.partial`, which the next recording of that episode replaces.

use crate::image::Image;
use labware::LabwareState;
use serde::Serialize;
use serde_json::json;
use std::collections::BTreeMap;
use std::fs::File;
use std::io::{BufWriter, Write};
use std::path::{Path, PathBuf};

pub mod compare;
pub mod proto;

/// 2: one joint-state and action channel per robot; labware state with poses, parts and logic.
/// 3: MuJoCo's state on `/physics/state`; camera frames as PNG in `foxglove.CompressedImage`.
pub const RECORDING_SCHEMA_VERSION: u32 = 3;

#[derive(Debug, thiserror::Error)]
pub enum RecordError {
    // The OS error is part of the message and not a `source`: a chain of causes prints it once.
    #[error("cannot write the recording: {0}")]
    Write(std::io::Error),
    #[error("cannot read the recording: {0}")]
    Read(std::io::Error),
    #[error("mcap: {0}")]
    Mcap(mcap::McapError),
    #[error("not a readable MCAP recording: {0}")]
    NotMcap(mcap::McapError),
    #[error("the recording has no `{0}` message")]
    Missing(&'static str),
    #[error("bad message on `{0}`: {1}")]
    Bad(String, String),
    #[error(
        "the recording has schema version {found}; this autobio reads version {RECORDING_SCHEMA_VERSION}"
    )]
    Version { found: u64 },
}

impl From<mcap::McapError> for RecordError {
    fn from(e: mcap::McapError) -> Self {
        RecordError::Mcap(e)
    }
}

const OBJECT: &str = r#"{"type":"object"}"#;
const IMAGE: &str = "foxglove.CompressedImage";
const STATE: &str = "autobio.PhysicsState";

pub struct Recorder {
    w: mcap::Writer<BufWriter<File>>,
    /// Where the finished recording goes, and where it is written until then.
    path: PathBuf,
    partial: PathBuf,
    channels: BTreeMap<String, u16>,
    schemas: BTreeMap<&'static str, u16>,
    seq: u32,
}

fn ns(t: f64) -> u64 {
    (t * 1e9).round().max(0.0) as u64
}

impl Recorder {
    /// Starts a recording for `path`, written as [`partial_path`] until [`Recorder::finish`].
    pub fn create(path: &Path) -> Result<Recorder, RecordError> {
        let partial = partial_path(path);
        let file = BufWriter::new(File::create(&partial).map_err(RecordError::Write)?);
        let w = mcap::WriteOptions::new()
            .compression(Some(mcap::Compression::Zstd))
            .profile("autobio")
            .create(file)?;
        Ok(Recorder {
            w,
            path: path.to_path_buf(),
            partial,
            channels: BTreeMap::new(),
            schemas: BTreeMap::new(),
            seq: 0,
        })
    }

    fn channel(&mut self, topic: &str, schema: &'static str) -> Result<u16, RecordError> {
        if let Some(&c) = self.channels.get(topic) {
            return Ok(c);
        }
        let protobuf = match schema {
            IMAGE => Some(proto::compressed_image_schema()),
            STATE => Some(proto::physics_state_schema()),
            _ => None,
        };
        let sid = match self.schemas.get(schema) {
            Some(&s) => s,
            None => {
                let s = match &protobuf {
                    Some(set) => self.w.add_schema(schema, "protobuf", set)?,
                    None => self.w.add_schema(schema, "jsonschema", OBJECT.as_bytes())?,
                };
                self.schemas.insert(schema, s);
                s
            }
        };
        let encoding = if protobuf.is_some() {
            "protobuf"
        } else {
            "json"
        };
        let c = self.w.add_channel(sid, topic, encoding, &BTreeMap::new())?;
        self.channels.insert(topic.to_string(), c);
        Ok(c)
    }

    pub fn write<T: Serialize>(
        &mut self,
        topic: &str,
        schema: &'static str,
        t: f64,
        msg: &T,
    ) -> Result<(), RecordError> {
        let data =
            serde_json::to_vec(msg).map_err(|e| RecordError::Bad(topic.into(), e.to_string()))?;
        self.write_bytes(topic, schema, t, &data)
    }

    fn write_bytes(
        &mut self,
        topic: &str,
        schema: &'static str,
        t: f64,
        data: &[u8],
    ) -> Result<(), RecordError> {
        let c = self.channel(topic, schema)?;
        self.seq += 1;
        let header = mcap::records::MessageHeader {
            channel_id: c,
            sequence: self.seq,
            log_time: ns(t),
            publish_time: ns(t),
        };
        self.w.write_to_known_channel(&header, data)?;
        Ok(())
    }

    /// Copies a message of another recording as it is (schema, channel, times, bytes).
    pub fn pass(&mut self, m: &mcap::Message<'_>) -> Result<(), RecordError> {
        let topic = &m.channel.topic;
        let c = match self.channels.get(topic.as_str()) {
            Some(&c) => c,
            None => {
                let sid = match &m.channel.schema {
                    Some(s) => self.w.add_schema(&s.name, &s.encoding, &s.data)?,
                    None => 0,
                };
                let c = self.w.add_channel(
                    sid,
                    topic,
                    &m.channel.message_encoding,
                    &m.channel.metadata,
                )?;
                self.channels.insert(topic.clone(), c);
                c
            }
        };
        self.seq += 1;
        let header = mcap::records::MessageHeader {
            channel_id: c,
            sequence: self.seq,
            log_time: m.log_time,
            publish_time: m.publish_time,
        };
        self.w.write_to_known_channel(&header, &m.data)?;
        Ok(())
    }

    pub fn task(
        &mut self,
        task_json: &serde_json::Value,
        instance: &serde_json::Value,
    ) -> Result<(), RecordError> {
        let msg = json!({"schema_version": RECORDING_SCHEMA_VERSION, "task": task_json, "instance": instance});
        self.write("/task", "autobio.Task", 0.0, &msg)
    }

    pub fn joint_state(
        &mut self,
        t: f64,
        robot: &str,
        position: &[f64],
        ctrl: &[f64],
    ) -> Result<(), RecordError> {
        self.write(
            &format!("/robot/{robot}/joint_state"),
            "autobio.JointState",
            t,
            &json!({"t": t, "position": position, "ctrl": ctrl}),
        )
    }

    pub fn action(&mut self, t: f64, robot: &str, action: &[f64]) -> Result<(), RecordError> {
        self.write(
            &format!("/robot/{robot}/action"),
            "autobio.Action",
            t,
            &json!({"t": t, "action": action}),
        )
    }

    pub fn labware(&mut self, t: f64, states: &[LabwareState]) -> Result<(), RecordError> {
        self.write(
            "/labware/state",
            "autobio.LabwareState",
            t,
            &json!({"t": t, "labware": states}),
        )
    }

    /// One camera frame, as PNG.
    pub fn image(&mut self, t: f64, img: &Image) -> Result<(), RecordError> {
        let png = img.to_png().map_err(RecordError::Write)?;
        let msg = proto::compressed_image(ns(t), &img.camera, "png", &png);
        self.write_bytes(&format!("/camera/{}", img.camera), IMAGE, t, &msg)
    }

    /// MuJoCo's state ([`proto::STATE_SPEC`]).
    pub fn physics(&mut self, t: f64, state: &[f64]) -> Result<(), RecordError> {
        let msg = proto::physics_state(ns(t), proto::STATE_SPEC, state);
        self.write_bytes("/physics/state", STATE, t, &msg)
    }

    /// One liquid's state (see the channel table).
    pub fn liquid(&mut self, t: f64, name: &str, frame: &LiquidFrame) -> Result<(), RecordError> {
        self.write(&format!("/liquid/{name}"), "autobio.Liquid", t, frame)
    }

    pub fn stage(&mut self, t: f64, label: &str) -> Result<(), RecordError> {
        self.write(
            "/stage",
            "autobio.StageEvent",
            t,
            &json!({"t": t, "label": label}),
        )
    }

    /// Writes the summary and footer and gives the recording its name.
    pub fn finish(mut self) -> Result<(), RecordError> {
        self.w.finish()?;
        let mut file = self
            .w
            .into_inner()
            .into_inner()
            .map_err(|e| RecordError::Write(e.into_error()))?;
        file.flush().map_err(RecordError::Write)?;
        std::fs::rename(&self.partial, &self.path).map_err(RecordError::Write)
    }
}

/// Where the recording for `path` is written until it is finished: `<path>.partial`.
pub fn partial_path(path: &Path) -> PathBuf {
    let mut name = path.as_os_str().to_owned();
    name.push(".partial");
    PathBuf::from(name)
}

/// What offline re-scoring needs from a recording.
pub struct RecordingSummary {
    pub task: serde_json::Value,
    pub instance: serde_json::Value,
    pub final_labware: Vec<LabwareState>,
    /// Every recorded labware state with its time (s), in order; the first is the initial state.
    pub labware_series: Vec<(f64, Vec<LabwareState>)>,
    pub verdict: Option<serde_json::Value>,
    /// Each robot's recorded actions, in time order (one per control step).
    pub actions: BTreeMap<String, Vec<Vec<f64>>>,
    /// Each robot's recorded state (its state layout), in time order (one per control step).
    pub robot_states: BTreeMap<String, Vec<Vec<f64>>>,
    /// MuJoCo's state ([`proto::STATE_SPEC`]) with its time: one per control step before the
    /// action, then the final state.
    pub physics: Vec<(f64, Vec<f64>)>,
    /// Each camera's frames (time, PNG bytes), in time order.
    pub images: BTreeMap<String, Vec<(f64, Vec<u8>)>>,
    pub messages: u64,
    pub topics: BTreeMap<String, u64>,
    pub duration_s: f64,
}

/// A liquid's state as recorded on `/liquid/<name>`.
#[derive(Clone, Debug, PartialEq, Serialize, serde::Deserialize)]
pub struct LiquidFrame {
    pub volume_ul: f64,
    /// Surface normal and plane offset (m) in the container's frame.
    pub normal: [f64; 3],
    pub offset_m: f64,
    /// The surface disk in the world: centre, orientation (w, x, y, z), radius (m).
    pub centre: [f64; 3],
    pub quat: [f64; 4],
    pub radius_m: f64,
}

/// Calls `each` with every message of a recording, in file order.
pub fn for_each_message(
    path: &Path,
    mut each: impl FnMut(&mcap::Message<'_>) -> Result<(), RecordError>,
) -> Result<(), RecordError> {
    let buf = std::fs::read(path).map_err(RecordError::Read)?;
    for m in mcap::MessageStream::new(&buf).map_err(RecordError::NotMcap)? {
        each(&m.map_err(RecordError::NotMcap)?)?;
    }
    Ok(())
}

pub fn read_recording(path: &Path) -> Result<RecordingSummary, RecordError> {
    let buf = std::fs::read(path).map_err(RecordError::Read)?;
    let (mut task, mut instance, mut verdict) = (None, None, None);
    let mut series: Vec<(f64, Vec<LabwareState>)> = Vec::new();
    let mut actions: BTreeMap<String, Vec<Vec<f64>>> = BTreeMap::new();
    let mut robot_states: BTreeMap<String, Vec<Vec<f64>>> = BTreeMap::new();
    let mut physics = Vec::new();
    let mut images: BTreeMap<String, Vec<(f64, Vec<u8>)>> = BTreeMap::new();
    let mut topics = BTreeMap::new();
    let mut messages = 0;
    let mut last_t = 0u64;
    for m in mcap::MessageStream::new(&buf).map_err(RecordError::NotMcap)? {
        let m = m.map_err(RecordError::NotMcap)?;
        messages += 1;
        last_t = last_t.max(m.log_time);
        *topics.entry(m.channel.topic.clone()).or_insert(0) += 1;
        let parse = |topic: &str| {
            serde_json::from_slice::<serde_json::Value>(&m.data)
                .map_err(|e| RecordError::Bad(topic.into(), e.to_string()))
        };
        match m.channel.topic.as_str() {
            "/task" => {
                let v = parse("/task")?;
                let found = v["schema_version"].as_u64().unwrap_or(0);
                if found != u64::from(RECORDING_SCHEMA_VERSION) {
                    return Err(RecordError::Version { found });
                }
                task = Some(v["task"].clone());
                instance = Some(v["instance"].clone());
            }
            "/labware/state" => {
                let v = parse("/labware/state")?;
                let states = serde_json::from_value(v["labware"].clone())
                    .map_err(|e| RecordError::Bad("/labware/state".into(), e.to_string()))?;
                series.push((m.log_time as f64 * 1e-9, states));
            }
            "/verdict" => verdict = Some(parse("/verdict")?),
            "/physics/state" => {
                let (spec, state) = proto::state_values(&m.data).ok_or_else(|| {
                    RecordError::Bad("/physics/state".into(), "not protobuf".into())
                })?;
                if spec != proto::STATE_SPEC {
                    return Err(RecordError::Bad(
                        "/physics/state".into(),
                        format!("state spec {spec}, expected {}", proto::STATE_SPEC),
                    ));
                }
                physics.push((m.log_time as f64 * 1e-9, state));
            }
            topic => {
                let robot_field =
                    |suffix: &str, key: &str| -> Result<Option<(String, Vec<f64>)>, RecordError> {
                        let Some(robot) = topic
                            .strip_prefix("/robot/")
                            .and_then(|t| t.strip_suffix(suffix))
                        else {
                            return Ok(None);
                        };
                        let v = parse(topic)?;
                        let values = serde_json::from_value(v[key].clone())
                            .map_err(|e| RecordError::Bad(topic.into(), e.to_string()))?;
                        Ok(Some((robot.to_string(), values)))
                    };
                if let Some((robot, a)) = robot_field("/action", "action")? {
                    actions.entry(robot).or_default().push(a);
                } else if let Some((robot, s)) = robot_field("/joint_state", "position")? {
                    robot_states.entry(robot).or_default().push(s);
                } else if let Some(camera) = topic.strip_prefix("/camera/") {
                    let png = proto::image_data(&m.data).ok_or_else(|| {
                        RecordError::Bad(topic.into(), "not a CompressedImage".into())
                    })?;
                    images
                        .entry(camera.to_string())
                        .or_default()
                        .push((m.log_time as f64 * 1e-9, png.to_vec()));
                }
            }
        }
    }
    let final_labware = series
        .last()
        .map(|(_, s)| s.clone())
        .ok_or(RecordError::Missing("/labware/state"))?;
    Ok(RecordingSummary {
        task: task.ok_or(RecordError::Missing("/task"))?,
        instance: instance.unwrap_or(serde_json::Value::Null),
        final_labware,
        labware_series: series,
        verdict,
        actions,
        robot_states,
        physics,
        images,
        messages,
        topics,
        duration_s: last_t as f64 * 1e-9,
    })
}
