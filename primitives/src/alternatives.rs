//! The alternatives a step may take where its first choice cannot be planned, in the one order
//! they are tried: a round part grasped from another side, a round carried item (or a held tool)
//! brought over its seat (or onto an opening) at another heading, the other of a symmetric
//! affordance's two grasps, and, for a step that turns a part in the hand, the grasps about the
//! part's axis with room for the turn.
//!
//! The scripted expert tries these where its first choice is blocked, and the reach check
//! (`autobio check`) checks the same ones, both by iterating here: a new kind of alternative is
//! written once and both follow. This module only enumerates frames; it does not solve,
//! route or judge them (the expert and the reach check do).

use crate::StepFrame;

/// Turns (degrees) tried about a round part's axis or a seat's: the step's own, then 30 degrees
/// more each way, up to half a turn.
pub const GRASP_TURNS: [f64; 12] = [
    0.0, 30.0, -30.0, 60.0, -60.0, 90.0, -90.0, 120.0, -120.0, 150.0, -150.0, 180.0,
];

/// How far an alternative reaches: the step's grasp (kept for the motions after it) or only the
/// heading of the one motion that brings an item over its seat (the motions after it take the
/// heading the item then has).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Scope {
    Step,
    Motion,
}

/// One alternative frame for a step and how far it reaches.
#[derive(Clone, Debug)]
pub struct Alternative {
    pub frame: StepFrame,
    pub scope: Scope,
}

impl StepFrame {
    /// The alternatives for a free-space motion whose first choice is blocked, in the order they
    /// are tried: for each further turn in [`GRASP_TURNS`], the round part grasped from that side
    /// (only where `regrasp`: before the step has moved, while its grasp is not yet committed),
    /// then the carried item or held tool brought over its seat at that heading.
    pub fn alternatives(&self, regrasp: bool) -> impl Iterator<Item = Alternative> + '_ {
        GRASP_TURNS.iter().skip(1).flat_map(move |deg| {
            let angle = deg.to_radians();
            let grasp = regrasp
                .then(|| self.turned_about_axis(angle))
                .flatten()
                .map(|frame| Alternative {
                    frame,
                    scope: Scope::Step,
                });
            let heading = self.seat_turned(angle).map(|frame| Alternative {
                frame,
                scope: Scope::Motion,
            });
            [grasp, heading].into_iter().flatten()
        })
    }

    /// Every heading over a seat or onto an opening at which the step may bring what it carries,
    /// its own first (empty where the item is not round).
    pub fn headings(&self) -> impl Iterator<Item = StepFrame> + '_ {
        GRASP_TURNS
            .iter()
            .filter_map(|deg| self.seat_turned(deg.to_radians()))
    }

    /// For a step that turns a round part in the hand, its grasps about the part's axis from
    /// `centre` (rad) turned by each of [`GRASP_TURNS`], nearest first (empty for other steps).
    pub fn turn_grasps(&self, centre: f64) -> impl Iterator<Item = StepFrame> + '_ {
        GRASP_TURNS
            .iter()
            .filter_map(move |deg| self.grasp_turned(centre + deg.to_radians()))
    }

    /// The step's own grasp, then the other of a symmetric affordance's two where it has one.
    pub fn symmetric_grasps(&self) -> impl Iterator<Item = StepFrame> {
        std::iter::once(self.clone()).chain(self.other_grasp())
    }
}
