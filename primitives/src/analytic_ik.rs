//! Closed-form inverse kinematics for arms shaped like the ViperX 300s ([`robots::AnalyticArm`]):
//! the wrist centre from the target, the waist from its bearing (and the bearing behind), the
//! shoulder and elbow from the planar two-link triangle (two branches), and the wrist's
//! roll-pitch-roll angles from the remaining rotation (two branches; the gimbal case keeps the
//! seed's forearm roll). Up to eight candidates; those inside the joint limits are ranked by
//! distance from the seed.
//!
//! The arm's mount is not passed in: it is read from the simulator's forward kinematics at zero
//! angles, where the geometry puts the TCP at a known pose. Every answer is checked against the
//! forward kinematics; what does not reach the target within the QP's tolerances (a geometry
//! that does not match the model, a pose out of reach) falls back to the QP solver, seeded with
//! the best candidate.

use crate::Kinematics;
use labware::Pose;
use nalgebra::{Isometry3, Matrix3, Rotation3, Translation3, UnitQuaternion, Vector3};
use robots::AnalyticArm;
use std::f64::consts::PI;

/// The tool frame in the last link's frame: z along the link's x, x along its y.
fn tool_offset() -> Rotation3<f64> {
    Rotation3::from_matrix_unchecked(Matrix3::new(0.0, 0.0, 1.0, 1.0, 0.0, 0.0, 0.0, 1.0, 0.0))
}

/// The TCP pose in the base frame at zero angles.
fn zero_pose(arm: &AnalyticArm) -> Pose {
    Isometry3::from_parts(
        Translation3::new(
            arm.upper_arm[0] + arm.forearm + arm.wrist_to_tcp,
            0.0,
            arm.shoulder_height + arm.upper_arm[1],
        ),
        UnitQuaternion::from_rotation_matrix(&tool_offset()),
    )
}

/// The arm's base frame in the world, from the TCP's world pose at zero angles.
pub fn base_frame(arm: &AnalyticArm, kin: &mut dyn Kinematics) -> Pose {
    let zero = vec![0.0; kin.dof()];
    kin.tcp(&zero) * zero_pose(arm).inverse()
}

fn wrap(a: f64) -> f64 {
    let w = (a + PI).rem_euclid(2.0 * PI) - PI;
    if w <= -PI { w + 2.0 * PI } else { w }
}

/// Every joint solution for `target` (base frame), unfiltered by limits.
pub fn candidates(arm: &AnalyticArm, target: &Pose, seed: &[f64]) -> Vec<[f64; 6]> {
    let r = target.rotation.to_rotation_matrix();
    let p = target.translation.vector;
    let w = p - arm.wrist_to_tcp * (r * Vector3::z());
    let [ux, uz] = arm.upper_arm;
    let f = arm.forearm;
    let link = (ux * ux + uz * uz).sqrt();
    let phi = uz.atan2(ux);
    let mut out = Vec::new();
    let bearing = w.y.atan2(w.x);
    let radius = (w.x * w.x + w.y * w.y).sqrt();
    for (q0, x) in [(bearing, radius), (bearing + PI, -radius)] {
        let z = w.z - arm.shoulder_height;
        let c = (x * x + z * z - link * link - f * f) / (2.0 * f * link);
        if c.abs() > 1.0 {
            continue;
        }
        for sign in [1.0, -1.0] {
            let q2 = sign * c.acos() - phi;
            let (vx, vz) = (ux + f * q2.cos(), uz - f * q2.sin());
            let q1 = vz.atan2(vx) - z.atan2(x);
            let arm_rot = Rotation3::from_axis_angle(&Vector3::z_axis(), q0)
                * Rotation3::from_axis_angle(&Vector3::y_axis(), q1 + q2);
            let m = arm_rot.inverse() * r * tool_offset().inverse();
            let m = m.matrix();
            let cb = m[(0, 0)].clamp(-1.0, 1.0);
            let b = cb.acos();
            if b.sin().abs() < 1e-9 {
                // Gimbal: the two rolls are one; keep the seed's forearm roll.
                let a = seed.get(3).copied().unwrap_or(0.0);
                let total = m[(2, 1)].atan2(m[(1, 1)]);
                let c5 = if cb > 0.0 { total - a } else { a - total };
                out.push([q0, q1, q2, a, if cb > 0.0 { 0.0 } else { PI }, c5]);
                continue;
            }
            for (q4, s) in [(b, 1.0), (-b, -1.0)] {
                let q3 = (s * m[(1, 0)]).atan2(-s * m[(2, 0)]);
                let q5 = (s * m[(0, 1)]).atan2(s * m[(0, 2)]);
                out.push([q0, q1, q2, q3, q4, q5]);
            }
        }
    }
    out.into_iter().map(|q| q.map(wrap)).collect()
}

/// The candidate inside `limits` closest to `seed` (each joint also tried a turn either way).
pub fn best_within(cands: &[[f64; 6]], limits: &[(f64, f64)], seed: &[f64]) -> Option<Vec<f64>> {
    const SLACK: f64 = 1e-9;
    let mut best: Option<(f64, Vec<f64>)> = None;
    for c in cands {
        let mut q = Vec::with_capacity(6);
        for (i, &a) in c.iter().enumerate() {
            let (lo, hi) = limits[i];
            let s = seed.get(i).copied().unwrap_or(0.0);
            let pick = [a, a - 2.0 * PI, a + 2.0 * PI]
                .into_iter()
                .filter(|v| *v >= lo - SLACK && *v <= hi + SLACK)
                .min_by(|x, y| (x - s).abs().total_cmp(&(y - s).abs()));
            match pick {
                Some(v) => q.push(v.clamp(lo, hi)),
                None => break,
            }
        }
        if q.len() != 6 {
            continue;
        }
        let d: f64 = q.iter().zip(seed).map(|(a, b)| (a - b) * (a - b)).sum();
        if best.as_ref().is_none_or(|(bd, _)| d < *bd) {
            best = Some((d, q));
        }
    }
    best.map(|(_, q)| q)
}
