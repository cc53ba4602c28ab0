//! Headless camera rendering (EGL on Mesa, no window): one renderer per episode thread, switched
//! between the task's cameras. Images are 8-bit RGB, row-major, top row first.
//!
//! Level of detail follows the image size: up to [`SIMPLIFIED_MAX_SIDE`] pixels a side the robots
//! are drawn with their simplified visual meshes (`robots::lod`), larger images with the full
//! ones. The simplified model never simulates.
//!
//! Every frame copies the simulated `qpos` and mocap poses into the renderer's own data and
//! recomputes positions (`mj_kinematics`, `mj_camlight`), whichever the model: a frame shows
//! exactly the state it is reported with (after `mj_step` the simulated data's positions are
//! those of the state before the last integration), and a replay that sets a recorded state
//! draws the same frame.

use crate::scene::Scene;
use mujoco_rs::prelude::*;
use mujoco_rs::renderer::MjRenderer;
use robots::Detail;
use std::sync::Arc;

/// The largest image side drawn with simplified meshes.
pub const SIMPLIFIED_MAX_SIDE: usize = 320;

pub struct Cameras {
    renderer: MjRenderer,
    ids: Vec<usize>,
    /// The renderer's own data: the drawn state, positions computed from its `qpos`.
    mirror: MjData<Arc<MjModel>>,
    pub detail: Detail,
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

impl Image {
    /// The frame as PNG (fast compression; the same pixels always give the same bytes).
    pub fn to_png(&self) -> std::io::Result<Vec<u8>> {
        let mut out = Vec::with_capacity(self.rgb.len() / 2);
        let mut enc = png::Encoder::new(&mut out, self.width as u32, self.height as u32);
        enc.set_color(png::ColorType::Rgb);
        enc.set_depth(png::BitDepth::Eight);
        enc.set_compression(png::Compression::Fast);
        let mut w = enc.write_header().map_err(std::io::Error::other)?;
        w.write_image_data(&self.rgb)
            .map_err(std::io::Error::other)?;
        w.finish().map_err(std::io::Error::other)?;
        Ok(out)
    }

    /// An 8-bit RGB PNG as a frame of `camera`.
    pub fn from_png(camera: &str, png_bytes: &[u8]) -> std::io::Result<Image> {
        let mut dec = png::Decoder::new(std::io::Cursor::new(png_bytes))
            .read_info()
            .map_err(std::io::Error::other)?;
        let info = dec.info();
        let (width, height) = (info.width as usize, info.height as usize);
        if (info.color_type, info.bit_depth) != (png::ColorType::Rgb, png::BitDepth::Eight) {
            return Err(std::io::Error::other("not an 8-bit RGB PNG"));
        }
        let mut rgb = vec![0; width * height * 3];
        dec.next_frame(&mut rgb).map_err(std::io::Error::other)?;
        Ok(Image {
            camera: camera.to_string(),
            width,
            height,
            rgb,
        })
    }
}

/// The level of detail for an image of this size.
pub fn detail_for(width: usize, height: usize) -> Detail {
    if width.max(height) <= SIMPLIFIED_MAX_SIDE {
        Detail::Simplified
    } else {
        Detail::Full
    }
}

impl Cameras {
    /// Cameras at this size, with the level of detail the size calls for.
    pub fn new(scene: &Scene, width: usize, height: usize) -> Result<Cameras, String> {
        Self::with_detail(scene, width, height, detail_for(width, height))
    }

    pub fn with_detail(
        scene: &Scene,
        width: usize,
        height: usize,
        detail: Detail,
    ) -> Result<Cameras, String> {
        let model = scene.render_model(detail).map_err(|e| e.to_string())?;
        let renderer = MjRenderer::builder()
            .width(width as u32)
            .height(height as u32)
            .rgb(true)
            .depth(false)
            .build(&model)
            .map_err(|e| format!("cannot start the renderer: {e:?}"))?;
        let mirror = MjData::new(model);
        Ok(Cameras {
            renderer,
            ids: scene.cameras.clone(),
            mirror,
            detail,
            width,
            height,
        })
    }

    /// Renders every camera of the task, in task order.
    pub fn render(
        &mut self,
        data: &MjData<Arc<MjModel>>,
        names: &[String],
    ) -> Result<Vec<Image>, String> {
        let m = &mut self.mirror;
        m.qpos_mut().copy_from_slice(data.qpos());
        m.mocap_pos_mut().copy_from_slice(data.mocap_pos());
        m.mocap_quat_mut().copy_from_slice(data.mocap_quat());
        m.kinematics();
        m.camlight();
        let mut out = Vec::with_capacity(self.ids.len());
        for (k, &id) in self.ids.iter().enumerate() {
            self.renderer.set_camera(MjvCamera::new_fixed(id));
            self.renderer
                .sync_data(&mut self.mirror)
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
