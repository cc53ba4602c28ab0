//! The compiled task: the contract between the compiler and everything downstream. Serialised as
//! JSON by `autobio compile`; `schema_version` changes whenever a field changes meaning.

use labware::{Pose, thermal_cycler};
use rand_core::{RngCore, SeedableRng};
use serde::{Deserialize, Serialize};
use std::collections::BTreeMap;

pub const TASK_SCHEMA_VERSION: u32 = 1;

#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Task {
    pub schema_version: u32,
    pub id: String,
    pub version: i64,
    pub level: String,
    pub instruction: String,
    pub source: String,
    pub time_limit_s: f64,
    pub physics: Physics,
    pub robots: Vec<RobotSpec>,
    pub labware: Vec<LabwareSpec>,
    pub cameras: Vec<CameraSpec>,
    pub plan: Vec<PlannedStep>,
    pub success: Vec<Predicate>,
}

#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Physics {
    pub timestep_s: f64,
    /// Physics steps each policy action is held for (500 Hz / 10 = 50 Hz control).
    pub substeps: u32,
}

impl Physics {
    pub fn control_hz(&self) -> f64 {
        1.0 / (self.timestep_s * self.substeps as f64)
    }
}

#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct RobotSpec {
    pub name: String,
    pub model: String,
    pub base: Pose,
    pub home: Vec<f64>,
    /// Uniform per-joint offsets added to `home` (rad), if randomised.
    pub joint_jitter: Option<JointJitter>,
}

#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct JointJitter {
    pub low: Vec<f64>,
    pub high: Vec<f64>,
}

#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct LabwareSpec {
    pub name: String,
    pub kind: String,
    pub placement: Pose,
    /// ± metres of uniform planar jitter, ± radians of uniform yaw jitter.
    pub xy_jitter_m: f64,
    pub yaw_jitter_rad: f64,
    pub initial: BTreeMap<String, String>,
    pub params: LabwareParams,
}

#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(tag = "kind", rename_all = "snake_case")]
pub enum LabwareParams {
    ThermalCycler(thermal_cycler::Params),
}

#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct CameraSpec {
    pub name: String,
    pub width: u32,
    pub height: u32,
    pub mount: CameraMount,
}

#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum CameraMount {
    /// Fixed in the world: position and the camera's x/y axes (MuJoCo `xyaxes`), vertical fov (deg).
    Fixed {
        pos: [f64; 3],
        xyaxes: [f64; 6],
        fovy_deg: f64,
    },
    /// On a robot's wrist.
    Wrist { robot: String },
}

#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct PlannedStep {
    pub primitive: String,
    pub labware: String,
    pub robot: String,
    /// The part state before and after, as traced by the compiler.
    pub from_state: String,
    pub to_state: String,
}

#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Predicate {
    /// As written: "cycler.lid is closed".
    pub text: String,
    pub labware: String,
    pub part: String,
    pub state: String,
    /// The named tolerance this predicate uses (rad).
    pub tolerance: f64,
}

/// One concrete episode's scene, drawn from a task and a seed.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct SceneInstance {
    pub seed: u64,
    /// Initial arm joint angles per robot, in task order.
    pub robot_q: Vec<Vec<f64>>,
    /// Placement per labware, in task order.
    pub labware_placement: Vec<Pose>,
}

/// Uniform draw in [lo, hi) from 53 random bits.
fn uniform(rng: &mut rand_chacha::ChaCha8Rng, lo: f64, hi: f64) -> f64 {
    let u = (rng.next_u64() >> 11) as f64 * (1.0 / (1u64 << 53) as f64);
    lo + (hi - lo) * u
}

impl Task {
    /// Draws the scene for `seed`. Draw order: robots in order (one draw per joint), then labware in
    /// order (x, y, yaw). The same task and seed always give the same instance.
    pub fn sample(&self, seed: u64) -> SceneInstance {
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(seed);
        let robot_q = self
            .robots
            .iter()
            .map(|r| {
                let mut q = r.home.clone();
                if let Some(j) = &r.joint_jitter {
                    for (i, qi) in q.iter_mut().enumerate() {
                        if i < j.low.len() {
                            *qi += uniform(&mut rng, j.low[i], j.high[i]);
                        }
                    }
                }
                q
            })
            .collect();
        let labware_placement = self
            .labware
            .iter()
            .map(|l| {
                let dx = uniform(&mut rng, -l.xy_jitter_m, l.xy_jitter_m);
                let dy = uniform(&mut rng, -l.xy_jitter_m, l.xy_jitter_m);
                let dyaw = uniform(&mut rng, -l.yaw_jitter_rad, l.yaw_jitter_rad);
                let p = l.placement.pos;
                Pose::new(
                    [p[0] + dx, p[1] + dy, p[2]],
                    l.placement
                        .quat
                        .times(labware::Quat::from_axis_angle([0.0, 0.0, 1.0], dyaw)),
                )
            })
            .collect();
        SceneInstance {
            seed,
            robot_q,
            labware_placement,
        }
    }

    pub fn labware_index(&self, name: &str) -> Option<usize> {
        self.labware.iter().position(|l| l.name == name)
    }

    pub fn robot_index(&self, name: &str) -> Option<usize> {
        self.robots.iter().position(|r| r.name == name)
    }
}
