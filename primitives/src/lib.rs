//! Lab primitives to motions for the scripted expert.
//!
//! A planned lab primitive (`close_lid` on a thermal cycler) expands into [`Motion`]s (approach,
//! grasp, follow the lid's arc, press, release, retreat). Each Cartesian motion is resolved
//! against live labware state into TCP poses, turned into joint waypoints by a clarabel QP
//! inverse kinematics ([`ik`]) and timed under velocity/acceleration limits by TOPP ([`topp`]).
//! Kinematics come from outside through the [`Kinematics`] trait (the runtime implements it on
//! MuJoCo), so this crate runs no simulation.

pub mod expand;
pub mod ik;
pub mod spline;
pub mod topp;

pub use expand::{GripContext, Motion, expand};
pub use ik::{IkError, solve_ik};
pub use topp::{Limits, Trajectory, plan_trajectory};

use labware::Pose;

/// Forward kinematics and Jacobian of one arm's tool centre point.
pub trait Kinematics {
    /// Number of arm joints.
    fn dof(&self) -> usize;
    /// Joint position limits (rad).
    fn limits(&self) -> Vec<(f64, f64)>;
    /// TCP pose (world frame) at joint angles `q`.
    fn tcp(&mut self, q: &[f64]) -> Pose;
    /// TCP pose and its 6 x dof Jacobian (rows: linear xyz, angular xyz; world frame) at `q`.
    fn jacobian(&mut self, q: &[f64]) -> (Pose, Vec<[f64; 6]>);
}
