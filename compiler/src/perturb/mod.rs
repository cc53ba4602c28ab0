//! Perturbations: how a task's episodes may vary beyond its own randomisation, along the
//! dimensions robustness studies name (light, materials, camera, image noise, the instruction's
//! wording, the robot's start pose, the layout, distractor items). A task carries them in [`Perturb`] (from its
//! `[perturb]` table, a suite's override or `--perturb`), so they are part of its content hash;
//! [`Task::sample`](crate::Task::sample) draws them per episode into a [`Drawn`] record, each
//! dimension from its own stream of the episode seed, so no draw of the task's own moves and
//! turning one dimension on leaves the others' draws as they were.
//!
//! The visual dimensions (light, material, camera, noise) are only drawn here: the runtime applies
//! them to its render model and frames, never to the simulated model. Language, start pose and
//! layout are applied here, to the instance; distractors are drawn here and built into the scene
//! by the runtime. This module checks nothing about a file (see
//! `lower.rs`) and renders nothing.

mod distractors;
mod draw;
mod language;
mod lower;

pub use distractors::Distractor;
pub(crate) use draw::draw;
pub use draw::{CameraDraw, Drawn, LightDraw, NoiseDraw, Tint};
pub use lower::camera_problem;

/// What a task's perturbations (however they came: its file, a suite, the command line) would
/// break: a camera shake that could lose the work, distractors with no free place (the checks
/// `autobio check` makes of a `[perturb]` table, E0045). Empty when nothing.
pub fn problems(task: &crate::Task) -> Vec<String> {
    let Some(p) = &task.perturb else {
        return Vec::new();
    };
    let mut out: Vec<String> = p
        .camera
        .as_ref()
        .and_then(|c| camera_problem(task, c))
        .into_iter()
        .collect();
    if let Some(d) = &p.distractors
        && d.count[1] > 0
        && distractors::room(task, d) == 0
    {
        out.push(distractors::NO_ROOM.to_string());
    }
    out
}
pub(crate) use lower::{check_paraphrases, lower};

use serde::{Deserialize, Serialize};
use std::fmt;

/// One perturbation dimension.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord, Hash, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Dimension {
    Light,
    Material,
    Camera,
    Noise,
    Language,
    RobotStart,
    Layout,
    Distractors,
}

impl Dimension {
    pub const ALL: [Dimension; 8] = [
        Dimension::Light,
        Dimension::Material,
        Dimension::Camera,
        Dimension::Noise,
        Dimension::Language,
        Dimension::RobotStart,
        Dimension::Layout,
        Dimension::Distractors,
    ];

    pub fn name(self) -> &'static str {
        match self {
            Dimension::Light => "light",
            Dimension::Material => "material",
            Dimension::Camera => "camera",
            Dimension::Noise => "noise",
            Dimension::Language => "language",
            Dimension::RobotStart => "robot_start",
            Dimension::Layout => "layout",
            Dimension::Distractors => "distractors",
        }
    }

    pub fn from_name(name: &str) -> Option<Dimension> {
        Dimension::ALL.into_iter().find(|d| d.name() == name)
    }

    /// Whether the dimension changes only what is seen or read (frames, the instruction), never
    /// the simulation: the expert's trajectory under it is the unperturbed one.
    pub fn leaves_physics(self) -> bool {
        !matches!(
            self,
            Dimension::RobotStart | Dimension::Layout | Dimension::Distractors
        )
    }
}

impl fmt::Display for Dimension {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
    }
}

/// The strengths a preset comes in.
pub const STRENGTHS: [u8; 2] = [1, 2];

/// The perturbations a task's episodes are drawn under; a dimension left `None` is not perturbed.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Perturb {
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub light: Option<Light>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub material: Option<Material>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub camera: Option<CameraShake>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub noise: Option<Noise>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub language: Option<Language>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub robot_start: Option<RobotStart>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub layout: Option<Layout>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub distractors: Option<Distractors>,
}

/// The room's lights: every light's brightness scaled by a factor drawn from `intensity`, its
/// direction tilted by up to `direction_deg`, its colour tinted by up to `colour` per channel
/// (0..1), and `lights` lights on (the ceiling light and up to three more around the room).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Light {
    pub intensity: [f64; 2],
    pub direction_deg: f64,
    pub colour: f64,
    pub lights: [u32; 2],
}

/// The most lights a light perturbation may turn on.
pub const MAX_LIGHTS: u32 = 4;

/// Colours of the named surfaces shifted: hue by up to `hue` turns, saturation and value by up
/// to these fractions, each surface (the bench, the room, each item, each robot) its own draw.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Material {
    pub of: Vec<Surface>,
    pub hue: f64,
    pub saturation: f64,
    pub value: f64,
}

/// What a material perturbation recolours.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Surface {
    Bench,
    Room,
    Labware,
    Robots,
}

impl Surface {
    pub const ALL: [Surface; 4] = [
        Surface::Bench,
        Surface::Room,
        Surface::Labware,
        Surface::Robots,
    ];

    pub fn name(self) -> &'static str {
        match self {
            Surface::Bench => "bench",
            Surface::Room => "room",
            Surface::Labware => "labware",
            Surface::Robots => "robots",
        }
    }
}

/// Each camera moved by up to `shift_m` (a point in a ball), turned by up to `turn_deg` (about
/// an axis in any direction) and its field of view changed by up to `fovy_deg`; `cameras` names
/// which (empty: every task camera).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct CameraShake {
    pub shift_m: f64,
    pub turn_deg: f64,
    pub fovy_deg: f64,
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub cameras: Vec<String>,
}

/// The sensor: Gaussian noise of this standard deviation (a fraction of full scale), a Gaussian
/// blur of this radius (pixels, sigma), and JPEG compression at a quality drawn from
/// `jpeg_quality` (1..100; none when absent).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Noise {
    pub gaussian: f64,
    pub blur_px: f64,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub jpeg_quality: Option<[u8; 2]>,
}

/// The instruction reworded: `rewrite` 1 draws one of the task's paraphrases (`[protocol]
/// paraphrases`), or a framing of the instruction where it has none; 2 also frames a paraphrase
/// and swaps verbs and nouns for synonyms. Deterministic: no language model.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Language {
    pub rewrite: u8,
}

/// Each robot's arm joints start up to `joints_rad` further from home than the task's own jitter.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct RobotStart {
    pub joints_rad: f64,
}

/// Each item standing on its own place (not in a slot or a hand) placed up to `shift_m` further
/// along x and y and turned up to `turn_deg` further than the task's own randomisation moves it
/// (which may be not at all): layouts out of the task's distribution.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Layout {
    pub shift_m: f64,
    pub turn_deg: f64,
}

/// Between `count[0]` and `count[1]` unused racks or blocks (of `kinds`; empty: any) placed on
/// the bench where they block nothing: clear of every item, every robot's base and the straight
/// way from each base to each item (`distractors.rs`).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Distractors {
    pub count: [u32; 2],
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub kinds: Vec<String>,
}

/// The most distractors a perturbation may place.
pub const MAX_DISTRACTORS: u32 = 4;

impl Perturb {
    /// The preset of `dimension` at `strength` (1 mild, 2 strong), alone.
    pub fn preset(dimension: Dimension, strength: u8) -> Perturb {
        let strong = strength >= 2;
        let pick = |mild: f64, hard: f64| if strong { hard } else { mild };
        let mut p = Perturb::default();
        match dimension {
            Dimension::Light => {
                p.light = Some(Light {
                    intensity: if strong { [0.3, 1.8] } else { [0.6, 1.4] },
                    direction_deg: pick(20.0, 45.0),
                    colour: pick(0.1, 0.3),
                    lights: if strong { [1, 3] } else { [1, 2] },
                })
            }
            Dimension::Material => {
                p.material = Some(Material {
                    of: Surface::ALL.to_vec(),
                    hue: pick(0.04, 0.5),
                    saturation: pick(0.2, 0.6),
                    value: pick(0.15, 0.35),
                })
            }
            Dimension::Camera => {
                p.camera = Some(CameraShake {
                    shift_m: pick(0.02, 0.05),
                    turn_deg: pick(2.0, 5.0),
                    fovy_deg: pick(3.0, 6.0),
                    cameras: Vec::new(),
                })
            }
            Dimension::Noise => {
                p.noise = Some(Noise {
                    gaussian: pick(0.02, 0.06),
                    blur_px: pick(0.5, 1.2),
                    jpeg_quality: Some(if strong { [15, 40] } else { [60, 90] }),
                })
            }
            Dimension::Language => {
                p.language = Some(Language {
                    rewrite: if strong { 2 } else { 1 },
                })
            }
            Dimension::RobotStart => {
                p.robot_start = Some(RobotStart {
                    joints_rad: pick(0.03, 0.08),
                })
            }
            Dimension::Layout => {
                p.layout = Some(Layout {
                    shift_m: pick(0.01, 0.025),
                    turn_deg: pick(5.0, 12.0),
                })
            }
            Dimension::Distractors => {
                p.distractors = Some(Distractors {
                    count: if strong { [2, 3] } else { [1, 1] },
                    kinds: Vec::new(),
                })
            }
        }
        p
    }

    /// `self` with every dimension `over` sets replaced by `over`'s: a suite's or the command
    /// line's perturbations over the task's own.
    pub fn overlay(mut self, over: &Perturb) -> Perturb {
        macro_rules! take {
            ($($f:ident),*) => {$(
                if over.$f.is_some() {
                    self.$f = over.$f.clone();
                }
            )*};
        }
        take!(
            light,
            material,
            camera,
            noise,
            language,
            robot_start,
            layout,
            distractors
        );
        self
    }

    /// The dimensions set, in [`Dimension::ALL`] order.
    pub fn dimensions(&self) -> Vec<Dimension> {
        let set = [
            self.light.is_some(),
            self.material.is_some(),
            self.camera.is_some(),
            self.noise.is_some(),
            self.language.is_some(),
            self.robot_start.is_some(),
            self.layout.is_some(),
            self.distractors.is_some(),
        ];
        Dimension::ALL
            .into_iter()
            .zip(set)
            .filter_map(|(d, on)| on.then_some(d))
            .collect()
    }

    pub fn is_empty(&self) -> bool {
        self.dimensions().is_empty()
    }
}

/// A preset named on a command line or in a suite: `light`, `light:2`.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord, Serialize, Deserialize)]
pub struct Preset {
    pub dimension: Dimension,
    pub strength: u8,
}

/// Why a preset's name does not read.
#[derive(Debug, thiserror::Error)]
pub enum PresetError {
    #[error("no perturbation dimension `{0}` (the dimensions: {dims})", dims = dimension_list())]
    Dimension(String),
    #[error("strength `{0}` is not 1 or 2")]
    Strength(String),
}

fn dimension_list() -> String {
    Dimension::ALL.map(Dimension::name).join(", ")
}

impl std::str::FromStr for Preset {
    type Err = PresetError;
    fn from_str(s: &str) -> Result<Preset, PresetError> {
        let (name, strength) = s.split_once(':').unwrap_or((s, "1"));
        let dimension =
            Dimension::from_name(name).ok_or_else(|| PresetError::Dimension(name.into()))?;
        let strength = strength
            .parse::<u8>()
            .ok()
            .filter(|s| STRENGTHS.contains(s))
            .ok_or_else(|| PresetError::Strength(strength.into()))?;
        Ok(Preset {
            dimension,
            strength,
        })
    }
}

impl fmt::Display for Preset {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{}:{}", self.dimension, self.strength)
    }
}

impl Preset {
    pub fn perturb(self) -> Perturb {
        Perturb::preset(self.dimension, self.strength)
    }

    /// Several presets as one perturbation (later ones win a dimension named twice).
    pub fn combine(presets: &[Preset]) -> Perturb {
        presets
            .iter()
            .fold(Perturb::default(), |p, q| p.overlay(&q.perturb()))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_language_and_the_compiler_name_the_same_dimensions() {
        let dsl: Vec<&str> = dsl::perturb_dimensions().collect();
        let ours: Vec<&str> = Dimension::ALL.map(Dimension::name).to_vec();
        assert_eq!(dsl, ours);
    }

    #[test]
    fn presets_read_and_say_what_is_wrong() {
        let p: Preset = "camera:2".parse().unwrap();
        assert_eq!((p.dimension, p.strength), (Dimension::Camera, 2));
        assert_eq!("light".parse::<Preset>().unwrap().strength, 1);
        assert_eq!(p.to_string(), "camera:2");
        assert!(
            "lite:1"
                .parse::<Preset>()
                .unwrap_err()
                .to_string()
                .contains("robot_start")
        );
        assert!("light:3".parse::<Preset>().is_err());
        // Every preset sets exactly its dimension, and the strong one is stronger.
        for d in Dimension::ALL {
            for s in STRENGTHS {
                assert_eq!(Perturb::preset(d, s).dimensions(), vec![d]);
            }
            assert_ne!(Perturb::preset(d, 1), Perturb::preset(d, 2));
        }
        let both = Preset::combine(&["light:1".parse().unwrap(), "light:2".parse().unwrap()]);
        assert_eq!(both, Perturb::preset(Dimension::Light, 2));
    }
}
