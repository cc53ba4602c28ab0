//! Lab primitive -> motions, and motions -> TCP poses against live labware state.

use labware::frame::{add, norm, scale, sub};
use labware::thermal_cycler::Params;
use labware::{Pose, Quat};
use serde::Serialize;

/// One motion of the scripted expert. Angles are the labware's joint angles (rad).
#[derive(Clone, Debug, PartialEq, Serialize)]
#[serde(tag = "motion", rename_all = "snake_case")]
pub enum Motion {
    /// Arc from the current TCP pose to a standoff before the grip (m back along the approach).
    Approach { lid: f64, lever: f64, standoff: f64 },
    /// Straight in from the standoff to the grip.
    Insert { lid: f64, lever: f64 },
    /// Follow the grip while the lid and lever move from their live angles to these.
    FollowGrip {
        lid: f64,
        lever: f64,
        samples: usize,
    },
    /// Command the gripper (0 open .. 255 closed) and hold still.
    Gripper { ctrl: f64, duration_s: f64 },
    /// Back off along the approach axis.
    Retreat { distance: f64 },
}

impl Motion {
    pub fn label(&self) -> &'static str {
        match self {
            Motion::Approach { .. } => "approach",
            Motion::Insert { .. } => "insert",
            Motion::FollowGrip { .. } => "follow_grip",
            Motion::Gripper { ctrl, .. } if *ctrl > 127.0 => "grasp",
            Motion::Gripper { .. } => "release",
            Motion::Retreat { .. } => "retreat",
        }
    }
}

pub const GRIP_CLOSED: f64 = 255.0;
pub const GRIP_OPEN: f64 = 0.0;
const GRIPPER_WAIT_S: f64 = 0.6;
const STANDOFF_M: f64 = 0.07;

/// Expands a lab primitive on a thermal cycler into the expert's motions.
pub fn expand(primitive: &str, p: &Params) -> Option<Vec<Motion>> {
    let press = p.lever_pressed * 0.9 + p.lever_raised * 0.1;
    let grasp = Motion::Gripper {
        ctrl: GRIP_CLOSED,
        duration_s: GRIPPER_WAIT_S,
    };
    let release = Motion::Gripper {
        ctrl: GRIP_OPEN,
        duration_s: GRIPPER_WAIT_S,
    };
    Some(match primitive {
        "close_lid" => vec![
            Motion::Approach {
                lid: p.lid_open,
                lever: p.lever_raised,
                standoff: STANDOFF_M,
            },
            Motion::Insert {
                lid: p.lid_open,
                lever: p.lever_raised,
            },
            grasp,
            Motion::FollowGrip {
                lid: p.lid_closed,
                lever: p.lever_raised,
                samples: 30,
            },
            Motion::FollowGrip {
                lid: p.lid_closed,
                lever: press,
                samples: 10,
            },
            release,
            Motion::Retreat { distance: 0.1 },
        ],
        "open_lid" => vec![
            Motion::Approach {
                lid: p.lid_closed,
                lever: p.lever_pressed,
                standoff: STANDOFF_M,
            },
            Motion::Insert {
                lid: p.lid_closed,
                lever: p.lever_pressed,
            },
            grasp,
            Motion::FollowGrip {
                lid: p.lid_closed,
                lever: p.lever_raised,
                samples: 10,
            },
            Motion::FollowGrip {
                lid: p.lid_open,
                lever: p.lever_raised,
                samples: 30,
            },
            release,
            Motion::Retreat { distance: 0.1 },
        ],
        _ => return None,
    })
}

/// The geometry a thermal-cycler primitive works in: instrument parameters, its placement, and
/// which of the two symmetric grasps (rotated 180° about the approach) the expert uses.
#[derive(Clone, Debug)]
pub struct GripContext {
    pub params: Params,
    pub placement: Pose,
    pub flip: bool,
}

impl GripContext {
    /// Picks the grasp closer in orientation to the current TCP.
    pub fn new(
        params: Params,
        placement: Pose,
        lid: f64,
        lever: f64,
        tcp_now: &Pose,
    ) -> GripContext {
        let mut cx = GripContext {
            params,
            placement,
            flip: false,
        };
        let a = cx
            .tool_pose(lid, lever)
            .quat
            .conj()
            .times(tcp_now.quat)
            .log();
        cx.flip = true;
        let b = cx
            .tool_pose(lid, lever)
            .quat
            .conj()
            .times(tcp_now.quat)
            .log();
        cx.flip = norm(b) < norm(a);
        cx
    }

    /// TCP pose gripping the bar: at the bar's centre, oriented as the bar frame would be with the
    /// lever raised (tool z, the approach, = -grip y; fingers, tool x, along grip z). The bar is
    /// round, so it turns inside the closed fingers while the lever moves: the tool follows the
    /// lid's rotation but not the lever's, and never has to come at the pressed lever from below.
    pub fn tool_pose(&self, lid: f64, lever: f64) -> Pose {
        let mut grip = self
            .params
            .grip_pose(&self.placement, lid, self.params.lever_raised);
        grip.pos = self.params.grip_pose(&self.placement, lid, lever).pos;
        let m = if self.flip {
            [0.0, 1.0, 0.0, 0.0, 0.0, -1.0, -1.0, 0.0, 0.0]
        } else {
            [0.0, -1.0, 0.0, 0.0, 0.0, -1.0, 1.0, 0.0, 0.0]
        };
        grip.compose(&Pose::new([0.0; 3], Quat::from_mat(&m)))
    }

    /// TCP poses for a path motion, starting at `tcp_now`, with live joint angles (lid, lever).
    /// Gripper motions have no path (empty).
    pub fn poses(&self, motion: &Motion, tcp_now: &Pose, live: (f64, f64)) -> Vec<Pose> {
        match *motion {
            Motion::Approach {
                lid,
                lever,
                standoff,
            } => {
                let target = self
                    .tool_pose(lid, lever)
                    .translated_local([0.0, 0.0, -standoff]);
                arc(tcp_now, &target, 16)
            }
            Motion::Insert { lid, lever } => line(tcp_now, &self.tool_pose(lid, lever), 6),
            Motion::FollowGrip {
                lid,
                lever,
                samples,
            } => {
                let mut out = vec![*tcp_now];
                for i in 1..=samples {
                    let t = i as f64 / samples as f64;
                    out.push(
                        self.tool_pose(live.0 + (lid - live.0) * t, live.1 + (lever - live.1) * t),
                    );
                }
                out
            }
            Motion::Retreat { distance } => {
                line(tcp_now, &tcp_now.translated_local([0.0, 0.0, -distance]), 6)
            }
            Motion::Gripper { .. } => Vec::new(),
        }
    }
}

fn line(a: &Pose, b: &Pose, n: usize) -> Vec<Pose> {
    (0..=n)
        .map(|i| {
            let t = i as f64 / n as f64;
            Pose::new(
                add(a.pos, scale(sub(b.pos, a.pos), t)),
                a.quat.slerp(b.quat, t),
            )
        })
        .collect()
}

/// Like [`line`] but lifted by a parabola whose apex is a quarter of the horizontal distance.
fn arc(a: &Pose, b: &Pose, n: usize) -> Vec<Pose> {
    let d = sub(b.pos, a.pos);
    let lift = 0.25 * (d[0] * d[0] + d[1] * d[1]).sqrt();
    line(a, b, n)
        .into_iter()
        .enumerate()
        .map(|(i, mut p)| {
            let t = i as f64 / n as f64;
            p.pos[2] += 4.0 * lift * t * (1.0 - t);
            p
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use labware::frame::dot;

    #[test]
    fn grasp_approaches_against_the_lever() {
        let p = Params::default();
        let cx = GripContext {
            params: p.clone(),
            placement: Pose::IDENTITY,
            flip: false,
        };
        let closed = cx.tool_pose(p.lid_closed, 0.0);
        // Lid closed, lever raised: the grip's outward axis is +y, so the tool approaches along -y.
        let z = closed.quat.rotate([0.0, 0.0, 1.0]);
        assert!((z[1] + 1.0).abs() < 1e-9, "{z:?}");
        let flipped = GripContext {
            flip: true,
            ..cx.clone()
        };
        // The flipped grasp holds the bar at the same point from the same side, fingers turned over.
        let (a, b) = (cx.tool_pose(-1.0, 0.0), flipped.tool_pose(-1.0, 0.0));
        assert!(norm(sub(a.pos, b.pos)) < 1e-12);
        assert!(
            dot(
                a.quat.rotate([0.0, 0.0, 1.0]),
                b.quat.rotate([0.0, 0.0, 1.0])
            ) > 1.0 - 1e-9
        );
        assert!(
            dot(
                a.quat.rotate([1.0, 0.0, 0.0]),
                b.quat.rotate([1.0, 0.0, 0.0])
            ) < -1.0 + 1e-9
        );
        assert_eq!(expand("close_lid", &p).unwrap().len(), 7);
        assert!(expand("dance", &p).is_none());
    }
}
