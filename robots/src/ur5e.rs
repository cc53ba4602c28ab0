//! What every UR5e-based robot shares: the arm's joints and actuators, its home pose and expert
//! limits, and its MJCF prepared from the MuJoCo Menagerie model that `make setup` installs
//! (absolute mesh paths, gravity compensation, no keyframe, light or options), with the flange's
//! attachment site where a robot file puts its tool. The tool (a gripper, a hand) is each
//! robot's own file.

use crate::assets::{self, AssetError};
use crate::{Detail, ExpertLimits, lod};
use std::f64::consts::FRAC_PI_2;
use std::path::Path;

pub(crate) const JOINTS: &[&str] = &[
    "shoulder_pan_joint",
    "shoulder_lift_joint",
    "elbow_joint",
    "wrist_1_joint",
    "wrist_2_joint",
    "wrist_3_joint",
];

pub(crate) const ACTUATORS: &[&str] = &[
    "shoulder_pan",
    "shoulder_lift",
    "elbow",
    "wrist_1",
    "wrist_2",
    "wrist_3",
];

/// Upper arm up, forearm level, tool pointing down.
pub(crate) const HOME: &[f64] = &[
    0.0, -FRAC_PI_2, FRAC_PI_2, -FRAC_PI_2, -FRAC_PI_2, -FRAC_PI_2,
];

/// As the upstream thermal-cycler expert.
pub(crate) const LIMITS: ExpertLimits = ExpertLimits {
    vmax: 1.5,
    amax: 1.0,
    // At the UR5e's 0.9 m reach, 0.02 rad is about 2 cm of tool travel at worst, less than
    // a rotor slot's width.
    check_step: 0.02,
    joint_space_transits: false,
};

/// The flange's attachment site in the prepared arm: a robot file replaces it with its tool.
pub(crate) const ATTACHMENT: &str =
    r#"<site name="attachment_site" pos="0 0.1 0" quat="-1 1 0 0"/>"#;

/// Gravity compensation on every body of a model's text.
pub(crate) fn gravcomp(s: &str) -> String {
    s.replace("<body ", "<body gravcomp=\"1\" ")
}

/// A package's mesh folder as an absolute path: its own meshes, or [`lod`]'s simplified copies.
pub(crate) fn meshes(deps: &Path, dir: &Path, detail: Detail) -> Result<String, AssetError> {
    match detail {
        Detail::Full => assets::absolute(dir),
        Detail::Simplified => assets::absolute(&lod::simplified_dir(dir, &deps.join("lod"))?),
    }
}

/// The Menagerie UR5e's MJCF, prepared: its tool goes where [`ATTACHMENT`] is.
pub(crate) fn arm(deps: &Path, detail: Detail) -> Result<String, AssetError> {
    let ur_dir = deps.join("robots/universal_robots_ur5e");
    let ur_file = ur_dir.join("ur5e.xml");
    if !ur_file.exists() {
        return Err(AssetError::Missing(deps.join("robots")));
    }
    let mut arm = assets::read(&ur_file)?;
    arm = gravcomp(&arm).replace(
        "meshdir=\"assets\"",
        &format!(
            "meshdir=\"{}\"",
            meshes(deps, &ur_dir.join("assets"), detail)?
        ),
    );
    arm = assets::strip_element(&arm, "<keyframe>", "</keyframe>");
    arm = assets::strip_element(&arm, "<light name=\"spotlight\"", "/>");
    Ok(assets::strip_element(&arm, "<option", "/>"))
}
