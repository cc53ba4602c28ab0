//! The scripted expert's vocabulary: what a lab primitive's motion expansion says, as data. Motions
//! aim at affordances of labware items and at joint goals by role (`("lid", "closed")`), never at
//! an instrument's fields; the `primitives` crate resolves them against live state into tool poses
//! and joint trajectories for the robot the step names. Gripper values and settle times come from
//! the robot model.

use serde::Serialize;
use std::collections::BTreeMap;

/// Joint goals by role and goal name, e.g. `[("lid", "closed"), ("lever", "raised")]`.
pub type Goals = Vec<(String, String)>;

/// Where a motion takes the tool.
#[derive(Clone, Debug, PartialEq, Serialize)]
#[serde(tag = "target", rename_all = "snake_case")]
pub enum Target {
    /// A labware item's affordance, with some of its joints at named goals (the rest live).
    Affordance {
        labware: String,
        name: String,
        goals: Goals,
    },
    /// The tool pose that stands the carried item's base on a slot's seat (`holder.slot`, a
    /// template over the task's parameters), lined up with the seat's axis (upright in a rack,
    /// leaning in a rotor) and `above` metres out along it.
    Seat { location: String, above: f64 },
    /// The tool pose that brings the held part's affordance `from` (where it is now) onto the
    /// item's affordance `to`, `above` metres back along `to`'s approach axis, keeping the hand's
    /// hold and the part's heading about `to`'s axis where `to` is round: a cap carried back
    /// onto its tube's mouth. Measured afresh at each motion, so a second reach corrects what
    /// the first left over.
    Carry {
        labware: String,
        from: String,
        to: String,
        above: f64,
    },
    /// The tool pose that brings the carried item's affordance `from` (where it is now in the
    /// hand) onto another item's affordance `to`, `above` metres back along `to`'s approach axis
    /// (negative: on past it), keeping the carried item's heading about `to`'s axis where `to`
    /// is round: a pipette's tip over a tube's mouth, or into its liquid.
    Bring {
        carried: String,
        from: String,
        labware: String,
        to: String,
        above: f64,
    },
    /// The button that moves an instrument's panel value `param` toward `value` (a quantity as
    /// the step renders it, e.g. `"1200 rpm"`), chosen from the live value.
    Button {
        labware: String,
        param: String,
        value: String,
    },
}

/// One motion of the scripted expert.
#[derive(Clone, Debug, PartialEq, Serialize)]
#[serde(tag = "motion", rename_all = "snake_case")]
pub enum Motion {
    /// A lifted arc from the current tool pose to `standoff` metres back along the target's
    /// approach axis.
    Approach { target: Target, standoff: f64 },
    /// A straight line to the target.
    Reach { target: Target },
    /// A straight line to the target and on along its approach axis by the robot's `enclose`
    /// depth: a round body gripped from the side deep in the fingers.
    Enclose { target: Target },
    /// To above the target, at the current height or a clearance above the target when that is
    /// higher: a straight line where that is clear, else planned around what it would hit.
    Transit { target: Target },
    /// Follow an affordance while the item's joints move from their live values to the goals.
    Follow {
        labware: String,
        affordance: String,
        goals: Goals,
        samples: usize,
    },
    /// Straight in along the target's approach axis until the closed fingertips are `depth`
    /// metres past it (a button pushed in).
    Press { target: Target, depth: f64 },
    /// Keep the tool still until the panel value `param` of `labware` shows `value` (a held
    /// button repeating), for at most `timeout_s`.
    HoldUntil {
        labware: String,
        param: String,
        value: String,
        timeout_s: f64,
    },
    /// Keep the tool still until `labware`'s run is done ([`labware::run`]), for at most
    /// `timeout_s`: the runtime may jump the clock meanwhile.
    AwaitRun { labware: String, timeout_s: f64 },
    /// Close the hand's actuated finger gradually (a thumb on a pipette's plunger) until every
    /// joint of the held `labware` named in `goals` has reached its goal (its value at the goal,
    /// from the side it started on), or `timeout_s` has passed; the finger then stays there.
    PressPart {
        labware: String,
        goals: Goals,
        timeout_s: f64,
    },
    /// Open the hand's actuated finger evenly over `seconds` (a thumb easing off a plunger, so
    /// that what the plunger draws flows in at a thumb's pace).
    EasePart { seconds: f64 },
    /// Back to the robot model's home pose, in joint space (routed around obstacles).
    Home,
    /// Keep the tool still for `seconds` (a key held down).
    Wait { seconds: f64 },
    /// Stop pushing: the arm's target becomes where its joints are. A hand that dragged a part
    /// to its stop lags the command it was given (the part held it back), and pressed on with
    /// the force of that lag; let go from there, its retreat would start where the hand is not,
    /// and the next free-space route would be checked from there too, while the real hand,
    /// still hooked on the part, dragged it along.
    Comply,
    /// Close the gripper and wait for it to settle.
    Grasp,
    /// Open the gripper and wait for it to settle.
    Release,
    /// Straight up (world z).
    Lift { height: f64 },
    /// Back off along the tool's approach axis.
    Retreat { distance: f64 },
    /// Turn the tool in place about its approach axis by `angle` (rad, right-handed about the
    /// approach direction: seen along it, positive is clockwise, so with the tool pointing down
    /// at a right-hand thread a positive turn tightens and a negative one loosens). With `thread`,
    /// the grasped part's affordance, the tool also advances along the axis by the thread's lead;
    /// with `stop` as well, it turns no further than brings the tool level with `stop` along
    /// its axis (a cap screwed on stops at its seat; turned on, the thread would tear it); a turn
    /// that moves the tool away from `stop` is not limited.
    Turn {
        angle: f64,
        thread: Option<Target>,
        stop: Option<Target>,
    },
    /// Turn the tool back in place by what the step's last `Turn` or `TurnDial` turned (an open
    /// hand returning to where it gripped, to grip again).
    TurnBack,
    /// Tilt the tool in place by `angle` rad through the tool centre, about the level axis across
    /// the robot's reach (square to the line from its base to the tool: the axis its shoulder,
    /// elbow and wrist bend about), turning it first about its approach axis, where needed, so
    /// that the fingers close across the tilt: a body pinched between two pads then turns with
    /// them instead of swinging about the pinch. A held tube turned upside down (π) and back
    /// (-π).
    Tilt { angle: f64 },
    /// Turn the gripped dial of `labware` that sets panel value `param` in place, from its live
    /// angle toward the notch nearest `value` (a quantity as the step renders it), in as few
    /// equal grips of at most `per_grip` rad as it takes: the tool turns about its approach axis, which lies along the dial's. Where
    /// more is left, the expert lets go, turns back, grips again and turns on, as a hand does;
    /// the step's grasp is taken half a grip back, so each grip sweeps the hand evenly either
    /// side of where it came in.
    TurnDial {
        labware: String,
        param: String,
        value: String,
        per_grip: f64,
    },
}

impl Motion {
    pub fn label(&self) -> &'static str {
        match self {
            Motion::Approach { .. } => "approach",
            Motion::Reach { .. } => "reach",
            Motion::Enclose { .. } => "enclose",
            Motion::Transit { .. } => "transit",
            Motion::Follow { .. } => "follow",
            Motion::Tilt { .. } => "tilt",
            Motion::Press { .. } => "press",
            Motion::HoldUntil { .. } => "hold until",
            Motion::AwaitRun { .. } => "await run",
            Motion::PressPart { .. } => "press part",
            Motion::EasePart { .. } => "ease part",
            Motion::Wait { .. } => "wait",
            Motion::Comply => "comply",
            Motion::Grasp => "grasp",
            Motion::Release => "release",
            Motion::Lift { .. } => "lift",
            Motion::Retreat { .. } => "retreat",
            Motion::Turn { .. } => "turn",
            Motion::TurnBack => "turn back",
            Motion::TurnDial { .. } => "turn dial",
            Motion::Home => "home",
        }
    }

    /// Whether the motion moves through free space between affordances (approach, transit, home):
    /// the expert keeps it clear of the scene, going around what its straight path would hit.
    /// The others end in contact, or leave it, on purpose.
    pub fn through_free_space(&self) -> bool {
        matches!(
            self,
            Motion::Approach { .. } | Motion::Transit { .. } | Motion::Home
        )
    }
}

/// A planned step with its arguments rendered for one episode, and the catalogue kind of the
/// item it acts `on` (what buttons and latches it has), when it names one.
pub struct MotionStep<'a> {
    pub args: &'a BTreeMap<String, String>,
    pub kind: Option<&'static labware::LabwareKind>,
    /// The liquid tool the step's robot carries, if any ([`crate::Task::liquid_tool`]).
    pub tool: Option<String>,
}

impl MotionStep<'_> {
    pub fn arg(&self, name: &str) -> String {
        self.args.get(name).cloned().unwrap_or_default()
    }
}

/// Goals from `(role, goal)` pairs.
pub fn goals(pairs: &[(&str, &str)]) -> Goals {
    pairs
        .iter()
        .map(|(r, g)| (r.to_string(), g.to_string()))
        .collect()
}
