//! The protocol AST: what a file says, with a span on everything a diagnostic may point at.
//! Names are not resolved here (see the compiler); quantities are already in SI units.

use crate::Span;
use serde::Serialize;

/// A value with the span of the text it came from.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Spanned<T> {
    pub value: T,
    pub span: Span,
}

impl<T> Spanned<T> {
    pub fn new(value: T, span: Span) -> Self {
        Spanned { value, span }
    }
}

#[derive(Clone, Debug, Default, PartialEq, Serialize)]
pub struct Protocol {
    pub format: Option<Spanned<i64>>,
    pub meta: Meta,
    pub robots: Vec<Robot>,
    pub labware: Vec<Labware>,
    pub randomise: Vec<Randomisation>,
    pub steps: Vec<Step>,
    pub success: Vec<Spanned<String>>,
}

#[derive(Clone, Debug, Default, PartialEq, Serialize)]
pub struct Meta {
    pub id: Option<Spanned<String>>,
    pub version: Option<Spanned<i64>>,
    pub level: Option<Spanned<String>>,
    pub instruction: Option<Spanned<String>>,
    /// Seconds.
    pub time_limit: Option<Spanned<f64>>,
    /// Span of the `[protocol]` header (or of the whole file when it is missing).
    pub span: Span,
}

/// Placement on the table: position in metres (world frame) and yaw in radians.
#[derive(Clone, Debug, Default, PartialEq, Serialize)]
pub struct Pose {
    pub pos: Option<Spanned<[f64; 3]>>,
    pub yaw: Option<Spanned<f64>>,
}

#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Robot {
    pub name: Spanned<String>,
    pub model: Option<Spanned<String>>,
    pub base: Pose,
}

#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Labware {
    pub name: Spanned<String>,
    pub kind: Option<Spanned<String>>,
    pub pose: Pose,
    /// Initial state, e.g. `lid = "open"`: (part, state).
    pub state: Vec<(Spanned<String>, Spanned<String>)>,
}

/// One `[randomise.<name>]` table.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Randomisation {
    pub target: Spanned<String>,
    pub items: Vec<RandomItem>,
}

#[derive(Clone, Debug, PartialEq, Serialize)]
pub enum RandomItem {
    /// Per-joint uniform offsets (radians) added to the robot's home pose.
    Joints {
        low: Spanned<Vec<f64>>,
        high: Spanned<Vec<f64>>,
        span: Span,
    },
    /// Uniform planar offset of a labware position: ± metres in x and y.
    Xy(Spanned<f64>),
    /// Uniform yaw offset: ± radians.
    Yaw(Spanned<f64>),
}

#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Step {
    pub primitive: Option<Spanned<String>>,
    pub on: Option<Spanned<String>>,
    pub with: Option<Spanned<String>>,
    pub span: Span,
}
