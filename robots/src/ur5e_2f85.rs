//! Universal Robots UR5e with a Robotiq 2F-85 gripper, both from the MuJoCo Menagerie models that
//! `make setup` installs (never from the repository). Preparation copies the two files with
//! absolute mesh paths and gravity compensation on every body, attaches the gripper at the flange
//! through a tool frame, and adds the TCP site (the 2F-85's pinch point) and a wrist camera.
//!
//! Layout: state = 6 arm joint angles (rad) + the gripper's right driver angle (rad, 0..0.8);
//! action = 6 joint position targets (rad) + the fingers actuator (0 open .. 255 closed).

use crate::assets::{self, AssetError};
use crate::{Detail, Gripper, IkMethod, RobotModel, ur5e};
use std::f64::consts::PI;
use std::path::{Path, PathBuf};

/// Distance from the flange to the 2F-85's pinch point along the tool axis (m).
const TCP_OFFSET: f64 = 0.1558;

pub const MODEL: RobotModel = RobotModel {
    name: "ur5e_2f85",
    description: "Universal Robots UR5e with a Robotiq 2F-85 gripper (MuJoCo Menagerie models)",
    arm_joints: ur5e::JOINTS,
    arm_actuators: ur5e::ACTUATORS,
    gripper: Gripper {
        actuator: "gripper/fingers_actuator",
        driver_joint: "gripper/right_driver_joint",
        open: 0.0,
        closed: 255.0,
        state_unit: "rad",
        action_unit: "actuator",
        settle_s: 0.6,
        // Measured from MuJoCo's contact points: closed, the 2F-85's pads meet a button or a lid
        // pushed along the tool axis 17.5 to 17.8 mm past the pinch point.
        finger_reach: 0.0175,
        // The 2F-85's pads are as broad at the pinch point as anywhere.
        enclose: 0.0,
    },
    tcp_site: "tcp",
    tcp_body: "tool",
    hand_bodies: &["gripper/base_mount", "gripper/base"],
    fingers: &["gripper/left_follower", "gripper/right_follower"],
    wrist_camera: "wrist_cam",
    // The Menagerie UR5e faces -x at zero pan; a half turn makes a mount yaw of 0 reach along +x.
    mount_yaw: PI,
    root_body: "base",
    home: ur5e::HOME,
    // The UR5e's rated reach (850 mm) plus the 2F-85's length to its fingertips.
    reach: 1.0,
    expert_limits: ur5e::LIMITS,
    ik: IkMethod::Qp,
    prepare,
};

fn prepare(deps: &Path, detail: Detail) -> Result<PathBuf, AssetError> {
    let gr_dir = deps.join("robots/robotiq_2f85");
    let gr_file = gr_dir.join("2f85.xml");
    if !gr_file.exists() {
        return Err(AssetError::Missing(deps.join("robots")));
    }
    let mut gripper = assets::read(&gr_file)?;
    gripper = assets::strip_element(&gripper, "<option", "/>");
    gripper = ur5e::gravcomp(&gripper).replace(
        "meshdir=\"assets\"",
        &format!(
            "meshdir=\"{}\"",
            ur5e::meshes(deps, &gr_dir.join("assets"), detail)?
        ),
    );
    if detail == Detail::Simplified {
        // Simplified meshes are OBJ files of the same names.
        gripper = gripper.replace(".stl\"", ".obj\"");
    }
    let mut arm = ur5e::arm(deps, detail)?;
    // The tool frame: z along the approach, fingers closing along x. The camera sits on the -y side
    // looking at the pinch point (RealSense D405-like fov).
    let tool = format!(
        r#"<site name="attachment_site" pos="0 0.1 0" quat="-1 1 0 0"/>
                  <body name="tool" pos="0 0.1 0" quat="-1 1 0 0">
                    <attach model="gripper" body="base_mount" prefix="gripper/"/>
                    <site name="tcp" pos="0 0 {TCP_OFFSET}" size="0.004" group="4"/>
                    <camera name="wrist_cam" pos="0 -0.08 0.02" xyaxes="1 0 0 0 -0.868 0.496" fovy="58"/>
                  </body>"#
    );
    // Named by everything written into it (the gripper's path aside, which names the folder).
    let dir = assets::content_dir("autobio-robot", &format!("{arm}{gripper}{tool}"))?;
    let gripper_path = dir.join("2f85.xml");
    arm = arm.replace(ur5e::ATTACHMENT, &tool);
    arm = arm.replace(
        "<asset>",
        &format!(
            "<asset>\n    <model name=\"gripper\" file=\"{}\"/>",
            gripper_path.display()
        ),
    );
    let arm_path = dir.join("ur5e_2f85.xml");
    assets::write_if_changed(&gripper_path, &gripper)?;
    assets::write_if_changed(&arm_path, &arm)?;
    Ok(arm_path)
}
