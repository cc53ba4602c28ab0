//! Inverse kinematics as a sequence of damped least-squares QPs with joint limits, solved by
//! clarabel: min ||J dq - e||^2 + lambda ||dq||^2  s.t.  lo - q <= dq <= hi - q, |dq| <= step;
//! and [`solve_with`], which picks the robot model's method (the closed form of
//! [`crate::analytic_ik`] with this QP as its fallback).

use crate::{Kinematics, analytic_ik};
use clarabel::algebra::CscMatrix;
use clarabel::solver::{
    DefaultSettingsBuilder, DefaultSolver, IPSolver, NonnegativeConeT, SupportedConeT,
};
use labware::Pose;

#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum IkError {
    #[error("ik did not converge: position error {pos_err:.4} m, rotation error {rot_err:.4} rad")]
    NoConvergence { pos_err: f64, rot_err: f64 },
    #[error("the qp solver failed: {0}")]
    Solver(String),
}

pub struct IkOptions {
    pub damping: f64,
    pub max_step: f64,
    pub iterations: usize,
    pub pos_tol: f64,
    pub rot_tol: f64,
}

impl Default for IkOptions {
    fn default() -> Self {
        IkOptions {
            damping: 1e-4,
            max_step: 0.3,
            iterations: 80,
            pos_tol: 2e-4,
            rot_tol: 2e-3,
        }
    }
}

/// Pose error as a 6-vector (position; rotation vector), world frame.
pub fn pose_error(target: &Pose, current: &Pose) -> [f64; 6] {
    let p = target.translation.vector - current.translation.vector;
    let r = (target.rotation * current.rotation.inverse()).scaled_axis();
    [p.x, p.y, p.z, r.x, r.y, r.z]
}

/// A pose error's position (m) and rotation (rad) magnitudes.
fn error_norms(e: &[f64; 6]) -> (f64, f64) {
    (
        (e[0] * e[0] + e[1] * e[1] + e[2] * e[2]).sqrt(),
        (e[3] * e[3] + e[4] * e[4] + e[5] * e[5]).sqrt(),
    )
}

/// A closed-form IK method: its candidate joint solutions for a target (every branch, each
/// joint taken nearest `seed`), before the joint limits prune them.
trait ClosedForm {
    fn candidates(&self, kin: &mut dyn Kinematics, target: &Pose, seed: &[f64]) -> Vec<[f64; 6]>;
}

/// The one place an [`robots::IkMethod`] meets its solver: the QP alone (`None`), or a closed
/// form the QP refines and stands in for. A new closed-form method is its [`ClosedForm`] and one
/// arm here.
fn closed_form(method: robots::IkMethod) -> Option<Box<dyn ClosedForm>> {
    match method {
        robots::IkMethod::Qp => None,
        robots::IkMethod::Analytic(arm) => Some(Box::new(Analytic(arm))),
    }
}

/// The closed form of [`analytic_ik`] for ViperX-shaped arms.
struct Analytic(robots::AnalyticArm);

impl ClosedForm for Analytic {
    fn candidates(&self, kin: &mut dyn Kinematics, target: &Pose, seed: &[f64]) -> Vec<[f64; 6]> {
        let local = analytic_ik::base_frame(&self.0, kin).inverse() * target;
        analytic_ik::candidates(&self.0, &local, seed)
    }
}

/// Solves for joint angles reaching `target` from `seed` with the method the robot model chooses.
pub fn solve_with(
    method: robots::IkMethod,
    kin: &mut dyn Kinematics,
    target: &Pose,
    seed: &[f64],
) -> Result<Vec<f64>, IkError> {
    let opt = IkOptions::default();
    let Some(closed) = closed_form(method) else {
        return solve_ik(kin, target, seed, &opt);
    };
    // The best branch within the limits where it is on target, refined by the QP where it is
    // not, and the QP alone where no branch is within the limits.
    let cands = closed.candidates(kin, target, seed);
    match analytic_ik::best_within(&cands, &kin.limits(), seed) {
        Some(q) => {
            let (pos, rot) = error_norms(&pose_error(target, &kin.tcp(&q)));
            if pos < opt.pos_tol && rot < opt.rot_tol {
                Ok(q)
            } else {
                solve_ik(kin, target, &q, &opt)
            }
        }
        None => solve_ik(kin, target, seed, &opt),
    }
}

/// The distinct joint solutions for `target` within the joint limits that the robot model's
/// method finds: an analytic arm's every branch (each joint taken nearest the first seed), a
/// numeric one's solve from each of `seeds`. Nearest the first seed first. The expert's goal
/// region where the solution nearest the arm leads into an obstacle or a dead end.
pub fn solutions(
    method: robots::IkMethod,
    kin: &mut dyn Kinematics,
    target: &Pose,
    seeds: &[Vec<f64>],
) -> Vec<Vec<f64>> {
    let Some(first) = seeds.first() else {
        return Vec::new();
    };
    let mut found: Vec<Vec<f64>> = Vec::new();
    let mut keep = |q: Vec<f64>, kin: &mut dyn Kinematics| {
        let (pos, rot) = error_norms(&pose_error(target, &kin.tcp(&q)));
        let opt = IkOptions::default();
        let new = found
            .iter()
            .all(|f| f.iter().zip(&q).any(|(a, b)| (a - b).abs() > 1e-3));
        if pos < opt.pos_tol && rot < opt.rot_tol && new {
            found.push(q);
        }
    };
    if let Some(closed) = closed_form(method) {
        for c in closed.candidates(kin, target, first) {
            if let Some(q) = analytic_ik::best_within(&[c], &kin.limits(), first) {
                keep(q, kin);
            }
        }
    }
    for seed in seeds {
        if let Ok(q) = solve_with(method, kin, target, seed) {
            keep(q, kin);
        }
    }
    let distance =
        |q: &Vec<f64>| -> f64 { q.iter().zip(first).map(|(a, b)| (a - b).powi(2)).sum() };
    found.sort_by(|a, b| distance(a).total_cmp(&distance(b)));
    found
}

/// Solves for joint angles reaching `target`, starting from `seed`.
pub fn solve_ik(
    kin: &mut dyn Kinematics,
    target: &Pose,
    seed: &[f64],
    opt: &IkOptions,
) -> Result<Vec<f64>, IkError> {
    let n = kin.dof();
    let limits = kin.limits();
    let mut q = seed.to_vec();
    let (mut pos_err, mut rot_err) = (f64::INFINITY, f64::INFINITY);
    for _ in 0..opt.iterations {
        let (pose, jac) = kin.jacobian(&q);
        let e = pose_error(target, &pose);
        (pos_err, rot_err) = error_norms(&e);
        if pos_err < opt.pos_tol && rot_err < opt.rot_tol {
            return Ok(q);
        }
        // Rotation errors are weighted so that 1 rad counts like 0.3 m.
        let w = [1.0, 1.0, 1.0, 0.3, 0.3, 0.3];
        let mut jtj = vec![0.0; n * n];
        let mut jte = vec![0.0; n];
        for r in 0..6 {
            for i in 0..n {
                jte[i] += jac[i][r] * w[r] * w[r] * e[r];
                for j in 0..n {
                    jtj[i * n + j] += jac[i][r] * w[r] * w[r] * jac[j][r];
                }
            }
        }
        let mut rows = Vec::new();
        let mut cols = Vec::new();
        let mut vals = Vec::new();
        for i in 0..n {
            for j in i..n {
                let v = 2.0 * (jtj[i * n + j] + if i == j { opt.damping } else { 0.0 });
                rows.push(i);
                cols.push(j);
                vals.push(v);
            }
        }
        let p = CscMatrix::new_from_triplets(n, n, rows, cols, vals);
        let c: Vec<f64> = jte.iter().map(|v| -2.0 * v).collect();
        let mut a_rows = Vec::new();
        let mut a_cols = Vec::new();
        let mut a_vals = Vec::new();
        let mut b = Vec::new();
        for i in 0..n {
            a_rows.push(i);
            a_cols.push(i);
            a_vals.push(1.0);
            b.push((limits[i].1 - q[i]).min(opt.max_step).max(0.0));
        }
        for i in 0..n {
            a_rows.push(n + i);
            a_cols.push(i);
            a_vals.push(-1.0);
            b.push((q[i] - limits[i].0).min(opt.max_step).max(0.0));
        }
        let a = CscMatrix::new_from_triplets(2 * n, n, a_rows, a_cols, a_vals);
        let cones: [SupportedConeT<f64>; 1] = [NonnegativeConeT(2 * n)];
        let settings = DefaultSettingsBuilder::default()
            .verbose(false)
            .build()
            .map_err(|e| IkError::Solver(format!("{e:?}")))?;
        let mut solver = DefaultSolver::new(&p, &c, &a, &b, &cones, settings)
            .map_err(|e| IkError::Solver(format!("{e:?}")))?;
        solver.solve();
        let dq = &solver.solution.x;
        if dq.iter().any(|v| !v.is_finite()) {
            return Err(IkError::Solver("non-finite step".into()));
        }
        for i in 0..n {
            q[i] = (q[i] + dq[i]).clamp(limits[i].0, limits[i].1);
        }
    }
    Err(IkError::NoConvergence { pos_err, rot_err })
}
