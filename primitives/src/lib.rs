//! Lab primitives to robot motion for the scripted expert.
//!
//! A planned lab step's motions (its expansion, declared beside the primitive in
//! `compiler::primitives`) are resolved against live labware state into tool poses
//! ([`Lab`]), turned into joint waypoints by a clarabel QP inverse kinematics ([`ik`]) and
//! timed under velocity/acceleration limits by TOPP ([`topp`]). Kinematics come from outside
//! through the [`Kinematics`] trait (the runtime implements it on MuJoCo), so this crate runs no
//! simulation and names no instrument: affordances and joint goals come from the labware models.
//!
//! Its tests are beside the code (unit tests of IK, TOPP and resolution) and the workspace's
//! tests/kinematics.rs and tests/planning.rs, which run them on the real robot models.

pub mod alternatives;
pub mod analytic_ik;
pub mod ik;
mod resolve;
pub mod spline;
pub mod topp;

pub use resolve::{Lab, PlanError, StepFrame, bring_miss, first_target};

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
