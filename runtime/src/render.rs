//! Headless camera rendering (EGL on Mesa, no window): one renderer per episode thread, switched
//! between the task's cameras. Images are 8-bit RGB, row-major, top row first.

use crate::scene::Scene;
use mujoco_rs::prelude::*;
use mujoco_rs::renderer::MjRenderer;
use std::sync::Arc;

pub struct Cameras {
    renderer: MjRenderer,
    ids: Vec<usize>,
    pub width: usize,
    pub height: usize,
}

/// One rendered frame.
#[derive(Clone, Debug, PartialEq)]
pub struct Image {
    pub camera: String,
    pub width: usize,
    pub height: usize,
    pub rgb: Vec<u8>,
}

impl Cameras {
    pub fn new(scene: &Scene, width: usize, height: usize) -> Result<Cameras, String> {
        let renderer = MjRenderer::builder()
            .width(width as u32)
            .height(height as u32)
            .rgb(true)
            .depth(false)
            .build(&scene.model)
            .map_err(|e| format!("cannot start the renderer: {e:?}"))?;
        Ok(Cameras {
            renderer,
            ids: scene.cameras.clone(),
            width,
            height,
        })
    }

    /// Renders every camera of the task, in task order.
    pub fn render(
        &mut self,
        data: &mut MjData<Arc<MjModel>>,
        names: &[String],
    ) -> Result<Vec<Image>, String> {
        let mut out = Vec::with_capacity(self.ids.len());
        for (k, &id) in self.ids.iter().enumerate() {
            self.renderer.set_camera(MjvCamera::new_fixed(id));
            self.renderer
                .sync_data(data)
                .map_err(|e| format!("render sync failed: {e:?}"))?;
            self.renderer
                .render()
                .map_err(|e| format!("render failed: {e:?}"))?;
            let rgb = self
                .renderer
                .rgb_flat()
                .ok_or("renderer produced no rgb")?
                .to_vec();
            out.push(Image {
                camera: names[k].clone(),
                width: self.width,
                height: self.height,
                rgb,
            });
        }
        Ok(out)
    }
}
