//! Robot models: one file per robot (an arm and its gripper or hand composed; `ur5e.rs` holds
//! what the two UR5e robots share), each a [`RobotModel`] of
//! plain facts: how its MJCF is prepared from the installed packages, its joints and actuators by
//! name, the gripper's actuator values and settle time, TCP site, wrist camera, mount facing, home
//! pose, expert limits and IK method. [`MODELS`] is the registry: one line per robot.
//!
//! Observation and action layouts derive from a model ([`RobotModel::state_names`],
//! [`RobotModel::action_names`]): arm joints in order, then the gripper. For a task with several
//! robots the layouts are concatenated in the task's robot order.
//!
//! Joint position limits are the installed MJCF's joint ranges (the package is their source of
//! truth; the runtime reads them from the compiled model for IK); the expert's velocity and
//! acceleration limits are the model's own.
//!
//! No MuJoCo API here: the runtime compiles what `prepare` writes; only file IO for the assets.
//!
//! Its tests are the workspace's tests/kinematics.rs and tests/aloha.rs (on the installed models).

pub mod aloha_vx300s;
mod assets;
pub mod lod;
mod ur5e;
pub mod ur5e_2f85;
pub mod ur5e_inspire;

pub use assets::AssetError;
use std::path::{Path, PathBuf};

/// A parallel gripper's one actuator.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Gripper {
    /// Actuator name (relative to the robot's prefix).
    pub actuator: &'static str,
    /// The joint whose angle is the gripper's state element.
    pub driver_joint: &'static str,
    /// Actuator values for fully open and fully closed.
    pub open: f64,
    pub closed: f64,
    /// The units of the gripper's state and action values (run records carry them): a
    /// linkage's driver angle in `rad` commanded in `actuator` units, a slide in `m`.
    pub state_unit: &'static str,
    pub action_unit: &'static str,
    /// How long a grasp or release takes to settle (s).
    pub settle_s: f64,
    /// How far the closed fingers reach past the TCP along the tool axis (m; negative: they stop
    /// short of it): where a press or push with the closed gripper as a finger touches.
    pub finger_reach: f64,
    /// How far past a round body's axis a grip from the side puts the TCP, so that the body sits
    /// in the broad part of the fingers and cannot pivot between two narrow pads (m; 0 for pads
    /// as broad at the TCP as anywhere).
    pub enclose: f64,
}

impl Gripper {
    /// Clamps a commanded value into the actuator's range.
    pub fn clamp(&self, v: f64) -> f64 {
        v.clamp(self.open.min(self.closed), self.open.max(self.closed))
    }
}

/// Which meshes a prepared model uses: the packages' own, or [`lod`]'s simplified copies for
/// small camera images.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Detail {
    Full,
    Simplified,
}

/// How the expert solves inverse kinematics for this arm.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum IkMethod {
    /// Damped least-squares QPs with joint limits (clarabel), on the simulator's Jacobian.
    Qp,
    /// Closed form for a waist-shoulder-elbow arm with a spherical roll-pitch-roll wrist
    /// ([`AnalyticArm`]), every branch pruned by the joint limits; the QP stays the fallback.
    Analytic(AnalyticArm),
}

/// The geometry an analytic solver needs, for arms shaped like the ViperX 300s: a waist about
/// the base's z, a shoulder and an elbow about y, a forearm roll about x, a wrist pitch about y
/// and a wrist roll about x, the three wrist axes meeting at the wrist centre. At zero angles the
/// arm points along the base's x; the tool frame's z runs along the last link's x and its x
/// along the last link's y.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct AnalyticArm {
    /// Height of the shoulder axis above the base (m).
    pub shoulder_height: f64,
    /// From the shoulder axis to the elbow axis at zero angles: along x, along z (m).
    pub upper_arm: [f64; 2],
    /// From the elbow axis to the wrist centre, along x (m).
    pub forearm: f64,
    /// From the wrist centre to the TCP along the tool axis (m).
    pub wrist_to_tcp: f64,
}

/// How the scripted expert moves this arm: joint-space speed limits (rad/s, rad/s²) and the
/// spacing of collision checks along a free-space motion (rad of joint travel, Euclidean), which
/// depends on the arm's reach: the tool must not skip past a thin obstacle between two checks.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ExpertLimits {
    pub vmax: f64,
    pub amax: f64,
    pub check_step: f64,
    /// Free-space motions (approaches, transits) go in a straight line in joint space to the
    /// goal's IK solution, rather than through IK along a straight tool path: for an arm whose
    /// wrist passes a singularity on the way (the ViperX's roll-pitch-roll wrist at pitch 0),
    /// where following the tool path swings the two rolls.
    pub joint_space_transits: bool,
}

#[derive(Debug)]
pub struct RobotModel {
    pub name: &'static str,
    pub description: &'static str,
    /// Arm joints and their position actuators, in layout order (names relative to the prefix).
    pub arm_joints: &'static [&'static str],
    pub arm_actuators: &'static [&'static str],
    pub gripper: Gripper,
    /// The tool centre point site and the wrist camera (relative to the prefix).
    pub tcp_site: &'static str,
    /// The body the TCP site is on, and the bodies of the hand an item held from the start sits
    /// among (`held_by`): the item is welded to `tcp_body` at its `grasp` and collides with none
    /// of these (relative to the prefix).
    pub tcp_body: &'static str,
    pub hand_bodies: &'static [&'static str],
    /// The bodies that are its fingers (with the bodies they carry: pads), relative to the
    /// prefix: what a `<robot> holds <item>` predicate measures contact with.
    pub fingers: &'static [&'static str],
    pub wrist_camera: &'static str,
    /// Yaw (rad) added to the mount so that a protocol's yaw 0 reaches along +x.
    pub mount_yaw: f64,
    /// The root body to attach under the mount.
    pub root_body: &'static str,
    pub home: &'static [f64],
    /// How far from its base the arm's tool can reach (m): a pose farther than this from every
    /// robot, and off the bench, is a unit mistake, not a place to work.
    pub reach: f64,
    pub expert_limits: ExpertLimits,
    pub ik: IkMethod,
    /// Writes the robot's MJCF from the installed packages under `deps` (idempotent) and returns
    /// its path; with [`Detail::Simplified`] its visual meshes are [`lod`]'s simplified ones (the
    /// bodies, joints and geoms are the same).
    pub prepare: fn(deps: &Path, detail: Detail) -> Result<PathBuf, AssetError>,
}

impl RobotModel {
    pub fn dof(&self) -> usize {
        self.arm_joints.len()
    }

    /// Observation state: arm joint angles (rad), then the gripper driver angle (rad).
    pub fn state_names(&self) -> Vec<String> {
        let mut n: Vec<String> = self.arm_joints.iter().map(|j| j.to_string()).collect();
        n.push(format!("gripper:{}", self.gripper.driver_joint));
        n
    }

    /// Action: arm joint targets (rad), then the gripper actuator command.
    pub fn action_names(&self) -> Vec<String> {
        let mut n: Vec<String> = self.arm_actuators.iter().map(|a| a.to_string()).collect();
        n.push(format!("gripper:{}", self.gripper.actuator));
        n
    }

    pub fn action_len(&self) -> usize {
        self.arm_actuators.len() + 1
    }
}

/// The registry: every robot a protocol may name.
pub const MODELS: &[&RobotModel] = &[
    &ur5e_2f85::MODEL,
    &aloha_vx300s::MODEL,
    &ur5e_inspire::MODEL,
];

pub fn model(name: &str) -> Option<&'static RobotModel> {
    MODELS.iter().copied().find(|m| m.name == name)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn layouts_derive_from_the_model() {
        let m = model("ur5e_2f85").unwrap();
        assert_eq!(m.state_names().len(), 7);
        assert_eq!(m.action_len(), 7);
        assert_eq!(m.home.len(), m.dof());
        assert_eq!(m.arm_actuators.len(), m.dof());
        assert_eq!(m.gripper.clamp(300.0), m.gripper.closed);
        assert!(model("ur10").is_none());
    }
}
