//! One episode on MuJoCo: reset to a scene instance, apply actions, step physics with instrument
//! logic after every step, and report robot and labware state.
//!
//! Layouts: an action is every robot's action concatenated in task order (each robot's layout from
//! its robot model: arm joint targets, then the gripper command); a state likewise. Labware is
//! reached only through each item's instrument model: reset from declared part states, its logic
//! after each physics step (the only writer of `eq_active`), and its readings by role.

use crate::scene::{LabwareIds, Scene};
use compiler::quantities::Quantities;
use compiler::{SceneInstance, Task};
use labware::frame::{from_wxyz, position, wxyz};
use labware::model::Effects;
use labware::process::Process;
use labware::{Instrument, LabwareState, Logic, Pose};
use mujoco_rs::prelude::*;
use std::collections::BTreeMap;
use std::sync::Arc;

/// Why a physics step was refused: the simulation became invalid.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum StepError {
    #[error("simulation became unstable at t={time:.3} s: {what}")]
    Unstable { time: f64, what: String },
    #[error("action has {got} values, the robots take {want}")]
    BadAction { got: usize, want: usize },
    #[error("action value {index} is not a finite number ({value})")]
    NonFinite { index: usize, value: f64 },
    /// A target outside its actuator's range (MuJoCo's `ctrlrange`; the gripper's command range).
    #[error("action value {index} ({value}) is outside its actuator's range [{low}, {high}]")]
    OutOfRange {
        index: usize,
        value: f64,
        low: f64,
        high: f64,
    },
}

/// A recorded state that does not fit this scene.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[error(
    "the recorded state does not fit this scene: {state} state values for {want}, logic for {logic} items of {items}"
)]
pub struct RestoreError {
    pub state: usize,
    pub want: usize,
    pub logic: usize,
    pub items: usize,
}

/// The rule every action meets before it is applied: one value per action component
/// (`bounds`, from [`Episode::action_bounds`]), each finite and within its range (a hair of
/// slack for values a model computed in f32). A refused action changes nothing.
pub fn check_action(bounds: &[(f64, f64)], action: &[f64]) -> Result<(), StepError> {
    if action.len() != bounds.len() {
        return Err(StepError::BadAction {
            got: action.len(),
            want: bounds.len(),
        });
    }
    if let Some(index) = action.iter().position(|v| !v.is_finite()) {
        return Err(StepError::NonFinite {
            index,
            value: action[index],
        });
    }
    for (index, (&value, &(low, high))) in action.iter().zip(bounds).enumerate() {
        let slack = 1e-6 * (1.0 + high.abs().max(low.abs()).min(1e6));
        if value < low - slack || value > high + slack {
            return Err(StepError::OutOfRange {
                index,
                value,
                low,
                high,
            });
        }
    }
    Ok(())
}

pub struct Episode {
    pub scene: Arc<Scene>,
    pub task: Task,
    pub data: MjData<Arc<MjModel>>,
    /// Each item's logic state and its joints by role (kept between steps to avoid allocation).
    logic: Vec<Logic>,
    joints: Vec<BTreeMap<String, f64>>,
    effects: Effects,
    /// Processes between items, from their models, run after each item's logic.
    processes: Vec<Box<dyn Process>>,
    /// Every item's root pose for the processes (kept between steps to avoid allocation).
    poses: Vec<Pose>,
    pub physics_steps: u64,
}

/// MuJoCo's warning counters that make a step invalid (mjtWarning: BADQPOS..BADCTRL).
const FATAL_WARNINGS: [(usize, &str); 4] = [
    (3, "bad qpos"),
    (4, "bad qvel"),
    (5, "bad qacc"),
    (6, "bad ctrl"),
];

fn instrument(task: &Task, i: usize) -> &dyn Instrument {
    task.labware[i]
        .params
        .instrument()
        .expect("Scene::build refuses labware without a model")
}

impl Episode {
    pub fn new(scene: Arc<Scene>, task: &Task, instance: &SceneInstance) -> Episode {
        let data = MjData::new(scene.model.clone());
        let n = task.labware.len();
        let mut ep = Episode {
            scene,
            task: task.clone(),
            data,
            logic: vec![Logic::new(); n],
            joints: vec![BTreeMap::new(); n],
            effects: Effects::default(),
            processes: Vec::new(),
            poses: Vec::with_capacity(n),
            physics_steps: 0,
        };
        ep.reset(instance);
        ep
    }

    /// Where a movable item starts: the seat of its `at` slot (`Scene::build` refused the scene if
    /// there is none), else its own placement.
    fn start_pose(&self, i: usize, instance: &SceneInstance) -> Pose {
        crate::scene::start_seat(&self.task, instance, i).unwrap_or(instance.labware_placement[i])
    }

    /// Resets physics to the instance: arm joints (and their position targets) from the sample,
    /// grippers open, labware in its declared initial state and place.
    pub fn reset(&mut self, instance: &SceneInstance) {
        self.data.reset();
        self.physics_steps = 0;
        let scene = self.scene.clone();
        for (r, ids) in scene.robots.iter().enumerate() {
            for (k, &adr) in ids.qpos.iter().enumerate() {
                self.data.qpos_mut()[adr] = instance.robot_q[r][k];
                self.data.ctrl_mut()[ids.actuators[k]] = instance.robot_q[r][k];
            }
            self.data.ctrl_mut()[ids.gripper_actuator] = ids.model.gripper.open;
        }
        for (i, ids) in scene.labware.iter().enumerate() {
            let model = instrument(&self.task, i);
            let reset = model.reset(&self.task.labware[i].initial);
            for (role, v) in reset.joints {
                if let Some((_, adr)) = ids.joints.iter().find(|(r, _)| *r == role) {
                    self.data.qpos_mut()[*adr] = v;
                }
            }
            let offsets = instance.labware_joints.get(&self.task.labware[i].name);
            for (role, offset) in offsets.into_iter().flatten() {
                if let Some((_, adr)) = ids.joints.iter().find(|(r, _)| r == role) {
                    self.data.qpos_mut()[*adr] += offset;
                }
            }
            self.logic[i] = reset.logic;
            let root = self.start_pose(i, instance);
            self.place_item(i, &root);
            self.place_apart(i, instance);
        }
        self.place_held();
        // `Scene::build` and `Scene::reuse_or_build` refuse an instance whose quantities do not
        // resolve; an episode started past them starts with the kinds' defaults.
        let quantities = Quantities::resolve(&self.task, &instance.params).unwrap_or_default();
        self.apply_panel_start(&quantities);
        self.start_volumes(&quantities);
        let vessels: Vec<labware::process::Vessel> = (0..self.task.labware.len())
            .filter_map(|item| {
                let model = instrument(&self.task, item);
                let liquid = model.liquid()?;
                let interior = liquid.interior().filter(|_| liquid.open_vessel())?;
                Some(labware::process::Vessel { item, interior })
            })
            .collect();
        self.processes = (0..self.task.labware.len())
            .flat_map(|i| {
                let liquid = instrument(&self.task, i).liquid();
                liquid
                    .map(|l| l.processes(&self.task.labware[i].name, i, &vessels))
                    .unwrap_or_default()
            })
            .collect();
        self.run_logic(0.0);
        self.data.forward();
    }

    /// Items a hand holds from the start go where the hand holds them (see [`Scene::held`]): on
    /// the robots' reset pose, so after their kinematics.
    fn place_held(&mut self) {
        if self.scene.held.is_empty() {
            return;
        }
        self.data.forward();
        let scene = self.scene.clone();
        for &(i, body, rel) in &scene.held {
            let root = self.body_pose(body) * rel;
            self.place_item(i, &root);
        }
    }

    /// Puts movable item `i` at rest with its root at `root`: each of its free joints where its
    /// model places it.
    fn place_item(&mut self, i: usize, root: &Pose) {
        let scene = self.scene.clone();
        let ids = &scene.labware[i];
        for (joint, pose) in instrument(&self.task, i).place(&self.task.labware[i].name, root) {
            if let Some(f) = ids.free.iter().find(|f| f.name == joint) {
                self.set_free(f, &pose);
            }
        }
    }

    /// Puts free joint `f` at `pose`, at rest.
    fn set_free(&mut self, f: &crate::scene::FreeJoint, pose: &Pose) {
        let (p, q) = (position(pose), wxyz(&pose.rotation));
        let qpos = self.data.qpos_mut();
        qpos[f.qpos..f.qpos + 3].copy_from_slice(&p);
        qpos[f.qpos + 3..f.qpos + 7].copy_from_slice(&q);
        self.data.qvel_mut()[f.dof..f.dof + 6].fill(0.0);
    }

    /// Loose parts of item `i` that start apart from it (a cap lying on the bench) go where the
    /// instance drew them, at rest.
    fn place_apart(&mut self, i: usize, instance: &SceneInstance) {
        let scene = self.scene.clone();
        let ids = &scene.labware[i];
        let name = &self.task.labware[i].name;
        let model = instrument(&self.task, i);
        let apart: Vec<(usize, Pose)> = ids
            .parts
            .iter()
            .filter_map(|(role, body)| {
                let at = instance.part_placement.get(&format!("{name}.{role}"))?;
                let lying = model
                    .part()
                    .filter(|(r, _)| r == role)
                    .map_or(Pose::identity(), |(_, p)| p.lying());
                let f = ids.free.iter().position(|f| f.body == *body)?;
                Some((f, at * lying))
            })
            .collect();
        for (f, pose) in apart {
            self.set_free(&ids.free[f], &pose);
        }
    }

    /// The liquid each container starts with (`[labware.x] volume`, resolved for this instance)
    /// in its logic; a container without a declared volume starts empty (no key: read as 0).
    /// A named liquid (`state = { liquid = ".." }`) is the whole start volume.
    fn start_volumes(&mut self, quantities: &Quantities) {
        for (i, ul) in quantities.start_volumes_ul.iter().enumerate() {
            if let Some(ul) = ul {
                labware::model::set(&mut self.logic[i], labware::process::VOLUME_UL, *ul);
                if let Some(liquid) = &self.task.labware[i].liquid {
                    let key = labware::process::liquid_key(liquid);
                    labware::model::set(&mut self.logic[i], &key, *ul);
                }
            }
        }
    }

    /// Panel values a protocol starts away from the kind's defaults (`[labware.x] state`), rendered
    /// for this instance: a value set with a dial starts with the dial turned to it (its joint),
    /// any other in the item's logic.
    fn apply_panel_start(&mut self, quantities: &Quantities) {
        let scene = self.scene.clone();
        for (i, starts) in quantities.panel_starts.iter().enumerate() {
            for (param, v) in starts {
                let v = *v;
                let dial = instrument(&self.task, i)
                    .panel()
                    .and_then(|p| p.dial_toward(param, v))
                    .and_then(|(role, angle)| {
                        let joints = &scene.labware[i].joints;
                        joints
                            .iter()
                            .find(|(r, _)| *r == role)
                            .map(|(_, a)| (*a, angle))
                    });
                match dial {
                    Some((adr, angle)) => self.data.qpos_mut()[adr] = angle,
                    None => labware::model::set(&mut self.logic[i], param, v),
                }
            }
        }
    }

    /// Every item's per-step logic after `dt` seconds of physics, the switches and actuator
    /// commands it asks for, then the processes between items.
    fn run_logic(&mut self, dt: f64) {
        let scene = self.scene.clone();
        for (i, ids) in scene.labware.iter().enumerate() {
            for (role, adr) in &ids.joints {
                labware::model::set(&mut self.joints[i], role, self.data.qpos()[*adr]);
            }
            self.effects.clear();
            instrument(&self.task, i).step(
                dt,
                &self.joints[i],
                &mut self.logic[i],
                &mut self.effects,
            );
            for (role, on) in &self.effects.switches {
                if let Some((_, eq)) = ids.switches.iter().find(|(r, _)| r == role) {
                    self.data.eq_active_mut()[*eq] = *on;
                }
            }
            for (role, value) in &self.effects.drives {
                if let Some((_, a)) = ids.actuators.iter().find(|(r, _)| r == role) {
                    self.data.ctrl_mut()[*a] = *value;
                }
            }
        }
        if !self.processes.is_empty() {
            self.poses.clear();
            for ids in &scene.labware {
                self.poses.push(self.body_pose(ids.root_body));
            }
            for p in &mut self.processes {
                p.step(dt, &self.poses, &mut self.logic);
            }
        }
    }

    pub fn time(&self) -> f64 {
        self.data.time()
    }

    /// The earliest next event of any item's timers ([`labware::Instrument::next_event`]):
    /// seconds from now, `None` while no instrument runs.
    pub fn next_event(&self) -> Option<f64> {
        (0..self.logic.len())
            .filter_map(|i| instrument(&self.task, i).next_event(&self.logic[i]))
            .min_by(f64::total_cmp)
    }

    /// The coordinates whose stillness lets the clock jump (`crate::clock`): every joint's
    /// position, a loose item's position but not its orientation (a tube in a sleeve chatters
    /// about its axis forever in MuJoCo's soft contacts; one that topples moves).
    pub fn still_coordinates(&self) -> Vec<f64> {
        let qpos = self.data.qpos();
        let mut keep = vec![true; qpos.len()];
        for item in &self.scene.labware {
            for f in &item.free {
                keep[(f.qpos + 3).min(qpos.len())..(f.qpos + 7).min(qpos.len())].fill(false);
            }
        }
        qpos.iter()
            .zip(keep)
            .filter_map(|(v, k)| k.then_some(*v))
            .collect()
    }

    /// Whether every robot's arm is still: each arm joint's velocity under `speed` (rad/s).
    pub fn arms_at_rest(&self, speed: f64) -> bool {
        let qvel = self.data.qvel();
        self.scene
            .robots
            .iter()
            .flat_map(|r| &r.dof)
            .all(|&d| qvel[d].abs() < speed)
    }

    /// Seconds one control step lasts (the task's substeps of physics).
    pub fn control_period(&self) -> f64 {
        self.task.physics.timestep_s * self.task.physics.substeps as f64
    }

    /// Jumps the clock to `time` over a span in which the physics stands still and only the
    /// items' timers run (`crate::clock`): MuJoCo's time moves on, its state does not; each
    /// item's timers advance by the span ([`labware::Instrument::skip`]) and its logic runs once
    /// more (a zero step) for the switches and commands it asks for then.
    pub fn skip_to(&mut self, time: f64) {
        let span = time - self.data.time();
        if span <= 0.0 {
            return;
        }
        self.data.set_time(time);
        for i in 0..self.logic.len() {
            instrument(&self.task, i).skip(span, &mut self.logic[i]);
        }
        self.run_logic(0.0);
    }

    /// Sets every robot's targets from one concatenated action (see the module doc).
    pub fn apply(&mut self, action: &[f64]) -> Result<(), StepError> {
        check_action(&self.action_bounds(), action)?;
        let scene = self.scene.clone();
        let mut rest = action;
        for ids in &scene.robots {
            let (mine, others) = rest.split_at(ids.model.action_len());
            rest = others;
            for (k, a) in ids.actuators.iter().enumerate() {
                self.data.ctrl_mut()[*a] = mine[k];
            }
            self.data.ctrl_mut()[ids.gripper_actuator] =
                ids.model.gripper.clamp(mine[ids.actuators.len()]);
        }
        Ok(())
    }

    /// Each action component's range, in the action layout: the arm actuators' `ctrlrange`
    /// (unbounded where the actuator is not limited), then the gripper's command range.
    pub fn action_bounds(&self) -> Vec<(f64, f64)> {
        let model = self.data.model();
        let (limited, range) = (model.actuator_ctrllimited(), model.actuator_ctrlrange());
        self.scene
            .robots
            .iter()
            .flat_map(|ids| {
                let g = &ids.model.gripper;
                ids.actuators
                    .iter()
                    .map(|&a| match limited[a] {
                        true => (range[a][0], range[a][1]),
                        false => (f64::NEG_INFINITY, f64::INFINITY),
                    })
                    .chain([(g.open.min(g.closed), g.open.max(g.closed))])
                    .collect::<Vec<_>>()
            })
            .collect()
    }

    /// One physics step: `mj_step` (detents and threads are plugins inside it), then every item's
    /// logic.
    pub fn physics_step(&mut self) -> Result<(), StepError> {
        self.data.step();
        self.physics_steps += 1;
        self.run_logic(self.data.model().opt().timestep);
        let warnings = &self.data.ffi().warning;
        for (idx, what) in FATAL_WARNINGS {
            if warnings[idx].number > 0 {
                return Err(StepError::Unstable {
                    time: self.time(),
                    what: what.into(),
                });
            }
        }
        if self.data.qpos().iter().any(|v| !v.is_finite()) {
            return Err(StepError::Unstable {
                time: self.time(),
                what: "non-finite qpos".into(),
            });
        }
        Ok(())
    }

    /// Holds the current action for the task's substeps (one control period).
    pub fn control_step(&mut self) -> Result<(), StepError> {
        for _ in 0..self.task.physics.substeps {
            self.physics_step()?;
        }
        Ok(())
    }

    /// Arm joint angles of one robot.
    pub fn arm_q(&self, robot: usize) -> Vec<f64> {
        self.scene.robots[robot]
            .qpos
            .iter()
            .map(|&a| self.data.qpos()[a])
            .collect()
    }

    /// Observation state of one robot: arm joints (rad) then the gripper driver angle (rad).
    pub fn robot_state(&self, robot: usize) -> Vec<f64> {
        let mut s = self.arm_q(robot);
        s.push(self.data.qpos()[self.scene.robots[robot].gripper_qpos]);
        s
    }

    /// The current targets of one robot, in its action layout.
    pub fn robot_ctrl(&self, robot: usize) -> Vec<f64> {
        let ids = &self.scene.robots[robot];
        let mut c: Vec<f64> = ids.actuators.iter().map(|&a| self.data.ctrl()[a]).collect();
        c.push(self.data.ctrl()[ids.gripper_actuator]);
        c
    }

    /// MuJoCo's generalized positions (every joint of every robot and item): what a collision
    /// check of the scene as it is now starts from ([`crate::clearance::Clearance::sync`]).
    pub fn qpos(&self) -> Vec<f64> {
        self.data.qpos().to_vec()
    }

    /// Every robot's state, concatenated in task order.
    pub fn state(&self) -> Vec<f64> {
        (0..self.scene.robots.len())
            .flat_map(|r| self.robot_state(r))
            .collect()
    }

    /// MuJoCo's full state ([`results::recording::proto::STATE_SPEC`]): with each item's logic,
    /// all a step depends on.
    pub fn physics_state(&self) -> Vec<f64> {
        self.data
            .state(results::recording::proto::STATE_SPEC)
            .into_vec()
    }

    /// Each item's logic state, in task order.
    pub fn logic(&self) -> &[Logic] {
        &self.logic
    }

    /// Puts the episode back into a recorded state: MuJoCo's state ([`Self::physics_state`]) and
    /// each item's logic. Stepping on from here with the recorded actions repeats the recording.
    pub fn restore(&mut self, state: &[f64], logic: Vec<Logic>) -> Result<(), RestoreError> {
        let want = self
            .scene
            .model
            .state_size(results::recording::proto::STATE_SPEC);
        if state.len() != want || logic.len() != self.logic.len() {
            return Err(RestoreError {
                state: state.len(),
                want,
                logic: logic.len(),
                items: self.logic.len(),
            });
        }
        let set = |d: &mut MjData<Arc<MjModel>>| {
            d.set_state(state, results::recording::proto::STATE_SPEC)
                .map_err(|_| RestoreError {
                    state: state.len(),
                    want,
                    logic: 0,
                    items: 0,
                })
        };
        set(&mut self.data)?;
        // Positions for the readings; then the state again, so nothing `mj_forward` wrote
        // (warm start aside, it writes only derived quantities) can differ.
        self.data.forward();
        set(&mut self.data)?;
        self.logic = logic;
        Ok(())
    }

    /// Every robot's current targets, concatenated in task order (the "no motion" action).
    pub fn ctrl(&self) -> Vec<f64> {
        (0..self.scene.robots.len())
            .flat_map(|r| self.robot_ctrl(r))
            .collect()
    }

    fn body_pose(&self, body: usize) -> Pose {
        labware::frame::pose(self.data.xpos()[body], from_wxyz(self.data.xquat()[body]))
    }

    fn item_state(&self, i: usize, ids: &LabwareIds) -> LabwareState {
        LabwareState {
            name: self.task.labware[i].name.clone(),
            pose: self.body_pose(ids.root_body),
            joints: ids
                .joints
                .iter()
                .map(|(role, adr)| (role.to_string(), self.data.qpos()[*adr]))
                .collect(),
            parts: ids
                .parts
                .iter()
                .map(|(role, body)| (role.to_string(), self.body_pose(*body)))
                .collect(),
            logic: self.logic[i].clone(),
            touched_by: self.touching(i),
            finger_contacts: self.fingering(i),
        }
    }

    /// The robots' fingers in contact with labware item `i` now, and where (its own body or a
    /// loose part), in task order, the item's body before its parts.
    fn fingering(&self, item: usize) -> Vec<labware::model::FingerContact> {
        use crate::scene::Owner;
        let geom_body = self.scene.model.geom_bodyid();
        let body = |g: i32| Some(*geom_body.get(usize::try_from(g).ok()?)? as usize);
        let mut found = std::collections::BTreeSet::new();
        for c in self.data.contact() {
            if c.exclude != 0 || c.dist > c.includemargin {
                continue;
            }
            let (Some(a), Some(b)) = (body(c.geom[0]), body(c.geom[1])) else {
                continue;
            };
            for (finger, other) in [(a, b), (b, a)] {
                let Some(robot) = self.scene.body_finger.get(finger).copied().flatten() else {
                    continue;
                };
                if self.scene.body_owner.get(other).copied().flatten() == Some(Owner::Labware(item))
                {
                    found.insert((robot, self.scene.body_part.get(other).copied().flatten()));
                }
            }
        }
        found
            .into_iter()
            .map(|(r, part)| labware::model::FingerContact {
                robot: self.scene.robots[r].name.clone(),
                part: part.map(str::to_string),
            })
            .collect()
    }

    /// The robots in contact with labware item `i` now, in task order.
    fn touching(&self, item: usize) -> Vec<String> {
        use crate::scene::Owner;
        let geom_body = self.scene.model.geom_bodyid();
        let owner = |g: i32| {
            let body = *geom_body.get(usize::try_from(g).ok()?)? as usize;
            self.scene.body_owner.get(body).copied().flatten()
        };
        let mut robots = vec![false; self.scene.robots.len()];
        for c in self.data.contact() {
            // Active contacts only: inside the margin a contact already pushes.
            if c.exclude != 0 || c.dist > c.includemargin {
                continue;
            }
            match (owner(c.geom[0]), owner(c.geom[1])) {
                (Some(Owner::Robot(r)), Some(Owner::Labware(l)))
                | (Some(Owner::Labware(l)), Some(Owner::Robot(r)))
                    if l == item =>
                {
                    robots[r] = true;
                }
                _ => {}
            }
        }
        self.scene
            .robots
            .iter()
            .zip(robots)
            .filter(|(_, t)| *t)
            .map(|(r, _)| r.name.clone())
            .collect()
    }

    /// Every labware item's live state, in task order.
    pub fn labware_state(&self) -> Vec<LabwareState> {
        self.scene
            .labware
            .iter()
            .enumerate()
            .map(|(i, ids)| self.item_state(i, ids))
            .collect()
    }
}
