//! The dataset folder: LeRobot v2.1 or v3.0 layout, plus `meta/autobio.jsonl` (one line per
//! committed episode: its task, seed, length, instruction and statistics), the commit record
//! from which every other metadata file is rebuilt, so a crash between files loses nothing and
//! duplicates nothing.
//!
//! v2.1: `data/chunk-XXX/episode_XXXXXX.parquet`, `videos/chunk-XXX/<key>/episode_XXXXXX.mp4`,
//! `meta/{info.json, episodes.jsonl, tasks.jsonl, episodes_stats.jsonl, stats.json}`.
//! v3.0: episodes staged in `.episodes/`, then assembled by `finish` into
//! `data/chunk-000/file-000.parquet`, `videos/<key>/chunk-000/file-000.mp4` (stream-copied),
//! `meta/episodes/chunk-000/file-000.parquet`, `meta/tasks.parquet`, `meta/{info,stats}.json`.

use crate::DatasetError;
use crate::capture::Capture;
use crate::parquet::{
    EpisodeRow, EpisodeVideo, Frame, Row, write_episodes, write_frames, write_tasks,
};
use crate::stats::{self, FeatureStats};
use crate::video::{self, Codec};
use results::environment_state::EnvironmentState;
use serde::{Deserialize, Serialize};
use serde_json::{Value, json};
use std::collections::BTreeMap;
use std::io::Write;
use std::path::{Path, PathBuf};

pub(crate) const FPS: u32 = 50;
const CHUNK: usize = 1000;

#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub enum Version {
    #[serde(rename = "v2.1")]
    V21,
    #[serde(rename = "v3.0")]
    V30,
}

impl Version {
    fn code(self) -> &'static str {
        match self {
            Version::V21 => "v2.1",
            Version::V30 => "v3.0",
        }
    }
}

/// One committed episode, as `meta/autobio.jsonl` keeps it.
#[derive(Clone, Debug, Serialize, Deserialize)]
pub(crate) struct Committed {
    pub episode_index: usize,
    pub task_id: String,
    pub seed: u64,
    /// Its position in the whole plan of the run that recorded it (across shards): merged
    /// shards are put back in this order.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub plan: Option<usize>,
    pub length: usize,
    pub instruction: String,
    /// Per feature: LeRobot's stats JSON with quantiles.
    pub stats: BTreeMap<String, Value>,
    /// What the episode's perturbations drew (light, colours, cameras, noise, wording, start
    /// pose, layout), when its task had any (docs/robustness.md).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub perturbation: Option<Value>,
    /// Who drew its frames, when not MuJoCo's rasteriser: Blender, its engine, samples and
    /// denoiser (docs/photoreal.md).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub renderer: Option<Value>,
}

/// What a dataset's frames observe: LeRobot's feature sets.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum Observations {
    /// Every task camera (`observation.images.<camera>`) and the robots' state.
    #[default]
    Vision,
    /// The task's environment state (`observation.environment_state`, privileged) and the
    /// robots' state; no camera is drawn.
    State,
    /// Both: cameras, environment state and robot state.
    All,
}

impl Observations {
    pub fn cameras(self) -> bool {
        self != Observations::State
    }

    pub fn environment_state(self) -> bool {
        self != Observations::Vision
    }

    /// The name `autobio demo --observation` takes and dataset metadata records.
    pub fn name(self) -> &'static str {
        match self {
            Observations::Vision => "vision",
            Observations::State => "state",
            Observations::All => "all",
        }
    }
}

/// Where and how captures are staged; a worker thread holds one.
#[derive(Clone, Debug)]
pub struct CaptureSpec {
    staging: PathBuf,
    cameras: usize,
    size: [usize; 2],
    codec: Codec,
    environment_state: bool,
}

impl CaptureSpec {
    /// A capture staged for an episode of `task` with `seed`.
    pub fn capture(&self, task: &str, seed: u64) -> Result<Capture, DatasetError> {
        let dir = self.staging.join(format!("{task}_seed{seed}"));
        let mut c = Capture::new(
            dir,
            self.cameras,
            self.size,
            FPS,
            self.codec,
            self.environment_state,
        )?;
        c.task_id = task.to_string();
        c.seed = seed;
        Ok(c)
    }
}

/// What every episode of a dataset shares: robots, state and action names, cameras.
#[derive(Clone, Debug, PartialEq)]
pub struct Layout {
    pub robot_type: String,
    pub state_names: Vec<String>,
    pub action_names: Vec<String>,
    /// Camera names and their feature keys (`observation.images.<camera>`); none for a
    /// state-only dataset.
    pub cameras: Vec<(String, String)>,
    /// `observation.environment_state`'s names; empty: the dataset has no environment state.
    pub environment_state_names: Vec<String>,
}

impl Layout {
    /// The layout of episodes of these tasks, which must share robots and cameras (and, with the
    /// environment state, its layout), observing `observations`.
    pub fn of(
        tasks: &[compiler::Task],
        root: &Path,
        observations: Observations,
    ) -> Result<Layout, DatasetError> {
        let first = tasks.first().ok_or_else(|| DatasetError::Existing {
            path: root.to_path_buf(),
            why: "no task to record".into(),
        })?;
        let mut state_names = Vec::new();
        let mut action_names = Vec::new();
        let mut robot_type = Vec::new();
        for r in &first.robots {
            if let Some(m) = robots::model(&r.model) {
                state_names.extend(m.state_names().iter().map(|n| format!("{}/{n}", r.name)));
                action_names.extend(m.action_names().iter().map(|n| format!("{}/{n}", r.name)));
                robot_type.push(m.name.to_string());
            }
        }
        for t in tasks {
            let same = t
                .robots
                .iter()
                .map(|r| &r.model)
                .eq(first.robots.iter().map(|r| &r.model))
                && t.cameras
                    .iter()
                    .map(|c| &c.name)
                    .eq(first.cameras.iter().map(|c| &c.name));
            if !same {
                return Err(DatasetError::Existing {
                    path: root.to_path_buf(),
                    why: format!(
                        "{} and {} have different robots or cameras; one dataset holds one layout",
                        first.id, t.id
                    ),
                });
            }
        }
        let cameras = first
            .cameras
            .iter()
            .filter(|_| observations.cameras())
            .map(|c| {
                (
                    c.name.clone(),
                    format!("observation.images.{}", c.name.replace('/', "_")),
                )
            })
            .collect();
        let mut environment_state_names = Vec::new();
        if observations.environment_state() {
            let layout = |t: &compiler::Task| EnvironmentState::of(t).names().to_vec();
            environment_state_names = layout(first);
            if let Some(t) = tasks.iter().find(|t| layout(t) != environment_state_names) {
                return Err(DatasetError::Existing {
                    path: root.to_path_buf(),
                    why: format!(
                        "{} and {} have different environment-state layouts; one dataset holds one layout",
                        first.id, t.id
                    ),
                });
            }
        }
        Ok(Layout {
            robot_type: robot_type.join("+"),
            state_names,
            action_names,
            cameras,
            environment_state_names,
        })
    }
}

pub struct DatasetWriter {
    root: PathBuf,
    version: Version,
    codec: Codec,
    size: [usize; 2],
    robot_type: String,
    state_names: Vec<String>,
    action_names: Vec<String>,
    /// Camera names and their feature keys (`observation.images.<camera>`).
    cameras: Vec<(String, String)>,
    environment_state_names: Vec<String>,
    done: Vec<Committed>,
    file_sizes: FileSizes,
}

fn create_dir(p: &Path) -> Result<(), DatasetError> {
    std::fs::create_dir_all(p).map_err(|e| DatasetError::io("create", p, e))
}

fn write_file(p: &Path, text: &str) -> Result<(), DatasetError> {
    results::run::record::write_atomic(p, text.as_bytes())
        .map_err(|e| DatasetError::io("write", p, e))
}

fn rename(from: &Path, to: &Path) -> Result<(), DatasetError> {
    if let Some(parent) = to.parent() {
        create_dir(parent)?;
    }
    std::fs::rename(from, to).map_err(|e| DatasetError::io("move", to, e))
}

impl DatasetWriter {
    /// Opens `root` for writing: a new dataset (the folder absent or empty), or with `resume`
    /// the dataset a run left there, of the same version, layout, codec and image size.
    pub fn open(
        root: &Path,
        version: Version,
        codec: Codec,
        layout: Layout,
        size: [usize; 2],
        resume: bool,
    ) -> Result<DatasetWriter, DatasetError> {
        let Layout {
            robot_type,
            state_names,
            action_names,
            cameras,
            environment_state_names,
        } = layout;
        let record = root.join("meta/autobio.jsonl");
        let mut done = Vec::new();
        let occupied = std::fs::read_dir(root).is_ok_and(|mut d| d.next().is_some());
        if occupied && !resume {
            return Err(DatasetError::Existing {
                path: root.to_path_buf(),
                why: "is not empty; continue its dataset with --resume, or use another --out"
                    .into(),
            });
        }
        if occupied {
            let info: Value = std::fs::read_to_string(root.join("meta/info.json"))
                .ok()
                .and_then(|t| serde_json::from_str(&t).ok())
                .unwrap_or(Value::Null);
            if info["codebase_version"] != version.code() {
                return Err(DatasetError::Existing {
                    path: root.to_path_buf(),
                    why: format!(
                        "holds a dataset of version {}, not {}",
                        info["codebase_version"],
                        version.code()
                    ),
                });
            }
            // One dataset holds one video encoding and size: v3.0 joins episodes' videos by
            // stream copy, and LeRobot reads `video.*` from the first episode.
            let [w, h] = size;
            let videos: Vec<&Value> = info["features"]
                .as_object()
                .into_iter()
                .flatten()
                .filter(|(_, f)| f["dtype"] == "video")
                .map(|(_, f)| &f["info"])
                .collect();
            if let Some(v) = videos.iter().find(|v| {
                v["video.codec"] != codec.name() || v["video.width"] != w || v["video.height"] != h
            }) {
                return Err(DatasetError::Existing {
                    path: root.to_path_buf(),
                    why: format!(
                        "holds {}x{} {} videos, not {w}x{h} {}; resume with the same --codec",
                        v["video.width"],
                        v["video.height"],
                        v["video.codec"].as_str().unwrap_or("unknown"),
                        codec.name()
                    ),
                });
            }
            let text = std::fs::read_to_string(&record).unwrap_or_default();
            for line in text.split_inclusive('\n').filter(|l| l.ends_with('\n')) {
                match serde_json::from_str::<Committed>(line) {
                    Ok(c) => done.push(c),
                    Err(e) => {
                        return Err(DatasetError::Existing {
                            path: record,
                            why: format!("a line is not a committed episode: {e}"),
                        });
                    }
                }
            }
        }
        create_dir(&root.join("meta"))?;
        let w = DatasetWriter {
            root: root.to_path_buf(),
            version,
            codec,
            size,
            robot_type,
            state_names,
            action_names,
            cameras,
            environment_state_names,
            done,
            file_sizes: FileSizes::default(),
        };
        // The record is the truth: drop a torn last line, rebuild the metadata from it.
        let kept: String = w
            .done
            .iter()
            .map(|c| serde_json::to_string(c).expect("json") + "\n")
            .collect();
        write_file(&record, &kept)?;
        w.write_metadata()?;
        Ok(w)
    }

    /// Where v3.0's shared files roll over (LeRobot's 100 MiB and 500 MiB by default).
    pub fn set_file_sizes(&mut self, sizes: FileSizes) {
        self.file_sizes = sizes;
    }

    /// Episodes committed so far.
    pub fn episodes(&self) -> usize {
        self.done.len()
    }

    /// Whether an episode of `task` with `seed` is already in the dataset.
    pub fn has(&self, task: &str, seed: u64) -> bool {
        self.done
            .iter()
            .any(|c| c.task_id == task && c.seed == seed)
    }

    /// Refuses to add frames drawn by `renderer` to a dataset whose committed episodes another
    /// renderer drew (or the same with other engine, samples or denoiser: threads aside): a
    /// dataset holds one look, as it holds one codec and image size.
    pub fn check_renderer(
        &self,
        renderer: &runtime::cameras::Renderer,
    ) -> Result<(), DatasetError> {
        let look = |v: Option<&Value>| -> Option<Value> {
            let mut v = v?.clone();
            v.as_object_mut()?.remove("threads");
            Some(v)
        };
        let wanted = match renderer {
            runtime::cameras::Renderer::Raster => None,
            r => look(Some(&r.describe())),
        };
        match self
            .done
            .iter()
            .find(|c| look(c.renderer.as_ref()) != wanted)
        {
            None => Ok(()),
            Some(c) => Err(DatasetError::Existing {
                path: self.root.clone(),
                why: format!(
                    "its frames were drawn by {} (episode {} of {}); resume it with the same --renderer, --engine, --samples and denoiser",
                    c.renderer
                        .as_ref()
                        .map_or_else(|| "MuJoCo's rasteriser".to_string(), |r| r.to_string()),
                    c.seed,
                    c.task_id
                ),
            }),
        }
    }

    /// What a worker thread needs to stage captures.
    pub fn capture_spec(&self) -> CaptureSpec {
        CaptureSpec {
            staging: self.root.join(".staging"),
            cameras: self.cameras.len(),
            size: self.size,
            codec: self.codec,
            environment_state: !self.environment_state_names.is_empty(),
        }
    }

    fn total_frames(&self) -> usize {
        self.done.iter().map(|c| c.length).sum()
    }

    fn tasks(&self) -> Vec<String> {
        let mut tasks: Vec<String> = Vec::new();
        for c in &self.done {
            if !tasks.contains(&c.instruction) {
                tasks.push(c.instruction.clone());
            }
        }
        tasks
    }

    /// Where episode `index`'s parquet and videos live (v2.1 final, v3.0 staged).
    fn episode_paths(&self, index: usize) -> (PathBuf, Vec<PathBuf>) {
        let keys: Vec<String> = self.cameras.iter().map(|(_, k)| k.clone()).collect();
        episode_paths(&self.root, self.version, &keys, index)
    }

    /// Moves a finished capture into the dataset as the next episode; `plan` is its position in
    /// the whole plan (across shards); returns its frames.
    pub fn commit(
        &mut self,
        mut capture: Capture,
        instruction: &str,
        plan: Option<usize>,
    ) -> Result<usize, DatasetError> {
        if let Some(e) = capture.take_error() {
            capture.discard();
            return Err(e);
        }
        let length = capture.rows.len();
        let videos = std::mem::take(&mut capture.videos);
        for v in videos {
            let frames = v.finish()?;
            if frames != length {
                return Err(DatasetError::Episode {
                    task: capture.task_id.clone(),
                    seed: capture.seed,
                    why: format!("a camera has {frames} frames for {length} steps"),
                });
            }
        }
        let episode = Episode {
            task_id: capture.task_id.clone(),
            seed: capture.seed,
            plan,
            instruction: instruction.to_string(),
            perturbation: capture.perturbation.take(),
            renderer: capture.renderer.take(),
            image_stats: capture
                .images
                .iter()
                .map(|img| img.finish().to_json(true))
                .collect(),
            videos: (0..self.cameras.len())
                .map(|k| capture.dir.join(format!("camera{k}.mp4")))
                .collect(),
            owned: true,
        };
        self.add(&episode, &capture.rows, &capture.dir)?;
        std::fs::remove_dir_all(&capture.dir).ok();
        Ok(length)
    }

    /// The episode `index` of another dataset of this layout, as the next episode here (its
    /// rows re-indexed, its videos copied, its image statistics kept).
    pub(crate) fn adopt(&mut self, from: &Source, index: usize) -> Result<usize, DatasetError> {
        let c = &from.done[index];
        let (data, videos) = episode_paths(&from.root, from.version, &from.keys(), index);
        let rows = crate::parquet::read_frames(&data)?;
        if rows.len() != c.length {
            return Err(DatasetError::Existing {
                path: data,
                why: format!(
                    "has {} frames; its commit record says {}",
                    rows.len(),
                    c.length
                ),
            });
        }
        let episode = Episode {
            task_id: c.task_id.clone(),
            seed: c.seed,
            plan: c.plan,
            instruction: c.instruction.clone(),
            perturbation: c.perturbation.clone(),
            renderer: c.renderer.clone(),
            image_stats: from
                .cameras
                .iter()
                .map(|(_, key)| c.stats.get(key).cloned().unwrap_or(Value::Null))
                .collect(),
            videos,
            owned: false,
        };
        let staging = self.root.join(".staging/adopted");
        create_dir(&staging)?;
        self.add(&episode, &rows, &staging)?;
        Ok(rows.len())
    }

    /// Writes an episode's table, places its videos, and appends its commit line.
    fn add(&mut self, e: &Episode, frames: &[Frame], staging: &Path) -> Result<(), DatasetError> {
        let index = self.done.len();
        let length = frames.len();
        let mut tasks = self.tasks();
        let task_index = tasks
            .iter()
            .position(|t| *t == e.instruction)
            .unwrap_or_else(|| {
                tasks.push(e.instruction.clone());
                tasks.len() - 1
            });
        let first = self.total_frames();
        let rows: Vec<Row> = frames
            .iter()
            .enumerate()
            .map(|(i, f)| Row {
                state: f.state.clone(),
                environment_state: f.environment_state.clone(),
                action: f.action.clone(),
                timestamp: (i as f64 / FPS as f64) as f32,
                frame_index: i as i64,
                episode_index: index as i64,
                index: (first + i) as i64,
                task_index: task_index as i64,
            })
            .collect();
        let staged = staging.join("data.parquet");
        write_frames(&staged, &rows)?;
        let mut stats: BTreeMap<String, Value> = BTreeMap::new();
        let column =
            |f: &dyn Fn(&Row) -> Vec<f64>| stats::vectors(&rows.iter().map(f).collect::<Vec<_>>());
        if !self.environment_state_names.is_empty() {
            let s = column(&|r| r.environment_state.iter().map(|&x| x as f64).collect());
            stats.insert("observation.environment_state".into(), s.to_json(true));
        }
        let features: [(&str, FeatureStats); 7] = [
            (
                "observation.state",
                column(&|r| r.state.iter().map(|&x| x as f64).collect()),
            ),
            (
                "action",
                column(&|r| r.action.iter().map(|&x| x as f64).collect()),
            ),
            ("timestamp", column(&|r| vec![r.timestamp as f64])),
            ("frame_index", column(&|r| vec![r.frame_index as f64])),
            ("episode_index", column(&|r| vec![r.episode_index as f64])),
            ("index", column(&|r| vec![r.index as f64])),
            ("task_index", column(&|r| vec![r.task_index as f64])),
        ];
        for (name, s) in features {
            stats.insert(name.into(), s.to_json(true));
        }
        for ((_, key), img) in self.cameras.iter().zip(&e.image_stats) {
            stats.insert(key.clone(), img.clone());
        }
        let (data, videos) = self.episode_paths(index);
        rename(&staged, &data)?;
        for (from, to) in e.videos.iter().zip(&videos) {
            if e.owned {
                rename(from, to)?;
            } else {
                copy(from, to)?;
            }
        }
        let committed = Committed {
            episode_index: index,
            task_id: e.task_id.clone(),
            seed: e.seed,
            plan: e.plan,
            length,
            instruction: e.instruction.clone(),
            stats,
            perturbation: e.perturbation.clone(),
            renderer: e.renderer.clone(),
        };
        // The commit point: the episode exists once its line is on disk.
        let record = self.root.join("meta/autobio.jsonl");
        std::fs::OpenOptions::new()
            .append(true)
            .create(true)
            .open(&record)
            .and_then(|mut f| {
                writeln!(f, "{}", serde_json::to_string(&committed).expect("json"))?;
                f.sync_data()
            })
            .map_err(|e| DatasetError::io("append to", &record, e))?;
        self.done.push(committed);
        if self.version == Version::V21 {
            self.write_metadata()?;
        }
        Ok(())
    }

    fn features(&self) -> Value {
        let scalar = |dtype: &str| json!({"dtype": dtype, "shape": [1], "names": null});
        let mut f = serde_json::Map::new();
        f.insert(
            "observation.state".into(),
            json!({"dtype": "float32", "shape": [self.state_names.len()], "names": self.state_names}),
        );
        if !self.environment_state_names.is_empty() {
            f.insert(
                "observation.environment_state".into(),
                json!({"dtype": "float32", "shape": [self.environment_state_names.len()],
                       "names": self.environment_state_names}),
            );
        }
        f.insert(
            "action".into(),
            json!({"dtype": "float32", "shape": [self.action_names.len()], "names": self.action_names}),
        );
        let [w, h] = self.size;
        for (_, key) in &self.cameras {
            f.insert(
                key.clone(),
                json!({"dtype": "video", "shape": [h, w, 3], "names": ["height", "width", "channel"],
                       "info": {"video.height": h, "video.width": w, "video.codec": self.codec.name(),
                                "video.pix_fmt": "yuv420p", "video.is_depth_map": false,
                                "video.fps": FPS, "video.channels": 3, "has_audio": false}}),
            );
        }
        f.insert("timestamp".into(), scalar("float32"));
        for k in ["frame_index", "episode_index", "index", "task_index"] {
            f.insert(k.into(), scalar("int64"));
        }
        Value::Object(f)
    }

    /// Aggregated statistics over every committed episode.
    fn stats(&self, quantiles: bool) -> Value {
        let mut out = serde_json::Map::new();
        let Some(first) = self.done.first() else {
            return Value::Object(out);
        };
        for name in first.stats.keys() {
            let parts: Vec<FeatureStats> = self
                .done
                .iter()
                .map(|c| from_json(&c.stats[name]))
                .collect();
            let refs: Vec<&FeatureStats> = parts.iter().collect();
            out.insert(name.clone(), stats::aggregate(&refs).to_json(quantiles));
        }
        Value::Object(out)
    }

    fn info(&self) -> Value {
        let n = self.done.len();
        let mut info = json!({
            "codebase_version": self.version.code(),
            "robot_type": self.robot_type,
            "total_episodes": n,
            "total_frames": self.total_frames(),
            "total_tasks": self.tasks().len(),
            "chunks_size": CHUNK,
            "fps": FPS,
            "splits": {"train": format!("0:{n}")},
            "features": self.features(),
        });
        match self.version {
            Version::V21 => {
                info["total_videos"] = json!(n * self.cameras.len());
                info["total_chunks"] = json!(n.div_ceil(CHUNK).max(1));
                info["data_path"] =
                    json!("data/chunk-{episode_chunk:03d}/episode_{episode_index:06d}.parquet");
                info["video_path"] = json!(
                    "videos/chunk-{episode_chunk:03d}/{video_key}/episode_{episode_index:06d}.mp4"
                );
            }
            Version::V30 => {
                info["data_files_size_in_mb"] = json!(self.file_sizes.data_mb);
                info["video_files_size_in_mb"] = json!(self.file_sizes.video_mb);
                info["data_path"] =
                    json!("data/chunk-{chunk_index:03d}/file-{file_index:03d}.parquet");
                info["video_path"] =
                    json!("videos/{video_key}/chunk-{chunk_index:03d}/file-{file_index:03d}.mp4");
            }
        }
        info
    }

    /// v2.1's metadata, rebuilt from the commit record (v3.0's is written by `finish`).
    fn write_metadata(&self) -> Result<(), DatasetError> {
        let meta = self.root.join("meta");
        write_file(
            &meta.join("info.json"),
            &serde_json::to_string_pretty(&self.info()).expect("json"),
        )?;
        if self.version != Version::V21 {
            return Ok(());
        }
        let tasks = self.tasks();
        let lines = |f: &dyn Fn(&Committed) -> Value| -> String {
            self.done.iter().map(|c| f(c).to_string() + "\n").collect()
        };
        write_file(
            &meta.join("episodes.jsonl"),
            &lines(
                &|c| json!({"episode_index": c.episode_index, "tasks": [c.instruction], "length": c.length}),
            ),
        )?;
        write_file(
            &meta.join("tasks.jsonl"),
            &tasks
                .iter()
                .enumerate()
                .map(|(i, t)| json!({"task_index": i, "task": t}).to_string() + "\n")
                .collect::<String>(),
        )?;
        write_file(
            &meta.join("episodes_stats.jsonl"),
            &lines(&|c| {
                let stats: serde_json::Map<String, Value> = c
                    .stats
                    .iter()
                    .map(|(k, v)| (k.clone(), from_json(v).to_json(false)))
                    .collect();
                json!({"episode_index": c.episode_index, "stats": stats})
            }),
        )?;
        write_file(
            &meta.join("stats.json"),
            &serde_json::to_string_pretty(&self.stats(false)).expect("json"),
        )
    }

    /// Completes the dataset (v3.0: assembles the shared files) and removes the staging area;
    /// returns the episodes written.
    pub fn finish(self) -> Result<usize, DatasetError> {
        std::fs::remove_dir_all(self.root.join(".staging")).ok();
        if self.version == Version::V30 {
            self.assemble_v30()?;
        }
        self.write_metadata()?;
        Ok(self.done.len())
    }

    fn assemble_v30(&self) -> Result<(), DatasetError> {
        let meta = self.root.join("meta");
        // The shared files are derived from `.episodes/`: rebuilt whole.
        for derived in ["data", "videos"] {
            let d = self.root.join(derived);
            if d.exists() {
                std::fs::remove_dir_all(&d).map_err(|e| DatasetError::io("clear", &d, e))?;
            }
        }
        let n = self.done.len();
        let data_parts: Vec<PathBuf> = (0..n).map(|i| self.episode_paths(i).0).collect();
        let data_files = roll_over(&data_parts, self.file_sizes.data_mb)?;
        for (g, group) in data_files.iter().enumerate() {
            let (chunk, file) = file_position(g);
            let out = self
                .root
                .join(format!("data/chunk-{chunk:03}/file-{file:03}.parquet"));
            create_dir(out.parent().expect("has a parent"))?;
            let parts: Vec<PathBuf> = group.iter().map(|&i| data_parts[i].clone()).collect();
            crate::parquet::concat_frames(&parts, &out)?;
        }
        let mut rows: Vec<EpisodeRow> = Vec::new();
        let mut from_index = 0;
        for (i, c) in self.done.iter().enumerate() {
            let g = data_files.iter().position(|f| f.contains(&i)).unwrap_or(0);
            let (chunk, file) = file_position(g);
            rows.push(EpisodeRow {
                episode_index: c.episode_index as i64,
                tasks: vec![c.instruction.clone()],
                length: c.length as i64,
                from_index,
                to_index: from_index + c.length as i64,
                data_file: (chunk as i64, file as i64),
                videos: Vec::new(),
            });
            from_index += c.length as i64;
        }
        for (k, (_, key)) in self.cameras.iter().enumerate() {
            let parts: Vec<PathBuf> = (0..n).map(|i| self.episode_paths(i).1[k].clone()).collect();
            for (g, group) in roll_over(&parts, self.file_sizes.video_mb)?
                .iter()
                .enumerate()
            {
                let (chunk, file) = file_position(g);
                let out = self
                    .root
                    .join(format!("videos/{key}/chunk-{chunk:03}/file-{file:03}.mp4"));
                create_dir(out.parent().expect("has a parent"))?;
                let mine: Vec<PathBuf> = group.iter().map(|&i| parts[i].clone()).collect();
                video::concatenate(&mine, &out)?;
                let mut from_s = 0.0;
                for &i in group {
                    let to_s = from_s + self.done[i].length as f64 / FPS as f64;
                    rows[i].videos.push(EpisodeVideo {
                        key: key.clone(),
                        file: (chunk as i64, file as i64),
                        from_s,
                        to_s,
                    });
                    from_s = to_s;
                }
            }
        }
        let eps = meta.join("episodes/chunk-000/file-000.parquet");
        create_dir(eps.parent().expect("has a parent"))?;
        write_episodes(&eps, &rows)?;
        write_tasks(&meta.join("tasks.parquet"), &self.tasks())?;
        write_file(
            &meta.join("stats.json"),
            &serde_json::to_string_pretty(&self.stats(true)).expect("json"),
        )
    }
}

/// LeRobot's file sequence: files 0..999 in chunk 0, then chunk 1, and so on.
fn file_position(g: usize) -> (usize, usize) {
    (g / CHUNK, g % CHUNK)
}

/// Consecutive episodes' parts grouped into shared files as LeRobot fills them: a file takes
/// episodes until it has reached `limit_mb` (MiB, as LeRobot counts), then the next one starts.
fn roll_over(parts: &[PathBuf], limit_mb: f64) -> Result<Vec<Vec<usize>>, DatasetError> {
    let limit = (limit_mb * 1024.0 * 1024.0) as u64;
    let mut files: Vec<Vec<usize>> = Vec::new();
    let mut size = 0u64;
    for (i, p) in parts.iter().enumerate() {
        if files.is_empty() || size >= limit {
            files.push(Vec::new());
            size = 0;
        }
        files.last_mut().expect("pushed above").push(i);
        size += std::fs::metadata(p)
            .map_err(|e| DatasetError::io("read", p, e))?
            .len();
    }
    Ok(files)
}

/// The sizes at which v3.0's shared files roll over to the next file (MiB).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct FileSizes {
    pub data_mb: f64,
    pub video_mb: f64,
}

impl Default for FileSizes {
    /// LeRobot's defaults.
    fn default() -> FileSizes {
        FileSizes {
            data_mb: 100.0,
            video_mb: 500.0,
        }
    }
}

/// Where episode `index` of a dataset at `root` keeps its parquet and videos (v2.1 final, v3.0
/// staged).
fn episode_paths(
    root: &Path,
    version: Version,
    keys: &[String],
    index: usize,
) -> (PathBuf, Vec<PathBuf>) {
    let chunk = index / CHUNK;
    match version {
        Version::V21 => (
            root.join(format!("data/chunk-{chunk:03}/episode_{index:06}.parquet")),
            keys.iter()
                .map(|key| {
                    root.join(format!(
                        "videos/chunk-{chunk:03}/{key}/episode_{index:06}.mp4"
                    ))
                })
                .collect(),
        ),
        Version::V30 => (
            root.join(format!(".episodes/episode_{index:06}.parquet")),
            keys.iter()
                .map(|key| root.join(format!(".episodes/episode_{index:06}/{key}.mp4")))
                .collect(),
        ),
    }
}

/// An episode as the writer takes it: per-camera image statistics (LeRobot's stats JSON) and
/// video files, moved in when `owned`, else copied.
struct Episode {
    task_id: String,
    seed: u64,
    plan: Option<usize>,
    instruction: String,
    perturbation: Option<Value>,
    renderer: Option<Value>,
    image_stats: Vec<Value>,
    videos: Vec<PathBuf>,
    owned: bool,
}

/// Another dataset read for merging: its layout and commit record.
pub(crate) struct Source {
    pub root: PathBuf,
    pub file_sizes: FileSizes,
    pub robot_type: String,
    pub version: Version,
    pub codec: String,
    pub size: [usize; 2],
    pub state_names: Vec<String>,
    pub action_names: Vec<String>,
    pub cameras: Vec<(String, String)>,
    pub environment_state_names: Vec<String>,
    pub done: Vec<Committed>,
}

impl Source {
    fn keys(&self) -> Vec<String> {
        self.cameras.iter().map(|(_, k)| k.clone()).collect()
    }

    /// Reads a dataset's layout and commit record (v3.0 needs its `.episodes/` parts).
    pub(crate) fn open(root: &Path) -> Result<Source, DatasetError> {
        let bad = |why: String| DatasetError::Existing {
            path: root.to_path_buf(),
            why,
        };
        let info_path = root.join("meta/info.json");
        let info: Value = std::fs::read_to_string(&info_path)
            .map_err(|e| DatasetError::io("read", &info_path, e))
            .and_then(|t| {
                serde_json::from_str(&t).map_err(|e| bad(format!("meta/info.json: {e}")))
            })?;
        let version = match info["codebase_version"].as_str() {
            Some("v2.1") => Version::V21,
            Some("v3.0") => Version::V30,
            other => return Err(bad(format!("is a dataset of version {other:?}"))),
        };
        let features = info["features"]
            .as_object()
            .ok_or_else(|| bad("meta/info.json has no features".into()))?;
        let names = |key: &str| -> Vec<String> {
            features
                .get(key)
                .and_then(|f| f["names"].as_array())
                .into_iter()
                .flatten()
                .filter_map(|n| n.as_str().map(str::to_string))
                .collect()
        };
        let videos: Vec<(&String, &Value)> = features
            .iter()
            .filter(|(_, f)| f["dtype"] == "video")
            .collect();
        let first = videos.first().map(|(_, f)| &f["info"]);
        let dim = |k: &str| first.and_then(|i| i[k].as_u64()).unwrap_or(0) as usize;
        let record = root.join("meta/autobio.jsonl");
        let text =
            std::fs::read_to_string(&record).map_err(|e| DatasetError::io("read", &record, e))?;
        let done = text
            .lines()
            .map(serde_json::from_str::<Committed>)
            .collect::<Result<Vec<_>, _>>()
            .map_err(|e| bad(format!("meta/autobio.jsonl: {e}")))?;
        let defaults = FileSizes::default();
        let source = Source {
            root: root.to_path_buf(),
            file_sizes: FileSizes {
                data_mb: info["data_files_size_in_mb"]
                    .as_f64()
                    .unwrap_or(defaults.data_mb),
                video_mb: info["video_files_size_in_mb"]
                    .as_f64()
                    .unwrap_or(defaults.video_mb),
            },
            robot_type: info["robot_type"].as_str().unwrap_or("").to_string(),
            version,
            codec: first
                .and_then(|i| i["video.codec"].as_str())
                .unwrap_or("")
                .to_string(),
            size: [dim("video.width"), dim("video.height")],
            state_names: names("observation.state"),
            action_names: names("action"),
            environment_state_names: names("observation.environment_state"),
            // Camera names are not kept in a dataset; the feature keys stand for them.
            cameras: videos
                .iter()
                .map(|(k, _)| ((*k).clone(), (*k).clone()))
                .collect(),
            done,
        };
        if version == Version::V30 && !source.done.is_empty() {
            let (data, _) = episode_paths(root, version, &source.keys(), 0);
            if !data.exists() {
                return Err(bad(
                    "has no per-episode parts in .episodes/ (kept by autobio demo); they are needed to merge it"
                        .into(),
                ));
            }
        }
        Ok(source)
    }

    /// The layout its episodes share.
    pub(crate) fn layout(&self) -> Layout {
        Layout {
            robot_type: self.robot_type.clone(),
            state_names: self.state_names.clone(),
            action_names: self.action_names.clone(),
            cameras: self.cameras.clone(),
            environment_state_names: self.environment_state_names.clone(),
        }
    }
}

fn copy(from: &Path, to: &Path) -> Result<(), DatasetError> {
    if let Some(parent) = to.parent() {
        create_dir(parent)?;
    }
    std::fs::copy(from, to)
        .map(|_| ())
        .map_err(|e| DatasetError::io("copy", from, e))
}

/// Stats back from their JSON (images' `[[[x]]]` flattened).
fn from_json(v: &Value) -> FeatureStats {
    let mut out = BTreeMap::new();
    let mut image = false;
    let mut count = 0;
    for (k, vals) in v.as_object().into_iter().flatten() {
        if k == "count" {
            count = vals[0].as_u64().unwrap_or(0);
            continue;
        }
        let flat: Vec<f64> = vals
            .as_array()
            .into_iter()
            .flatten()
            .map(|x| {
                if x.is_array() {
                    image = true;
                    x[0][0].as_f64().unwrap_or(f64::NAN)
                } else {
                    x.as_f64().unwrap_or(f64::NAN)
                }
            })
            .collect();
        let key: &'static str = match k.as_str() {
            "min" => "min",
            "max" => "max",
            "mean" => "mean",
            "std" => "std",
            "q01" => "q01",
            "q10" => "q10",
            "q50" => "q50",
            "q90" => "q90",
            "q99" => "q99",
            _ => continue,
        };
        out.insert(key, flat);
    }
    FeatureStats {
        stats: out,
        count,
        image,
    }
}
