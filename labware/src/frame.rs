//! Rigid-body frames on nalgebra: [`Pose`] is an `Isometry3<f64>`, [`Rot`] a `UnitQuaternion<f64>`.
//! This module adds only what nalgebra leaves to the caller: constructors from the plain arrays the
//! task contract and MuJoCo use (MuJoCo quaternions are w-x-y-z, its matrices row-major), pose
//! interpolation, and the task contract's serde form of a pose (`{"pos": [x, y, z], "quat": [w, x,
//! y, z]}`), kept so compiled tasks and recordings read the same as before the move to nalgebra.

use nalgebra::{Isometry3, Matrix3, Quaternion, Rotation3, Translation3, UnitQuaternion, Vector3};

/// A plain 3-vector as parameters and the task contract store it (metres).
pub type Vec3 = [f64; 3];
pub type Pose = Isometry3<f64>;
pub type Rot = UnitQuaternion<f64>;

pub fn vector(v: Vec3) -> Vector3<f64> {
    Vector3::new(v[0], v[1], v[2])
}

pub fn pose(pos: Vec3, rot: Rot) -> Pose {
    Isometry3::from_parts(Translation3::new(pos[0], pos[1], pos[2]), rot)
}

/// A pose at `pos` turned by `yaw` about +z.
pub fn yaw(pos: Vec3, yaw: f64) -> Pose {
    pose(pos, axis_angle([0.0, 0.0, 1.0], yaw))
}

pub fn translation(pos: Vec3) -> Pose {
    pose(pos, Rot::identity())
}

pub fn axis_angle(axis: Vec3, angle: f64) -> Rot {
    match nalgebra::Unit::try_new(vector(axis), 1e-12) {
        Some(a) => Rot::from_axis_angle(&a, angle),
        None => Rot::identity(),
    }
}

/// A turn about +x (a hinge along x: lids and levers).
pub fn x_turn(angle: f64) -> Rot {
    axis_angle([1.0, 0.0, 0.0], angle)
}

pub fn position(p: &Pose) -> Vec3 {
    let t = p.translation.vector;
    [t.x, t.y, t.z]
}

/// MuJoCo's quaternion order: w, x, y, z.
pub fn wxyz(r: &Rot) -> [f64; 4] {
    let q = r.quaternion();
    [q.w, q.i, q.j, q.k]
}

pub fn from_wxyz(q: [f64; 4]) -> Rot {
    Rot::from_quaternion(Quaternion::new(q[0], q[1], q[2], q[3]))
}

/// From a row-major rotation matrix (MuJoCo's `xmat`).
pub fn from_rows(m: &[f64; 9]) -> Rot {
    let mat = Matrix3::new(m[0], m[1], m[2], m[3], m[4], m[5], m[6], m[7], m[8]);
    Rot::from_rotation_matrix(&Rotation3::from_matrix_unchecked(mat))
}

/// The rotation taking the world axes to the given tool axes (columns x, y, z).
pub fn from_axes(x: Vec3, y: Vec3, z: Vec3) -> Rot {
    let mat = Matrix3::from_columns(&[vector(x), vector(y), vector(z)]);
    Rot::from_rotation_matrix(&Rotation3::from_matrix_unchecked(mat))
}

/// Straight-line position and spherical rotation interpolation from `a` (t=0) to `b` (t=1).
pub fn interpolate(a: &Pose, b: &Pose, t: f64) -> Pose {
    let ta = a.translation.vector;
    let tb = b.translation.vector;
    let rot = a
        .rotation
        .try_slerp(&b.rotation, t, 1e-9)
        .unwrap_or(if t < 0.5 { a.rotation } else { b.rotation });
    Isometry3::from_parts(Translation3::from(ta + (tb - ta) * t), rot)
}

/// A pose moved by `offset` along its own axes.
pub fn translated_local(p: &Pose, offset: Vec3) -> Pose {
    p * translation(offset)
}

/// The task contract's form of a pose: `{"pos": [x, y, z], "quat": [w, x, y, z]}`.
#[derive(serde::Serialize, serde::Deserialize)]
struct PoseForm {
    pos: Vec3,
    quat: [f64; 4],
}

impl From<&Pose> for PoseForm {
    fn from(p: &Pose) -> Self {
        PoseForm {
            pos: position(p),
            quat: wxyz(&p.rotation),
        }
    }
}

impl From<PoseForm> for Pose {
    fn from(f: PoseForm) -> Self {
        pose(f.pos, from_wxyz(f.quat))
    }
}

/// `#[serde(with = "labware::frame::serde_pose")]` for a `Pose` field.
pub mod serde_pose {
    use super::{Pose, PoseForm};
    use serde::{Deserialize, Deserializer, Serialize, Serializer};

    pub fn serialize<S: Serializer>(p: &Pose, s: S) -> Result<S::Ok, S::Error> {
        PoseForm::from(p).serialize(s)
    }

    pub fn deserialize<'de, D: Deserializer<'de>>(d: D) -> Result<Pose, D::Error> {
        PoseForm::deserialize(d).map(Pose::from)
    }
}

/// `#[serde(with = "labware::frame::serde_poses")]` for a `Vec<Pose>` field.
pub mod serde_poses {
    use super::{Pose, PoseForm};
    use serde::{Deserialize, Deserializer, Serialize, Serializer};

    pub fn serialize<S: Serializer>(p: &[Pose], s: S) -> Result<S::Ok, S::Error> {
        let forms: Vec<PoseForm> = p.iter().map(PoseForm::from).collect();
        forms.serialize(s)
    }

    pub fn deserialize<'de, D: Deserializer<'de>>(d: D) -> Result<Vec<Pose>, D::Error> {
        Vec::<PoseForm>::deserialize(d).map(|v| v.into_iter().map(Pose::from).collect())
    }
}

/// `#[serde(with = "labware::frame::serde_pose_map")]` for a `BTreeMap<String, Pose>` field.
pub mod serde_pose_map {
    use super::{Pose, PoseForm};
    use serde::{Deserialize, Deserializer, Serialize, Serializer};
    use std::collections::BTreeMap;

    pub fn serialize<S: Serializer>(m: &BTreeMap<String, Pose>, s: S) -> Result<S::Ok, S::Error> {
        let forms: BTreeMap<&String, PoseForm> =
            m.iter().map(|(k, p)| (k, PoseForm::from(p))).collect();
        forms.serialize(s)
    }

    pub fn deserialize<'de, D: Deserializer<'de>>(
        d: D,
    ) -> Result<BTreeMap<String, Pose>, D::Error> {
        BTreeMap::<String, PoseForm>::deserialize(d)
            .map(|m| m.into_iter().map(|(k, f)| (k, Pose::from(f))).collect())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn mujoco_conventions_round_trip() {
        let r = axis_angle([1.0, 2.0, 3.0], 0.7);
        let m = r.to_rotation_matrix();
        let rows: [f64; 9] = std::array::from_fn(|i| m[(i / 3, i % 3)]);
        assert!(from_rows(&rows).angle_to(&r) < 1e-12);
        assert!(from_wxyz(wxyz(&r)).angle_to(&r) < 1e-12);
        // A quarter turn about z takes +x to +y.
        let v = axis_angle([0.0, 0.0, 1.0], std::f64::consts::FRAC_PI_2) * vector([1.0, 0.0, 0.0]);
        assert!((v.y - 1.0).abs() < 1e-12 && v.x.abs() < 1e-12);
        let half = interpolate(&Pose::identity(), &pose([2.0, 0.0, 0.0], r), 0.5);
        assert!((half.rotation.angle() - 0.35).abs() < 1e-12);
        assert!((position(&half)[0] - 1.0).abs() < 1e-12);
    }

    #[test]
    fn the_contract_form_is_w_first() {
        let p = yaw([1.0, 2.0, 3.0], std::f64::consts::PI);
        let json = serde_json::to_value(PoseForm::from(&p)).unwrap();
        assert_eq!(json["pos"], serde_json::json!([1.0, 2.0, 3.0]));
        assert!(json["quat"][0].as_f64().unwrap().abs() < 1e-12);
        assert!((json["quat"][3].as_f64().unwrap() - 1.0).abs() < 1e-12);
    }
}
