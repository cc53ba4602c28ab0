//! One episode's perturbations drawn: each dimension from its own ChaCha8 stream of the episode
//! seed (stream 1 + the dimension's place in [`Dimension::ALL`]; the task's own draws are
//! stream 0), recorded in a [`Drawn`] that the instance carries (so recordings and datasets say
//! what each episode saw). The instruction, the start pose and the layout are changed here; the
//! visual draws are only recorded, for the runtime to apply.

use super::{Dimension, Perturb, Surface, language};
use crate::params::{Bindings, uniform};
use crate::{SceneInstance, Task};
use rand_chacha::ChaCha8Rng;
use rand_core::SeedableRng;
use serde::{Deserialize, Serialize};
use std::collections::BTreeMap;

/// What one episode's perturbations drew.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct Drawn {
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub light: Option<LightDraw>,
    /// By surface: `bench`, `room`, an item's or a robot's name.
    #[serde(default, skip_serializing_if = "BTreeMap::is_empty")]
    pub material: BTreeMap<String, Tint>,
    /// By task camera name.
    #[serde(default, skip_serializing_if = "BTreeMap::is_empty")]
    pub camera: BTreeMap<String, CameraDraw>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub noise: Option<NoiseDraw>,
    /// How the instruction was reworded (`paraphrase 2`, `framing 4`, `synonyms`).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub language: Option<String>,
    /// Offsets added to each robot's arm joints (rad), in task order.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub robot_start: Vec<Vec<f64>>,
    /// Offsets added to an item's placement: x, y (m), yaw (rad), by item.
    #[serde(default, skip_serializing_if = "BTreeMap::is_empty")]
    pub layout: BTreeMap<String, [f64; 3]>,
    /// Unused items stood where they block nothing (the runtime builds them into the scene).
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub distractors: Vec<super::Distractor>,
}

impl Drawn {
    /// Whether anything drawn changes what the cameras see.
    pub fn is_visual(&self) -> bool {
        self.light.is_some()
            || !self.material.is_empty()
            || !self.camera.is_empty()
            || self.noise.is_some()
    }
}

/// The lights: brightness factor, tilt about x and y (rad), per-channel colour factors, and how
/// many lights are on.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct LightDraw {
    pub scale: f64,
    pub tilt_rad: [f64; 2],
    pub tint: [f64; 3],
    pub lights: u32,
}

/// A surface's colour change: hue shifted (turns), saturation and value multiplied.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct Tint {
    pub hue: f64,
    pub saturation: f64,
    pub value: f64,
}

/// A camera's change: moved (m, world frame for a fixed camera, the camera's body frame for a
/// wrist camera), turned (a rotation vector, rad, in the same frame), field of view widened (deg).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct CameraDraw {
    pub shift_m: [f64; 3],
    pub turn_rad: [f64; 3],
    pub fovy_deg: f64,
}

/// The sensor's noise for the episode: each frame's own noise comes from the episode seed, the
/// control step and the camera (`runtime::perturb`).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct NoiseDraw {
    pub gaussian: f64,
    pub blur_px: f64,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub jpeg_quality: Option<u8>,
}

/// The share of a camera shake's shift a wrist camera takes.
pub(super) const WRIST_SHIFT: f64 = 0.25;

/// The stream a dimension draws from.
fn stream(seed: u64, d: Dimension) -> ChaCha8Rng {
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let place = Dimension::ALL.iter().position(|x| *x == d).unwrap_or(0);
    rng.set_stream(1 + place as u64);
    rng
}

/// A point uniform in the ball of `radius`.
fn in_ball(rng: &mut ChaCha8Rng, radius: f64) -> [f64; 3] {
    loop {
        let p = [0, 1, 2].map(|_| uniform(rng, -1.0, 1.0));
        if p.iter().map(|x| x * x).sum::<f64>() <= 1.0 {
            return p.map(|x| x * radius);
        }
    }
}

/// A whole number uniform in `[lo, hi]`.
fn whole(rng: &mut ChaCha8Rng, lo: u32, hi: u32) -> u32 {
    let span = f64::from(hi - lo + 1);
    (lo + uniform(rng, 0.0, span) as u32).min(hi)
}

/// Draws `p` for `instance`'s episode and applies the instruction, start-pose and layout draws to
/// it; returns what was drawn.
pub(crate) fn draw(p: &Perturb, task: &Task, instance: &mut SceneInstance) -> Drawn {
    let seed = instance.seed;
    let mut d = Drawn::default();
    if let Some(l) = &p.light {
        let mut rng = stream(seed, Dimension::Light);
        let tilt = l.direction_deg.to_radians();
        d.light = Some(LightDraw {
            scale: uniform(&mut rng, l.intensity[0], l.intensity[1]),
            tilt_rad: [0, 1].map(|_| uniform(&mut rng, -tilt, tilt)),
            tint: [0, 1, 2].map(|_| 1.0 + uniform(&mut rng, -l.colour, l.colour)),
            lights: whole(&mut rng, l.lights[0], l.lights[1]),
        });
    }
    if let Some(m) = &p.material {
        let mut rng = stream(seed, Dimension::Material);
        let mut surfaces: Vec<String> = Vec::new();
        for s in Surface::ALL.into_iter().filter(|s| m.of.contains(s)) {
            match s {
                Surface::Bench | Surface::Room => surfaces.push(s.name().into()),
                Surface::Labware => surfaces.extend(task.labware.iter().map(|l| l.name.clone())),
                Surface::Robots => surfaces.extend(task.robots.iter().map(|r| r.name.clone())),
            }
        }
        for s in surfaces {
            let tint = Tint {
                hue: uniform(&mut rng, -m.hue, m.hue),
                saturation: 1.0 + uniform(&mut rng, -m.saturation, m.saturation),
                value: 1.0 + uniform(&mut rng, -m.value, m.value),
            };
            d.material.insert(s, tint);
        }
    }
    if let Some(c) = &p.camera {
        let mut rng = stream(seed, Dimension::Camera);
        for cam in &task.cameras {
            if !c.cameras.is_empty() && !c.cameras.contains(&cam.name) {
                continue;
            }
            // A wrist camera sits among the fingers: it moves a quarter as far as a fixed one.
            let reach = match cam.mount {
                crate::CameraMount::Wrist { .. } => WRIST_SHIFT * c.shift_m,
                crate::CameraMount::Fixed { .. } => c.shift_m,
            };
            let draw = CameraDraw {
                shift_m: in_ball(&mut rng, reach),
                turn_rad: in_ball(&mut rng, c.turn_deg.to_radians()),
                fovy_deg: uniform(&mut rng, -c.fovy_deg, c.fovy_deg),
            };
            d.camera.insert(cam.name.clone(), draw);
        }
    }
    if let Some(n) = &p.noise {
        let mut rng = stream(seed, Dimension::Noise);
        d.noise = Some(NoiseDraw {
            gaussian: n.gaussian,
            blur_px: n.blur_px,
            jpeg_quality: n.jpeg_quality.map(|[lo, hi]| {
                u8::try_from(whole(&mut rng, u32::from(lo), u32::from(hi))).unwrap_or(hi)
            }),
        });
    }
    if let Some(l) = &p.language {
        let mut rng = stream(seed, Dimension::Language);
        let (said, how) = reword(task, &instance.params, l.rewrite, &mut rng);
        instance.instruction = said.0;
        instance.stage_instructions = said.1;
        d.language = Some(how);
    }
    if let Some(r) = &p.robot_start {
        let mut rng = stream(seed, Dimension::RobotStart);
        for q in &mut instance.robot_q {
            let offsets: Vec<f64> = q
                .iter()
                .map(|_| uniform(&mut rng, -r.joints_rad, r.joints_rad))
                .collect();
            for (qi, o) in q.iter_mut().zip(&offsets) {
                *qi += o;
            }
            d.robot_start.push(offsets);
        }
    }
    if let Some(l) = &p.layout {
        let mut rng = stream(seed, Dimension::Layout);
        let turn = l.turn_deg.to_radians();
        // Every item standing on its own place (not in a slot, not in a hand) moves.
        for (item, placement) in task.labware.iter().zip(&mut instance.labware_placement) {
            if item.at.is_some() || item.held_by.is_some() {
                continue;
            }
            let o = [
                uniform(&mut rng, -l.shift_m, l.shift_m),
                uniform(&mut rng, -l.shift_m, l.shift_m),
                uniform(&mut rng, -turn, turn),
            ];
            let p = labware::frame::position(placement);
            *placement = labware::frame::pose(
                [p[0] + o[0], p[1] + o[1], p[2]],
                placement.rotation * labware::frame::axis_angle([0.0, 0.0, 1.0], o[2]),
            );
            d.layout.insert(item.name.clone(), o);
        }
    }
    // After the layout: distractors keep clear of the items where they now stand.
    if let Some(x) = &p.distractors {
        let mut rng = stream(seed, Dimension::Distractors);
        d.distractors = super::distractors::draw(x, task, instance, &mut rng);
    }
    d
}

/// The task's instruction and each stage's, reworded: the task's paraphrases apply to the task's
/// instruction (and to its one stage's where that says the same); every other stage's is framed.
fn reword(
    task: &Task,
    params: &Bindings,
    rewrite: u8,
    rng: &mut ChaCha8Rng,
) -> ((String, Vec<String>), String) {
    let fill = |t: &str| crate::params::render(t, params).unwrap_or_else(|_| t.to_string());
    let (task_text, how) = language::reword(&task.instruction, &task.paraphrases, rewrite, rng);
    let stages = task
        .stages
        .iter()
        .map(|s| {
            if s.instruction == task.instruction {
                task_text.clone()
            } else {
                language::reword(&s.instruction, &[], rewrite, rng).0
            }
        })
        .map(|t| fill(&t))
        .collect();
    ((fill(&task_text), stages), how)
}
