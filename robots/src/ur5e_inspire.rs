//! Universal Robots UR5e with an Inspire right hand that holds a pipette and works its plunger
//! with its thumb, as the paper's pipetting arm (its DexHand with one thumb degree of freedom).
//! The arm is the MuJoCo Menagerie model and the hand robosuite's (1.5.2), both installed by
//! `make setup`, never from the repository.
//!
//! Preparation fixes every joint of the hand but the thumb's flexion: the four fingers are curled
//! into a fist (their joint angles folded into their bodies' frames) and the thumb's rotation and
//! its two outer joints are held at fixed angles. The one joint left (`joint_r_thumb_proximal_2`)
//! gets one position actuator in radians, the hand's action and state. The TCP is the fist's
//! grip point on a held pipette's handle, z down the pipette's axis toward its tip, placed from
//! the thumb's path: pressing the thumb moves its pad along the pipette's axis onto the plunger
//! button (see [`THUMB_PAD`]).
//!
//! Layout: state = 6 arm joint angles (rad) + the thumb's flexion (rad, 0..0.68);
//! action = 6 joint position targets (rad) + the thumb's target (rad, 0 off the button).

use crate::assets::{self, AssetError};
use crate::{Detail, Gripper, IkMethod, RobotModel, ur5e};
use std::f64::consts::PI;
use std::path::{Path, PathBuf};

pub const MODEL: RobotModel = RobotModel {
    name: "ur5e_inspire",
    description: "Universal Robots UR5e with an Inspire right hand holding a pipette, its thumb on \
                  the plunger (MuJoCo Menagerie and robosuite models)",
    arm_joints: ur5e::JOINTS,
    arm_actuators: ur5e::ACTUATORS,
    gripper: Gripper {
        actuator: "hand/thumb",
        driver_joint: "hand/joint_r_thumb_proximal_2",
        open: 0.0,
        closed: THUMB_RANGE,
        state_unit: "rad",
        action_unit: "rad",
        settle_s: 0.3,
        finger_reach: 0.0,
        enclose: 0.0,
    },
    tcp_site: "tcp",
    wrist_camera: "wrist_cam",
    tcp_body: "tool",
    hand_bodies: &[
        "hand/r_palm",
        "hand/r_thumb_proximal_1",
        "hand/r_thumb_proximal_2",
        "hand/r_thumb_middle",
        "hand/r_thumb_distal",
        "hand/r_index_proximal",
        "hand/r_index_distal",
        "hand/r_middle_proximal",
        "hand/r_middle_distal",
        "hand/r_ring_proximal",
        "hand/r_ring_distal",
        "hand/r_pinky_proximal",
        "hand/r_pinky_distal",
    ],
    // The thumb and the four fingers from their first phalanx on.
    fingers: &[
        "hand/r_thumb_proximal_1",
        "hand/r_index_proximal",
        "hand/r_middle_proximal",
        "hand/r_ring_proximal",
        "hand/r_pinky_proximal",
    ],
    mount_yaw: PI,
    root_body: "base",
    home: HOME,
    reach: 1.0,
    expert_limits: ur5e::LIMITS,
    ik: IkMethod::Qp,
    prepare,
};

/// The thumb flexion's range (rad), robosuite's.
const THUMB_RANGE: f64 = 0.68;

/// Upper arm up, forearm level, the wrist turned so that the held pipette points down.
const HOME: &[f64] = &[-0.3, -1.877, 2.065, -0.64, -0.331, -2.61];

/// Where the thumb's pad first meets the plunger button, in the hand file's frame (m; its fingers
/// along -z, the palm facing -x): measured from the hand's meshes with the thumb's outer joints
/// at [`THUMB_BEND`] and its flexion at 0.16 rad, 10 mm from where it rests at 0. Pressing moves
/// the pad along [`PRESS_AXIS`] about 0.75 mm per 0.01 rad, so the button's first stop (7.5 mm)
/// is at about 0.25 rad and blow-out (2.5 mm more) at about 0.28.
const THUMB_PAD: [f64; 3] = [-0.0348, 0.0769, -0.0999];

/// The pipette's axis toward its tip, in the hand file's frame: across the fist from the thumb's
/// side to the little finger's, tilted 10° toward the fingertips (the thumb's own path runs 20°
/// steeper; the button takes the part along the axis).
const PRESS_AXIS: [f64; 3] = [0.100_04, -0.980_34, -0.170_06];

/// How far the held pipette's grip point lies from its button's top along its axis (m): the
/// pipette model's, 30 mm below its handle's top (`labware::pipette`).
const GRIP_BELOW_BUTTON: f64 = 0.056;

/// The thumb's outer joints (middle, distal), held bent (rad).
const THUMB_BEND: f64 = 0.3;

/// The fingers' proximal and distal joints, held in a fist around the handle (rad).
const FIST: [f64; 2] = [1.2, 1.0];

fn mul(a: [f64; 4], b: [f64; 4]) -> [f64; 4] {
    [
        a[0] * b[0] - a[1] * b[1] - a[2] * b[2] - a[3] * b[3],
        a[0] * b[1] + a[1] * b[0] + a[2] * b[3] - a[3] * b[2],
        a[0] * b[2] - a[1] * b[3] + a[2] * b[0] + a[3] * b[1],
        a[0] * b[3] + a[1] * b[2] - a[2] * b[1] + a[3] * b[0],
    ]
}

/// The hand file with the joint of `body` (about its frame's z by `angle`) folded into the body's
/// frame and removed.
fn fix_joint(
    file: &Path,
    hand: &str,
    body: &str,
    joint: &str,
    angle: f64,
) -> Result<String, AssetError> {
    let open = format!("<body name=\"{body}\"");
    let at = hand
        .find(&open)
        .ok_or_else(|| assets::malformed(file, &format!("no body `{body}`")))?;
    let malformed = |what: &str| assets::malformed(file, &format!("body `{body}`: {what}"));
    let end = at
        + hand[at..]
            .find('>')
            .ok_or_else(|| malformed("no end to its tag"))?;
    let tag = &hand[at..end];
    let quat: Vec<f64> = assets::between(tag, "quat=\"", "\"")
        .ok_or_else(|| malformed("no quat"))?
        .split_whitespace()
        .filter_map(|v| v.parse().ok())
        .collect();
    let [w, x, y, z] = quat.as_slice() else {
        return Err(malformed("a quat of other than four numbers"));
    };
    let q = [*w, *x, *y, *z];
    let joint_tag = format!("<joint name=\"{joint}\"");
    if !hand[end..].contains(&joint_tag) {
        return Err(malformed(&format!("no joint `{joint}`")));
    }
    let turned = mul(q, [(angle / 2.0).cos(), 0.0, 0.0, (angle / 2.0).sin()]);
    let new_tag = format!(
        "{} quat=\"{} {} {} {}\"",
        assets::strip_attribute(tag, "quat").trim_end(),
        turned[0],
        turned[1],
        turned[2],
        turned[3]
    );
    let out = format!("{}{}{}", &hand[..at], new_tag, &hand[end..]);
    Ok(assets::strip_element(
        &out,
        &format!("<joint name=\"{joint}\""),
        "/>",
    ))
}

/// The hand's MJCF: fingers in a fist, the thumb's one joint and its actuator.
fn hand(deps: &Path, detail: Detail) -> Result<String, AssetError> {
    let dir = deps.join("robots/inspire_hand");
    let file = dir.join("inspire_right_hand.xml");
    if !file.exists() {
        return Err(AssetError::Missing(dir));
    }
    let mut hand = assets::read(&file)?;
    for (open, close) in [
        ("<statistic", "/>"),
        ("<visual>", "</visual>"),
        ("<actuator>", "</actuator>"),
        ("<sensor>", "</sensor>"),
        // robosuite's end-effector frame and its markers (a green ray), and the force sensor's site.
        ("<body name=\"eef\"", "</body>"),
        ("<site name=\"ft_frame\"", "/>"),
    ] {
        hand = assets::strip_element(&hand, open, close);
    }
    // The thumb's rotation is held where the file's zero puts it (its joint turns about -z).
    hand = fix_joint(
        &file,
        &hand,
        "r_thumb_proximal_1",
        "joint_r_thumb_proximal_1",
        0.0,
    )?;
    hand = fix_joint(
        &file,
        &hand,
        "r_thumb_middle",
        "joint_r_thumb_middle",
        THUMB_BEND,
    )?;
    hand = fix_joint(
        &file,
        &hand,
        "r_thumb_distal",
        "joint_r_thumb_distal",
        THUMB_BEND,
    )?;
    for finger in ["index", "middle", "ring", "pinky"] {
        for (link, angle) in [("proximal", FIST[0]), ("distal", FIST[1])] {
            hand = fix_joint(
                &file,
                &hand,
                &format!("r_{finger}_{link}"),
                &format!("joint_r_{finger}_{link}"),
                angle,
            )?;
        }
    }
    let meshes = ur5e::meshes(deps, &dir.join("meshes"), detail)?;
    hand = ur5e::gravcomp(&hand)
        .replace("meshdir=\"./\"", &format!("meshdir=\"{meshes}\""))
        .replace("file=\"meshes/inspire_hands/", "file=\"");
    if detail == Detail::Simplified {
        hand = hand.replace(".STL\"", ".obj\"");
    }
    // One position servo on the thumb's flexion: 10 N·m/rad, at most 1.5 N·m (over 20 N at the
    // pad, past the button's blow-out spring's 13 N).
    let actuator = format!(
        r#"  <actuator>
        <position name="thumb" joint="joint_r_thumb_proximal_2" kp="10" ctrlrange="0 {THUMB_RANGE}" forcelimited="true" forcerange="-1.5 1.5"/>
    </actuator>
</mujoco>"#
    );
    Ok(hand.replace("</mujoco>", &actuator))
}

/// The TCP in the tool frame: the hand sits in it turned half a turn about x (its fingers along
/// the tool's z), so a hand-frame (x, y, z) is (x, -y, -z) here.
fn tcp() -> String {
    let u = PRESS_AXIS;
    let g: Vec<f64> = (0..3)
        .map(|i| THUMB_PAD[i] + GRIP_BELOW_BUTTON * u[i])
        .collect();
    let z = [u[0], -u[1], -u[2]];
    // x: the hand's x, square to z.
    let x = [1.0 - z[0] * z[0], -z[0] * z[1], -z[0] * z[2]];
    let y = [
        z[1] * x[2] - z[2] * x[1],
        z[2] * x[0] - z[0] * x[2],
        z[0] * x[1] - z[1] * x[0],
    ];
    format!(
        r#"<site name="tcp" pos="{} {} {}" xyaxes="{} {} {} {} {} {}" size="0.004" group="4"/>"#,
        g[0], -g[1], -g[2], x[0], x[1], x[2], y[0], y[1], y[2]
    )
}

fn prepare(deps: &Path, detail: Detail) -> Result<PathBuf, AssetError> {
    let hand = hand(deps, detail)?;
    let mut arm = ur5e::arm(deps, detail)?;
    let tool = format!(
        r#"<site name="attachment_site" pos="0 0.1 0" quat="-1 1 0 0"/>
                  <body name="tool" pos="0 0.1 0" quat="-1 1 0 0">
                    <body name="hand_mount" quat="0 1 0 0">
                      <attach model="hand" body="right_hand" prefix="hand/"/>
                    </body>
                    {}
                    <camera name="wrist_cam" pos="0.05 -0.02 0.05" xyaxes="0 0.105 -0.995 0.954 0.298 0.031" fovy="58"/>
                  </body>"#,
        tcp()
    );
    let dir = assets::content_dir("autobio-robot", &format!("{arm}{hand}{tool}"))?;
    let hand_path = dir.join("inspire_right_hand.xml");
    arm = arm.replace(ur5e::ATTACHMENT, &tool);
    arm = arm.replace(
        "<asset>",
        &format!(
            "<asset>\n    <model name=\"hand\" file=\"{}\"/>",
            hand_path.display()
        ),
    );
    let arm_path = dir.join("ur5e_inspire.xml");
    assets::write_if_changed(&hand_path, &hand)?;
    assets::write_if_changed(&arm_path, &arm)?;
    Ok(arm_path)
}
