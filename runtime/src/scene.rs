//! Scene assembly: a compiled task (and one sampled instance of it) to a MuJoCo model, plus the
//! indices the episode needs, found by the roles the robot and labware models name.
//!
//! Robots come from their robot model ([`robots::RobotModel`]): its `prepare` writes the robot
//! file from the installed packages, and the scene `<attach>`es it once per robot with the robot's
//! name as prefix. Labware comes from each item's instrument model ([`labware::Instrument`]): its
//! MJCF fragment, and the mechanisms it asks for, which become `autobio.*` plugin instances here.
//! Nothing in this file knows an instrument kind or a robot's joint.

use crate::deps;
use compiler::params::render;
use compiler::{CameraMount, SceneInstance, Task};
use labware::mjcf::{Fragment, pose_attrs};
use labware::{LabwareState, Logic, Mechanism, Pose};
use mujoco_rs::prelude::*;
use robots::{Detail, RobotModel};
use std::collections::BTreeMap;
use std::sync::{Arc, OnceLock};

#[derive(Debug, thiserror::Error)]
pub enum SceneError {
    #[error(transparent)]
    Robot(#[from] robots::AssetError),
    #[error("robot `{0}` names the model `{1}`, which is not in the robot registry")]
    UnknownRobot(String, String),
    #[error("mujoco rejected the scene: {0}")]
    Compile(String),
    #[error("the scene has no {0} named `{1}`")]
    MissingName(&'static str, String),
    #[error(
        "labware `{0}` is a {1}, which has no simulation model yet; it can be compiled and described, not run"
    )]
    Unmodelled(String, String),
    #[error("labware `{0}` cannot start as declared: {1}")]
    Unsupported(String, String),
    #[error("labware `{0}` starts at `{1}`, which is no slot of a holder in this scene")]
    NoSlot(String, String),
    #[error(
        "the success check `{0}` cannot be measured in simulation yet ({1}); the task can be compiled and described, not run"
    )]
    Unmeasurable(String, &'static str),
    /// A quantity template that the instance's parameters do not resolve (a task written by
    /// hand: the compiler proves every template resolves over the parameters' domains).
    #[error(transparent)]
    Quantity(#[from] compiler::quantities::QuantityError),
}

/// Per-robot indices into the model.
#[derive(Clone, Debug)]
pub struct RobotIds {
    pub name: String,
    pub model: &'static RobotModel,
    pub joints: Vec<usize>,
    pub qpos: Vec<usize>,
    pub dof: Vec<usize>,
    pub actuators: Vec<usize>,
    pub gripper_actuator: usize,
    pub gripper_qpos: usize,
    pub tcp_site: usize,
}

/// A free joint of a movable item: its name (as the model's `place` names it) and addresses.
#[derive(Clone, Debug)]
pub struct FreeJoint {
    pub name: String,
    /// The body it frees (an item's root or a loose part).
    pub body: usize,
    pub qpos: usize,
    pub dof: usize,
}

/// Per-labware indices, by the roles its model names.
#[derive(Clone, Debug)]
pub struct LabwareIds {
    pub root_body: usize,
    /// Hinge and slide joints: role, qpos address.
    pub joints: Vec<(&'static str, usize)>,
    /// Equality constraints the logic switches: role, equality id.
    pub switches: Vec<(&'static str, usize)>,
    /// The item's own actuators its logic drives: role, actuator id.
    pub actuators: Vec<(&'static str, usize)>,
    pub free: Vec<FreeJoint>,
    /// Loose parts: role, body id.
    pub parts: Vec<(&'static str, usize)>,
    /// The texture id of each display the model draws (in its `displays` order).
    pub displays: Vec<usize>,
}

/// What a body belongs to: a robot or a labware item (task indices).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Owner {
    Robot(usize),
    Labware(usize),
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
    /// The distractors the model was built with (a `distractors` perturbation's draw): inert
    /// items no step, check or state names.
    pub distractors: Vec<compiler::perturb::Distractor>,
    /// Each body's owner (`None`: the world, the bench, the room), for contact predicates.
    pub body_owner: Vec<Option<Owner>>,
    /// Each body's finger (the robot whose finger it is or hangs from) and loose part (the
    /// role of the part it is or hangs from), for `holds` predicates.
    pub body_finger: Vec<Option<usize>>,
    pub body_part: Vec<Option<&'static str>>,
    /// Items a hand holds from the start: the item, the robot's TCP body and the item's root
    /// pose in that body's frame (where reset puts it; the weld keeps it there).
    pub held: Vec<(usize, usize, Pose)>,
    /// What the simplified model is built from, and that model once a camera asked for it.
    task: Task,
    simplified: OnceLock<Result<Arc<MjModel>, SimplifiedError>>,
}

/// Why a scene's simplified render model could not be built; kept, so every camera that asks is
/// told the same.
#[derive(Clone, Debug, thiserror::Error)]
enum SimplifiedError {
    #[error(transparent)]
    Xml(Arc<SceneError>),
    #[error(transparent)]
    Mujoco(#[from] mujoco_rs::error::MjModelError),
    #[error("the simplified model's structure differs from the simulated one")]
    Structure,
}

impl Scene {
    /// The task the scene was built for.
    pub fn task(&self) -> &Task {
        &self.task
    }

    /// The total action length: every robot's action, concatenated in task order.
    pub fn action_len(&self) -> usize {
        self.robots.iter().map(|r| r.model.action_len()).sum()
    }
}

fn robot_model(task: &Task, index: usize) -> Result<&'static RobotModel, SceneError> {
    let r = &task.robots[index];
    robots::model(&r.model).ok_or_else(|| SceneError::UnknownRobot(r.name.clone(), r.model.clone()))
}

/// The scene MJCF for a task with the given labware placements.
/// The lab room around the bench: a vinyl floor, four walls with a skirting, a ceiling light
/// panel (visual only: the walls collide with nothing), so that cameras see a room, not a void.
/// The bench stands at the origin; the fixed camera looks from -y towards the +y wall.
const ROOM: &str = r#"    <light name="ceiling" pos="0 0 3" dir="0 0 -1" directional="true" castshadow="false" diffuse="0.4 0.4 0.4"/>
    <geom name="floor" type="plane" size="3 3 0.1" rgba="0.48 0.51 0.54 1"/>
    <geom name="room/wall_back" type="box" size="3 0.05 1.5" pos="0 2.2 1.5" rgba="0.84 0.85 0.82 1" contype="0" conaffinity="0"/>
    <geom name="room/wall_front" type="box" size="3 0.05 1.5" pos="0 -2.6 1.5" rgba="0.84 0.85 0.82 1" contype="0" conaffinity="0"/>
    <geom name="room/wall_left" type="box" size="0.05 2.4 1.5" pos="-2.4 -0.2 1.5" rgba="0.80 0.82 0.80 1" contype="0" conaffinity="0"/>
    <geom name="room/wall_right" type="box" size="0.05 2.4 1.5" pos="2.4 -0.2 1.5" rgba="0.80 0.82 0.80 1" contype="0" conaffinity="0"/>
    <geom name="room/skirting" type="box" size="2.35 0.02 0.05" pos="0 2.13 0.05" rgba="0.35 0.37 0.40 1" contype="0" conaffinity="0"/>
    <geom name="room/cabinet" type="box" size="0.9 0.3 0.45" pos="-1.2 1.85 0.45" rgba="0.70 0.72 0.74 1" contype="0" conaffinity="0"/>
    <geom name="room/shelf" type="box" size="0.9 0.15 0.015" pos="-1.2 2.0 1.55" rgba="0.62 0.55 0.45 1" contype="0" conaffinity="0"/>
    <geom name="room/ceiling_panel" type="box" size="0.6 0.3 0.01" pos="0 -0.4 2.95" rgba="1 1 0.97 1" contype="0" conaffinity="0"/>
"#;

use compiler::bench::{BENCH_HALF, BENCH_TOP};
/// A robot base this far above what it stands over gets a pedestal (m).
const PEDESTAL_FROM: f64 = 0.01;
const PEDESTAL_RADIUS: f64 = 0.09;

/// A riser under a robot whose base stands above the bench (or, off the bench, above the floor):
/// a grey column from the surface to the base, so that a raised arm stands on something that
/// is seen and collides, as a lab mounts an arm on a riser. Empty for a base on the surface.
fn pedestal(robot: &str, base: &Pose) -> String {
    let [x, y, z] = [base.translation.x, base.translation.y, base.translation.z];
    let on_bench = x.abs() <= BENCH_HALF[0] && y.abs() <= BENCH_HALF[1];
    let surface = if on_bench { BENCH_TOP } else { 0.0 };
    let height = z - surface;
    if height < PEDESTAL_FROM {
        return String::new();
    }
    format!(
        "<geom name=\"{robot}/pedestal\" type=\"cylinder\" size=\"{PEDESTAL_RADIUS} {h}\" pos=\"{x} {y} {c}\" rgba=\"0.42 0.44 0.47 1\"/>\n",
        h = height / 2.0,
        c = surface + height / 2.0,
    )
}

/// The name prefix of distractor items in the scene (`perturb/distractor1`, ...).
pub(crate) const DISTRACTOR: &str = "perturb/distractor";

/// The distractors an instance's perturbation drew (none without one).
fn distractors_of(instance: &SceneInstance) -> Vec<compiler::perturb::Distractor> {
    instance
        .perturbation
        .as_ref()
        .map(|p| p.distractors.clone())
        .unwrap_or_default()
}

/// The lights a task's light perturbation may turn on beyond the ceiling's, off as built (none
/// for a task without one, whose scene stays as it was).
fn spare_lights(task: &Task) -> String {
    let most = task
        .perturb
        .as_ref()
        .and_then(|p| p.light.as_ref())
        .map_or(1, |l| l.lights[1]);
    spare_light_mjcf(most.saturating_sub(1))
}

/// The name prefix of the lights a light perturbation may turn on (off in the scene as built;
/// `crate::perturb` turns them on).
pub(crate) const SPARE_LIGHT: &str = "perturb/light";

/// The MJCF of `n` spare lights around the room, off until a light perturbation turns them on.
fn spare_light_mjcf(n: u32) -> String {
    const PLACES: [[f64; 3]; 3] = [[-1.6, -1.4, 2.4], [1.6, -1.2, 2.2], [0.0, 1.6, 2.6]];
    PLACES
        .iter()
        .take(n as usize)
        .enumerate()
        .map(|(k, p)| {
            // Each looks at the bench's middle.
            let d = [-p[0], -p[1], 0.9 - p[2]];
            format!(
                "    <light name=\"{SPARE_LIGHT}{}\" pos=\"{} {} {}\" dir=\"{} {} {}\" directional=\"false\" castshadow=\"false\" diffuse=\"0.3 0.3 0.3\" active=\"false\"/>\n",
                k + 1,
                p[0],
                p[1],
                p[2],
                d[0],
                d[1],
                d[2]
            )
        })
        .collect()
}

/// The scene's MJCF; `detail` picks the robots' visual meshes (nothing else differs).
pub(crate) fn scene_xml(
    task: &Task,
    placements: &[Pose],
    distractors: &[compiler::perturb::Distractor],
    detail: Detail,
) -> Result<String, SceneError> {
    let mut world = String::new();
    let mut assets = String::new();
    for cam in &task.cameras {
        if let CameraMount::Fixed {
            pos,
            xyaxes,
            fovy_deg,
        } = &cam.mount
        {
            let a = xyaxes;
            world += &format!(
                "<camera name=\"{}\" pos=\"{} {} {}\" xyaxes=\"{} {} {} {} {} {}\" fovy=\"{fovy_deg}\"/>\n",
                cam.name, pos[0], pos[1], pos[2], a[0], a[1], a[2], a[3], a[4], a[5]
            );
        }
    }
    let mut prepared: Vec<&str> = Vec::new();
    for (i, r) in task.robots.iter().enumerate() {
        let model = robot_model(task, i)?;
        if !prepared.contains(&model.name) {
            let file = (model.prepare)(&deps::deps_dir(), detail)?;
            assets += &format!(
                "<model name=\"{}\" file=\"{}\"/>\n",
                model.name,
                file.display()
            );
            prepared.push(model.name);
        }
        world += &pedestal(&r.name, &r.base);
        let mount = r.base * labware::frame::axis_angle([0.0, 0.0, 1.0], model.mount_yaw);
        world += &format!(
            "<body name=\"{n}/mount\" {}>\n  <attach model=\"{}\" body=\"{}\" prefix=\"{n}/\"/>\n</body>\n",
            pose_attrs(&mount),
            model.name,
            model.root_body,
            n = r.name
        );
    }
    let mut labware = Fragment::default();
    labware.append(held_items(task)?);
    let mut plugins: Vec<(&'static str, String)> = Vec::new();
    for (l, placement) in task.labware.iter().zip(placements) {
        let model = l
            .params
            .instrument()
            .ok_or_else(|| SceneError::Unmodelled(l.name.clone(), l.kind.clone()))?;
        labware.append(model.fragment(&l.name, placement));
        plugins.extend(
            model
                .mechanisms(&l.name)
                .iter()
                .map(Mechanism::plugin_instance),
        );
    }
    // No more than a perturbation may draw, whatever an instance says.
    let most = compiler::perturb::MAX_DISTRACTORS as usize;
    for (k, d) in distractors.iter().take(most).enumerate() {
        let name = format!("{DISTRACTOR}{}", k + 1);
        let model = labware::Model::for_kind(&d.kind)
            .ok_or_else(|| SceneError::Unmodelled(name.clone(), d.kind.clone()))?;
        let instrument = model
            .instrument()
            .ok_or_else(|| SceneError::Unmodelled(name.clone(), d.kind.clone()))?;
        labware.append(instrument.fragment(&name, &d.pose()));
        plugins.extend(
            instrument
                .mechanisms(&name)
                .iter()
                .map(Mechanism::plugin_instance),
        );
    }
    let mut extension = String::new();
    for plugin in ["autobio.detent", "autobio.thread"] {
        let instances: String = plugins
            .iter()
            .filter(|(p, _)| *p == plugin)
            .map(|(_, i)| i.as_str())
            .collect();
        if !instances.is_empty() {
            extension += &format!("<plugin plugin=\"{plugin}\">{instances}</plugin>\n");
        }
    }
    Ok(format!(
        r#"<mujoco model="autobio:{id}">
  <compiler angle="radian" autolimits="true"/>
{size}  <option timestep="{dt}" integrator="implicitfast" cone="elliptic" impratio="10" noslip_iterations="2" sdf_iterations="3" sdf_initpoints="8">
    <flag multiccd="enable" autoreset="disable"/>
  </option>
  <visual>
    <global offwidth="640" offheight="480"/>
    <quality shadowsize="0" offsamples="0"/>
    <headlight ambient="0.45 0.45 0.45" diffuse="0.5 0.5 0.5" specular="0.1 0.1 0.1"/>
  </visual>
  <extension>
{extension}  </extension>
  <asset>
{assets}{labware_assets}  </asset>
  <worldbody>
{room}    <body name="table">
      <geom name="table/top" type="box" size="{bx} {by} {bz}" pos="0 0 {bz}" rgba="0.72 0.66 0.56 1"/>
    </body>
{world}{labware_world}  </worldbody>
  <equality>
{equality}  </equality>
  <contact>
{contact}  </contact>
{actuator}</mujoco>
"#,
        id = task.id,
        room = ROOM.to_string() + &spare_lights(task),
        bx = BENCH_HALF[0],
        by = BENCH_HALF[1],
        bz = BENCH_TOP / 2.0,
        dt = task.physics.timestep_s,
        labware_assets = labware.asset,
        labware_world = labware.worldbody,
        equality = labware.equality,
        contact = labware.contact,
        // Only a scene whose items ask for more arena than the default says so: the others stay
        // as they were.
        size = if labware.arena_mb > 0 {
            format!("  <size memory=\"{}M\"/>\n", labware.arena_mb)
        } else {
            String::new()
        },
        // Only items with their own motors add the section: other scenes stay as they were.
        actuator = if labware.actuator.is_empty() {
            String::new()
        } else {
            format!("  <actuator>\n{}  </actuator>\n", labware.actuator)
        },
    ))
}

/// Items a hand holds from the start (`held_by`): a weld from the robot's TCP body to the item's
/// root at the pose that puts the item's `grasp` on the TCP, and no contact between the item's
/// root and the hand's palm bodies (the fingers around it; a thumb that works a part on the item,
/// a plunger, still touches that part).
fn held_items(task: &Task) -> Result<Fragment, SceneError> {
    let mut out = Fragment::default();
    for l in &task.labware {
        let Some(robot) = &l.held_by else { continue };
        let r = task
            .robot_index(robot)
            .ok_or_else(|| SceneError::MissingName("robot", robot.clone()))?;
        let model = robot_model(task, r)?;
        let item = l
            .params
            .instrument()
            .ok_or_else(|| SceneError::Unmodelled(l.name.clone(), l.kind.clone()))?;
        let root = item.root_body(&l.name);
        let relpose = held_pose(task, r, l)?;
        let p = labware::frame::position(&relpose);
        let q = labware::frame::wxyz(&relpose.rotation);
        out.equality += &format!(
            "<weld name=\"{}/held\" body1=\"{robot}/{}\" body2=\"{root}\" relpose=\"{} {} {} {} {} {} {}\" solref=\"0.004 1\"/>\n",
            l.name, model.tcp_body, p[0], p[1], p[2], q[0], q[1], q[2], q[3]
        );
        let mut bodies = vec![model.tcp_body];
        bodies.extend(model.hand_bodies.iter().filter(|b| **b != model.tcp_body));
        for b in bodies {
            for held in item.held_bodies(&l.name) {
                out.contact += &format!("<exclude body1=\"{robot}/{b}\" body2=\"{held}\"/>\n");
            }
        }
    }
    Ok(out)
}

/// Where item `l`, held from the start by robot `r`, sits in the frame of the robot's TCP body:
/// the item's `grasp` on the TCP site.
pub(crate) fn held_pose(
    task: &Task,
    r: usize,
    l: &compiler::LabwareSpec,
) -> Result<Pose, SceneError> {
    let model = robot_model(task, r)?;
    let tcp = tcp_in_body(model)?;
    let item = l
        .params
        .instrument()
        .ok_or_else(|| SceneError::Unmodelled(l.name.clone(), l.kind.clone()))?;
    let at_origin = LabwareState {
        name: l.name.clone(),
        pose: Pose::identity(),
        joints: Default::default(),
        parts: Default::default(),
        logic: Default::default(),
        touched_by: Vec::new(),
        finger_contacts: Vec::new(),
    };
    let grasp = item
        .affordance("grasp", &at_origin)
        .ok_or_else(|| SceneError::MissingName("affordance", format!("{}.grasp", l.name)))?;
    Ok(tcp * grasp.pose.inverse())
}

/// The TCP site's pose in its body's frame, from the robot's prepared file compiled alone (once
/// per robot model).
fn tcp_in_body(model: &'static RobotModel) -> Result<Pose, SceneError> {
    static CACHE: OnceLock<std::sync::Mutex<BTreeMap<&'static str, Pose>>> = OnceLock::new();
    let cache = CACHE.get_or_init(Default::default);
    if let Some(p) = cache
        .lock()
        .unwrap_or_else(|e| e.into_inner())
        .get(model.name)
    {
        return Ok(*p);
    }
    let file = (model.prepare)(&deps::deps_dir(), Detail::Full)?;
    let m = MjModel::from_xml(&file).map_err(|e| SceneError::Compile(e.to_string()))?;
    let site = id_of(&m, MjtObjBase::mjOBJ_SITE, "site", model.tcp_site)?;
    let body = id_of(&m, MjtObjBase::mjOBJ_BODY, "body", model.tcp_body)?;
    if m.site_bodyid()[site] as usize != body {
        return Err(SceneError::MissingName(
            "TCP site on the body",
            model.tcp_body.to_string(),
        ));
    }
    let pose = labware::frame::pose(
        m.site_pos()[site],
        labware::frame::from_wxyz(m.site_quat()[site]),
    );
    cache
        .lock()
        .unwrap_or_else(|e| e.into_inner())
        .insert(model.name, pose);
    Ok(pose)
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

fn joint_id(m: &MjModel, name: &str) -> Result<usize, SceneError> {
    id_of(m, MjtObjBase::mjOBJ_JOINT, "joint", name)
}

fn robot_ids(m: &MjModel, name: &str, model: &'static RobotModel) -> Result<RobotIds, SceneError> {
    let full = |n: &str| format!("{name}/{n}");
    let joints = model
        .arm_joints
        .iter()
        .map(|j| joint_id(m, &full(j)))
        .collect::<Result<Vec<_>, _>>()?;
    let actuators = model
        .arm_actuators
        .iter()
        .map(|a| id_of(m, MjtObjBase::mjOBJ_ACTUATOR, "actuator", &full(a)))
        .collect::<Result<Vec<_>, _>>()?;
    let driver = joint_id(m, &full(model.gripper.driver_joint))?;
    Ok(RobotIds {
        name: name.to_string(),
        model,
        qpos: joints.iter().map(|&j| joint_qposadr(m, j)).collect(),
        dof: joints.iter().map(|&j| joint_dofadr(m, j)).collect(),
        joints,
        actuators,
        gripper_actuator: id_of(
            m,
            MjtObjBase::mjOBJ_ACTUATOR,
            "actuator",
            &full(model.gripper.actuator),
        )?,
        gripper_qpos: joint_qposadr(m, driver),
        tcp_site: id_of(m, MjtObjBase::mjOBJ_SITE, "site", &full(model.tcp_site))?,
    })
}

fn labware_ids(m: &MjModel, l: &compiler::LabwareSpec) -> Result<LabwareIds, SceneError> {
    let model = l
        .params
        .instrument()
        .ok_or_else(|| SceneError::Unmodelled(l.name.clone(), l.kind.clone()))?;
    let name = &l.name;
    let joints = model
        .joints(name)
        .into_iter()
        .map(|(role, j)| Ok((role, joint_qposadr(m, joint_id(m, &j)?))))
        .collect::<Result<Vec<_>, SceneError>>()?;
    let switches = model
        .switches(name)
        .into_iter()
        .map(|(role, e)| Ok((role, id_of(m, MjtObjBase::mjOBJ_EQUALITY, "equality", &e)?)))
        .collect::<Result<Vec<_>, SceneError>>()?;
    let actuators = model
        .actuators(name)
        .into_iter()
        .map(|(role, a)| Ok((role, id_of(m, MjtObjBase::mjOBJ_ACTUATOR, "actuator", &a)?)))
        .collect::<Result<Vec<_>, SceneError>>()?;
    let free = model
        .place(name, &Pose::identity())
        .into_iter()
        .map(|(j, _)| {
            let id = joint_id(m, &j)?;
            Ok(FreeJoint {
                name: j,
                body: m.jnt_bodyid()[id] as usize,
                qpos: joint_qposadr(m, id),
                dof: joint_dofadr(m, id),
            })
        })
        .collect::<Result<Vec<_>, SceneError>>()?;
    let parts = model
        .part_bodies(name)
        .into_iter()
        .map(|(role, b)| Ok((role, id_of(m, MjtObjBase::mjOBJ_BODY, "body", &b)?)))
        .collect::<Result<Vec<_>, SceneError>>()?;
    let displays = model
        .panel()
        .map(|p| p.displays(name))
        .unwrap_or_default()
        .iter()
        .map(|d| id_of(m, MjtObjBase::mjOBJ_TEXTURE, "texture", &d.texture))
        .collect::<Result<Vec<_>, SceneError>>()?;
    Ok(LabwareIds {
        root_body: id_of(m, MjtObjBase::mjOBJ_BODY, "body", &model.root_body(name))?,
        displays,
        joints,
        switches,
        actuators,
        free,
        parts,
    })
}

impl Scene {
    /// Builds the model for one scene instance of a task.
    /// The scene in `slot` when it fits `instance` (the same labware placements: a scene depends
    /// on nothing else), or a new one built into it. Runs of many seeds keep one slot per thread.
    pub fn reuse_or_build(
        slot: &mut Option<std::sync::Arc<Scene>>,
        task: &Task,
        instance: &SceneInstance,
    ) -> Result<std::sync::Arc<Scene>, SceneError> {
        // Every instance an episode starts from resolves its quantities: the episode's start
        // (`Episode::reset`) relies on it.
        compiler::quantities::Quantities::resolve(task, &instance.params)?;
        match slot {
            Some(s)
                if s.placements == instance.labware_placement
                    && s.distractors == distractors_of(instance) =>
            {
                Ok(s.clone())
            }
            _ => {
                let built = std::sync::Arc::new(Scene::build(task, instance)?);
                *slot = Some(built.clone());
                Ok(built)
            }
        }
    }

    pub fn build(task: &Task, instance: &SceneInstance) -> Result<Scene, SceneError> {
        // Refused before anything is compiled: a task with an item that has no model, that
        // cannot start as declared, or that could never be won is not built.
        check_starts(task, instance)?;
        check_measurable(task)?;
        compiler::quantities::Quantities::resolve(task, &instance.params)?;
        let placements = instance.labware_placement.clone();
        let distractors = distractors_of(instance);
        physics::register().map_err(|e| SceneError::Compile(e.to_string()))?;
        let xml = scene_xml(task, &placements, &distractors, Detail::Full)?;
        let model =
            MjModel::from_xml_string(&xml).map_err(|e| SceneError::Compile(e.to_string()))?;
        let errors = physics::instance_errors(model.ffi(), MjData::new(&model).ffi());
        if !errors.is_empty() {
            return Err(SceneError::Compile(errors.join("; ")));
        }
        let m = &model;
        let robots = (0..task.robots.len())
            .map(|i| robot_ids(m, &task.robots[i].name, robot_model(task, i)?))
            .collect::<Result<Vec<_>, _>>()?;
        let labware = task
            .labware
            .iter()
            .map(|l| labware_ids(m, l))
            .collect::<Result<Vec<_>, _>>()?;
        let mut cameras = Vec::new();
        for c in &task.cameras {
            let name = match &c.mount {
                CameraMount::Fixed { .. } => c.name.clone(),
                CameraMount::Wrist { robot } => {
                    let r = task
                        .robot_index(robot)
                        .ok_or_else(|| SceneError::MissingName("robot", robot.clone()))?;
                    format!("{robot}/{}", robot_model(task, r)?.wrist_camera)
                }
            };
            cameras.push(id_of(m, MjtObjBase::mjOBJ_CAMERA, "camera", &name)?);
        }
        let body_owner = body_owners(m, &robots, &labware)?;
        let mut fingers = Vec::new();
        for (r, ids) in robots.iter().enumerate() {
            for finger in ids.model.fingers {
                let body = format!("{}/{finger}", ids.name);
                fingers.push((id_of(m, MjtObjBase::mjOBJ_BODY, "body", &body)?, r));
            }
        }
        let body_finger = below(m, &fingers);
        let parts: Vec<(usize, &'static str)> = labware
            .iter()
            .flat_map(|ids| ids.parts.iter().map(|(role, b)| (*b, *role)))
            .collect();
        let body_part = below(m, &parts);
        let mut held = Vec::new();
        for (i, l) in task.labware.iter().enumerate() {
            let Some(robot) = &l.held_by else { continue };
            let r = task
                .robot_index(robot)
                .ok_or_else(|| SceneError::MissingName("robot", robot.clone()))?;
            let body = format!("{robot}/{}", robot_model(task, r)?.tcp_body);
            let body = id_of(m, MjtObjBase::mjOBJ_BODY, "body", &body)?;
            held.push((i, body, held_pose(task, r, l)?));
        }
        Ok(Scene {
            held,
            model: Arc::new(model),
            robots,
            labware,
            cameras,
            xml,
            placements,
            distractors,
            body_owner,
            body_finger,
            body_part,
            task: task.clone(),
            simplified: OnceLock::new(),
        })
    }

    /// The model cameras render with at `detail`: the simulated model itself, or the same scene
    /// with the robots' simplified visual meshes (compiled once, on first use). Both have the same
    /// bodies, joints and geoms, so a renderer copies the simulated `qpos` into its own data; the
    /// simulation never runs on the simplified model.
    pub fn render_model(&self, detail: Detail) -> Result<Arc<MjModel>, SceneError> {
        if detail == Detail::Full {
            return Ok(self.model.clone());
        }
        self.simplified
            .get_or_init(|| {
                let xml = scene_xml(
                    &self.task,
                    &self.placements,
                    &self.distractors,
                    Detail::Simplified,
                )
                .map_err(|e| SimplifiedError::Xml(Arc::new(e)))?;
                let m = MjModel::from_xml_string(&xml)?;
                let same = |a: &MjModel, b: &MjModel| {
                    let (a, b) = (a.ffi(), b.ffi());
                    (a.nq, a.nbody, a.ngeom, a.ncam, a.nmocap)
                        == (b.nq, b.nbody, b.ngeom, b.ncam, b.nmocap)
                };
                if !same(&m, &self.model) {
                    return Err(SimplifiedError::Structure);
                }
                Ok(Arc::new(m))
            })
            .clone()
            .map_err(|e| SceneError::Compile(e.to_string()))
    }
}

/// Each body's owner: the robot or item whose root body (or loose part) it hangs from.
fn body_owners(
    m: &MjModel,
    robots: &[RobotIds],
    labware: &[LabwareIds],
) -> Result<Vec<Option<Owner>>, SceneError> {
    let mut roots: Vec<(usize, Owner)> = Vec::new();
    for (r, ids) in robots.iter().enumerate() {
        let root = format!("{}/{}", ids.name, ids.model.root_body);
        roots.push((
            id_of(m, MjtObjBase::mjOBJ_BODY, "body", &root)?,
            Owner::Robot(r),
        ));
    }
    for (i, ids) in labware.iter().enumerate() {
        roots.push((ids.root_body, Owner::Labware(i)));
        roots.extend(ids.parts.iter().map(|(_, b)| (*b, Owner::Labware(i))));
    }
    Ok(below(m, &roots))
}

/// For each body, the value of the nearest of `roots` it is or hangs from (`None`: none).
fn below<T: Copy>(m: &MjModel, roots: &[(usize, T)]) -> Vec<Option<T>> {
    let parent = m.body_parentid();
    (0..parent.len())
        .map(|b| {
            let mut at = b;
            loop {
                if let Some((_, v)) = roots.iter().find(|(root, _)| *root == at) {
                    return Some(*v);
                }
                if at == 0 {
                    return None;
                }
                at = parent[at] as usize;
            }
        })
        .collect()
}

/// Every success check can be measured: a task whose check the judge cannot measure could never
/// be won, so it is refused instead of run.
fn check_measurable(task: &Task) -> Result<(), SceneError> {
    use compiler::predicates::Check;
    for p in task.stages.iter().flat_map(|s| &s.success) {
        let why = match &p.check {
            Check::Volume { container, .. } => {
                let holds = task
                    .labware
                    .iter()
                    .find(|l| &l.name == container)
                    .and_then(|l| l.params.instrument())
                    .is_some_and(|m| m.liquid().is_some_and(|l| l.interior().is_some()));
                if holds {
                    continue;
                }
                "the container's model holds no liquid"
            }
            Check::Panel {
                instrument, param, ..
            } => {
                let shows = task
                    .labware
                    .iter()
                    .find(|l| &l.name == instrument)
                    .and_then(|l| l.params.instrument())
                    .is_some_and(|m| {
                        let probe = labware::LabwareState::probe(instrument);
                        m.panel()
                            .is_some_and(|p| p.panel_value(param, &probe).is_some())
                    });
                if shows {
                    continue;
                }
                "the instrument's model has no such panel value"
            }
            _ => continue,
        };
        return Err(SceneError::Unmeasurable(p.text.clone(), why));
    }
    Ok(())
}

/// Every item can start as declared, and every `at` names a slot a holder model can seat.
fn check_starts(task: &Task, instance: &SceneInstance) -> Result<(), SceneError> {
    for (i, l) in task.labware.iter().enumerate() {
        let model = l
            .params
            .instrument()
            .ok_or_else(|| SceneError::Unmodelled(l.name.clone(), l.kind.clone()))?;
        if let Some(why) = model.unsupported_start(&l.initial) {
            return Err(SceneError::Unsupported(l.name.clone(), why));
        }
        if l.held_by.is_none() && l.at.is_some() && start_seat(task, instance, i).is_none() {
            let at = l.at.clone().unwrap_or_default();
            let at = compiler::params::render(&at, &instance.params).unwrap_or(at);
            return Err(SceneError::NoSlot(l.name.clone(), at));
        }
    }
    Ok(())
}

pub(crate) fn joint_qposadr(m: &MjModel, joint: usize) -> usize {
    m.jnt_qposadr()[joint] as usize
}

pub(crate) fn joint_dofadr(m: &MjModel, joint: usize) -> usize {
    m.jnt_dofadr()[joint] as usize
}

/// The seat of item `i`'s `at` slot, on the holder as placed in this instance.
pub(crate) fn start_seat(task: &Task, instance: &SceneInstance, i: usize) -> Option<Pose> {
    let at = task.labware[i].at.as_ref()?;
    let at = render(at, &instance.params).ok()?;
    let (holder, slot) = at.split_once('.')?;
    let h = task.labware_index(holder)?;
    // The holder's joints as reset puts them: its declared state, plus its drawn offsets (a
    // rotor's turn).
    let model = task.labware[h].params.instrument()?;
    let mut joints: BTreeMap<String, f64> = model
        .reset(&task.labware[h].initial)
        .joints
        .into_iter()
        .map(|(role, v)| (role.to_string(), v))
        .collect();
    for (role, offset) in instance.labware_joints.get(holder).into_iter().flatten() {
        *joints.entry(role.clone()).or_insert(0.0) += offset;
    }
    let holder_state = LabwareState {
        name: holder.to_string(),
        pose: instance.labware_placement[h],
        joints,
        parts: BTreeMap::new(),
        logic: Logic::new(),
        touched_by: Vec::new(),
        finger_contacts: Vec::new(),
    };
    model.slot_seat(slot, &holder_state)
}
