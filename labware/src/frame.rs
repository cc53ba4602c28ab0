//! Minimal rigid-body frame math (3-vectors, unit quaternions w-x-y-z, poses) shared by labware
//! affordances and the motion primitives. Conventions follow MuJoCo: quaternions are (w, x, y, z),
//! rotation matrices are row-major.

use serde::{Deserialize, Serialize};

pub type Vec3 = [f64; 3];

pub fn add(a: Vec3, b: Vec3) -> Vec3 {
    [a[0] + b[0], a[1] + b[1], a[2] + b[2]]
}
pub fn sub(a: Vec3, b: Vec3) -> Vec3 {
    [a[0] - b[0], a[1] - b[1], a[2] - b[2]]
}
pub fn scale(a: Vec3, s: f64) -> Vec3 {
    [a[0] * s, a[1] * s, a[2] * s]
}
pub fn dot(a: Vec3, b: Vec3) -> f64 {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}
pub fn norm(a: Vec3) -> f64 {
    dot(a, a).sqrt()
}

#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct Quat(pub [f64; 4]);

impl Quat {
    pub const IDENTITY: Quat = Quat([1.0, 0.0, 0.0, 0.0]);

    pub fn from_axis_angle(axis: Vec3, angle: f64) -> Quat {
        let n = norm(axis);
        let (s, c) = (angle / 2.0).sin_cos();
        Quat([c, axis[0] / n * s, axis[1] / n * s, axis[2] / n * s])
    }

    pub fn times(self, o: Quat) -> Quat {
        let [a1, b1, c1, d1] = self.0;
        let [a2, b2, c2, d2] = o.0;
        Quat([
            a1 * a2 - b1 * b2 - c1 * c2 - d1 * d2,
            a1 * b2 + b1 * a2 + c1 * d2 - d1 * c2,
            a1 * c2 - b1 * d2 + c1 * a2 + d1 * b2,
            a1 * d2 + b1 * c2 - c1 * b2 + d1 * a2,
        ])
    }

    pub fn conj(self) -> Quat {
        let [w, x, y, z] = self.0;
        Quat([w, -x, -y, -z])
    }

    pub fn normalized(self) -> Quat {
        let n = self.0.iter().map(|v| v * v).sum::<f64>().sqrt();
        Quat(self.0.map(|v| v / n))
    }

    pub fn rotate(self, v: Vec3) -> Vec3 {
        let p = Quat([0.0, v[0], v[1], v[2]]);
        let r = self.times(p).times(self.conj());
        [r.0[1], r.0[2], r.0[3]]
    }

    /// Row-major rotation matrix.
    pub fn to_mat(self) -> [f64; 9] {
        let [w, x, y, z] = self.0;
        [
            1.0 - 2.0 * (y * y + z * z),
            2.0 * (x * y - w * z),
            2.0 * (x * z + w * y),
            2.0 * (x * y + w * z),
            1.0 - 2.0 * (x * x + z * z),
            2.0 * (y * z - w * x),
            2.0 * (x * z - w * y),
            2.0 * (y * z + w * x),
            1.0 - 2.0 * (x * x + y * y),
        ]
    }

    pub fn from_mat(m: &[f64; 9]) -> Quat {
        let tr = m[0] + m[4] + m[8];
        let q = if tr > 0.0 {
            let s = (tr + 1.0).sqrt() * 2.0;
            [
                0.25 * s,
                (m[7] - m[5]) / s,
                (m[2] - m[6]) / s,
                (m[3] - m[1]) / s,
            ]
        } else if m[0] > m[4] && m[0] > m[8] {
            let s = (1.0 + m[0] - m[4] - m[8]).sqrt() * 2.0;
            [
                (m[7] - m[5]) / s,
                0.25 * s,
                (m[1] + m[3]) / s,
                (m[2] + m[6]) / s,
            ]
        } else if m[4] > m[8] {
            let s = (1.0 + m[4] - m[0] - m[8]).sqrt() * 2.0;
            [
                (m[2] - m[6]) / s,
                (m[1] + m[3]) / s,
                0.25 * s,
                (m[5] + m[7]) / s,
            ]
        } else {
            let s = (1.0 + m[8] - m[0] - m[4]).sqrt() * 2.0;
            [
                (m[3] - m[1]) / s,
                (m[2] + m[6]) / s,
                (m[5] + m[7]) / s,
                0.25 * s,
            ]
        };
        Quat(q).normalized()
    }

    /// Rotation vector (axis * angle) of this rotation, angle in [0, pi].
    pub fn log(self) -> Vec3 {
        let q = if self.0[0] < 0.0 {
            Quat(self.0.map(|v| -v))
        } else {
            self
        };
        let v = [q.0[1], q.0[2], q.0[3]];
        let s = norm(v);
        if s < 1e-12 {
            return scale(v, 2.0);
        }
        let angle = 2.0 * s.atan2(q.0[0]);
        scale(v, angle / s)
    }

    /// Spherical interpolation from self (t=0) to o (t=1).
    pub fn slerp(self, o: Quat, t: f64) -> Quat {
        let rel = self.conj().times(o);
        let w = rel.log();
        let angle = norm(w);
        if angle < 1e-12 {
            return self;
        }
        self.times(Quat::from_axis_angle(w, angle * t)).normalized()
    }
}

/// A rigid transform: position (m) and orientation.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct Pose {
    pub pos: Vec3,
    pub quat: Quat,
}

impl Pose {
    pub const IDENTITY: Pose = Pose {
        pos: [0.0; 3],
        quat: Quat::IDENTITY,
    };

    pub fn new(pos: Vec3, quat: Quat) -> Pose {
        Pose { pos, quat }
    }

    /// self * o: `o` expressed in self's frame, mapped to self's parent frame.
    pub fn compose(&self, o: &Pose) -> Pose {
        Pose {
            pos: add(self.pos, self.quat.rotate(o.pos)),
            quat: self.quat.times(o.quat).normalized(),
        }
    }

    pub fn translated_local(&self, offset: Vec3) -> Pose {
        Pose {
            pos: add(self.pos, self.quat.rotate(offset)),
            quat: self.quat,
        }
    }

    pub fn yaw(pos: Vec3, yaw: f64) -> Pose {
        Pose {
            pos,
            quat: Quat::from_axis_angle([0.0, 0.0, 1.0], yaw),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn rotation_round_trips() {
        let q = Quat::from_axis_angle([1.0, 2.0, 3.0], 0.7);
        let back = Quat::from_mat(&q.to_mat());
        assert!(q.0.iter().zip(back.0).all(|(a, b)| (a - b).abs() < 1e-12));
        let r = Quat::from_axis_angle([0.0, 0.0, 1.0], std::f64::consts::FRAC_PI_2)
            .rotate([1.0, 0.0, 0.0]);
        assert!((r[1] - 1.0).abs() < 1e-12 && r[0].abs() < 1e-12);
        assert!((norm(q.log()) - 0.7).abs() < 1e-12);
        let half = Quat::IDENTITY.slerp(q, 0.5);
        assert!((norm(half.log()) - 0.35).abs() < 1e-12);
    }
}
