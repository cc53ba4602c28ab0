//! The protocol AST: what a file says, with a span on everything a diagnostic may point at.
//! Names are not resolved here (see the compiler); fixed quantities are already in canonical units,
//! while values that may hold `{param}` placeholders stay as written ([`Scalar`]).

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

/// A TOML scalar kept as written, for values the compiler interprets (step arguments, parameter
/// choices, initial states).
#[derive(Clone, Debug, PartialEq, Serialize)]
#[serde(untagged)]
pub enum Scalar {
    Str(String),
    Int(i64),
    Float(f64),
    Bool(bool),
}

impl Scalar {
    /// The value as text, as it is substituted into templates.
    pub fn text(&self) -> String {
        match self {
            Scalar::Str(s) => s.clone(),
            Scalar::Int(i) => i.to_string(),
            Scalar::Float(f) => f.to_string(),
            Scalar::Bool(b) => b.to_string(),
        }
    }
}

/// A file is either one protocol or a chain of protocols.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub enum Document {
    Protocol(Box<Protocol>),
    // Boxed too: both are large and a document is made once per file.
    Chain(Box<Chain>),
    /// A scene file (`[scene]`): robots, labware, randomisation and camera that protocols share
    /// with `scene = "<file>"`. Only those tables of the protocol are filled.
    Scene(Box<Protocol>),
}

#[derive(Clone, Debug, Default, PartialEq, Serialize)]
pub struct Protocol {
    pub format: Option<Spanned<i64>>,
    /// `scene = "<file>"`: the scene file whose robots, labware, randomisation and camera this
    /// protocol stands in (the compiler reads it and merges it in, see `compiler::scene_file`).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub scene: Option<Spanned<String>>,
    pub meta: Meta,
    pub robots: Vec<Robot>,
    pub labware: Vec<Labware>,
    pub params: Vec<Param>,
    pub randomise: Vec<Randomisation>,
    pub steps: Vec<Step>,
    pub success: Success,
    /// `[tolerances]`: name -> quantity as written (the compiler checks its dimension).
    pub tolerances: Vec<(Spanned<String>, Spanned<String>)>,
    /// `[camera]`: where the fixed camera stands, when not at the bench's default.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub camera: Option<Camera>,
    /// `[perturb]`: how episodes vary beyond the task's own randomisation (docs/robustness.md).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub perturb: Option<Perturb>,
}

/// The `[perturb]` table: one entry per dimension, as written. Which dimensions and fields
/// exist, and their units, is the parser's; ranges and names are checked by the compiler.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Perturb {
    pub dimensions: Vec<PerturbDimension>,
    pub span: Span,
}

/// One dimension (`light = 2`, `camera = { shift_m = 0.02 }`).
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct PerturbDimension {
    pub name: Spanned<String>,
    pub setting: PerturbSetting,
}

#[derive(Clone, Debug, PartialEq, Serialize)]
pub enum PerturbSetting {
    /// `light = 2`: the dimension's preset of that strength.
    Strength(Spanned<i64>),
    /// `light = { ... }`: its fields given (those not given are the strength-1 preset's).
    Fields(Vec<PerturbField>),
}

/// One field of a dimension: its base name (the unit suffix taken off) and value, in canonical
/// units (metres, radians).
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct PerturbField {
    pub key: Spanned<String>,
    pub value: Spanned<PerturbValue>,
}

#[derive(Clone, Debug, PartialEq, Serialize)]
pub enum PerturbValue {
    Number(f64),
    /// `[low, high]`.
    Range([f64; 2]),
    Texts(Vec<Spanned<String>>),
}

/// The `[camera]` table: the fixed camera's position and the point it looks at (metres, world
/// frame) and its vertical field of view (radians).
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Camera {
    pub pos: Option<Spanned<[f64; 3]>>,
    pub look_at: Option<Spanned<[f64; 3]>>,
    pub fovy: Option<Spanned<f64>>,
    pub span: Span,
}

#[derive(Clone, Debug, Default, PartialEq, Serialize)]
pub struct Meta {
    pub id: Option<Spanned<String>>,
    pub version: Option<Spanned<i64>>,
    pub level: Option<Spanned<String>>,
    pub instruction: Option<Spanned<String>>,
    /// Seconds.
    pub time_limit: Option<Spanned<f64>>,
    /// Span of the `[protocol]` (or `[chain]`) header, or of the file's start when it is missing.
    pub span: Span,
    /// `imported_from = { file, format, sha256 }`: the file `autobio import` wrote this protocol
    /// from (docs/import.md).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub imported_from: Option<ImportedFrom>,
    /// `paraphrases = [..]`: other wordings of the instruction, with the same placeholders, that
    /// the `language` perturbation draws from.
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub paraphrases: Vec<Spanned<String>>,
}

/// Where an imported protocol came from: the source file's name, its format (as `autobio import`
/// names it) and the SHA-256 of its bytes (64 hex digits).
#[derive(Clone, Debug, Default, PartialEq, Serialize)]
pub struct ImportedFrom {
    pub file: String,
    pub format: String,
    pub sha256: String,
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
    /// Where a movable item starts: `"<holder>.<slot>"`, may use placeholders.
    pub at: Option<Spanned<String>>,
    /// The robot whose hand holds the item at the start (a pipette in the pipetting hand).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub held_by: Option<Spanned<String>>,
    /// Initial state, e.g. `lid = "open"`, `volume = "1 mL"`, `speed = "900 rpm"`: (key, value).
    pub state: Vec<(Spanned<String>, Spanned<Scalar>)>,
    /// Where each loose part that starts apart from the item lies (`parts = { cap = { pos_m =
    /// [..] } }`, with `state = { cap = "apart" }`): (part, pose).
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub parts: Vec<(Spanned<String>, Pose)>,
}

/// One `[params.<name>]` table: a value drawn per episode.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Param {
    pub name: Spanned<String>,
    pub domain: Option<ParamDomain>,
    /// Values never drawn; may be `{other}` placeholders naming earlier parameters.
    pub exclude: Vec<Spanned<Scalar>>,
    pub span: Span,
}

#[derive(Clone, Debug, PartialEq, Serialize)]
pub enum ParamDomain {
    /// One of the listed values, uniformly.
    Choice(Vec<Spanned<Scalar>>),
    /// An integer in `[low, high]` (inclusive) on a grid of `step`.
    Int {
        low: Spanned<i64>,
        high: Spanned<i64>,
        step: Option<Spanned<i64>>,
    },
    /// A real quantity, uniform in `[low, high]` (both as written, same dimension).
    Real {
        low: Spanned<String>,
        high: Spanned<String>,
    },
    /// A slot of a holder; `free` excludes slots occupied at the start; `opposite` makes it the
    /// slot across the rotor from another parameter's slot.
    Slot {
        of: Spanned<String>,
        free: bool,
        opposite: Option<Spanned<String>>,
        /// With `opposite` (or its spelling `balances`): the rotor load it balances has this
        /// many tubes, evenly spaced; the slot is the next of them after `opposite`'s (2, the
        /// default: the slot across).
        #[serde(skip_serializing_if = "Option::is_none")]
        tubes: Option<Spanned<i64>>,
    },
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
    /// Where a labware item's loose parts that start apart lie: uniformly in a disc of this
    /// radius (m) about each one's `parts` pose.
    PartsRadius(Spanned<f64>),
    /// Uniform offsets of a labware item's joints, by role: ± radians (a rotor's start angle).
    LabwareJoints {
        joints: Vec<(Spanned<String>, Spanned<f64>)>,
        span: Span,
    },
}

#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Step {
    pub primitive: Option<Spanned<String>>,
    pub with: Option<Spanned<String>>,
    /// `together = true`: the step starts with the step before it, on another robot.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub together: Option<Spanned<bool>>,
    /// Every other key of the step (`on`, `to`, `volume`, ...), as written.
    pub args: Vec<(Spanned<String>, Spanned<Scalar>)>,
    pub span: Span,
    /// A loop (no `do` of its own): run `body` this many times.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub repeat: Option<Spanned<i64>>,
    /// A loop (no `do` of its own): run `body` once per value, the loop variables (`{tube}`)
    /// standing for their values in its steps' arguments; several variables step together.
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub for_each: Vec<(Spanned<String>, Spanned<LoopValues>)>,
    /// A loop's steps (`[[steps.body]]`), loops among them.
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub body: Vec<Step>,
    /// `id = "into_block"`: a name later steps time themselves from (`after`).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub id: Option<Spanned<String>>,
    /// `within = "45 s"`: the step's outcome must come at most this long after the outcome of
    /// the step `after` names (the step before, without `after`), on the episode's clock.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub within: Option<Spanned<String>>,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub after: Option<Spanned<String>>,
}

/// What a `for_each` variable runs over.
#[derive(Clone, Debug, PartialEq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum LoopValues {
    /// The values listed, in order.
    List(Vec<Spanned<Scalar>>),
    /// Every slot of a holder (`"rack.slots"`), in the holder's order.
    Slots(String),
}

impl Step {
    /// Whether the step is a loop (`repeat` or `for_each` over a `body`).
    pub fn is_loop(&self) -> bool {
        self.repeat.is_some() || !self.for_each.is_empty() || !self.body.is_empty()
    }
}

impl Step {
    pub fn arg(&self, name: &str) -> Option<&Spanned<Scalar>> {
        self.args
            .iter()
            .find(|(k, _)| k.value == name)
            .map(|(_, v)| v)
    }
}

#[derive(Clone, Debug, Default, PartialEq, Serialize)]
pub struct Success {
    /// Predicates that must all hold.
    pub all: Vec<Spanned<String>>,
    /// `binary` (default) or `progress`.
    pub scoring: Option<Spanned<String>>,
    /// One weight per predicate, for progress scoring.
    pub weights: Option<Spanned<Vec<f64>>>,
    /// How long every predicate must go on holding before the stage counts as done (s).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub settle: Option<Spanned<f64>>,
    pub span: Span,
}

/// A chain file: protocols run one after another on the first one's scene.
#[derive(Clone, Debug, Default, PartialEq, Serialize)]
pub struct Chain {
    pub format: Option<Spanned<i64>>,
    pub meta: Meta,
    pub stages: Vec<StageRef>,
}

#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct StageRef {
    /// Path of the protocol file, relative to the chain file.
    pub protocol: Option<Spanned<String>>,
    /// Overrides the protocol's instruction for this stage.
    pub instruction: Option<Spanned<String>>,
    /// Overrides the protocol's time limit (seconds).
    pub time_limit: Option<Spanned<f64>>,
    pub span: Span,
}

impl Protocol {
    /// Moves every span of the scene's tables (robots, labware, randomisation, camera) `by` bytes
    /// on: a scene file's tables merged into a protocol point past the protocol's own text, where
    /// the compiler maps them back to the scene file.
    pub fn shift_scene_spans(&mut self, by: usize) {
        let s = |span: &mut Span| {
            span.start += by;
            span.end += by;
        };
        fn pose(p: &mut Pose, s: &impl Fn(&mut Span)) {
            if let Some(x) = &mut p.pos {
                s(&mut x.span);
            }
            if let Some(x) = &mut p.yaw {
                s(&mut x.span);
            }
        }
        for r in &mut self.robots {
            s(&mut r.name.span);
            if let Some(m) = &mut r.model {
                s(&mut m.span);
            }
            pose(&mut r.base, &s);
        }
        for l in &mut self.labware {
            s(&mut l.name.span);
            if let Some(k) = &mut l.kind {
                s(&mut k.span);
            }
            pose(&mut l.pose, &s);
            if let Some(a) = &mut l.at {
                s(&mut a.span);
            }
            for (k, v) in &mut l.state {
                s(&mut k.span);
                s(&mut v.span);
            }
            for (k, p) in &mut l.parts {
                s(&mut k.span);
                pose(p, &s);
            }
        }
        for r in &mut self.randomise {
            s(&mut r.target.span);
            for item in &mut r.items {
                match item {
                    RandomItem::Joints { low, high, span } => {
                        s(&mut low.span);
                        s(&mut high.span);
                        s(span);
                    }
                    RandomItem::Xy(x) | RandomItem::Yaw(x) | RandomItem::PartsRadius(x) => {
                        s(&mut x.span)
                    }
                    RandomItem::LabwareJoints { joints, span } => {
                        for (k, v) in joints {
                            s(&mut k.span);
                            s(&mut v.span);
                        }
                        s(span);
                    }
                }
            }
        }
        if let Some(c) = &mut self.camera {
            for x in [&mut c.pos, &mut c.look_at].into_iter().flatten() {
                s(&mut x.span);
            }
            if let Some(f) = &mut c.fovy {
                s(&mut f.span);
            }
            s(&mut c.span);
        }
        if let Some(p) = &mut self.perturb {
            s(&mut p.span);
            for d in &mut p.dimensions {
                s(&mut d.name.span);
                match &mut d.setting {
                    PerturbSetting::Strength(x) => s(&mut x.span),
                    PerturbSetting::Fields(fields) => {
                        for f in fields {
                            s(&mut f.key.span);
                            s(&mut f.value.span);
                            if let PerturbValue::Texts(texts) = &mut f.value.value {
                                for t in texts {
                                    s(&mut t.span);
                                }
                            }
                        }
                    }
                }
            }
        }
    }
}
