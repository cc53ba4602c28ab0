//! Photoreal frames: the task's cameras drawn by Blender (Cycles on the CPU with
//! OpenImageDenoise, or Eevee), from the same drawn state as the rasteriser's
//! ([`crate::render::Mirror`]): the same meshes, poses, camera intrinsics and poses, display
//! pixels and liquid surfaces, with physically based finishes (clear plastic, water, brushed
//! metal, paint, plastic, rubber, laminate), an HDR-like room environment and the scene's lights
//! as area and sun lights.
//!
//! Blender runs in a worker process ([`worker`]) from the `bpy` wheel `make setup` installs; a
//! [`Cameras`] owns one worker and builds the scene in it once ([`stage`]), then sends poses
//! per frame. Drawing never touches the simulation: a photoreal frame is a second pass over a
//! state, so the same episode gives the same trajectory whichever renderer draws it.
//!
//! [`Cameras::masks`] draws each body in a flat colour of its own, for the silhouette
//! agreement with the rasteriser ([`crate::render::masks`]).

pub mod stage;
pub mod worker;

use crate::render::{Mirror, RenderError};
use crate::scene::Scene;
use labware::Logic;
use mujoco_rs::prelude::*;
use results::Image;
use robots::Detail;
use stage::Stage;
use std::sync::Arc;
use worker::Worker;
pub use worker::{BlenderError, installed};

/// Blender's render engine.
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum Engine {
    /// The path tracer, on the CPU.
    Cycles,
    /// The rasterising engine (OpenGL; headless through EGL on Mesa here, slow on the CPU).
    Eevee,
}

/// How Blender draws: engine, samples a pixel, the denoiser, threads.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Settings {
    pub engine: Engine,
    pub samples: u32,
    /// OpenImageDenoise after Cycles' samples (Eevee ignores it).
    pub denoise: bool,
    /// Threads Blender renders with (0: one).
    pub threads: usize,
}

impl Default for Settings {
    /// Cycles at 16 samples, denoised: a clean frame at 224x224 (docs/photoreal.md).
    fn default() -> Self {
        Settings {
            engine: Engine::Cycles,
            samples: 16,
            denoise: true,
            threads: 1,
        }
    }
}

impl Settings {
    /// The settings as datasets name them (`meta/autobio.jsonl`).
    pub fn describe(&self) -> serde_json::Value {
        serde_json::json!({
            "renderer": "blender",
            "engine": self.engine,
            "samples": self.samples,
            "denoiser": if self.denoise && self.engine == Engine::Cycles { "openimagedenoise" } else { "none" },
            "threads": self.threads.max(1),
        })
    }
}

/// The task's cameras drawn by Blender.
pub struct Cameras {
    worker: Worker,
    mirror: Mirror,
    stage: Stage,
    ids: Vec<usize>,
    settings: Settings,
    pub width: usize,
    pub height: usize,
}

impl Cameras {
    /// Starts a worker and builds `scene` in it, drawn at `width` x `height` with its full meshes.
    pub fn new(
        scene: &Scene,
        width: usize,
        height: usize,
        settings: Settings,
    ) -> Result<Cameras, RenderError> {
        let model = scene.render_model(Detail::Full)?;
        let mirror = Mirror::new(scene, model);
        let mut worker = Worker::start()?;
        let (stage, header, blob) =
            Stage::request(&mirror, &scene.cameras, [width, height], &settings);
        worker.request(&header, &blob)?;
        Ok(Cameras {
            worker,
            mirror,
            stage,
            ids: scene.cameras.clone(),
            settings,
            width,
            height,
        })
    }

    /// Blender's version, as its worker reported it.
    pub fn blender(&self) -> &str {
        &self.worker.blender
    }

    pub fn settings(&self) -> &Settings {
        &self.settings
    }

    /// Shows `drawn`'s look from the next frame on (as [`crate::render::Cameras::set_look`]): the
    /// scene is built again in the worker when the look changed.
    pub fn set_look(
        &mut self,
        scene: &Scene,
        drawn: Option<&compiler::perturb::Drawn>,
    ) -> Result<(), RenderError> {
        if self.mirror.set_look(scene, drawn) {
            let (stage, header, blob) = Stage::request(
                &self.mirror,
                &self.ids,
                [self.width, self.height],
                &self.settings,
            );
            self.worker.request(&header, &blob)?;
            self.stage = stage;
        }
        Ok(())
    }

    /// Every camera of the task, in task order, as the rasteriser's
    /// [`crate::render::Cameras::render`].
    pub fn render(
        &mut self,
        data: &MjData<Arc<MjModel>>,
        logic: &[Logic],
        names: &[String],
    ) -> Result<Vec<Image>, RenderError> {
        self.draw(data, logic, names, "photo")
    }

    /// Each camera's silhouettes: every drawn body in its own flat colour
    /// ([`crate::render::masks::mask_colour`]) on black, one sample at each pixel's centre.
    pub fn masks(
        &mut self,
        data: &MjData<Arc<MjModel>>,
        logic: &[Logic],
        names: &[String],
    ) -> Result<Vec<Image>, RenderError> {
        self.draw(data, logic, names, "mask")
    }

    /// Every camera drawn in `mode` (`photo` or `mask`), decoded and named in task order.
    fn draw(
        &mut self,
        data: &MjData<Arc<MjModel>>,
        logic: &[Logic],
        names: &[String],
        mode: &str,
    ) -> Result<Vec<Image>, RenderError> {
        let changed = self.mirror.sync(data, logic)?;
        let draw: Vec<usize> = (0..self.ids.len()).collect();
        let (header, blob) = self.stage.frame(&self.mirror, &changed, &draw, mode);
        let (answer, pngs) = match self.worker.request(&header, &blob) {
            Ok(a) => a,
            Err(e) => {
                self.mirror.redraw_displays(&changed);
                return Err(e.into());
            }
        };
        let sizes = answer["sizes"]
            .as_array()
            .filter(|s| s.len() == draw.len())
            .ok_or_else(|| {
                BlenderError::Answer(format!(
                    "{} frames for {} cameras",
                    answer["sizes"],
                    draw.len()
                ))
            })?;
        let mut out = Vec::with_capacity(sizes.len());
        let mut at = 0;
        for (s, name) in sizes.iter().zip(names) {
            let n = s.as_u64().unwrap_or(0) as usize;
            let png = pngs
                .get(at..at + n)
                .ok_or_else(|| BlenderError::Answer("frames longer than the blob".into()))?;
            out.push(decode(name, png)?);
            at += n;
        }
        Ok(out)
    }
}

fn decode(camera: &str, png: &[u8]) -> Result<Image, RenderError> {
    Image::from_png(camera, png).map_err(|e| {
        RenderError::from(BlenderError::Answer(format!(
            "a frame that is not a PNG: {e}"
        )))
    })
}
