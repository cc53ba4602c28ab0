//! The FFI boundary to the OMPL shim: one call, a trampoline that turns the caller's closure
//! into the C callback (a panic in it is caught and counts as "not valid", it never unwinds
//! into C++), and the shim's status codes as typed errors.

use std::ffi::c_void;
use std::panic::{AssertUnwindSafe, catch_unwind};

/// A joint-space planning problem.
#[derive(Debug, Clone, PartialEq)]
pub struct Problem {
    /// Per joint: (lowest, highest) angle the path may use (rad).
    pub bounds: Vec<(f64, f64)>,
    pub start: Vec<f64>,
    pub goal: Vec<f64>,
    /// Validity is checked along every motion at steps of at most this (rad, Euclidean).
    pub step: f64,
    /// How far RRTConnect extends a tree at once (rad, Euclidean; 0: OMPL's default).
    pub range: f64,
    /// The planner gives up after this many validity checks.
    pub max_checks: u64,
    pub seed: u64,
}

#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum PlanError {
    #[error("the start configuration collides")]
    StartInvalid,
    #[error("the goal configuration collides")]
    GoalInvalid,
    #[error("RRTConnect found no collision-free path within {0} validity checks")]
    NoPath(u64),
    #[error("the planning problem is malformed: {0}")]
    Malformed(&'static str),
    #[error("OMPL failed (shim status {0})")]
    Ompl(i32),
}

/// The most states a raw RRTConnect path may have (it has tens in practice).
const MAX_STATES: usize = 4096;

type ValidFn = unsafe extern "C" fn(user: *mut c_void, q: *const f64, dim: u32) -> bool;

unsafe extern "C" {
    fn autobio_rrt_connect(
        dim: u32,
        lo: *const f64,
        hi: *const f64,
        start: *const f64,
        goal: *const f64,
        range: f64,
        resolution: f64,
        max_checks: u64,
        seed: u64,
        valid: ValidFn,
        user: *mut c_void,
        out: *mut f64,
        max_states: u32,
    ) -> i32;
}

unsafe extern "C" fn trampoline<F: FnMut(&[f64]) -> bool>(
    user: *mut c_void,
    q: *const f64,
    dim: u32,
) -> bool {
    // SAFETY: `user` is the `&mut F` that `plan` passed for the duration of the call, and the
    // shim hands `dim` doubles that live for the duration of this callback.
    let (f, q) = unsafe {
        (
            &mut *(user as *mut F),
            std::slice::from_raw_parts(q, dim as usize),
        )
    };
    catch_unwind(AssertUnwindSafe(|| f(q))).unwrap_or(false)
}

/// A path from `problem.start` to `problem.goal` (both included) whose states and straight
/// motions between them (checked at `problem.step`) all satisfy `valid`.
pub fn plan<F: FnMut(&[f64]) -> bool>(
    problem: &Problem,
    mut valid: F,
) -> Result<Vec<Vec<f64>>, PlanError> {
    let dim = problem.bounds.len();
    if dim == 0 || problem.start.len() != dim || problem.goal.len() != dim {
        return Err(PlanError::Malformed(
            "start, goal and bounds differ in length",
        ));
    }
    // Written so that NaN fails too.
    let ordered = problem.bounds.iter().all(|(lo, hi)| lo < hi);
    if !ordered || problem.step.partial_cmp(&0.0) != Some(std::cmp::Ordering::Greater) {
        return Err(PlanError::Malformed("empty bounds or a non-positive step"));
    }
    let inside = |q: &[f64]| {
        q.iter()
            .zip(&problem.bounds)
            .all(|(v, (lo, hi))| (lo..=hi).contains(&v))
    };
    if !inside(&problem.start) || !inside(&problem.goal) {
        return Err(PlanError::Malformed(
            "the start or the goal lies outside the bounds",
        ));
    }
    let lo: Vec<f64> = problem.bounds.iter().map(|b| b.0).collect();
    let hi: Vec<f64> = problem.bounds.iter().map(|b| b.1).collect();
    // OMPL's resolution is a fraction of the space's extent (its diameter).
    let extent = crate::distance(&lo, &hi);
    if problem.step >= extent {
        return Err(PlanError::Malformed("the check step spans the whole space"));
    }
    // OMPL's generator takes 32 bits: fold all 64 in.
    let seed = {
        let s = crate::mix(problem.seed, 0);
        (s ^ (s >> 32)) & 0xFFFF_FFFF
    };
    let mut out = vec![0.0; MAX_STATES * dim];
    // SAFETY: every pointer is valid for the lengths the shim reads or writes (dim, and
    // MAX_STATES * dim for `out`), and `valid` outlives the call.
    let n = unsafe {
        autobio_rrt_connect(
            dim as u32,
            lo.as_ptr(),
            hi.as_ptr(),
            problem.start.as_ptr(),
            problem.goal.as_ptr(),
            problem.range,
            problem.step / extent,
            problem.max_checks,
            seed,
            trampoline::<F>,
            &mut valid as *mut F as *mut c_void,
            out.as_mut_ptr(),
            MAX_STATES as u32,
        )
    };
    match n {
        -1 => Err(PlanError::StartInvalid),
        -2 => Err(PlanError::GoalInvalid),
        0 => Err(PlanError::NoPath(problem.max_checks)),
        n if n > 0 => Ok(out
            .chunks(dim)
            .take(n as usize)
            .map(<[f64]>::to_vec)
            .collect()),
        n => Err(PlanError::Ompl(n)),
    }
}
