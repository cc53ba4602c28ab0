//! The compiled task: the contract between the compiler and everything downstream. Serialised as
//! JSON by `autobio compile`; `schema_version` changes whenever a field changes meaning.

use crate::params::{Bindings, ParamSpec, draw_all, render, uniform};
use crate::predicates::Check;
use labware::frame::{serde_pose, serde_poses};
use labware::{Model, Pose};
use rand_core::SeedableRng;
use serde::{Deserialize, Serialize};
use std::collections::BTreeMap;

/// 2: stages (chains), parameters, typed checks with named tolerances, progress scoring.
/// 3: a state check may be `ever` (the `was` predicate: held at some control step so far), which
/// a reader of version 2 would take for a check of the present.
pub const TASK_SCHEMA_VERSION: u32 = 3;

#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Task {
    pub schema_version: u32,
    pub id: String,
    pub version: i64,
    pub level: String,
    /// The whole task's instruction (template over `params`).
    pub instruction: String,
    pub source: String,
    /// The sum of the stages' limits.
    pub time_limit_s: f64,
    pub physics: Physics,
    pub robots: Vec<RobotSpec>,
    pub labware: Vec<LabwareSpec>,
    pub cameras: Vec<CameraSpec>,
    /// Drawn per episode, in order, after the scene randomisation.
    pub params: Vec<ParamSpec>,
    /// One for a protocol; one per protocol of a chain, run in order on one scene.
    pub stages: Vec<Stage>,
    /// The file `autobio import` wrote the protocol from (`[protocol] imported_from`); part of
    /// the task's content, so its hash covers it.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub imported_from: Option<ImportedFrom>,
    /// Other wordings of `instruction` (same placeholders) that the `language` perturbation
    /// draws from (`[protocol] paraphrases`).
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub paraphrases: Vec<String>,
    /// How episodes vary beyond the randomisation (`[perturb]`, a suite's or `--perturb`'s
    /// presets over it): part of the task's content, so its hash covers it.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub perturb: Option<crate::perturb::Perturb>,
}

/// Where an imported protocol came from: the source file's name, its format and the SHA-256 of
/// its bytes.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct ImportedFrom {
    pub file: String,
    pub format: String,
    pub sha256: String,
}

/// One stage: its own instruction, plan, checks and time limit.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Stage {
    pub id: String,
    pub source: String,
    /// Template over the task's params.
    pub instruction: String,
    pub time_limit_s: f64,
    pub plan: Vec<PlannedStep>,
    pub success: Vec<Predicate>,
    pub scoring: Scoring,
    /// How long every predicate must go on holding before the stage counts as done (s):
    /// success is a state, not a moment (a lid flung through "open" and falling back is not
    /// open). Tasks compiled before it existed read as 0.
    #[serde(default)]
    pub settle_s: f64,
}

/// The settle time a protocol gets when its `[success] settle` names none (s): a part that only
/// passes through its target band (tests/settle.rs: a lid open for 0.3 s) does not count, and a
/// successful episode lasts 25 control steps longer (docs/tasks.md: the expert's mean episode
/// 0.5 s longer on every task, its success unchanged).
pub const DEFAULT_SETTLE_S: f64 = 0.5;

#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Scoring {
    /// 1 when every predicate holds, else 0; the stage ends as soon as they all hold.
    Binary,
    /// The weighted mean of each predicate's progress toward its target.
    Progress,
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
    #[serde(with = "serde_pose")]
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
    #[serde(with = "serde_pose")]
    pub placement: Pose,
    /// ± metres of uniform planar jitter, ± radians of uniform yaw jitter.
    pub xy_jitter_m: f64,
    pub yaw_jitter_rad: f64,
    /// ± radians of uniform jitter of a joint's start angle, by role (a rotor's).
    #[serde(default, skip_serializing_if = "BTreeMap::is_empty")]
    pub joint_jitter: BTreeMap<String, f64>,
    /// Initial part states (every part of the kind).
    pub initial: BTreeMap<String, String>,
    /// Where each loose part that starts `apart` lies (world), by role; the item's own place is
    /// `placement` or `at` as for any item.
    #[serde(
        default,
        skip_serializing_if = "BTreeMap::is_empty",
        with = "labware::frame::serde_pose_map"
    )]
    pub parts: BTreeMap<String, Pose>,
    /// Radius (m) of the disc each part lying apart is drawn in about its `parts` pose.
    #[serde(default, skip_serializing_if = "is_zero")]
    pub parts_radius_m: f64,
    /// Where a movable item starts (template `holder.slot`); `None`: at `placement`.
    pub at: Option<String>,
    /// The robot whose hand holds the item at the start (welded at its grasp; `at` is then none).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub held_by: Option<String>,
    /// Initial liquid volume (template quantity), for containers.
    pub volume: Option<String>,
    /// The named liquid the start volume is (`state = { liquid = "water" }`, Opentrons'
    /// `loadLiquid`): predicates may ask how much of it a container holds.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub liquid: Option<String>,
    /// Initial panel values (template quantities) that differ from the kind's defaults.
    pub panel: BTreeMap<String, String>,
    /// The kind's simulation model and its parameters (`Model::Unmodelled` when it has none).
    pub params: Model,
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
    pub robot: String,
    /// The `on` argument, when the primitive takes one.
    pub labware: Option<String>,
    /// Every argument as written (templates over the task's params), `on` included.
    pub args: BTreeMap<String, String>,
    /// The step starts with the one before it (`together = true`), on another robot: the
    /// expert runs one motion lane per robot, and the steps of a group move at once.
    #[serde(default, skip_serializing_if = "std::ops::Not::not")]
    pub together: bool,
    /// Where the step is written in its stage's file ([`Stage::source`]): what a diagnostic
    /// after lowering points at.
    #[serde(skip)]
    pub span: StepSpan,
}

/// Where a planned step is written: its `with`, else the whole step; a step a loop expanded
/// keeps the span of the body step it came from, so the third expansion of a `for_each` points
/// at the loop's body. Not part of the task's content: never serialised (a task read back from
/// JSON, a recording's, has the default) and equal whatever it is, so that a task compiled here
/// equals the same task read back.
#[derive(Clone, Copy, Debug, Default)]
pub struct StepSpan(pub dsl::Span);

impl PartialEq for StepSpan {
    fn eq(&self, _: &StepSpan) -> bool {
        true
    }
}

#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Predicate {
    /// As written: "cycler.lid is closed".
    pub text: String,
    pub check: Check,
    /// Weight in progress scoring.
    pub weight: f64,
    /// A time constraint on the check (`... for 30 s to 40 s`): it holds when the check has
    /// held for a total time within these bounds during the stage, as the judge measures it on
    /// the episode's clock.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub dwell: Option<crate::predicates::Dwell>,
    /// A step's timing (`within` on a step): the check holds once it first holds no later than
    /// [`Since::within_s`] after the earlier step's outcome first held, on the episode's clock,
    /// and goes on holding whatever happens next (the judge keeps the two times).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub since: Option<Since>,
}

/// What a timed step's outcome is timed from: the earlier step's outcome as a check.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Since {
    /// The earlier step's outcome as a predicate ("cells in mixer.{well}").
    pub text: String,
    pub check: Check,
    pub within_s: f64,
}

impl Since {
    /// The earlier step's outcome as a predicate of its own (what the judge resolves).
    pub fn predicate(&self) -> Predicate {
        Predicate {
            text: self.text.clone(),
            check: self.check.clone(),
            weight: 0.0,
            dwell: None,
            since: None,
        }
    }
}

/// One concrete episode's scene, drawn from a task and a seed.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct SceneInstance {
    pub seed: u64,
    /// Initial arm joint angles per robot, in task order.
    pub robot_q: Vec<Vec<f64>>,
    /// Placement per labware, in task order.
    #[serde(with = "serde_poses")]
    pub labware_placement: Vec<Pose>,
    /// The drawn parameter values.
    pub params: Bindings,
    /// Offsets of labware joints' start angles (rad), by item and role: only the jittered ones.
    #[serde(default, skip_serializing_if = "BTreeMap::is_empty")]
    pub labware_joints: BTreeMap<String, BTreeMap<String, f64>>,
    /// Where each loose part that starts apart lies (world), by `item.part`.
    #[serde(
        default,
        skip_serializing_if = "BTreeMap::is_empty",
        with = "labware::frame::serde_pose_map"
    )]
    pub part_placement: BTreeMap<String, Pose>,
    /// The task's instruction, and each stage's, with the parameters filled in.
    pub instruction: String,
    pub stage_instructions: Vec<String>,
    /// What the task's perturbations drew for this episode (their changes to the instruction,
    /// start pose and layout are already in the fields above).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub perturbation: Option<crate::perturb::Drawn>,
}

impl Task {
    /// The task with each item's model running the programmes its run steps carry
    /// ([`labware::run`]), in the order the stages run them. A run step's arguments are fixed
    /// when the task compiles (the checks refuse a placeholder in them); a step whose programme
    /// does not read was reported by the proof.
    pub fn with_programmes(mut self) -> Task {
        let mut runs: BTreeMap<String, Vec<labware::run::Programme>> = BTreeMap::new();
        for step in self.stages.iter().flat_map(|s| &s.plan) {
            let Some(on) = &step.labware else { continue };
            let kind = self
                .labware
                .iter()
                .find(|l| &l.name == on)
                .map(|l| l.kind.as_str());
            let Some(Ok(p)) = crate::primitives::run::programme(&step.primitive, &step.args, kind)
            else {
                continue;
            };
            runs.entry(on.clone()).or_default().push(p);
        }
        for item in &mut self.labware {
            if let Some(p) = runs.remove(&item.name) {
                item.params = std::mem::replace(&mut item.params, labware::Model::Unmodelled)
                    .with_programmes(p);
            }
        }
        self
    }

    /// Draws the scene for `seed`. Draw order: robots in order (one draw per joint), then labware in
    /// order (x, y, yaw), then parameters in order, then labware joint offsets (items in order,
    /// roles in name order), then the places of parts lying apart (items in order, parts in name
    /// order: radius, then angle, upstream's disc draw; only where a radius is given). Each kind
    /// of draw comes after the older ones, so that adding one leaves every other draw as it was.
    /// The task's perturbations draw last, each from a stream of its own (`perturb::draw`).
    /// The same task and seed always give the same instance.
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
                let p = labware::frame::position(&l.placement);
                labware::frame::pose(
                    [p[0] + dx, p[1] + dy, p[2]],
                    l.placement.rotation * labware::frame::axis_angle([0.0, 0.0, 1.0], dyaw),
                )
            })
            .collect();
        // The compiler proved every combination it traced drawable; a sampled proof may miss one,
        // in which case the episode gets no parameters and its templates stay as written.
        let params = draw_all(&self.params, &mut rng).unwrap_or_default();
        let labware_joints = self
            .labware
            .iter()
            .filter(|l| !l.joint_jitter.is_empty())
            .map(|l| {
                let offsets = l
                    .joint_jitter
                    .iter()
                    .map(|(role, &j)| (role.clone(), uniform(&mut rng, -j, j)))
                    .collect();
                (l.name.clone(), offsets)
            })
            .collect();
        let mut part_placement = BTreeMap::new();
        for l in &self.labware {
            for (part, pose) in &l.parts {
                let mut p = *pose;
                if l.parts_radius_m > 0.0 {
                    let r = l.parts_radius_m * uniform(&mut rng, 0.0, 1.0).sqrt();
                    let a = uniform(&mut rng, 0.0, std::f64::consts::TAU);
                    p.translation.vector.x += r * a.cos();
                    p.translation.vector.y += r * a.sin();
                }
                part_placement.insert(format!("{}.{part}", l.name), p);
            }
        }
        let fill = |t: &str| render(t, &params).unwrap_or_else(|_| t.to_string());
        let mut instance = SceneInstance {
            seed,
            robot_q,
            labware_placement,
            instruction: fill(&self.instruction),
            stage_instructions: self.stages.iter().map(|s| fill(&s.instruction)).collect(),
            params,
            labware_joints,
            part_placement,
            perturbation: None,
        };
        if let Some(p) = self.perturb.as_ref().filter(|p| !p.is_empty()) {
            instance.perturbation = Some(crate::perturb::draw(p, self, &mut instance));
        }
        instance
    }

    /// The task with `over`'s perturbation dimensions replacing its own (a suite's or the
    /// command line's presets).
    pub fn with_perturb(mut self, over: &crate::perturb::Perturb) -> Task {
        if !over.is_empty() {
            let own = self.perturb.take().unwrap_or_default();
            self.perturb = Some(own.overlay(over));
        }
        self
    }

    pub fn labware_index(&self, name: &str) -> Option<usize> {
        self.labware.iter().position(|l| l.name == name)
    }

    pub fn robot_index(&self, name: &str) -> Option<usize> {
        self.robots.iter().position(|r| r.name == name)
    }

    /// Every planned step of every stage, with its stage index.
    pub fn steps(&self) -> impl Iterator<Item = (usize, &PlannedStep)> {
        self.stages
            .iter()
            .enumerate()
            .flat_map(|(i, s)| s.plan.iter().map(move |p| (i, p)))
    }

    /// The liquid tool (a pipette) `robot` carries when step `before` (counted over every
    /// stage's plan) begins: one it holds from the start, picked or was handed over since, and
    /// has not put down. What `aspirate` and `dispense` work with (the proof has checked there
    /// is one).
    pub fn liquid_tool(&self, robot: &str, before: usize) -> Option<String> {
        let is_tool = |item: &str| {
            self.labware
                .iter()
                .find(|l| l.name == item)
                .and_then(|l| labware::kind(&l.kind))
                .is_some_and(|k| k.liquid_tool)
        };
        let mut carried = self
            .labware
            .iter()
            .find(|l| l.held_by.as_deref() == Some(robot))
            .map(|l| l.name.clone());
        for (_, step) in self.steps().take(before) {
            let on = step.labware.clone();
            match step.primitive.as_str() {
                "pick" if step.robot == robot => carried = on,
                "place" if step.robot == robot => carried = None,
                "hand_over" if step.robot == robot => carried = None,
                "hand_over" if step.args.get("to").map(String::as_str) == Some(robot) => {
                    carried = on
                }
                _ => {}
            }
        }
        carried.filter(|c| is_tool(c))
    }
}

fn is_zero(v: &f64) -> bool {
    *v == 0.0
}
