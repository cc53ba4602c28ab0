//! The task's cameras whoever draws them: [`Renderer`] names the renderer (MuJoCo's rasteriser,
//! what policies are scored on, or Blender for photoreal datasets) and [`TaskCameras`] is either
//! behind one type, for the environment, replays and pictures. It draws nothing itself
//! (`crate::render`, `crate::blender`).

use crate::render::{Cameras, RenderError, View, detail_for};
use crate::scene::Scene;
use labware::Logic;
use mujoco_rs::prelude::*;
use results::Image;
use robots::Detail;
use std::sync::Arc;

/// Which renderer draws the task cameras: MuJoCo's rasteriser (the default, what policies are
/// scored with) or Blender ([`crate::blender`], a second pass for photoreal datasets).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum Renderer {
    #[default]
    Raster,
    Blender(crate::blender::Settings),
}

impl Renderer {
    /// The renderer and its settings as datasets and recordings name them.
    pub fn describe(&self) -> serde_json::Value {
        match self {
            Renderer::Raster => serde_json::json!({"renderer": "mujoco"}),
            Renderer::Blender(s) => s.describe(),
        }
    }
}

/// The task's cameras, drawn by either renderer.
pub enum TaskCameras {
    Raster(Box<Cameras>),
    Blender(Box<crate::blender::Cameras>),
}

impl TaskCameras {
    /// Cameras at this size; the rasteriser's level of detail follows the size unless `detail`
    /// says (Blender draws the full meshes).
    pub fn new(
        scene: &Scene,
        width: usize,
        height: usize,
        renderer: Renderer,
        detail: Option<Detail>,
    ) -> Result<TaskCameras, RenderError> {
        Ok(match renderer {
            Renderer::Raster => TaskCameras::Raster(Box::new(Cameras::with_detail(
                scene,
                width,
                height,
                detail.unwrap_or_else(|| detail_for(width, height)),
            )?)),
            Renderer::Blender(s) => TaskCameras::Blender(Box::new(crate::blender::Cameras::new(
                scene, width, height, s,
            )?)),
        })
    }

    /// Shows the episode's drawn look from the next frame on.
    pub fn set_look(
        &mut self,
        scene: &Scene,
        drawn: Option<&compiler::perturb::Drawn>,
    ) -> Result<(), RenderError> {
        match self {
            TaskCameras::Raster(c) => {
                c.set_look(scene, drawn);
                Ok(())
            }
            TaskCameras::Blender(c) => c.set_look(scene, drawn),
        }
    }

    /// Every task camera's frame, in task order.
    pub fn render(
        &mut self,
        data: &MjData<Arc<MjModel>>,
        logic: &[Logic],
        names: &[String],
    ) -> Result<Vec<Image>, RenderError> {
        match self {
            TaskCameras::Raster(c) => c.render(data, logic, names),
            TaskCameras::Blender(c) => c.render(data, logic, names),
        }
    }

    /// A free view of the state (the rasteriser only: `autobio render`'s view from above).
    pub fn render_view(
        &mut self,
        data: &MjData<Arc<MjModel>>,
        logic: &[Logic],
        view: &View,
    ) -> Result<Image, RenderError> {
        match self {
            TaskCameras::Raster(c) => c.render_view(data, logic, view),
            TaskCameras::Blender(_) => Err(RenderError::Draw {
                camera: view.name.clone(),
                why: "Blender draws the task's cameras only; free views are the rasteriser's"
                    .into(),
            }),
        }
    }
}
