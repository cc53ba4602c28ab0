//! The one MJCF helper every labware model writes through: number formatting, pose attributes,
//! box and cylinder inertia, and the [`Fragment`] a model contributes to a scene. Text only; the
//! runtime splices fragments into the scene document and compiles it.

use crate::frame::{Pose, Vec3, position, wxyz};

/// The parts of a scene document one placed labware item contributes.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Fragment {
    pub asset: String,
    pub worldbody: String,
    pub equality: String,
    pub contact: String,
    /// The item's own actuators (a mixer's motor): `<actuator>` children.
    pub actuator: String,
    /// MuJoCo's arena (contacts, constraints, the solver's stack) the item needs at the least
    /// (MB); 0: the default (about 15 MB) suffices.
    pub arena_mb: usize,
}

impl Fragment {
    pub fn append(&mut self, other: Fragment) {
        self.asset += &other.asset;
        self.worldbody += &other.worldbody;
        self.equality += &other.equality;
        self.contact += &other.contact;
        self.actuator += &other.actuator;
        // The scene's items touch at once: their needs add up.
        self.arena_mb += other.arena_mb;
    }
}

pub fn v3(v: Vec3) -> String {
    format!("{} {} {}", v[0], v[1], v[2])
}

/// `pos="…" quat="…"` of a pose (MuJoCo's w-x-y-z quaternion).
pub fn pose_attrs(p: &Pose) -> String {
    let q = wxyz(&p.rotation);
    format!(
        r#"pos="{}" quat="{} {} {} {}""#,
        v3(position(p)),
        q[0],
        q[1],
        q[2],
        q[3]
    )
}

/// Diagonal inertia of a solid box of mass `m` and half extents `h`.
pub fn box_inertia(m: f64, h: Vec3) -> Vec3 {
    let (a, b, c) = (2.0 * h[0], 2.0 * h[1], 2.0 * h[2]);
    [
        m * (b * b + c * c) / 12.0,
        m * (a * a + c * c) / 12.0,
        m * (a * a + b * b) / 12.0,
    ]
}

/// Diagonal inertia of a solid cylinder along z of mass `m`, radius `r` and half height `h`.
pub fn cylinder_inertia(m: f64, r: f64, h: f64) -> Vec3 {
    let side = m * (3.0 * r * r + 4.0 * h * h) / 12.0;
    [side, side, m * r * r / 2.0]
}

/// An RGBA colour attribute value.
pub fn rgba(c: [f64; 4]) -> String {
    format!("{} {} {} {}", c[0], c[1], c[2], c[3])
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn inertia_of_a_cube_and_a_disc() {
        let i = box_inertia(12.0, [0.5, 0.5, 0.5]);
        assert!(i.iter().all(|v| (v - 2.0).abs() < 1e-12));
        let c = cylinder_inertia(2.0, 1.0, 0.0);
        assert!((c[2] - 1.0).abs() < 1e-12 && (c[0] - 0.5).abs() < 1e-12);
        assert_eq!(
            pose_attrs(&crate::frame::translation([1.0, 0.0, 0.5])),
            r#"pos="1 0 0.5" quat="1 0 0 0""#
        );
    }
}
