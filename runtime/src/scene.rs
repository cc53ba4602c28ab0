//! Scene assembly: a compiled task (and one sampled instance of it) to a MuJoCo model, plus the
//! indices the episode needs (joint addresses, actuators, sites, equality constraints).
//!
//! Robots come from the installed MuJoCo Menagerie files (never from the repository): the UR5e and
//! the 2F-85 are copied into a content-addressed folder under the temp dir with absolute mesh paths,
//! gravity compensation on every body, the gripper attached at the flange, a wrist camera and a TCP
//! site added. The scene then `<attach>`es that robot file once per robot with a name prefix.

use crate::deps;
use compiler::{CameraMount, LabwareParams, SceneInstance, Task};
use labware::{Pose, Quat};
use mujoco_rs::prelude::*;
use sha2::{Digest, Sha256};
use std::path::{Path, PathBuf};
use std::sync::Arc;

#[derive(Debug, thiserror::Error)]
pub enum SceneError {
    #[error("robot model files not found under {0} (run `make setup`)")]
    MissingRobot(PathBuf),
    #[error("cannot prepare the robot model: {0}")]
    Io(#[from] std::io::Error),
    #[error("mujoco rejected the scene: {0}")]
    Compile(String),
    #[error("the scene has no {0} named `{1}`")]
    MissingName(&'static str, String),
    #[error(
        "labware `{0}` is a {1}, which has no simulation model yet; it can be compiled and described, not run"
    )]
    Unmodelled(String, String),
}

/// Per-robot indices into the model.
#[derive(Clone, Debug)]
pub struct RobotIds {
    pub qpos: Vec<usize>,
    pub dof: Vec<usize>,
    pub actuators: Vec<usize>,
    pub gripper_actuator: usize,
    pub gripper_qpos: usize,
    pub tcp_site: usize,
}

/// Per-labware indices (thermal cycler).
#[derive(Clone, Debug)]
pub struct LabwareIds {
    pub lid_qpos: usize,
    pub lid_dof: usize,
    pub lever_qpos: usize,
    pub lever_dof: usize,
    pub lock_eq: usize,
    pub grip_site: usize,
}

/// A compiled MuJoCo model for a task with its indices. Cheap to share (`Arc`).
pub struct Scene {
    pub model: Arc<MjModel>,
    pub robots: Vec<RobotIds>,
    pub labware: Vec<LabwareIds>,
    pub cameras: Vec<usize>,
    pub xml: String,
    /// Labware placements the model was built with.
    pub placements: Vec<Pose>,
}

pub const ARM_JOINTS: [&str; 6] = [
    "shoulder_pan_joint",
    "shoulder_lift_joint",
    "elbow_joint",
    "wrist_1_joint",
    "wrist_2_joint",
    "wrist_3_joint",
];
pub const ARM_ACTUATORS: [&str; 6] = [
    "shoulder_pan",
    "shoulder_lift",
    "elbow",
    "wrist_1",
    "wrist_2",
    "wrist_3",
];
/// Gripper actuator range: 0 open, 255 closed.
pub const GRIPPER_CLOSED: f64 = 255.0;
/// Distance from the flange to the 2F-85's pinch point along the tool axis (m).
pub const TCP_OFFSET: f64 = 0.1558;

fn v3(v: [f64; 3]) -> String {
    format!("{} {} {}", v[0], v[1], v[2])
}
fn q4(q: Quat) -> String {
    format!("{} {} {} {}", q.0[0], q.0[1], q.0[2], q.0[3])
}

/// Writes the UR5e + 2F-85 robot file (idempotent, content-addressed) and returns its path.
pub fn prepare_ur5e_2f85() -> Result<PathBuf, SceneError> {
    let ur_dir = deps::robot_dir("universal_robots_ur5e");
    let gr_dir = deps::robot_dir("robotiq_2f85");
    let (ur_file, gr_file) = (ur_dir.join("ur5e.xml"), gr_dir.join("2f85.xml"));
    if !ur_file.exists() || !gr_file.exists() {
        return Err(SceneError::MissingRobot(deps::robot_dir("")));
    }
    let abs = |p: &Path| std::fs::canonicalize(p).map(|p| p.display().to_string());
    let gravcomp = |s: &str| s.replace("<body ", "<body gravcomp=\"1\" ");
    let mut gripper = std::fs::read_to_string(&gr_file)?;
    gripper = strip_element(&gripper, "<option", "/>");
    gripper = gravcomp(&gripper).replace(
        "meshdir=\"assets\"",
        &format!("meshdir=\"{}\"", abs(&gr_dir.join("assets"))?),
    );
    let mut arm = std::fs::read_to_string(&ur_file)?;
    arm = gravcomp(&arm).replace(
        "meshdir=\"assets\"",
        &format!("meshdir=\"{}\"", abs(&ur_dir.join("assets"))?),
    );
    arm = strip_element(&arm, "<keyframe>", "</keyframe>");
    arm = strip_element(&arm, "<light name=\"spotlight\"", "/>");
    arm = strip_element(&arm, "<option", "/>");
    let dir = std::env::temp_dir().join(format!(
        "autobio-robot-{}",
        short_hash(&(arm.clone() + &gripper))
    ));
    std::fs::create_dir_all(&dir)?;
    let gripper_path = dir.join("2f85.xml");
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
    arm = arm.replace(
        r#"<site name="attachment_site" pos="0 0.1 0" quat="-1 1 0 0"/>"#,
        &tool,
    );
    arm = arm.replace(
        "<asset>",
        &format!(
            "<asset>\n    <model name=\"gripper\" file=\"{}\"/>",
            gripper_path.display()
        ),
    );
    let arm_path = dir.join("ur5e_2f85.xml");
    write_if_changed(&gripper_path, &gripper)?;
    write_if_changed(&arm_path, &arm)?;
    Ok(arm_path)
}

fn strip_element(s: &str, open: &str, close: &str) -> String {
    match s.find(open) {
        Some(a) => match s[a..].find(close) {
            Some(b) => format!("{}{}", &s[..a], &s[a + b + close.len()..]),
            None => s.to_string(),
        },
        None => s.to_string(),
    }
}

fn short_hash(s: &str) -> String {
    let d = Sha256::digest(s.as_bytes());
    d.iter().take(8).map(|b| format!("{b:02x}")).collect()
}

fn write_if_changed(path: &Path, text: &str) -> std::io::Result<()> {
    if std::fs::read_to_string(path).ok().as_deref() == Some(text) {
        return Ok(());
    }
    // Unique per process and per call: tests build scenes from several threads at once, and a shared
    // temporary name lets one thread rename the other's file away.
    static WRITES: std::sync::atomic::AtomicU64 = std::sync::atomic::AtomicU64::new(0);
    let n = WRITES.fetch_add(1, std::sync::atomic::Ordering::Relaxed);
    let tmp = path.with_extension(format!("tmp{}-{n}", std::process::id()));
    std::fs::write(&tmp, text)?;
    std::fs::rename(tmp, path)
}

/// The scene MJCF for a task with the given labware placements.
pub fn scene_xml(task: &Task, placements: &[Pose]) -> Result<String, SceneError> {
    let robot_file = prepare_ur5e_2f85()?;
    let mut world = String::new();
    let mut equality = String::new();
    let mut contact = String::new();
    for cam in &task.cameras {
        if let CameraMount::Fixed {
            pos,
            xyaxes,
            fovy_deg,
        } = &cam.mount
        {
            let a = xyaxes;
            world += &format!(
                "<camera name=\"{}\" pos=\"{}\" xyaxes=\"{} {} {} {} {} {}\" fovy=\"{fovy_deg}\"/>\n",
                cam.name,
                v3(*pos),
                a[0],
                a[1],
                a[2],
                a[3],
                a[4],
                a[5]
            );
        }
    }
    // The Menagerie UR5e faces -x at zero pan; turn it so that a mount yaw of 0 reaches along +x.
    let facing = Quat::from_axis_angle([0.0, 0.0, 1.0], std::f64::consts::PI);
    for r in &task.robots {
        world += &format!(
            "<body name=\"{n}/mount\" pos=\"{}\" quat=\"{}\">\n  <attach model=\"{}\" body=\"base\" prefix=\"{n}/\"/>\n</body>\n",
            v3(r.base.pos),
            q4(r.base.quat.times(facing)),
            r.model,
            n = r.name
        );
    }
    let mut detents = String::new();
    for (l, placement) in task.labware.iter().zip(placements) {
        let LabwareParams::ThermalCycler(p) = &l.params else {
            return Err(SceneError::Unmodelled(l.name.clone(), l.kind.clone()));
        };
        let m = p.mjcf(&l.name, placement);
        // The lever's two notches: the `autobio.detent` plugin.
        let lever = physics::detent::Detent {
            lo: p.lever_pressed.min(p.lever_raised),
            hi: p.lever_pressed.max(p.lever_raised),
            n: 2,
            stiffness: p.detent_stiffness,
            damping: p.detent_damping,
        };
        let joint = labware::thermal_cycler::Names::new(&l.name).lever_joint;
        detents += &lever.mjcf_instance(&format!("{}/lever_detent", l.name), &joint);
        world += &m.worldbody;
        equality += &m.equality;
        contact += &m.contact;
    }
    Ok(format!(
        r#"<mujoco model="autobio:{id}">
  <compiler angle="radian" autolimits="true"/>
  <option timestep="{dt}" integrator="implicitfast" cone="elliptic" impratio="10" noslip_iterations="2">
    <flag multiccd="enable"/>
  </option>
  <visual>
    <global offwidth="640" offheight="480"/>
    <quality shadowsize="0" offsamples="0"/>
    <headlight ambient="0.45 0.45 0.45" diffuse="0.5 0.5 0.5" specular="0.1 0.1 0.1"/>
  </visual>
  <extension>
    <plugin plugin="autobio.detent">{detents}</plugin>
  </extension>
  <asset>
    <model name="ur5e_2f85" file="{robot}"/>
  </asset>
  <worldbody>
    <light name="ceiling" pos="0 0 3" dir="0 0 -1" directional="true" castshadow="false" diffuse="0.4 0.4 0.4"/>
    <geom name="floor" type="plane" size="4 4 0.1" rgba="0.42 0.43 0.45 1"/>
    <body name="table">
      <geom name="table/top" type="box" size="0.409 0.652 0.412" pos="0 0 0.412" rgba="0.72 0.66 0.56 1"/>
    </body>
{world}  </worldbody>
  <equality>
{equality}  </equality>
  <contact>
{contact}  </contact>
</mujoco>
"#,
        id = task.id,
        dt = task.physics.timestep_s,
        robot = robot_file.display(),
    ))
}

fn id_of(
    model: &MjModel,
    ty: MjtObjBase,
    what: &'static str,
    name: &str,
) -> Result<usize, SceneError> {
    model
        .name_to_id(ty, name)
        .ok_or_else(|| SceneError::MissingName(what, name.to_string()))
}

impl Scene {
    /// Builds the model for one scene instance of a task.
    pub fn build(task: &Task, instance: &SceneInstance) -> Result<Scene, SceneError> {
        let placements = instance.labware_placement.clone();
        physics::register().map_err(|e| SceneError::Compile(e.to_string()))?;
        let xml = scene_xml(task, &placements)?;
        let model =
            MjModel::from_xml_string(&xml).map_err(|e| SceneError::Compile(e.to_string()))?;
        let errors = physics::instance_errors(model.ffi(), MjData::new(&model).ffi());
        if !errors.is_empty() {
            return Err(SceneError::Compile(errors.join("; ")));
        }
        let m = &model;
        let mut robots = Vec::new();
        for r in &task.robots {
            let mut qpos = Vec::new();
            let mut dof = Vec::new();
            let mut actuators = Vec::new();
            for (j, a) in ARM_JOINTS.iter().zip(ARM_ACTUATORS) {
                let jid = id_of(
                    m,
                    MjtObjBase::mjOBJ_JOINT,
                    "joint",
                    &format!("{}/{j}", r.name),
                )?;
                qpos.push(joint_qposadr(m, jid));
                dof.push(joint_dofadr(m, jid));
                actuators.push(id_of(
                    m,
                    MjtObjBase::mjOBJ_ACTUATOR,
                    "actuator",
                    &format!("{}/{a}", r.name),
                )?);
            }
            let driver = id_of(
                m,
                MjtObjBase::mjOBJ_JOINT,
                "joint",
                &format!("{}/gripper/right_driver_joint", r.name),
            )?;
            robots.push(RobotIds {
                qpos,
                dof,
                actuators,
                gripper_actuator: id_of(
                    m,
                    MjtObjBase::mjOBJ_ACTUATOR,
                    "actuator",
                    &format!("{}/gripper/fingers_actuator", r.name),
                )?,
                gripper_qpos: joint_qposadr(m, driver),
                tcp_site: id_of(
                    m,
                    MjtObjBase::mjOBJ_SITE,
                    "site",
                    &format!("{}/tcp", r.name),
                )?,
            });
        }
        let mut labware = Vec::new();
        for l in &task.labware {
            let n = labware::thermal_cycler::Names::new(&l.name);
            let lid = id_of(m, MjtObjBase::mjOBJ_JOINT, "joint", &n.lid_joint)?;
            let lever = id_of(m, MjtObjBase::mjOBJ_JOINT, "joint", &n.lever_joint)?;
            labware.push(LabwareIds {
                lid_qpos: joint_qposadr(m, lid),
                lid_dof: joint_dofadr(m, lid),
                lever_qpos: joint_qposadr(m, lever),
                lever_dof: joint_dofadr(m, lever),
                lock_eq: id_of(m, MjtObjBase::mjOBJ_EQUALITY, "equality", &n.lock)?,
                grip_site: id_of(m, MjtObjBase::mjOBJ_SITE, "site", &n.grip_site)?,
            });
        }
        let mut cameras = Vec::new();
        for c in &task.cameras {
            let name = match &c.mount {
                CameraMount::Fixed { .. } => c.name.clone(),
                CameraMount::Wrist { robot } => format!("{robot}/wrist_cam"),
            };
            cameras.push(id_of(m, MjtObjBase::mjOBJ_CAMERA, "camera", &name)?);
        }
        Ok(Scene {
            model: Arc::new(model),
            robots,
            labware,
            cameras,
            xml,
            placements,
        })
    }
}

pub fn joint_qposadr(m: &MjModel, joint: usize) -> usize {
    m.jnt_qposadr()[joint] as usize
}

pub fn joint_dofadr(m: &MjModel, joint: usize) -> usize {
    m.jnt_dofadr()[joint] as usize
}
