//! One episode on MuJoCo: reset to a scene instance, apply actions, step physics with instrument
//! logic after every step, and report robot and labware state.

use crate::scene::{GRIPPER_CLOSED, Scene};
use compiler::{LabwareParams, SceneInstance, Task};
use labware::thermal_cycler::Latch;
use mujoco_rs::prelude::*;
use serde::{Deserialize, Serialize};
use std::collections::BTreeMap;
use std::sync::Arc;

/// Why a physics step was refused: the simulation became invalid.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum StepError {
    #[error("simulation became unstable at t={time:.3} s: {what}")]
    Unstable { time: f64, what: String },
    #[error("action has {got} values, the robot takes {want}")]
    BadAction { got: usize, want: usize },
}

/// Joint-level state of one labware item, enough to evaluate any predicate on it offline.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct LabwareState {
    pub name: String,
    pub joints: BTreeMap<String, f64>,
    pub locked: bool,
    pub jammed: bool,
}

pub struct Episode {
    pub scene: Arc<Scene>,
    pub task: Task,
    pub data: MjData<Arc<MjModel>>,
    latches: Vec<Latch>,
    pub physics_steps: u64,
}

/// MuJoCo's warning counters that make a step invalid (mjtWarning: BADQPOS..BADCTRL).
const FATAL_WARNINGS: [(usize, &str); 4] = [
    (3, "bad qpos"),
    (4, "bad qvel"),
    (5, "bad qacc"),
    (6, "bad ctrl"),
];

impl Episode {
    pub fn new(scene: Arc<Scene>, task: &Task, instance: &SceneInstance) -> Episode {
        let data = MjData::new(scene.model.clone());
        let mut ep = Episode {
            latches: vec![Latch::default(); task.labware.len()],
            scene,
            task: task.clone(),
            data,
            physics_steps: 0,
        };
        ep.reset(instance);
        ep
    }

    /// Resets physics to the instance: arm joints (and their position targets) from the sample,
    /// grippers open, labware in its declared initial state.
    pub fn reset(&mut self, instance: &SceneInstance) {
        self.data.reset();
        self.physics_steps = 0;
        let scene = self.scene.clone();
        for (r, ids) in scene.robots.iter().enumerate() {
            for (k, &adr) in ids.qpos.iter().enumerate() {
                self.data.qpos_mut()[adr] = instance.robot_q[r][k];
                self.data.ctrl_mut()[ids.actuators[k]] = instance.robot_q[r][k];
            }
            self.data.ctrl_mut()[ids.gripper_actuator] = 0.0;
        }
        for (i, (spec, ids)) in self.task.labware.iter().zip(&scene.labware).enumerate() {
            let LabwareParams::ThermalCycler(p) = &spec.params else {
                continue;
            };
            let state = spec
                .initial
                .get("lid")
                .map(String::as_str)
                .unwrap_or("open");
            let (lid, lever) = match state {
                "open" => (p.lid_open, p.lever_raised),
                "closed" => (p.lid_closed, p.lever_raised),
                _ => (p.lid_closed, p.lever_pressed),
            };
            self.data.qpos_mut()[ids.lid_qpos] = lid;
            self.data.qpos_mut()[ids.lever_qpos] = lever;
            self.latches[i] = Latch::default();
            let locked = self.latches[i].update(p, lid, lever);
            self.data.eq_active_mut()[ids.lock_eq] = locked;
        }
        self.data.forward();
    }

    pub fn time(&self) -> f64 {
        self.data.time()
    }

    /// Sets one robot's targets: its arm joint angles (rad) then the gripper (0 open .. 255 closed).
    pub fn apply(&mut self, robot: usize, action: &[f64]) -> Result<(), StepError> {
        let ids = &self.scene.robots[robot];
        if action.len() != ids.actuators.len() + 1 {
            return Err(StepError::BadAction {
                got: action.len(),
                want: ids.actuators.len() + 1,
            });
        }
        if let Some(bad) = action.iter().position(|v| !v.is_finite()) {
            return Err(StepError::Unstable {
                time: self.time(),
                what: format!("action element {bad} is not finite"),
            });
        }
        let acts = ids.actuators.clone();
        let grip = ids.gripper_actuator;
        for (k, a) in acts.iter().enumerate() {
            self.data.ctrl_mut()[*a] = action[k];
        }
        self.data.ctrl_mut()[grip] = action[acts.len()].clamp(0.0, GRIPPER_CLOSED);
        Ok(())
    }

    /// One physics step: `mj_step` (the lever's detent is the `autobio.detent` plugin inside it),
    /// then the latches.
    pub fn physics_step(&mut self) -> Result<(), StepError> {
        let scene = self.scene.clone();
        self.data.step();
        self.physics_steps += 1;
        for (i, (spec, ids)) in self.task.labware.iter().zip(&scene.labware).enumerate() {
            let LabwareParams::ThermalCycler(p) = &spec.params else {
                continue;
            };
            let (lid, lever) = (
                self.data.qpos()[ids.lid_qpos],
                self.data.qpos()[ids.lever_qpos],
            );
            let locked = self.latches[i].update(p, lid, lever);
            self.data.eq_active_mut()[ids.lock_eq] = locked;
        }
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

    /// Arm joint angles of a robot.
    pub fn arm_q(&self, robot: usize) -> Vec<f64> {
        self.scene.robots[robot]
            .qpos
            .iter()
            .map(|&a| self.data.qpos()[a])
            .collect()
    }

    /// Observation state of a robot: arm joints (rad) then the gripper driver angle (rad, 0..0.8).
    pub fn robot_state(&self, robot: usize) -> Vec<f64> {
        let mut s = self.arm_q(robot);
        s.push(self.data.qpos()[self.scene.robots[robot].gripper_qpos]);
        s
    }

    /// The current targets of a robot, in action layout.
    pub fn robot_ctrl(&self, robot: usize) -> Vec<f64> {
        let ids = &self.scene.robots[robot];
        let mut c: Vec<f64> = ids.actuators.iter().map(|&a| self.data.ctrl()[a]).collect();
        c.push(self.data.ctrl()[ids.gripper_actuator]);
        c
    }

    pub fn labware_state(&self) -> Vec<LabwareState> {
        self.task
            .labware
            .iter()
            .zip(&self.scene.labware)
            .zip(&self.latches)
            .map(|((spec, ids), latch)| LabwareState {
                name: spec.name.clone(),
                joints: BTreeMap::from([
                    ("lid".to_string(), self.data.qpos()[ids.lid_qpos]),
                    ("lever".to_string(), self.data.qpos()[ids.lever_qpos]),
                ]),
                locked: latch.locked,
                jammed: latch.jammed,
            })
            .collect()
    }
}
