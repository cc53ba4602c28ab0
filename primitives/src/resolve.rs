//! Motions to tool poses against live labware state. A lab step's motions ([`compiler::motion`])
//! name affordances, joint goals by role and slot seats; here they become world-frame tool poses,
//! read through each item's instrument model ([`labware::Instrument`]). Choices that must hold for
//! a whole step (which of an affordance's symmetric grasps to use, how a carried item sits in the
//! hand) are made once, at the step's start, in a [`StepFrame`]. A carry target (a held part's
//! affordance brought onto another's) is resolved from where the tool is, and a turn follows a
//! thread's lead up to its stop; a dial is turned from its live angle to a value's notch; a turn
//! back undoes the step's last turn; a tilt turns the tool over about the level axis across the
//! robot's reach (the frame knows the robot's base: [`StepFrame::with_base`]).

use compiler::motion::{Goals, Motion, Target};
use compiler::params::{Bindings, render};
use labware::frame::{axis_angle, interpolate, position, translated_local, translation};
use labware::{Affordance, Instrument, LabwareState, Pose, Rot, Symmetry};

#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum PlanError {
    #[error("no labware named `{0}`")]
    NoLabware(String),
    #[error("`{0}` has no simulation model")]
    Unmodelled(String),
    #[error("`{labware}` offers no affordance `{name}`")]
    NoAffordance { labware: String, name: String },
    #[error("`{labware}` has no goal `{goal}` for its joint `{role}`")]
    NoGoal {
        labware: String,
        role: String,
        goal: String,
    },
    #[error("`{0}` does not name a slot of a holder in this scene")]
    NoSlot(String),
    #[error("a slot is targeted, but the step carries nothing to seat")]
    NothingCarried,
    #[error(
        "a carry target is resolved from where the tool is, in a motion; it has no pose of its own"
    )]
    CarryFromNowhere,
    #[error("a turn back with no turn before it in the step to undo")]
    NoTurnToUndo,
    #[error("`{labware}` has no button that sets `{param}` toward `{value}`")]
    NoButton {
        labware: String,
        param: String,
        value: String,
    },
    #[error("`{labware}` has no dial that sets `{param}` to `{value}`")]
    NoDial {
        labware: String,
        param: String,
        value: String,
    },
    #[error("`{labware}`'s dial did not reach `{param}` = `{value}` in {grips} grips")]
    DialStuck {
        labware: String,
        param: String,
        value: String,
        grips: usize,
    },
}

/// The labware as the expert sees it at one moment: each item's model and live state, and the
/// episode's drawn parameters (slot locations are templates over them).
pub struct Lab<'a> {
    pub items: Vec<(&'a str, &'a dyn Instrument, &'a LabwareState)>,
    pub params: &'a Bindings,
}

impl<'a> Lab<'a> {
    /// The scene of `task` with live `states` (in task order).
    pub fn new(
        task: &'a compiler::Task,
        states: &'a [LabwareState],
        params: &'a Bindings,
    ) -> Lab<'a> {
        let items = task
            .labware
            .iter()
            .zip(states)
            .filter_map(|(spec, s)| Some((spec.name.as_str(), spec.params.instrument()?, s)))
            .collect();
        Lab { items, params }
    }

    /// The item's model and its live state.
    pub fn item(&self, name: &str) -> Result<(&'a dyn Instrument, &'a LabwareState), PlanError> {
        self.items
            .iter()
            .find(|(n, ..)| *n == name)
            .map(|(_, m, s)| (*m, *s))
            .ok_or_else(|| PlanError::NoLabware(name.to_string()))
    }

    /// The live state of an item with some joints set to named goals. A goal for a role the
    /// item has no joint for is skipped: the lid primitives also move the lever that only some
    /// lids have (a lidded instrument without one is moved by its lid alone).
    pub fn at_goals(&self, labware: &str, goals: &Goals) -> Result<LabwareState, PlanError> {
        let (model, state) = self.item(labware)?;
        let roles = model.joints(labware);
        let joints = goals
            .iter()
            .filter(|(role, _)| roles.iter().any(|(r, _)| r == role))
            .map(|(role, goal)| {
                let v = model
                    .joint_goal(role, goal)
                    .ok_or_else(|| PlanError::NoGoal {
                        labware: labware.into(),
                        role: role.clone(),
                        goal: goal.clone(),
                    })?;
                Ok((role.clone(), v))
            })
            .collect::<Result<Vec<_>, PlanError>>()?;
        Ok(state.with_joints(&joints))
    }

    fn affordance(
        &self,
        labware: &str,
        name: &str,
        s: &LabwareState,
    ) -> Result<Affordance, PlanError> {
        let (model, _) = self.item(labware)?;
        model
            .affordance(name, s)
            .ok_or_else(|| PlanError::NoAffordance {
                labware: labware.into(),
                name: name.into(),
            })
    }

    /// The seat of a slot location (`holder.slot`, a template over the drawn parameters).
    fn seat(&self, location: &str) -> Result<Pose, PlanError> {
        let text = render(location, self.params).unwrap_or_else(|_| location.to_string());
        let (holder, slot) = text
            .split_once('.')
            .ok_or_else(|| PlanError::NoSlot(text.clone()))?;
        let (model, state) = self.item(holder)?;
        model
            .slot_seat(slot, state)
            .ok_or_else(|| PlanError::NoSlot(text.clone()))
    }

    /// The affordance of the button that moves a panel value toward `value` from its live value.
    fn button(&self, labware: &str, param: &str, value: &str) -> Result<Affordance, PlanError> {
        let (model, state) = self.item(labware)?;
        let no_button = || PlanError::NoButton {
            labware: labware.into(),
            param: param.into(),
            value: value.into(),
        };
        let target =
            compiler::predicates::panel_quantity(value, self.params).ok_or_else(no_button)?;
        let name = model
            .panel()
            .and_then(|p| p.button_toward(param, target, state))
            .ok_or_else(no_button)?;
        self.affordance(labware, &name, state)
    }

    /// How far the dial that sets a panel value must turn from its live angle to the notch
    /// nearest `value` (rad, right-handed about the dial's affordance's approach axis).
    pub fn dial_turn(&self, labware: &str, param: &str, value: &str) -> Result<f64, PlanError> {
        let (model, state) = self.item(labware)?;
        let no_dial = || PlanError::NoDial {
            labware: labware.into(),
            param: param.into(),
            value: value.into(),
        };
        let target =
            compiler::predicates::panel_quantity(value, self.params).ok_or_else(no_dial)?;
        let (role, angle) = model
            .panel()
            .and_then(|p| p.dial_toward(param, target))
            .ok_or_else(no_dial)?;
        Ok(angle - state.joint(role))
    }

    /// The value a panel shows now, and the target `value` (a quantity) read in its unit.
    pub fn panel(&self, labware: &str, param: &str, value: &str) -> Option<(f64, f64)> {
        let (model, state) = self.item(labware).ok()?;
        let shown = model.panel()?.panel_value(param, state)?;
        Some((
            shown,
            compiler::predicates::panel_quantity(value, self.params)?,
        ))
    }

    /// Whether an item's run is done ([`labware::run`]).
    pub fn run_done(&self, labware: &str) -> bool {
        self.item(labware).is_ok_and(|(model, state)| {
            model
                .measure(labware::run::RUN, "done", None, state)
                .is_some_and(|m| m.holds)
        })
    }

    /// How many runs an item has started since the episode began (0 for an item that runs
    /// nothing).
    pub fn runs_started(&self, labware: &str) -> f64 {
        self.item(labware).map_or(0.0, |(_, state)| {
            state
                .logic
                .get(labware::run::STARTED)
                .copied()
                .unwrap_or(0.0)
        })
    }

    /// The live pose of an item's root body.
    pub fn pose_of(&self, labware: &str) -> Result<Pose, PlanError> {
        Ok(self.item(labware)?.1.pose)
    }
}

/// How far a seat's axis must lean from vertical (its sine) to count as leaning: a rack's
/// seats stand upright.
const LEANING_SEAT: f64 = 0.087;

/// For a seat whose axis leans (a fixed-angle rotor's slot), how far up (m) a metre out along
/// that axis goes; `None` for an upright seat.
fn leaning_rise(seat: &Pose) -> Option<f64> {
    let axis = seat.rotation * nalgebra::Vector3::z();
    (axis.x.hypot(axis.y) >= LEANING_SEAT && axis.z > 0.0).then_some(axis.z)
}

/// How far above its target a transit passes at least (m).
const TRANSIT_CLEARANCE: f64 = 0.06;

/// Choices a lab step makes once, at its start, so that all its motions agree.
#[derive(Clone, Debug, PartialEq)]
pub struct StepFrame {
    /// Turn about the approach axis applied to every affordance (the chosen symmetric grasp).
    turn: Rot,
    /// The carried item and its pose in the tool frame, when the step seats it somewhere.
    carried: Option<(String, Pose)>,
    /// How far the robot's closed fingertips reach past its TCP along the tool axis (m).
    finger_reach: f64,
    /// How far past a round body's axis the robot's side grip puts its TCP (m).
    enclose: f64,
    /// The step turns a part in the hand and grips it again (`Turn` motions): a reach to a round
    /// part then grips it at the turn nearest the tool as it is, not at the step's first choice,
    /// which the part has turned away from.
    regrasp_nearest: bool,
    /// Whether the first affordance allows the grasp turned half a turn (see [`Self::other_grasp`]).
    half_turn: bool,
    /// The axis (in the first affordance's frame) about which any turn grasps it the same, where
    /// it is round: its z for a cap from above, the item's axis for a slanted side grasp.
    round: Option<[f64; 3]>,
    /// The angle the step's last [`Motion::Turn`] or [`Motion::TurnDial`] turned (rad), until a
    /// [`Motion::TurnBack`] undoes it.
    turned: Option<f64>,
    /// Whether the carried item is round (its grasp turns freely about its axis), so that it may
    /// go into its seat at any heading.
    carried_round: bool,
    /// Whether the step brings a held tool onto a round opening ([`Target::Bring`] to an axial
    /// affordance: a pipette over a tube's mouth), so that it may come at any heading.
    brings_round: bool,
    /// A turn (rad) about the seat's axis added to the heading the carried item has now, for
    /// the motion that brings it over its seat (see [`Self::seat_turned`]); likewise about a
    /// round opening's axis for the motion that brings a held tool onto it.
    seat_turn: f64,
    /// Where the robot's base stands (world), which a [`Motion::Tilt`] tilts across from; none
    /// known: the tilt is about the tool's own y axis.
    base: Option<[f64; 3]>,
}

impl StepFrame {
    /// The frame with the robot's base position known (what a tilt needs).
    pub fn with_base(mut self, base: [f64; 3]) -> StepFrame {
        self.base = Some(base);
        self
    }

    /// Chooses, for the step's first affordance target, the symmetric grasp closest to the current
    /// tool orientation, and measures how `carried` (if any) sits in the hand. `finger_reach`: the
    /// robot's closed fingertips past its TCP (for presses); `enclose`: how deep its side grip
    /// takes a round body (`robots::Gripper::enclose`).
    pub fn new(
        motions: &[Motion],
        lab: &Lab,
        tcp_now: &Pose,
        carried: Option<&str>,
        finger_reach: f64,
        enclose: f64,
    ) -> Result<StepFrame, PlanError> {
        let mut frame = StepFrame {
            turn: Rot::identity(),
            carried: None,
            finger_reach,
            enclose,
            regrasp_nearest: motions
                .iter()
                .any(|m| matches!(m, Motion::Turn { .. } | Motion::TurnDial { .. })),
            half_turn: false,
            round: None,
            turned: None,
            carried_round: false,
            brings_round: false,
            seat_turn: 0.0,
            base: None,
        };
        match first_target(motions) {
            Some(Target::Affordance {
                labware,
                name,
                goals,
            }) => {
                let a = lab.affordance(labware, name, &lab.at_goals(labware, goals)?)?;
                frame.turn = closest_turn(&a, tcp_now);
                frame.half_turn = a.symmetry != Symmetry::None;
                frame.round = match a.symmetry {
                    Symmetry::Axial => Some([0.0, 0.0, 1.0]),
                    Symmetry::About(axis) => Some(axis),
                    _ => None,
                };
            }
            Some(Target::Button {
                labware,
                param,
                value,
            }) => {
                let a = lab.button(labware, param, value)?;
                frame.turn = closest_turn(&a, tcp_now);
                frame.half_turn = a.symmetry != Symmetry::None;
            }
            _ => {}
        }
        let seats = motions.iter().any(|m| {
            matches!(
                m,
                Motion::Reach {
                    target: Target::Seat { .. }
                } | Motion::Transit {
                    target: Target::Seat { .. }
                }
            )
        });
        frame.brings_round = motions.iter().any(|m| match m {
            Motion::Approach { target, .. }
            | Motion::Reach { target }
            | Motion::Transit { target } => {
                matches!(target, Target::Bring { labware, to, .. }
                if lab.item(labware).is_ok_and(|(_, live)| {
                    lab.affordance(labware, to, live)
                        .is_ok_and(|a| a.symmetry == Symmetry::Axial)
                }))
            }
            _ => false,
        });
        if seats {
            let item = carried.ok_or(PlanError::NothingCarried)?;
            frame.carried = Some((item.to_string(), tcp_now.inverse() * lab.pose_of(item)?));
            frame.carried_round = lab.item(item).is_ok_and(|(_, live)| {
                lab.affordance(item, "grasp", live)
                    .is_ok_and(|a| a.symmetry == Symmetry::Axial)
            });
        }
        Ok(frame)
    }

    fn target(&self, target: &Target, lab: &Lab) -> Result<Pose, PlanError> {
        match target {
            Target::Affordance {
                labware,
                name,
                goals,
            } => {
                let s = lab.at_goals(labware, goals)?;
                Ok(self.tool_at(&lab.affordance(labware, name, &s)?))
            }
            Target::Seat { location, above } => {
                let (item, item_in_tool) =
                    self.carried.as_ref().ok_or(PlanError::NothingCarried)?;
                // Along the seat's axis (upright in a rack, leaning in a fixed-angle rotor),
                // `above` out of it, keeping the heading the item has now about that axis: a
                // round item need not turn to the slot's yaw (and a half turn of the wrist would
                // gain nothing).
                let seat = lab.seat(location)?;
                let now = lab.pose_of(item)?.rotation;
                let x = seat.rotation.inverse() * (now * nalgebra::Vector3::x());
                let heading = axis_angle([0.0, 0.0, 1.0], x.y.atan2(x.x) + self.seat_turn);
                let target = translated_local(&seat, [0.0, 0.0, *above]);
                let target = labware::frame::pose(position(&target), seat.rotation * heading);
                Ok(target * item_in_tool.inverse())
            }
            Target::Button {
                labware,
                param,
                value,
            } => Ok(self.tool_at(&lab.button(labware, param, value)?)),
            Target::Carry { .. } | Target::Bring { .. } => Err(PlanError::CarryFromNowhere),
        }
    }

    /// The tool pose for a [`Target::Carry`] or a [`Target::Bring`] from the tool at `tcp_now`
    /// (a Bring at the heading closest to the held tool's now, turned by the frame's
    /// `seat_turn`); other targets as [`Self::target`].
    fn target_from(&self, target: &Target, lab: &Lab, tcp_now: &Pose) -> Result<Pose, PlanError> {
        if let Target::Bring {
            carried,
            from,
            labware,
            to,
            above,
        } = target
        {
            let (held, goal, model) = bring_ends(lab, carried, from, labware, to)?;
            let heading =
                closest_turn(&goal, &held.pose) * axis_angle([0.0, 0.0, 1.0], self.seat_turn);
            let goal =
                translated_local(&(goal.pose * heading), [0.0, 0.0, -into(model, to, *above)]);
            return Ok(goal * held.pose.inverse() * tcp_now);
        }
        let Target::Carry {
            labware,
            from,
            to,
            above,
        } = target
        else {
            return self.target(target, lab);
        };
        let (_, live) = lab.item(labware)?;
        let held = lab.affordance(labware, from, live)?;
        let goal = lab.affordance(labware, to, live)?;
        let goal = translated_local(
            &(goal.pose * closest_turn(&goal, &held.pose)),
            [0.0, 0.0, -above],
        );
        Ok(goal * held.pose.inverse() * tcp_now)
    }

    /// Where a transit to `target` ends: above it at the tool's current height, or
    /// `TRANSIT_CLEARANCE` above it when that is higher (a rotor in its housing, a rack's tubes).
    /// Over a leaning seat (a fixed-angle rotor's slot) that clearance is taken out along the
    /// seat's axis, so that the way in after it goes straight down that axis: come down
    /// vertically over the slot instead, the tube's base was swung across the rotor's rim to
    /// reach the axis, and the tube was left a centimetre high or knocked out of the rotor
    /// (`workflows.centrifuge_run`, seeds 18 and 75).
    fn transit_goal(&self, target: &Target, lab: &Lab, tcp_now: &Pose) -> Result<Pose, PlanError> {
        let z_now = tcp_now.translation.vector.z;
        if let Target::Seat { location, above } = target
            && let Some(rise) = leaning_rise(&lab.seat(location)?)
        {
            let out = Target::Seat {
                location: location.clone(),
                above: above + TRANSIT_CLEARANCE / rise,
            };
            let mut goal = self.target(&out, lab)?;
            goal.translation.vector.z = z_now.max(goal.translation.vector.z);
            return Ok(goal);
        }
        let mut goal = self.target_from(target, lab, tcp_now)?;
        goal.translation.vector.z = z_now.max(goal.translation.vector.z + TRANSIT_CLEARANCE);
        Ok(goal)
    }

    /// Measures again how the carried item (if any) sits in the hand, with the tool at
    /// `tcp_now`: a step's later seat motions then aim with the grasp as it is, not as it was
    /// when the step began.
    pub fn regrip(&mut self, lab: &Lab, tcp_now: &Pose) -> Result<(), PlanError> {
        if let Some((item, in_tool)) = &mut self.carried {
            *in_tool = tcp_now.inverse() * lab.pose_of(item)?;
        }
        Ok(())
    }

    /// The lead (m per rad) a turn follows: that of its `thread` target's affordance, else none.
    fn lead(&self, thread: Option<&Target>, lab: &Lab) -> Result<f64, PlanError> {
        Ok(match thread {
            Some(Target::Affordance { labware, name, .. })
            | Some(Target::Carry {
                labware, to: name, ..
            }) => {
                let (_, live) = lab.item(labware)?;
                lab.affordance(labware, name, live)?.lead
            }
            _ => 0.0,
        })
    }

    /// The angle a [`Motion::Turn`] turns from the tool at `tcp_now`: its own, or less where
    /// advancing along its thread would carry the tool past its `stop`. A [`Motion::TurnDial`]'s
    /// is one grip's share of what is left of the dial's turn; any other motion's is 0.
    pub fn turn_angle(&self, motion: &Motion, lab: &Lab, tcp_now: &Pose) -> Result<f64, PlanError> {
        if let Motion::TurnDial {
            labware,
            param,
            value,
            per_grip,
        } = motion
        {
            // What is left, in as few equal grips as `per_grip` allows.
            let left = lab.dial_turn(labware, param, value)?;
            let grips = (left.abs() / per_grip - 1e-9).ceil().max(1.0);
            return Ok(left / grips);
        }
        let Motion::Turn {
            angle,
            thread,
            stop,
        } = motion
        else {
            return Ok(0.0);
        };
        let lead = self.lead(thread.as_ref(), lab)?;
        match stop {
            // Only a turn that advances the tool (along its axis) toward the stop is limited.
            Some(stop) if lead * angle > 0.0 => {
                let at = self.target(stop, lab)?;
                let ahead = (tcp_now.inverse() * at).translation.vector.z.max(0.0);
                Ok(angle.signum() * angle.abs().min(ahead / lead.abs()))
            }
            _ => Ok(*angle),
        }
    }

    /// After `motion` (from the tool at `tcp_now`) is under way: a [`Motion::Turn`] (or
    /// [`Motion::TurnDial`]) is noted for
    /// the step's next [`Motion::TurnBack`], which forgets it (a second turn back has nothing to
    /// undo).
    pub fn record_turn(
        &mut self,
        motion: &Motion,
        lab: &Lab,
        tcp_now: &Pose,
    ) -> Result<(), PlanError> {
        match motion {
            Motion::Turn { .. } | Motion::TurnDial { .. } => {
                self.turned = Some(self.turn_angle(motion, lab, tcp_now)?)
            }
            Motion::TurnBack => self.turned = None,
            _ => {}
        }
        Ok(())
    }

    /// The item the step carries to a seat.
    pub fn carried(&self) -> Option<&str> {
        self.carried.as_ref().map(|(item, _)| item.as_str())
    }

    /// The same step with the other of a symmetric affordance's two grasps (half a turn about the
    /// approach axis), when it has one: the expert's second try where the closest grasp winds a
    /// wrist joint into its limit.
    pub fn other_grasp(&self) -> Option<StepFrame> {
        self.half_turn.then(|| StepFrame {
            turn: self.turn * axis_angle([0.0, 0.0, 1.0], std::f64::consts::PI),
            ..self.clone()
        })
    }

    /// For a step that turns a round part in the hand (`Turn` or `TurnDial` motions), the same step with its
    /// grasp turned a further `angle` (rad) about the part's axis; `None` for any other step.
    /// The expert's choice where the closest grasp leaves the wrist short of the turn.
    pub fn grasp_turned(&self, angle: f64) -> Option<StepFrame> {
        self.regrasp_nearest
            .then(|| self.turned_about_axis(angle))
            .flatten()
    }

    /// The same step with its grasp turned a further `angle` (rad) about a round first
    /// affordance's axis (a tube taken from another side); `None` where it is not round. The
    /// expert's choice where the grasp closest to the tool as it is cannot be reached on. A turn
    /// over a seat or an opening made for one motion ([`Self::seat_turned`]) is not carried into
    /// the step's grasp.
    pub fn turned_about_axis(&self, angle: f64) -> Option<StepFrame> {
        self.round.map(|axis| StepFrame {
            // About z (a cap from above) every turn of the grasp is about the same axis, so
            // the order is immaterial; about a slanted grasp's item axis the turn goes first,
            // so that it stays about the item's axis after the other grasp's half turn.
            turn: if axis == [0.0, 0.0, 1.0] {
                self.turn * axis_angle(axis, angle)
            } else {
                axis_angle(axis, angle) * self.turn
            },
            seat_turn: 0.0,
            ..self.clone()
        })
    }

    /// The same step bringing its carried item over the seat turned a further `angle` (rad) about
    /// the seat's axis from the heading it has now; `None` unless the item is round. For the one
    /// motion that brings it there: the motions after it keep the heading it then has. The
    /// expert's choice where every arm pose over the seat at the item's heading is blocked.
    /// Likewise a held tool brought onto a round opening (a pipette turned about the tube's axis,
    /// its arm then clear of the arm that holds the tube).
    pub fn seat_turned(&self, angle: f64) -> Option<StepFrame> {
        ((self.carried_round && self.carried.is_some()) || self.brings_round).then(|| StepFrame {
            seat_turn: angle,
            ..self.clone()
        })
    }

    /// The tool pose for `target` with the tool at `tcp_now` (a carried item or a held tool is
    /// brought there as it sits in the hand now).
    pub fn pose_toward(
        &self,
        target: &Target,
        lab: &Lab,
        tcp_now: &Pose,
    ) -> Result<Pose, PlanError> {
        self.target_from(target, lab, tcp_now)
    }

    /// The tool pose at the step's first target (where its grasp is taken), if it has one.
    pub fn first_pose(&self, motions: &[Motion], lab: &Lab) -> Result<Option<Pose>, PlanError> {
        first_target(motions)
            .map(|t| self.target(t, lab))
            .transpose()
    }

    /// The TCP pose for an affordance: the chosen symmetric turn, and for a touch, standing off
    /// so that the closed fingertips are at the point.
    fn tool_at(&self, a: &Affordance) -> Pose {
        let pose = a.pose * self.turn;
        if a.touch {
            translated_local(&pose, [0.0, 0.0, -self.finger_reach])
        } else {
            pose
        }
    }

    /// Tool poses for a path motion starting at `tcp_now` (empty for gripper motions).
    pub fn poses(
        &self,
        motion: &Motion,
        lab: &Lab,
        tcp_now: &Pose,
    ) -> Result<Vec<Pose>, PlanError> {
        Ok(match motion {
            Motion::Approach { target, standoff } => {
                let goal = translated_local(
                    &self.target_from(target, lab, tcp_now)?,
                    [0.0, 0.0, -standoff],
                );
                arc(tcp_now, &goal, 16)
            }
            Motion::Reach { target } => {
                let goal = match target {
                    Target::Affordance { labware, name, .. } if self.regrasp_nearest => {
                        let (_, live) = lab.item(labware)?;
                        let a = lab.affordance(labware, name, live)?;
                        if a.symmetry == Symmetry::Axial {
                            a.pose * closest_turn(&a, tcp_now)
                        } else {
                            self.target(target, lab)?
                        }
                    }
                    _ => self.target_from(target, lab, tcp_now)?,
                };
                line(tcp_now, &goal, 6)
            }
            Motion::Enclose { target } => line(
                tcp_now,
                &translated_local(&self.target(target, lab)?, [0.0, 0.0, self.enclose]),
                8,
            ),
            Motion::Transit { target } => {
                // In a straight line: the expert goes around whatever that line would hit
                // (`expert::route`).
                let goal = self.transit_goal(target, lab, tcp_now)?;
                line(tcp_now, &goal, 10)
            }
            Motion::Follow {
                labware,
                affordance,
                goals,
                samples,
            } => {
                let (_, live) = lab.item(labware)?;
                let end = lab.at_goals(labware, goals)?;
                let mut out = vec![*tcp_now];
                for i in 1..=*samples {
                    let t = i as f64 / *samples as f64;
                    let joints: Vec<(String, f64)> = end
                        .joints
                        .iter()
                        .map(|(role, v)| {
                            let from = live.joint(role);
                            (role.clone(), from + (v - from) * t)
                        })
                        .collect();
                    let s = live.with_joints(&joints);
                    out.push(self.tool_at(&lab.affordance(labware, affordance, &s)?));
                }
                out
            }
            Motion::Lift { height } => {
                line(tcp_now, &(translation([0.0, 0.0, *height]) * tcp_now), 8)
            }
            Motion::Retreat { distance } => line(
                tcp_now,
                &translated_local(tcp_now, [0.0, 0.0, -distance]),
                6,
            ),
            // In steps of at most 0.1 rad, so that the IK's nearest solution follows the turn.
            Motion::Turn { thread, .. } => {
                let lead = self.lead(thread.as_ref(), lab)?;
                turn_path(tcp_now, self.turn_angle(motion, lab, tcp_now)?, lead)
            }
            Motion::TurnDial { .. } => {
                turn_path(tcp_now, self.turn_angle(motion, lab, tcp_now)?, 0.0)
            }
            Motion::TurnBack => {
                turn_path(tcp_now, -self.turned.ok_or(PlanError::NoTurnToUndo)?, 0.0)
            }
            Motion::Tilt { angle } => tilt_path(tcp_now, *angle, self.base),
            Motion::Press { target, depth } => {
                let at = self.target(target, lab)?;
                line(tcp_now, &translated_local(&at, [0.0, 0.0, *depth]), 6)
            }
            Motion::Grasp
            | Motion::Release
            | Motion::HoldUntil { .. }
            | Motion::AwaitRun { .. }
            | Motion::PressPart { .. }
            | Motion::EasePart { .. }
            | Motion::Wait { .. }
            | Motion::Comply
            | Motion::Home => Vec::new(),
        })
    }
}

impl StepFrame {
    /// Other tool paths that do what `motion` is for, tried in order when its own path cannot be
    /// solved. A retreat has such freedom: the hand has let go and needs only to be clear of
    /// what it held, so where backing off along the tool runs out of reach (a lid's grip at the
    /// top of its arc) it may rise, or back off and rise, instead. So has a reach to a round
    /// part: any turn about its axis grasps it, and where the step's choice (made when the step
    /// began, from the part's heading then) cannot be reached, the turn nearest the tool as it
    /// is now is taken (a tube that turned in its rack while the arm came). Empty for every
    /// other motion.
    pub fn fallback_poses(
        &self,
        motion: &Motion,
        lab: &Lab,
        tcp_now: &Pose,
    ) -> Result<Vec<Vec<Pose>>, PlanError> {
        if let Motion::Reach {
            target: Target::Affordance { labware, name, .. },
        } = motion
        {
            let (_, live) = lab.item(labware)?;
            let a = lab.affordance(labware, name, live)?;
            return Ok(if a.symmetry == Symmetry::Axial {
                vec![line(tcp_now, &(a.pose * closest_turn(&a, tcp_now)), 6)]
            } else {
                Vec::new()
            });
        }
        let Motion::Retreat { distance } = motion else {
            return Ok(Vec::new());
        };
        let up = |d: f64| translation([0.0, 0.0, d]) * tcp_now;
        let half = distance * std::f64::consts::FRAC_1_SQRT_2;
        Ok(vec![
            line(tcp_now, &up(*distance), 6),
            line(
                tcp_now,
                &(translation([0.0, 0.0, half]) * translated_local(tcp_now, [0.0, 0.0, -half])),
                6,
            ),
            line(tcp_now, &up(-distance), 6),
        ])
    }
}

/// The tool turned in place about its axis by `angle` from `tcp`, advancing `lead` per radian
/// along it, in steps of at most 0.1 rad.
fn turn_path(tcp: &Pose, angle: f64, lead: f64) -> Vec<Pose> {
    let n = ((angle.abs() / 0.1).ceil() as usize).max(1);
    (0..=n)
        .map(|i| {
            let a = angle * i as f64 / n as f64;
            let mut p = translated_local(tcp, [0.0, 0.0, lead * a]);
            p.rotation *= axis_angle([0.0, 0.0, 1.0], a);
            p
        })
        .collect()
}

/// The tool tilted in place by `angle` ([`Motion::Tilt`]): about the level axis square to the
/// line from `base` to the tool (about the tool's own y where no base is known or the tool is
/// over it), after a turn about the tool's approach axis that brings its y onto that axis (the
/// fingers, closing along x, then close across the tilt), the shorter of the two turns that do.
/// In steps of at most 0.1 rad, so that the IK's nearest solution follows.
fn tilt_path(tcp: &Pose, angle: f64, base: Option<[f64; 3]>) -> Vec<Pose> {
    let steps = |a: f64| ((a.abs() / 0.1).ceil() as usize).max(1);
    let reach = base.map(|b| {
        let t = tcp.translation.vector;
        nalgebra::Vector3::new(t.x - b[0], t.y - b[1], 0.0)
    });
    let across = reach
        .filter(|r| r.norm() > 1e-3)
        .map(|r| nalgebra::Vector3::new(-r.y, r.x, 0.0).normalize());
    let Some(axis) = across else {
        let n = steps(angle);
        return (0..=n)
            .map(|i| {
                let mut p = *tcp;
                p.rotation *= axis_angle([0.0, 1.0, 0.0], angle * i as f64 / n as f64);
                p
            })
            .collect();
    };
    // The turn about the approach axis (tool z) that lays the tool's y along the axis: in the
    // tool frame the axis has components (ax, ay, az); a turn by ψ moves y to (-sin ψ, cos ψ).
    let local = tcp.rotation.inverse() * axis;
    let psi = f64::atan2(-local.x, local.y);
    // y and -y tilt alike (the sign of the tilt flips): take the smaller turn.
    let (psi, sign) = if psi.abs() > std::f64::consts::FRAC_PI_2 {
        (psi - std::f64::consts::PI.copysign(psi), -1.0)
    } else {
        (psi, 1.0)
    };
    let mut out = Vec::new();
    let n = steps(psi);
    for i in 0..=n {
        let mut p = *tcp;
        p.rotation *= axis_angle([0.0, 0.0, 1.0], psi * i as f64 / n as f64);
        out.push(p);
    }
    let turned = *out.last().unwrap_or(tcp);
    let n = steps(angle);
    for i in 1..=n {
        let mut p = turned;
        p.rotation *= axis_angle([0.0, 1.0, 0.0], sign * angle * i as f64 / n as f64);
        out.push(p);
    }
    out
}

/// The step's first target that the tool goes to.
pub fn first_target(motions: &[Motion]) -> Option<&Target> {
    motions.iter().find_map(|m| match m {
        Motion::Approach { target, .. }
        | Motion::Reach { target }
        | Motion::Enclose { target }
        | Motion::Transit { target }
        | Motion::Press { target, .. } => Some(target),
        _ => None,
    })
}

/// How far along its affordance's axis a [`Target::Bring`] brings its tool (`above` back from
/// the affordance, negative: past it), no deeper than a narrow opening lets a tool go.
fn into(model: &dyn Instrument, to: &str, above: f64) -> f64 {
    model
        .opening(to)
        .map_or(above, |opening| above.max(-opening.depth))
}

/// A [`Target::Bring`]'s two ends as they are now: the carried item's affordance `from`, the
/// other item's affordance `to`, and that item's model.
fn bring_ends<'a>(
    lab: &Lab<'a>,
    carried: &str,
    from: &str,
    labware: &str,
    to: &str,
) -> Result<(Affordance, Affordance, &'a dyn Instrument), PlanError> {
    let (_, live) = lab.item(carried)?;
    let held = lab.affordance(carried, from, live)?;
    let (model, other) = lab.item(labware)?;
    let goal = lab.affordance(labware, to, other)?;
    Ok((held, goal, model))
}

/// How far a [`Target::Bring`]'s carried affordance is from its goal now (m), where the goal is
/// a narrow opening, with how closely the opening asks to be aimed: what the expert checks once a
/// path into it has ended, and moves again while it misses. `None` for every other target.
pub fn bring_miss(target: &Target, lab: &Lab) -> Result<Option<(f64, f64)>, PlanError> {
    let Target::Bring {
        carried,
        from,
        labware,
        to,
        above,
    } = target
    else {
        return Ok(None);
    };
    let (held, goal, model) = bring_ends(lab, carried, from, labware, to)?;
    let Some(opening) = model.opening(to) else {
        return Ok(None);
    };
    let goal = translated_local(&goal.pose, [0.0, 0.0, -into(model, to, *above)]);
    let miss = (goal.translation.vector - held.pose.translation.vector).norm();
    Ok(Some((miss, opening.aim)))
}

/// The turn allowed by the affordance's symmetry (about its z axis; for `AboutY`, about its y
/// axis; for `About`, about the axis it names) that brings it closest to `tool`'s orientation.
fn closest_turn(a: &Affordance, tool: &Pose) -> Rot {
    match a.symmetry {
        Symmetry::None => Rot::identity(),
        Symmetry::HalfTurn => {
            let half = axis_angle([0.0, 0.0, 1.0], std::f64::consts::PI);
            let keep = (a.pose.rotation).angle_to(&tool.rotation);
            let flip = (a.pose.rotation * half).angle_to(&tool.rotation);
            if flip < keep { half } else { Rot::identity() }
        }
        Symmetry::Axial => {
            let rel = (a.pose.rotation.inverse() * tool.rotation).to_rotation_matrix();
            axis_angle([0.0, 0.0, 1.0], rel[(1, 0)].atan2(rel[(0, 0)]))
        }
        // The turn about y that points the approach where the tool points now (projected
        // across the item's axis): the hold is taken from the side the tool comes from.
        Symmetry::AboutY => {
            let rel = (a.pose.rotation.inverse() * tool.rotation).to_rotation_matrix();
            axis_angle([0.0, 1.0, 0.0], rel[(0, 2)].atan2(rel[(2, 2)]))
        }
        // The same for a slanted approach: the turn about the item's axis that brings the
        // approach's part across that axis onto the tool's.
        Symmetry::About(axis) => {
            let k = nalgebra::Vector3::from(axis).normalize();
            let across = |v: nalgebra::Vector3<f64>| v - k * k.dot(&v);
            let approach = across(nalgebra::Vector3::z());
            let tool_z = across(a.pose.rotation.inverse() * tool.rotation * nalgebra::Vector3::z());
            axis_angle(
                axis,
                k.dot(&approach.cross(&tool_z)).atan2(approach.dot(&tool_z)),
            )
        }
    }
}

fn line(a: &Pose, b: &Pose, n: usize) -> Vec<Pose> {
    (0..=n)
        .map(|i| interpolate(a, b, i as f64 / n as f64))
        .collect()
}

/// Like [`line`] but lifted by a parabola whose apex is a quarter of the horizontal distance.
fn arc(a: &Pose, b: &Pose, n: usize) -> Vec<Pose> {
    let (pa, pb) = (position(a), position(b));
    let lift = 0.25 * ((pb[0] - pa[0]).powi(2) + (pb[1] - pa[1]).powi(2)).sqrt();
    line(a, b, n)
        .into_iter()
        .enumerate()
        .map(|(i, mut p)| {
            let t = i as f64 / n as f64;
            p.translation.vector.z += 4.0 * lift * t * (1.0 - t);
            p
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use compiler::motion::goals;
    use nalgebra::Vector3;
    use std::collections::BTreeMap;

    /// An item at `pose` with no joints, parts or logic.
    fn state(name: &str, pose: Pose) -> LabwareState {
        LabwareState {
            name: name.into(),
            pose,
            joints: BTreeMap::new(),
            parts: BTreeMap::new(),
            logic: BTreeMap::new(),
            touched_by: Vec::new(),
            finger_contacts: Vec::new(),
        }
    }

    fn cycler_state() -> LabwareState {
        LabwareState {
            name: "cycler".into(),
            pose: Pose::identity(),
            joints: BTreeMap::from([("lid".into(), 0.0), ("lever".into(), 0.0)]),
            parts: BTreeMap::new(),
            logic: BTreeMap::new(),
            touched_by: Vec::new(),
            finger_contacts: Vec::new(),
        }
    }

    #[test]
    fn the_lever_is_approached_against_it_and_either_grasp_follows_the_same_path() {
        // Models come through the registry, as the runtime and the expert get them.
        let cycler = labware::Model::for_kind("thermal_cycler").unwrap();
        let s = cycler_state();
        let params = Bindings::new();
        let lab = Lab {
            items: vec![("cycler", cycler.instrument().unwrap(), &s)],
            params: &params,
        };
        let grip = Target::Affordance {
            labware: "cycler".into(),
            name: "lid_close".into(),
            goals: goals(&[("lid", "closed"), ("lever", "raised")]),
        };
        let reach = [Motion::Reach {
            target: grip.clone(),
        }];
        let plain = StepFrame::new(&reach, &lab, &Pose::identity(), None, 0.0, 0.0).unwrap();
        let closed = plain.target(&grip, &lab).unwrap();
        // Lid closed, lever raised: the grip's outward axis is +y, so the tool approaches along -y.
        let z = closed.rotation * Vector3::z();
        assert!((z.y + 1.0).abs() < 1e-9, "{z:?}");
        // A tool held the other way round picks the flipped grasp: same point, same approach,
        // fingers turned over.
        let flipped_tool =
            closed * labware::frame::pose([0.0; 3], axis_angle([0.0, 0.0, 1.0], 3.0));
        let flipped = StepFrame::new(&reach, &lab, &flipped_tool, None, 0.0, 0.0).unwrap();
        let other = flipped.target(&grip, &lab).unwrap();
        assert!((other.translation.vector - closed.translation.vector).norm() < 1e-12);
        assert!((other.rotation * Vector3::z()).dot(&z) > 1.0 - 1e-9);
        assert!(
            (other.rotation * Vector3::x()).dot(&(closed.rotation * Vector3::x())) < -1.0 + 1e-9
        );
        // Following the lid shut ends at the closed grasp.
        let follow = Motion::Follow {
            labware: "cycler".into(),
            affordance: "lid_close".into(),
            goals: goals(&[("lid", "closed"), ("lever", "raised")]),
            samples: 5,
        };
        let path = plain.poses(&follow, &lab, &Pose::identity()).unwrap();
        assert_eq!(path.len(), 6);
        assert!((path[5].translation.vector - closed.translation.vector).norm() < 1e-12);
        let bad = Target::Affordance {
            labware: "cycler".into(),
            name: "lid_close".into(),
            goals: goals(&[("lid", "ajar")]),
        };
        assert!(matches!(
            plain.target(&bad, &lab),
            Err(PlanError::NoGoal { .. })
        ));
    }

    #[test]
    fn a_carried_tube_is_seated_upright_on_the_slot() {
        let rack = labware::Model::for_kind("tube_rack").unwrap();
        let tube = labware::Model::for_kind("tube_50ml").unwrap();
        let rack_s = LabwareState {
            name: "rack".into(),
            pose: labware::frame::yaw([0.3, 0.2, 0.854], std::f64::consts::FRAC_PI_2),
            joints: BTreeMap::new(),
            parts: BTreeMap::new(),
            logic: BTreeMap::new(),
            touched_by: Vec::new(),
            finger_contacts: Vec::new(),
        };
        // The tube hangs slightly tilted in the hand, somewhere above the bench.
        let tube_s = LabwareState {
            name: "tube".into(),
            pose: labware::frame::pose([0.4, 0.0, 1.0], axis_angle([1.0, 0.0, 0.0], 0.05)),
            ..rack_s.clone()
        };
        let params = Bindings::new();
        let lab = Lab {
            items: vec![
                ("rack", rack.instrument().unwrap(), &rack_s),
                ("tube", tube.instrument().unwrap(), &tube_s),
            ],
            params: &params,
        };
        let tcp = translated_local(&tube_s.pose, [0.0, 0.0, 0.11]);
        let seat_b3 = Target::Seat {
            location: "rack.B3".into(),
            above: 0.0,
        };
        let place = [Motion::Reach {
            target: seat_b3.clone(),
        }];
        let frame = StepFrame::new(&place, &lab, &tcp, Some("tube"), 0.0, 0.0).unwrap();
        let tool = frame.target(&seat_b3, &lab).unwrap();
        // Where the tube would be with the tool there: exactly on the seat, upright.
        let tube_then = tool * frame.carried.clone().unwrap().1;
        let seat = lab.seat("rack.B3").unwrap();
        assert!((tube_then.translation.vector - seat.translation.vector).norm() < 1e-12);
        assert!((tube_then.rotation * Vector3::z()).z > 1.0 - 1e-12);
        assert!(matches!(
            StepFrame::new(&place, &lab, &tcp, None, 0.0, 0.0),
            Err(PlanError::NothingCarried)
        ));
    }

    /// A transit over a fixed-angle rotor's slot ends out along the slot's leaning axis, so that
    /// the way down after it is that axis; over a rack's upright slot it ends straight above.
    #[test]
    fn a_transit_ends_on_a_leaning_slots_axis_and_over_an_upright_one() {
        let centrifuge = labware::Model::for_kind("centrifuge_5430").unwrap();
        let rack = labware::Model::for_kind("tube_rack").unwrap();
        let tube = labware::Model::for_kind("tube_1_5ml").unwrap();
        let centrifuge_s = LabwareState {
            name: "centrifuge".into(),
            pose: labware::frame::yaw([0.0, 0.0, 0.824], 0.2),
            joints: BTreeMap::from([
                ("lid".into(), 0.0),
                ("open".into(), 0.0),
                ("rotor".into(), 0.4),
            ]),
            parts: BTreeMap::new(),
            logic: BTreeMap::new(),
            touched_by: Vec::new(),
            finger_contacts: Vec::new(),
        };
        let rack_s = LabwareState {
            name: "rack".into(),
            pose: labware::frame::yaw([0.3, 0.4, 0.835], 0.0),
            joints: BTreeMap::new(),
            ..centrifuge_s.clone()
        };
        // Carried lower than either seat: the transit rises to its clearance over each.
        let tube_s = LabwareState {
            name: "tube".into(),
            pose: labware::frame::pose([0.4, 0.3, 0.78], Rot::identity()),
            ..rack_s.clone()
        };
        let params = Bindings::new();
        let lab = Lab {
            items: vec![
                (
                    "centrifuge",
                    centrifuge.instrument().unwrap(),
                    &centrifuge_s,
                ),
                ("rack", rack.instrument().unwrap(), &rack_s),
                ("tube", tube.instrument().unwrap(), &tube_s),
            ],
            params: &params,
        };
        let tcp = translated_local(&tube_s.pose, [0.0, 0.0, 0.04]);
        for location in ["centrifuge.7", "rack.B3"] {
            let transit = [Motion::Transit {
                target: Target::Seat {
                    location: location.into(),
                    above: 0.0,
                },
            }];
            let frame = StepFrame::new(&transit, &lab, &tcp, Some("tube"), 0.0, 0.0).unwrap();
            let path = frame.poses(&transit[0], &lab, &tcp).unwrap();
            let tube_then = path.last().unwrap() * frame.carried.clone().unwrap().1;
            let seat = lab.seat(location).unwrap();
            let out = tube_then.translation.vector - seat.translation.vector;
            let axis = seat.rotation * Vector3::z();
            let leaning = location.starts_with("centrifuge");
            assert_eq!(leaning, axis.z < 0.99, "{location}: axis {axis:?}");
            // On the seat's axis, `TRANSIT_CLEARANCE` higher than the seat.
            assert!(
                out.cross(&axis).norm() < 1e-9,
                "{location}: {out:?} off {axis:?}"
            );
            assert!(
                (out.z - TRANSIT_CLEARANCE).abs() < 1e-9,
                "{location}: {out:?}"
            );
            assert!(out.dot(&axis) > 0.0);
        }
    }

    /// A tube held from the side is approached from where the tool comes, across its axis, and
    /// taken `enclose` deep; a cap turned to loosen is followed up its thread by its lead.
    #[test]
    fn a_side_hold_comes_from_the_tool_and_a_turned_cap_rises_by_its_lead() {
        let tube = labware::Model::for_kind("tube_50ml").unwrap();
        let model = tube.instrument().unwrap();
        let labware::Model::Tube(p) = &tube else {
            panic!("a tube")
        };
        let at = labware::frame::pose([0.1, -0.2, 0.83], Rot::identity());
        let placed = model.place("tube", &at);
        let s = LabwareState {
            name: "tube".into(),
            pose: at,
            joints: BTreeMap::new(),
            parts: BTreeMap::from([("cap".into(), placed[1].1)]),
            logic: BTreeMap::new(),
            touched_by: Vec::new(),
            finger_contacts: Vec::new(),
        };
        let params = Bindings::new();
        let lab = Lab {
            items: vec![("tube", model, &s)],
            params: &params,
        };
        let hold = Target::Affordance {
            labware: "tube".into(),
            name: "hold".into(),
            goals: Vec::new(),
        };
        // A tool pointing along +y (coming from -y), fingers closing along x.
        let tool = labware::frame::pose(
            [0.1, -0.5, 0.92],
            labware::frame::from_axes([1.0, 0.0, 0.0], [0.0, 0.0, -1.0], [0.0, 1.0, 0.0]),
        );
        let motions = [Motion::Enclose {
            target: hold.clone(),
        }];
        let frame = StepFrame::new(&motions, &lab, &tool, None, 0.0, 0.03).unwrap();
        let path = frame.poses(&motions[0], &lab, &tool).unwrap();
        let end = path.last().unwrap();
        let z = end.rotation * Vector3::z();
        assert!((z - Vector3::y()).norm() < 1e-9, "approach {z:?}");
        // On the tube's axis, then 30 mm on through it.
        let axis = end.translation.vector - Vector3::new(0.1, -0.2, 0.0);
        assert!(
            (axis.x).abs() < 1e-9 && (axis.y - 0.03).abs() < 1e-9,
            "{axis:?}"
        );
        // Turned to loosen (anticlockwise from above: negative about a downward tool), the tool
        // rises a pitch per turn.
        let cap = Target::Affordance {
            labware: "tube".into(),
            name: "grasp".into(),
            goals: Vec::new(),
        };
        let grip = model.affordance("grasp", &s).unwrap().pose;
        let turn = Motion::Turn {
            angle: -std::f64::consts::PI,
            thread: Some(cap.clone()),
            stop: None,
        };
        let path = frame.poses(&turn, &lab, &grip).unwrap();
        let rise = path.last().unwrap().translation.vector.z - grip.translation.vector.z;
        assert!((rise - p.pitch / 2.0).abs() < 1e-12, "rose {rise}");
        assert!(path.len() > 30, "in steps of at most 0.1 rad");
        let back = Motion::Turn {
            angle: std::f64::consts::PI,
            thread: None,
            stop: None,
        };
        let path = frame.poses(&back, &lab, &grip).unwrap();
        assert!((path.last().unwrap().translation.vector - grip.translation.vector).norm() < 1e-12);
        // A turn back undoes the step's last turn, once; with none to undo it is an error.
        let mut frame = frame.clone();
        assert_eq!(
            frame.poses(&Motion::TurnBack, &lab, &grip),
            Err(PlanError::NoTurnToUndo)
        );
        frame.record_turn(&turn, &lab, &grip).unwrap();
        let turned = *frame.poses(&turn, &lab, &grip).unwrap().last().unwrap();
        let undone = *frame
            .poses(&Motion::TurnBack, &lab, &turned)
            .unwrap()
            .last()
            .unwrap();
        assert!(undone.rotation.angle_to(&grip.rotation) < 1e-12);
        frame.record_turn(&Motion::TurnBack, &lab, &turned).unwrap();
        assert!(frame.poses(&Motion::TurnBack, &lab, &grip).is_err());
        // Turned to tighten from a millimetre above the seat with the seat as its stop, the tool
        // goes down to the seat, not a whole half pitch; turned to loosen, the stop does not
        // hold it back.
        let above = translation([0.0, 0.0, 0.001]) * grip;
        let tighten = Motion::Turn {
            angle: std::f64::consts::PI,
            thread: Some(cap.clone()),
            stop: Some(Target::Affordance {
                labware: "tube".into(),
                name: "cap_seated".into(),
                goals: Vec::new(),
            }),
        };
        let path = frame.poses(&tighten, &lab, &above).unwrap();
        let fall = above.translation.vector.z - path.last().unwrap().translation.vector.z;
        assert!((fall - 0.001).abs() < 1e-9, "fell {fall}");
        let Motion::Turn { thread, stop, .. } = tighten else {
            unreachable!()
        };
        let loosen = Motion::Turn {
            angle: -std::f64::consts::PI,
            thread,
            stop,
        };
        let path = frame.poses(&loosen, &lab, &above).unwrap();
        let rise = path.last().unwrap().translation.vector.z - above.translation.vector.z;
        assert!((rise - p.pitch / 2.0).abs() < 1e-12, "rose {rise}");
    }

    /// An open tube is picked from the side the tool comes from, the approach slanted down
    /// across the tube and the fingers closing level; a grasp turned about the tube's axis, from
    /// either of the two grasps, keeps that slant.
    #[test]
    fn an_open_tube_is_picked_at_a_slant_from_the_tools_side() {
        let open = BTreeMap::from([("cap".to_string(), "off".to_string())]);
        let tube = labware::Model::for_kind("tube_50ml")
            .unwrap()
            .for_start(&open);
        let model = tube.instrument().unwrap();
        let s = state("tube", labware::frame::translation([0.1, -0.2, 0.83]));
        let params = Bindings::new();
        let lab = Lab {
            items: vec![("tube", model, &s)],
            params: &params,
        };
        let grasp = Target::Affordance {
            labware: "tube".into(),
            name: "grasp".into(),
            goals: Vec::new(),
        };
        // A tool pointing down and a little toward -y (it stands on the tube's +y side).
        let (cos, sin) = (0.4f64.cos(), 0.4f64.sin());
        let tool = labware::frame::pose(
            [0.1, 0.2, 1.2],
            labware::frame::from_axes([1.0, 0.0, 0.0], [0.0, -cos, sin], [0.0, -sin, -cos]),
        );
        let motions = [Motion::Reach { target: grasp }];
        let frame = StepFrame::new(&motions, &lab, &tool, None, 0.0, 0.0).unwrap();
        // The grasp's approach is `approach`; its fingers close level.
        let grips = |f: &StepFrame, approach: Vector3<f64>| {
            let end = *f.poses(&motions[0], &lab, &tool).unwrap().last().unwrap();
            let (z, x) = (end.rotation * Vector3::z(), end.rotation * Vector3::x());
            assert!(
                (z - approach).norm() < 1e-9,
                "approach {z:?}, not {approach:?}"
            );
            assert!(x.z.abs() < 1e-9, "fingers close along {x:?}");
        };
        let (down_c, down_s) = (30f64.to_radians().cos(), 30f64.to_radians().sin());
        // From +y toward the axis, 30 degrees below the level.
        grips(&frame, Vector3::new(0.0, -down_c, -down_s));
        // A quarter turn anticlockwise about the tube's axis (seen from above): from -x; the
        // other grasp (the fingers swapped) turned the same way comes the same way.
        let quarter = std::f64::consts::FRAC_PI_2;
        let from_minus_x = Vector3::new(down_c, 0.0, -down_s);
        grips(&frame.turned_about_axis(quarter).unwrap(), from_minus_x);
        let other = frame.other_grasp().unwrap();
        grips(&other.turned_about_axis(quarter).unwrap(), from_minus_x);
        // A pick neither seats a carried item nor brings a tool onto an opening: it has no
        // heading over a target to turn.
        assert!(frame.seat_turned(0.5).is_none());
    }

    /// A pipette held in the hand is brought onto an open tube's mouth: its opening on the
    /// mouth's axis, pointing down, at the heading it has now; turned for another heading
    /// (`seat_turned`), its opening is at the same place and the tool turns about the axis.
    #[test]
    fn a_pipette_is_brought_onto_a_mouth_at_its_heading_or_a_turned_one() {
        let open = BTreeMap::from([("cap".to_string(), "off".to_string())]);
        let tube = labware::Model::for_kind("tube_50ml")
            .unwrap()
            .for_start(&open);
        let pipette = labware::Model::for_kind("pipette").unwrap();
        let (tube_m, pipette_m) = (tube.instrument().unwrap(), pipette.instrument().unwrap());
        let t = state("tube", labware::frame::translation([0.1, -0.2, 0.83]));
        let p = state(
            "pipette",
            labware::frame::pose([0.3, -0.4, 1.1], axis_angle([0.0, 0.0, 1.0], 0.7)),
        );
        let params = Bindings::new();
        let lab = Lab {
            items: vec![("tube", tube_m, &t), ("pipette", pipette_m, &p)],
            params: &params,
        };
        let onto = Target::Bring {
            carried: "pipette".into(),
            from: "opening".into(),
            labware: "tube".into(),
            to: "mouth".into(),
            above: 0.03,
        };
        let tcp = pipette_m.affordance("grasp", &p).unwrap().pose;
        let motions = [Motion::Reach {
            target: onto.clone(),
        }];
        let frame = StepFrame::new(&motions, &lab, &tcp, None, 0.0, 0.0).unwrap();
        let opening_in_tool = tcp.inverse() * p.pose;
        let mouth = tube_m
            .affordance("mouth", &t)
            .unwrap()
            .pose
            .translation
            .vector;
        let brought = |f: &StepFrame| f.pose_toward(&onto, &lab, &tcp).unwrap() * opening_in_tool;
        let here = brought(&frame);
        let turned = brought(&frame.seat_turned(0.5).unwrap());
        for at in [here, turned] {
            let off = at.translation.vector - mouth;
            assert!(
                off.xy().norm() < 1e-9 && (off.z - 0.03).abs() < 1e-9,
                "{off:?}"
            );
            // The pipette upright: its opening points down.
            assert!((at.rotation * Vector3::z() - Vector3::z()).norm() < 1e-9);
        }
        // The heading it had (turned 0.7 about the vertical), then 0.5 about the mouth's axis,
        // which points down the tube: clockwise seen from above.
        let heading = |r: &Rot| {
            let x = r * Vector3::x();
            x.y.atan2(x.x)
        };
        assert!(
            (heading(&here.rotation) - 0.7).abs() < 1e-9,
            "{}",
            heading(&here.rotation)
        );
        assert!(
            (heading(&turned.rotation) - 0.2).abs() < 1e-9,
            "{}",
            heading(&turned.rotation)
        );
    }

    /// A dial is turned from its live angle to the target's notch in as few equal grips as the
    /// motion's most per grip allows; each turn is the tool turned in place about its axis.
    #[test]
    fn a_dial_turns_from_where_it_is_to_the_notch_in_equal_grips() {
        let mixer = labware::Model::for_kind("vortex_mixer").unwrap();
        let model = mixer.instrument().unwrap();
        let at = |knob: f64| LabwareState {
            name: "vortex".into(),
            pose: Pose::identity(),
            joints: BTreeMap::from([("knob".into(), knob)]),
            parts: BTreeMap::new(),
            logic: BTreeMap::new(),
            touched_by: Vec::new(),
            finger_contacts: Vec::new(),
        };
        let params = Bindings::from([("rpm".to_string(), "2000".to_string())]);
        let turn = |knob: f64, per_grip: f64| {
            let s = at(knob);
            let lab = Lab {
                items: vec![("vortex", model, &s)],
                params: &params,
            };
            let dial = Motion::TurnDial {
                labware: "vortex".into(),
                param: "speed".into(),
                value: "{rpm} rpm".into(),
                per_grip,
            };
            let frame = StepFrame::new(&[], &lab, &Pose::identity(), None, 0.0, 0.0).unwrap();
            let angle = frame.turn_angle(&dial, &lab, &Pose::identity()).unwrap();
            let path = frame.poses(&dial, &lab, &Pose::identity()).unwrap();
            (angle, path)
        };
        // 2,000 rpm: the sixth notch (2,044 rpm), 2.76 rad from the stop: three grips of 0.92.
        let (angle, path) = turn(0.0, 1.2);
        assert!((angle - 0.92).abs() < 1e-9, "{angle}");
        let end = path.last().unwrap().rotation * Vector3::x();
        assert!((end.y.atan2(end.x) - 0.92).abs() < 1e-9);
        assert!(path.iter().all(|p| p.translation.vector.norm() < 1e-12));
        // From past the notch it turns back, in one grip.
        assert!((turn(3.0, 1.2).0 - (2.76 - 3.0)).abs() < 1e-9);
        // A large enough grip turns it all at once.
        assert!((turn(0.0, 3.0).0 - 2.76).abs() < 1e-9);
        let s = at(0.0);
        let lab = Lab {
            items: vec![("vortex", model, &s)],
            params: &params,
        };
        assert!(matches!(
            lab.dial_turn("vortex", "time", "{rpm} rpm"),
            Err(PlanError::NoDial { .. })
        ));
    }
}
