//! [`primitives::Kinematics`] on MuJoCo: forward kinematics and site Jacobians of an arm's TCP,
//! computed on a private `MjData` so the episode's state is never touched.

use crate::scene::{RobotIds, Scene};
use labware::Pose;
use mujoco_rs::prelude::*;
use std::sync::Arc;

pub struct ArmKinematics {
    data: MjData<Arc<MjModel>>,
    ids: RobotIds,
    limits: Vec<(f64, f64)>,
}

impl ArmKinematics {
    pub fn new(scene: &Scene, robot: usize) -> ArmKinematics {
        let ids = scene.robots[robot].clone();
        let m = &scene.model;
        // A joint's range, narrowed to its servo's command range where that is limited (the
        // UR5e's wrist 3 turns over ±2π but takes commands over ±6.2831 only): what the IK may
        // choose and the expert may command.
        let (limited, ctrl) = (m.actuator_ctrllimited(), m.actuator_ctrlrange());
        let limits = ids
            .joints
            .iter()
            .zip(&ids.actuators)
            .map(|(&j, &a)| {
                let r = m.jnt_range()[j];
                if limited[a] {
                    (r[0].max(ctrl[a][0]), r[1].min(ctrl[a][1]))
                } else {
                    (r[0], r[1])
                }
            })
            .collect();
        ArmKinematics {
            data: MjData::new(scene.model.clone()),
            ids,
            limits,
        }
    }

    fn set(&mut self, q: &[f64]) {
        for (k, &adr) in self.ids.qpos.iter().enumerate() {
            self.data.qpos_mut()[adr] = q[k];
        }
        self.data.kinematics();
    }

    fn site_pose(&self) -> Pose {
        let s = self.ids.tcp_site;
        labware::frame::pose(
            self.data.site_xpos()[s],
            labware::frame::from_rows(&self.data.site_xmat()[s]),
        )
    }
}

impl primitives::Kinematics for ArmKinematics {
    fn dof(&self) -> usize {
        self.ids.qpos.len()
    }

    fn limits(&self) -> Vec<(f64, f64)> {
        self.limits.clone()
    }

    fn tcp(&mut self, q: &[f64]) -> Pose {
        self.set(q);
        self.site_pose()
    }

    fn jacobian(&mut self, q: &[f64]) -> (Pose, Vec<[f64; 6]>) {
        self.set(q);
        self.data.com_pos();
        let (jp, jr) = self.data.jac_site(true, true, self.ids.tcp_site);
        let nv = self.data.model().ffi().nv as usize;
        let cols = self
            .ids
            .dof
            .iter()
            .map(|&d| {
                [
                    jp[d],
                    jp[nv + d],
                    jp[2 * nv + d],
                    jr[d],
                    jr[nv + d],
                    jr[2 * nv + d],
                ]
            })
            .collect();
        (self.site_pose(), cols)
    }
}
