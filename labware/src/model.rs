//! The instrument model: what one labware kind tells the rest of the system about itself. Each kind
//! with a simulation model implements [`Instrument`] in its own file; the runtime, the judge and the
//! expert reach instruments only through this trait (and [`crate::Model`], which maps a
//! kind to its model). Pure: numbers and MJCF text, no MuJoCo API.
//!
//! What a model owns: its MJCF (through [`crate::mjcf`]), the mechanisms it asks the runtime for
//! ([`Mechanism`]), its joints, equality switches and actuators by role, reset from declared part
//! states, the per-step logic hook (latches, buttons, a motor driven from its switch: [`Effects`]),
//! processes with other items ([`crate::process`]), panel values and the displays that show them (drawn into
//! textures the runtime uploads), what the judge scores ([`Instrument::measure`] of the one
//! [`Part`] a kind's states are about, [`Instrument::panel_value`]) and the readout people see
//! ([`Instrument::readout`]), and affordances as functions of live state. A lidded instrument
//! answers for its lid through [`Lidded`] ([`Instrument::lidded`]; `crate::lid` composes it).

use crate::frame::{Pose, serde_pose};
use crate::mjcf::Fragment;
use serde::{Deserialize, Serialize};
use std::collections::BTreeMap;

/// Instrument logic state that is not a joint (latch flags, panel values), by name.
pub type Logic = BTreeMap<String, f64>;

/// Joint values by role (rad or m).
pub type Joints = BTreeMap<String, f64>;

/// Sets one value of a name-keyed map, allocating the key only the first time (logic runs after
/// every physics step).
pub fn set(map: &mut BTreeMap<String, f64>, key: &str, value: f64) {
    match map.get_mut(key) {
        Some(v) => *v = value,
        None => {
            map.insert(key.to_string(), value);
        }
    }
}

/// Whether a flag in a name-keyed map is set (present and not 0).
pub fn flag(map: &BTreeMap<String, f64>, key: &str) -> bool {
    map.get(key).is_some_and(|v| *v != 0.0)
}

/// Sets a flag in a name-keyed map: 1 when `on`, else 0 ([`set`]).
pub fn set_flag(map: &mut BTreeMap<String, f64>, key: &str, on: bool) {
    set(map, key, f64::from(u8::from(on)));
}

/// Live state of one placed labware item: everything a predicate, an affordance or a replay needs.
/// The runtime fills it after every control step; recordings store it as `/labware/state`.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct LabwareState {
    pub name: String,
    /// World pose of the item's root body (where a movable item is now).
    #[serde(with = "serde_pose")]
    pub pose: Pose,
    pub joints: Joints,
    /// World poses of loose parts by role (a tube's cap).
    #[serde(default, with = "crate::frame::serde_pose_map")]
    pub parts: BTreeMap<String, Pose>,
    pub logic: Logic,
    /// The robots whose bodies touch this item's bodies (a MuJoCo contact at zero or negative
    /// distance), in task order; what a `<robot> touches <item>` predicate measures.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub touched_by: Vec<String>,
    /// The robots whose fingers touch this item, and where: what a `<robot> holds <item>`
    /// predicate measures. In task order, then the item's own body before its parts.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub finger_contacts: Vec<FingerContact>,
}

/// A robot's finger touching an item (a MuJoCo contact at zero or negative distance).
#[derive(Clone, Debug, PartialEq, Eq, PartialOrd, Ord, Serialize, Deserialize)]
pub struct FingerContact {
    pub robot: String,
    /// The loose part touched (a tube's cap); `None`: the item's own body.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub part: Option<String>,
}

impl LabwareState {
    /// An item's state with nothing measured yet (identity pose, no joints, parts or logic): what
    /// asks a model which values it can answer at all.
    pub fn probe(name: &str) -> LabwareState {
        LabwareState {
            name: name.to_string(),
            pose: Pose::identity(),
            joints: Joints::new(),
            parts: BTreeMap::new(),
            logic: Logic::new(),
            touched_by: Vec::new(),
            finger_contacts: Vec::new(),
        }
    }

    pub fn joint(&self, role: &str) -> f64 {
        self.joints.get(role).copied().unwrap_or(f64::NAN)
    }

    pub fn flag(&self, name: &str) -> bool {
        flag(&self.logic, name)
    }

    /// The same state with some joints set to other values (for affordances at planned angles).
    pub fn with_joints(&self, joints: &[(String, f64)]) -> LabwareState {
        let mut s = self.clone();
        for (role, v) in joints {
            s.joints.insert(role.clone(), *v);
        }
        s
    }
}

/// A lab mechanism a model asks the runtime for, defined once by the `physics` crate's own type;
/// the runtime writes it as the plugin instance [`Mechanism::plugin_instance`] gives.
#[derive(Clone, Debug, PartialEq)]
pub enum Mechanism {
    /// `autobio.detent`: evenly spaced rest positions over a joint's range.
    Detent {
        instance: String,
        joint: String,
        detent: physics::detent::Detent,
    },
    /// `autobio.thread`: one helical thread SDF (a bolt or a nut); the model's MJCF names the mesh
    /// and geom that use `instance` and the contact pair between bolt and nut.
    Thread {
        instance: String,
        thread: physics::thread::Thread,
    },
}

impl Mechanism {
    /// The plugin it is an instance of, and the MJCF `<instance>` element.
    pub fn plugin_instance(&self) -> (&'static str, String) {
        match self {
            Mechanism::Detent {
                instance,
                joint,
                detent,
            } => ("autobio.detent", detent.mjcf_instance(instance, joint)),
            Mechanism::Thread { instance, thread } => {
                ("autobio.thread", thread.mjcf_instance(instance))
            }
        }
    }
}

/// A predicate's measured value against its target, and whether it holds.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Measure {
    pub value: f64,
    pub target: f64,
    pub tolerance: f64,
    pub holds: bool,
}

impl Measure {
    /// `value` within `tolerance` of `target`.
    pub fn near(value: f64, target: f64, tolerance: f64) -> Measure {
        Measure {
            value,
            target,
            tolerance,
            holds: (value - target).abs() <= tolerance,
        }
    }
}

/// The part of an item whose states the judge measures (`lid is locked`, `cap is on`, `tip is
/// in`): each kind with a model has at most one (the catalogue's `parts`), named by
/// [`Instrument::part`].
pub trait Part {
    /// The measured value of `state` (tolerance: the predicate's, else the part's); `None` for
    /// a state the part does not have.
    fn state(&self, state: &str, tolerance: Option<f64>, s: &LabwareState) -> Option<Measure>;

    /// How far the part stands above its seat on the item, along the item's axis (m; negative:
    /// pushed below it); `None` where the part is not there to measure (a tube made open) or
    /// moves on a joint (a lid).
    fn rise(&self, _s: &LabwareState) -> Option<f64> {
        None
    }

    /// The part's frame when it lies apart from the item the right way up, relative to the point
    /// of the bench under it (what a protocol's `parts` pose names); identity for a part with
    /// its frame at its base.
    fn lying(&self) -> crate::frame::Pose {
        crate::frame::Pose::identity()
    }
}

/// How an affordance frame may be turned and still be the same grasp.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Symmetry {
    None,
    /// Turned half a turn about its z (approach) axis: a bar held with the fingers swapped.
    HalfTurn,
    /// Any turn about its z axis: a round cap grasped from above.
    Axial,
    /// Any turn about its y axis, which runs along the item: a round body gripped from the side,
    /// from whichever side the tool comes.
    AboutY,
    /// Any turn about this axis (in the frame's own coordinates), which runs along the item: a
    /// round body gripped from the side at a slant, from whichever side the tool comes, the
    /// approach keeping its angle to the item.
    About([f64; 3]),
}

/// A frame a robot tool can be brought to: z is the approach direction, x the fingers' closing
/// direction.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Affordance {
    pub pose: Pose,
    pub symmetry: Symmetry,
    /// A point the closed fingertips touch (a button pressed, a lid pushed), not a grasp: the TCP
    /// stands off it by the robot's finger reach, which only the robot model knows.
    pub touch: bool,
    /// How far the grasped part advances along the approach axis per radian it is turned about
    /// it (m/rad; right-handed about the approach): a screw cap's thread lead, pitch / 2π, so that
    /// a cap turned to loosen is followed as it rises. 0 for what does not turn on a thread.
    pub lead: f64,
}

/// A narrow opening ([`Instrument::opening`]): how far past its affordance, along the axis, a
/// carried tool may be brought, and how far from its aiming point over the mouth it may stop
/// before it goes in (m).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Opening {
    pub depth: f64,
    pub aim: f64,
}

/// A display an instrument draws: the MuJoCo texture (declared in the model's fragment, 8-bit RGB)
/// that [`Panel::draw_display`] fills.
#[derive(Clone, Debug, PartialEq)]
pub struct Display {
    pub texture: String,
    pub width: usize,
    pub height: usize,
    /// The logic values it shows: the runtime redraws it when one of them changes.
    pub shows: Vec<String>,
}

/// A process between items (liquid drawn into a tip), run after every physics step; the ones
/// there are live in [`crate::process`].
pub trait Process: std::fmt::Debug + Send {
    /// After `dt` seconds of physics: `poses` is every item's root pose and `logic` every item's
    /// logic state, both in task order; a process moves quantities by writing `logic`.
    fn step(&mut self, dt: f64, poses: &[Pose], logic: &mut [Logic]);
}

/// An item whose interior holds liquid a tip can reach (an open tube, not a capped one), as the
/// runtime finds it in the scene ([`Instrument::open_vessel`]).
#[derive(Clone, Debug)]
pub struct Vessel {
    /// Index in task order.
    pub item: usize,
    /// Its interior in its root frame.
    pub interior: physics::liquid::Container,
}

/// What an item's logic asks of the simulation after a step, by role: equality constraints on or
/// off, and commands for the item's own actuators.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Effects {
    pub switches: Vec<(&'static str, bool)>,
    pub drives: Vec<(&'static str, f64)>,
}

impl Effects {
    /// Turns the equality constraint `role` on or off.
    pub fn switch(&mut self, role: &'static str, on: bool) {
        self.switches.push((role, on));
    }

    /// Commands the item's actuator `role` (its control value: a velocity motor's speed).
    pub fn drive(&mut self, role: &'static str, value: f64) {
        self.drives.push((role, value));
    }

    pub fn clear(&mut self) {
        self.switches.clear();
        self.drives.clear();
    }
}

/// Joint values and logic state an item starts an episode with.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Reset {
    pub joints: Vec<(&'static str, f64)>,
    pub logic: Logic,
}

/// Everything the system knows about one labware kind's simulation. `name` is the item's name in
/// the protocol: every MuJoCo name a model generates starts with `name/`.
pub trait Instrument {
    /// The item's MJCF at `placement` (world frame). Movable items get a free joint.
    fn fragment(&self, name: &str, placement: &Pose) -> Fragment;

    /// The radius (m) of a circle about the item's origin that its footprint on the bench lies
    /// within: what keeps a distractor clear of it (`compiler::perturb`). Small items (a tube,
    /// a pipette) keep the default.
    fn footprint_radius(&self) -> f64 {
        0.05
    }

    /// Plugin instances the item needs.
    fn mechanisms(&self, _name: &str) -> Vec<Mechanism> {
        Vec::new()
    }

    /// The body whose world pose is [`LabwareState::pose`].
    fn root_body(&self, name: &str) -> String {
        format!("{name}/base")
    }

    /// Hinge and slide joints by role, with their MuJoCo names.
    fn joints(&self, _name: &str) -> Vec<(&'static str, String)> {
        Vec::new()
    }

    /// The free joints of a movable item and their poses when its root body is at `root`.
    fn place(&self, _name: &str, _root: &Pose) -> Vec<(String, Pose)> {
        Vec::new()
    }

    /// The bodies a hand that holds the item from the start (`held_by`) does not collide with:
    /// all but the parts the hand works (a pipette's plunger button, under the thumb).
    fn held_bodies(&self, name: &str) -> Vec<String> {
        vec![self.root_body(name)]
    }

    /// Loose parts (bodies on their own free joints) by role, whose world poses the runtime reports.
    fn part_bodies(&self, _name: &str) -> Vec<(&'static str, String)> {
        Vec::new()
    }

    /// Equality constraints the logic switches on and off, by role.
    fn switches(&self, _name: &str) -> Vec<(&'static str, String)> {
        Vec::new()
    }

    /// The item's own actuators (a mixer's motor), by role, with their MuJoCo names: the logic
    /// drives them ([`Effects::drive`]); robots never do.
    fn actuators(&self, _name: &str) -> Vec<(&'static str, String)> {
        Vec::new()
    }

    /// Makes the model for the declared part states where they change what is built (a tube
    /// whose cap starts off is built without one). The compiler calls it once per item, before
    /// [`Instrument::unsupported_start`].
    fn start_from(&mut self, _initial: &BTreeMap<String, String>) {}

    /// Why the model cannot start in the declared part states, if it cannot.
    fn unsupported_start(&self, _initial: &BTreeMap<String, String>) -> Option<String> {
        None
    }

    /// Joint values and logic for the declared initial part states.
    fn reset(&self, _initial: &BTreeMap<String, String>) -> Reset {
        Reset::default()
    }

    /// Instrument logic after each physics step of `dt` seconds: updates `logic` from the joints
    /// and says what the simulation must do in `effects`: each switch's wanted state, each of its
    /// actuators' command (the runtime empties and reuses it, so a step allocates nothing). Also
    /// called once right after reset, with `dt` 0.
    fn step(&self, _dt: f64, _joints: &Joints, _logic: &mut Logic, _effects: &mut Effects) {}

    /// The item's lid, for an instrument with one ([`crate::lid`]): by default its `lid is …`
    /// measures, its readout and its `lid` goals are the lid's.
    fn lidded(&self) -> Option<&dyn Lidded> {
        None
    }

    /// A named joint goal, e.g. `("lid", "closed")` -> the lid's closed angle.
    fn joint_goal(&self, role: &str, goal: &str) -> Option<f64> {
        self.lidded().filter(|_| role == LID)?.lid_goal(goal)
    }

    /// The part [`Instrument::measure`] measures, by its catalogue name (`cap`, `tip`...): a
    /// lidded instrument's lid unless it says otherwise; `None`: nothing to measure.
    fn part(&self) -> Option<(&'static str, &dyn Part)> {
        self.lidded().map(|l| (LID, l as &dyn Part))
    }

    /// The measured value of `part is state` (tolerance: the predicate's, else the model's): a
    /// state of [`Instrument::part`].
    fn measure(
        &self,
        part: &str,
        state: &str,
        tolerance: Option<f64>,
        s: &LabwareState,
    ) -> Option<Measure> {
        if part == crate::run::RUN && !self.programmes().is_empty() {
            let (now, wanted) = self.run().measure(state, &s.logic)?;
            return Some(Measure {
                value: now,
                target: wanted,
                tolerance: 0.0,
                holds: now == wanted,
            });
        }
        let (_, judged) = self.part().filter(|(name, _)| *name == part)?;
        judged.state(state, tolerance, s)
    }

    /// The current state of every part (for recordings and reports).
    fn readout(&self, s: &LabwareState) -> BTreeMap<String, String> {
        let mut out = self.lidded().map(|l| l.lid_readout(s)).unwrap_or_default();
        if !self.programmes().is_empty() {
            out.extend([self.run().readout(&s.logic)]);
        }
        out
    }

    /// The programmes the item runs ([`crate::run`]), in the protocol's order; empty: it runs
    /// none (and has no `run` part to measure).
    fn programmes(&self) -> &[crate::run::Programme] {
        &[]
    }

    /// The radius (m) at which a centrifuge's relative centrifugal force is given (its load's
    /// outermost point, as manuals state a rotor's × g), so a spin written in `× g` converts
    /// to rotor speed; `None` for anything that does not spin.
    fn rcf_radius_m(&self) -> Option<f64> {
        None
    }

    /// Gives a model that runs programmes the protocol's (the compiler, once per item); a model
    /// that runs none ignores them (the compiler refuses run steps on its kind first).
    fn set_programmes(&mut self, _programmes: Vec<crate::run::Programme>) {}

    /// The item's runs over its programmes.
    fn run(&self) -> crate::run::Run<'_> {
        crate::run::Run {
            programmes: self.programmes(),
        }
    }

    /// Seconds until the item's next event while only its timers run (a run's phase ending);
    /// `None` while nothing runs. The runtime jumps the clock no further than this.
    fn next_event(&self, logic: &Logic) -> Option<f64> {
        self.run().next_event(logic)
    }

    /// Advances the item's timers over `span` seconds in which the physics stood still (the
    /// runtime's clock jump): exactly what `span` of physics steps would have done to them.
    fn skip(&self, span: f64, logic: &mut Logic) {
        self.run().advance(logic, span);
    }

    /// A named affordance in the world frame, from live (or planned) state.
    fn affordance(&self, _name: &str, _s: &LabwareState) -> Option<Affordance> {
        None
    }

    /// A narrow opening a carried tool is brought into at affordance `affordance` (a shallow
    /// tube's mouth): how deep the tool may go and how closely it must be aimed. `None`: the
    /// affordance takes a tool as deep as a motion asks, aimed as a path ends.
    fn opening(&self, _affordance: &str) -> Option<Opening> {
        None
    }

    /// Where an item stands in one of this holder's slots: its base frame (z up), world frame.
    fn slot_seat(&self, _slot: &str, _s: &LabwareState) -> Option<Pose> {
        None
    }

    /// The item's panel, for an instrument with one: the values it shows, the buttons and dials
    /// that set them, and its screens.
    fn panel(&self) -> Option<&dyn Panel> {
        None
    }

    /// The item's liquid, for an item that holds it (a tube, a pipette's tip): its interior,
    /// how it is drawn and the processes it runs with the other vessels.
    fn liquid(&self) -> Option<&dyn Liquid> {
        None
    }
}

/// A lid's joint role, and the part its states are about.
pub const LID: &str = "lid";

/// What a lidded instrument tells the rest of the system about its lid ([`Instrument::lidded`];
/// every instrument composing a `crate::lid::Lid` is one): the angles the expert drives it to,
/// its readout, and, as the [`Part`] the judge measures, its states (open and closed, a latch's
/// `locked` and `unlocked` as the instrument's latch works).
pub trait Lidded: Part {
    /// The angle the expert drives the lid to for a named goal (`open`, `closed`).
    fn lid_goal(&self, goal: &str) -> Option<f64>;
    /// The lid's state for recordings and reports.
    fn lid_readout(&self, s: &LabwareState) -> BTreeMap<String, String>;
}

/// What an instrument with a panel answers ([`Instrument::panel`]): each method's default is
/// "not on this panel".
pub trait Panel {
    /// The value a panel shows (`speed`, `temperature`...), from live state.
    fn panel_value(&self, _param: &str, _s: &LabwareState) -> Option<f64> {
        None
    }

    /// The button that moves a panel value toward `target` (an affordance name).
    fn button_toward(&self, _param: &str, _target: f64, _s: &LabwareState) -> Option<String> {
        None
    }

    /// The dial that sets panel value `param` (a knob on a detent): its joint's role and the
    /// joint angle that sets the value nearest `target`. The dial's affordance has the role's name
    /// and its approach axis along the joint's axis, so that turning the tool right-handed about
    /// its approach turns the joint's angle up. `None` for a value set with buttons.
    fn dial_toward(&self, _param: &str, _target: f64) -> Option<(&'static str, f64)> {
        None
    }

    /// The displays the item draws, in the order [`Panel::draw_display`] numbers them.
    fn displays(&self, _name: &str) -> Vec<Display> {
        Vec::new()
    }

    /// Draws display `index` for the logic state into `rgb` (its texture's pixels, row-major, top
    /// row first). Pure: the same logic always draws the same pixels.
    fn draw_display(&self, _index: usize, _logic: &Logic, _rgb: &mut [u8]) {}
}

/// What an item that holds liquid answers ([`Instrument::liquid`]).
pub trait Liquid {
    /// Processes between this item (index `me` in task order) and others that the runtime runs
    /// after every physics step (a pipette's tip working among `vessels`, every item with an
    /// [`Instrument::interior`]), each written in the item's own model.
    fn processes(&self, _name: &str, _me: usize, _vessels: &[Vessel]) -> Vec<Box<dyn Process>> {
        Vec::new()
    }

    /// The mocap bodies that draw the surface of the liquid the item holds (see
    /// [`crate::liquid_view`]), declared in its fragment; empty: nothing to draw.
    fn liquid_bodies(&self, _name: &str) -> Vec<String> {
        Vec::new()
    }

    /// Whether a tip can reach the liquid in its interior: an open container (a capped tube's
    /// liquid is out of reach, and a drop over it lands on the cap). Only such items are the
    /// vessels a pipetting process works among.
    fn open_vessel(&self) -> bool {
        self.interior().is_some()
    }

    /// The space inside the item that holds liquid (a tube's bore, a pipette's tip), in its root
    /// frame; `None`: it holds none. Its volume is `volume_ul` in the logic.
    fn interior(&self) -> Option<physics::liquid::Container> {
        None
    }
}

/// How an item with root pose `item` stands against a slot seated at `seat`: its distance from
/// the seat in the seat's plane (m), its height along the seat's axis (m, signed) and its tilt
/// from the seat's axis (rad). A rack's seats are upright; a fixed-angle rotor's lean.
pub fn seat_offsets(seat: &Pose, item: &Pose) -> (f64, f64, f64) {
    let d = seat.rotation.inverse() * (item.translation.vector - seat.translation.vector);
    let planar = (d.x * d.x + d.y * d.y).sqrt();
    let axis = seat.rotation * nalgebra::Vector3::z();
    let up = item.rotation * nalgebra::Vector3::z();
    let tilted = up.dot(&axis).clamp(-1.0, 1.0).acos();
    (planar, d.z, tilted)
}

/// Whether an item with root pose `item` stands in a slot seated at `seat`: distance (value) from
/// the seat in the seat's plane within `xy`, height along the seat's axis within `z` and tilt from
/// the seat's axis within `tilt` (rad) ([`seat_offsets`]).
pub fn seated(seat: &Pose, item: &Pose, xy: f64, z: f64, tilt: f64) -> Measure {
    let (planar, height, tilted) = seat_offsets(seat, item);
    Measure {
        value: planar,
        target: 0.0,
        tolerance: xy,
        holds: planar <= xy && height.abs() <= z && tilted <= tilt,
    }
}
