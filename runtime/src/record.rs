//! Episode recordings as MCAP (zstd chunks), readable by the `mcap` CLI and Foxglove.
//!
//! Channels (all JSON messages with a JSON schema; log time = simulation time in ns):
//!
//! | topic | schema | rate | content |
//! |---|---|---|---|
//! | `/task` | `autobio.Task` | once | compiled task, scene instance, seed |
//! | `/robot/<name>/joint_state` | `autobio.JointState` | control (50 Hz) | one robot's `position` (its state layout: arm joints + gripper driver, rad) and `ctrl` |
//! | `/robot/<name>/action` | `autobio.Action` | control | that robot's part of the action applied for the next period |
//! | `/labware/state` | `autobio.LabwareState` | control | per labware: root pose, joints by role, loose parts' poses, logic state (latch flags), the robots touching it (`touched_by`, omitted when none) |
//! | `/camera/<name>` | `foxglove.RawImage` | `image_every` control steps (default 10 Hz) | 224x224 `rgb8`, base64 |
//! | `/stage` | `autobio.StageEvent` | on event | expert motion / lab-step starts |
//! | `/verdict` | `autobio.Verdict` | once, at the end | success and every predicate's value |
//! | `/liquid/<name>` | `autobio.Liquid` | physics or control | volume (µL), surface normal and offset (container frame), the surface disk's world pose and radius |

use crate::LabwareState;
use crate::render::Image;
use base64::Engine;
use serde::Serialize;
use serde_json::json;
use std::collections::BTreeMap;
use std::fs::File;
use std::io::BufWriter;
use std::path::Path;

/// 2: one joint-state and action channel per robot; labware state with poses, parts and logic.
pub const RECORDING_SCHEMA_VERSION: u32 = 2;

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
const RAW_IMAGE_SCHEMA: &str = r#"{"title":"foxglove.RawImage","type":"object","properties":{"timestamp":{"type":"object","properties":{"sec":{"type":"integer"},"nsec":{"type":"integer"}}},"frame_id":{"type":"string"},"width":{"type":"integer"},"height":{"type":"integer"},"encoding":{"type":"string"},"step":{"type":"integer"},"data":{"type":"string","contentEncoding":"base64"}}}"#;

pub struct Recorder {
    w: mcap::Writer<BufWriter<File>>,
    channels: BTreeMap<String, u16>,
    schemas: BTreeMap<&'static str, u16>,
    seq: u32,
}

fn ns(t: f64) -> u64 {
    (t * 1e9).round().max(0.0) as u64
}

impl Recorder {
    pub fn create(path: &Path) -> Result<Recorder, RecordError> {
        let file = BufWriter::new(File::create(path).map_err(RecordError::Write)?);
        let w = mcap::WriteOptions::new()
            .compression(Some(mcap::Compression::Zstd))
            .profile("autobio")
            .create(file)?;
        Ok(Recorder {
            w,
            channels: BTreeMap::new(),
            schemas: BTreeMap::new(),
            seq: 0,
        })
    }

    fn channel(&mut self, topic: &str, schema: &'static str) -> Result<u16, RecordError> {
        if let Some(&c) = self.channels.get(topic) {
            return Ok(c);
        }
        let sid = match self.schemas.get(schema) {
            Some(&s) => s,
            None => {
                let body = if schema == "foxglove.RawImage" {
                    RAW_IMAGE_SCHEMA
                } else {
                    OBJECT
                };
                let s = self.w.add_schema(schema, "jsonschema", body.as_bytes())?;
                self.schemas.insert(schema, s);
                s
            }
        };
        let c = self.w.add_channel(sid, topic, "json", &BTreeMap::new())?;
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
        let c = self.channel(topic, schema)?;
        let data =
            serde_json::to_vec(msg).map_err(|e| RecordError::Bad(topic.into(), e.to_string()))?;
        self.seq += 1;
        let header = mcap::records::MessageHeader {
            channel_id: c,
            sequence: self.seq,
            log_time: ns(t),
            publish_time: ns(t),
        };
        self.w.write_to_known_channel(&header, &data)?;
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

    pub fn image(&mut self, t: f64, img: &Image) -> Result<(), RecordError> {
        let ns = ns(t);
        let msg = json!({
            "timestamp": {"sec": ns / 1_000_000_000, "nsec": ns % 1_000_000_000},
            "frame_id": img.camera, "width": img.width, "height": img.height, "encoding": "rgb8",
            "step": img.width * 3, "data": base64::engine::general_purpose::STANDARD.encode(&img.rgb),
        });
        self.write(
            &format!("/camera/{}", img.camera),
            "foxglove.RawImage",
            t,
            &msg,
        )
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

    pub fn finish(mut self) -> Result<(), RecordError> {
        self.w.finish()?;
        Ok(())
    }
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

pub fn read_recording(path: &Path) -> Result<RecordingSummary, RecordError> {
    let buf = std::fs::read(path).map_err(RecordError::Read)?;
    let (mut task, mut instance, mut verdict) = (None, None, None);
    let mut series: Vec<(f64, Vec<LabwareState>)> = Vec::new();
    let mut actions: BTreeMap<String, Vec<Vec<f64>>> = BTreeMap::new();
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
            topic => {
                if let Some(robot) = topic
                    .strip_prefix("/robot/")
                    .and_then(|t| t.strip_suffix("/action"))
                {
                    let v = parse(topic)?;
                    let action: Vec<f64> = serde_json::from_value(v["action"].clone())
                        .map_err(|e| RecordError::Bad(topic.into(), e.to_string()))?;
                    actions.entry(robot.to_string()).or_default().push(action);
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
        messages,
        topics,
        duration_s: last_t as f64 * 1e-9,
    })
}
