//! Model profiles: how autobio's observations and actions map onto what one model expects (keys,
//! image size and cameras, state layout and dtype, chunk size and how much of it runs, reset
//! frames, timeouts). A profile is a TOML file a user can write; `pi0` and `rdt` are built in
//! (`profiles/*.toml`). Every field is written into the run's results, so a number always says
//! what it was measured under.
//!
//! It does not speak any wire protocol (`scoring::remote` does) and does not render.

use compiler::{CameraMount, Task};
use serde::{Deserialize, Serialize};
use std::path::{Path, PathBuf};

/// The built-in profiles, by name, with their text.
pub const BUILT_IN: &[(&str, &str)] = &[
    ("pi0", include_str!("../../profiles/pi0.toml")),
    ("rdt", include_str!("../../profiles/rdt.toml")),
    (
        "lerobot-state",
        include_str!("../../profiles/lerobot-state.toml"),
    ),
    (
        "lerobot-vision",
        include_str!("../../profiles/lerobot-vision.toml"),
    ),
];

#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Profile {
    pub name: String,
    /// Actions per chunk the model may answer; a longer chunk fails the episode.
    pub chunk: usize,
    /// Actions of each chunk run before the next query (the replanning interval).
    pub execute: usize,
    /// Rendered image size (width, height).
    pub image_size: [usize; 2],
    #[serde(default)]
    pub image_encoding: ImageEncoding,
    pub state_key: String,
    #[serde(default)]
    pub state_dtype: StateDtype,
    pub prompt_key: String,
    #[serde(default)]
    pub reset_frame: bool,
    pub timeout_s: f64,
    /// The length of the state (and action) vector the model works in; autobio's own when absent.
    #[serde(default)]
    pub state_dim: Option<usize>,
    /// Where each component of autobio's state (and action) sits in that vector.
    #[serde(default)]
    pub state_indices: Option<Vec<usize>>,
    /// Also send each image from this many control steps before the query (0: none).
    #[serde(default)]
    pub history_steps: u32,
    #[serde(default, rename = "image")]
    pub images: Vec<ImageKey>,
    /// Also send the task's environment state (`results::environment_state`: the poses, joints
    /// and panel values its success checks read) under this key. Privileged: a run with it is a
    /// state-based run, shown apart from vision models on the leaderboard.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub environment_state_key: Option<String>,
}

impl Profile {
    /// The observation this profile's model reads: `state` when it is sent the environment
    /// state (privileged), else `vision`.
    pub fn observation_mode(&self) -> &'static str {
        if self.environment_state_key.is_some() {
            "state"
        } else {
            "vision"
        }
    }
}

#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ImageKey {
    pub key: String,
    /// A task camera name, or `wrist:N` for the N-th robot's wrist camera.
    pub camera: String,
    /// The key of the same camera's earlier frame (needs `history_steps` > 0).
    #[serde(default)]
    pub previous_key: Option<String>,
}

#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum ImageEncoding {
    #[default]
    Png,
    Raw,
}

#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum StateDtype {
    #[default]
    Float32,
    Float64,
}

#[derive(Debug, thiserror::Error)]
pub enum ProfileError {
    #[error("cannot read profile {path}: {source}")]
    Read {
        path: PathBuf,
        source: std::io::Error,
    },
    #[error("profile {origin}: {message}")]
    Invalid { origin: String, message: String },
    #[error("profile `{profile}` does not fit task `{task}`: {message}")]
    Task {
        profile: String,
        task: String,
        message: String,
    },
}

/// A profile with where it came from and the exact text it was read from (hashed into the
/// manifest).
#[derive(Clone, Debug)]
pub struct LoadedProfile {
    pub profile: Profile,
    /// `built-in pi0` or the file's path.
    pub origin: String,
    pub text: String,
}

impl LoadedProfile {
    /// A built-in profile by name, or a profile file.
    pub fn load(spec: &str) -> Result<LoadedProfile, ProfileError> {
        let (origin, text) = match BUILT_IN.iter().find(|(n, _)| *n == spec) {
            Some((name, text)) => (format!("built-in {name}"), text.to_string()),
            None => {
                let path = Path::new(spec);
                let text = std::fs::read_to_string(path).map_err(|source| ProfileError::Read {
                    path: path.to_path_buf(),
                    source,
                })?;
                (path.display().to_string(), text)
            }
        };
        LoadedProfile::from_text(text, origin)
    }

    /// A profile from its text; `origin` says where the text came from.
    pub fn from_text(text: String, origin: String) -> Result<LoadedProfile, ProfileError> {
        let profile = Profile::parse(&text, &origin)?;
        Ok(LoadedProfile {
            profile,
            origin,
            text,
        })
    }
}

impl Profile {
    pub fn parse(text: &str, origin: &str) -> Result<Profile, ProfileError> {
        let invalid = |message: String| ProfileError::Invalid {
            origin: origin.to_string(),
            message,
        };
        let p: Profile = toml::from_str(text).map_err(|e| invalid(e.to_string()))?;
        if p.chunk == 0 || p.execute == 0 || p.execute > p.chunk {
            return Err(invalid(format!(
                "`execute` ({}) must be between 1 and `chunk` ({})",
                p.execute, p.chunk
            )));
        }
        if p.image_size.contains(&0) || p.image_size.iter().any(|&s| s > 4096) {
            return Err(invalid(format!(
                "`image_size` {:?} must be between 1 and 4096 pixels a side",
                p.image_size
            )));
        }
        if !(0.001..=86_400.0).contains(&p.timeout_s) {
            return Err(invalid(format!(
                "`timeout_s` must be positive, between 0.001 and 86400 s, not {}",
                p.timeout_s
            )));
        }
        if p.state_dim.is_some() != p.state_indices.is_some() {
            return Err(invalid(
                "`state_dim` and `state_indices` go together: give both or neither".into(),
            ));
        }
        if let (Some(dim), Some(ix)) = (p.state_dim, &p.state_indices) {
            if let Some(bad) = ix.iter().find(|&&i| i >= dim) {
                return Err(invalid(format!(
                    "state index {bad} is outside `state_dim` {dim}"
                )));
            }
            let mut seen = std::collections::HashSet::new();
            if let Some(dup) = ix.iter().find(|i| !seen.insert(**i)) {
                return Err(invalid(format!("state index {dup} is used twice")));
            }
        }
        for im in &p.images {
            if im.previous_key.is_some() && p.history_steps == 0 {
                return Err(invalid(format!(
                    "image `{}` has a `previous_key` but `history_steps` is 0",
                    im.key
                )));
            }
        }
        Ok(p)
    }

    /// Where this profile's cameras and state go in `task`.
    pub fn resolve(&self, task: &Task) -> Result<Layout, ProfileError> {
        let err = |message: String| ProfileError::Task {
            profile: self.name.clone(),
            task: task.id.clone(),
            message,
        };
        let cameras = self
            .images
            .iter()
            .map(|im| camera_index(task, &im.camera).map_err(|e| err(e.to_string())))
            .collect::<Result<Vec<_>, _>>()?;
        let state_len: usize = task
            .robots
            .iter()
            .map(|r| robots::model(&r.model).map(|m| m.action_len()).unwrap_or(0))
            .sum();
        if let Some(ix) = &self.state_indices
            && ix.len() < state_len
        {
            return Err(err(format!(
                "the task's state has {state_len} components but `state_indices` places {}",
                ix.len()
            )));
        }
        Ok(Layout { cameras, state_len })
    }

    /// autobio's state (or action) in the model's vector.
    pub fn to_model(&self, v: &[f64]) -> Vec<f64> {
        match (self.state_dim, &self.state_indices) {
            (Some(dim), Some(ix)) => {
                let mut out = vec![0.0; dim];
                for (k, &x) in v.iter().enumerate() {
                    out[ix[k]] = x;
                }
                out
            }
            _ => v.to_vec(),
        }
    }

    /// An action in the model's vector back in autobio's layout (`len` components), or `None`
    /// when its length is not the model's.
    pub fn from_model(&self, a: &[f64], len: usize) -> Option<Vec<f64>> {
        match (self.state_dim, &self.state_indices) {
            (Some(dim), Some(ix)) if a.len() == dim => {
                Some(ix[..len].iter().map(|&i| a[i]).collect())
            }
            (Some(_), Some(_)) => None,
            _ if a.len() == len => Some(a.to_vec()),
            _ => None,
        }
    }

    /// The action length the model answers with for a task whose action has `len` components.
    pub fn action_dim(&self, len: usize) -> usize {
        self.state_dim.unwrap_or(len)
    }
}

/// A profile resolved against one task.
#[derive(Clone, Debug, PartialEq)]
pub struct Layout {
    /// Per profile image, the task camera's index (`None`: the task has no such camera).
    pub cameras: Vec<Option<usize>>,
    /// autobio's state (and action) length for the task.
    pub state_len: usize,
}

/// Why a profile image's camera is not one of a task's.
#[derive(Clone, Debug, PartialEq, Eq, thiserror::Error)]
enum CameraError {
    #[error("camera `{camera}`: `wrist:` takes a robot number")]
    WristNumber { camera: String },
    /// `cameras`: the task's camera names.
    #[error("it has no camera `{camera}` (it has {}, and `wrist:N`)", .cameras.join(", "))]
    NoCamera {
        camera: String,
        cameras: Vec<String>,
    },
}

fn camera_index(task: &Task, camera: &str) -> Result<Option<usize>, CameraError> {
    if let Some(n) = camera.strip_prefix("wrist:") {
        let n: usize = n.parse().map_err(|_| CameraError::WristNumber {
            camera: camera.to_string(),
        })?;
        let Some(robot) = task.robots.get(n) else {
            return Ok(None);
        };
        return Ok(task.cameras.iter().position(
            |c| matches!(&c.mount, CameraMount::Wrist { robot: r } if *r == robot.name),
        ));
    }
    task.cameras
        .iter()
        .position(|c| c.name == camera)
        .map(Some)
        .ok_or_else(|| CameraError::NoCamera {
            camera: camera.to_string(),
            cameras: task.cameras.iter().map(|c| c.name.clone()).collect(),
        })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn built_in_profiles_parse() {
        for (name, _) in BUILT_IN {
            let p = LoadedProfile::load(name).unwrap();
            assert_eq!(p.profile.name, *name);
        }
        let rdt = LoadedProfile::load("rdt").unwrap().profile;
        let state = [1.0, 2.0, 3.0, 4.0, 5.0, 6.0, 0.5];
        let v = rdt.to_model(&state);
        assert_eq!(v.len(), 128);
        assert_eq!((v[5], v[10], v[6]), (6.0, 0.5, 0.0));
        assert_eq!(rdt.from_model(&v, 7).unwrap(), state);
        assert_eq!(rdt.from_model(&state, 7), None);
    }

    #[test]
    fn bad_profiles_say_what_is_wrong() {
        let base = BUILT_IN[0].1;
        for (edit, want) in [
            (
                ("execute = 50", "execute = 51"),
                "must be between 1 and `chunk`",
            ),
            (
                ("timeout_s = 30.0", "timeout_s = 0.0"),
                "`timeout_s` must be positive",
            ),
            (
                ("chunk = 50", "chunk = 50\nbogus = 1"),
                "unknown field `bogus`",
            ),
            (
                ("image_size = [224, 224]", "image_size = [0, 224]"),
                "`image_size`",
            ),
            (
                ("reset_frame = false", "reset_frame = false\nstate_dim = 8"),
                "go together",
            ),
        ] {
            let text = base.replacen(edit.0, edit.1, 1);
            assert_ne!(text, base, "edit {edit:?} did not apply");
            let e = Profile::parse(&text, "test").unwrap_err().to_string();
            assert!(e.contains(want), "{edit:?}: {e}");
        }
    }

    #[test]
    fn camera_errors_name_the_camera() {
        let wrist = CameraError::WristNumber {
            camera: "wrist:left".into(),
        };
        assert_eq!(
            wrist.to_string(),
            "camera `wrist:left`: `wrist:` takes a robot number"
        );
        let missing = CameraError::NoCamera {
            camera: "top".into(),
            cameras: vec!["front".into(), "side".into()],
        };
        assert_eq!(
            missing.to_string(),
            "it has no camera `top` (it has front, side, and `wrist:N`)"
        );
    }
}
