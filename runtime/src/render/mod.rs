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
//!
//! Instrument displays are textures the instrument model draws (`labware::Instrument::
//! draw_display`) from its logic state. They are retained: a display is redrawn and uploaded only
//! when a value it shows changes, so a frame costs nothing extra while the panel is unchanged, and
//! a replay that restores the recorded logic draws the same screen.

use crate::scene::Scene;
use labware::Logic;
use mujoco_rs::prelude::*;
use mujoco_rs::renderer::MjRenderer;
use robots::Detail;
use std::sync::Arc;

pub mod masks;
pub mod mirror;
pub use mirror::Mirror;

/// A free camera: where it looks, from how far, and from which direction (degrees, MuJoCo's
/// azimuth and elevation: -90 looks straight down).
#[derive(Clone, Debug, PartialEq)]
pub struct View {
    pub name: String,
    pub lookat: [f64; 3],
    pub distance: f64,
    pub azimuth_deg: f64,
    pub elevation_deg: f64,
}

/// The largest image side drawn with simplified meshes.
pub const SIMPLIFIED_MAX_SIDE: usize = 320;

pub struct Cameras {
    renderer: MjRenderer,
    ids: Vec<usize>,
    /// The drawn state and its displays.
    mirror: Mirror,
    pub detail: Detail,
    pub width: usize,
    pub height: usize,
}

use results::Image;

/// Why cameras could not be made or could not draw a frame. MuJoCo's renderer reports its
/// failures as debug text, kept here as it came.
#[derive(Debug, thiserror::Error)]
pub enum RenderError {
    #[error("cannot prepare the render model: {0}")]
    Model(#[from] crate::SceneError),
    #[error("cannot start the renderer (EGL): {0}")]
    Start(String),
    #[error("cannot draw camera `{camera}`: {why}")]
    Draw { camera: String, why: String },
    #[error("cannot draw an instrument display: {0}")]
    Display(String),
    /// Blender could not draw (`crate::blender::BlenderError`, kept as its source).
    #[error("Blender cannot draw: {0}")]
    Blender(Box<dyn std::error::Error + Send + Sync>),
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
    pub fn new(scene: &Scene, width: usize, height: usize) -> Result<Cameras, RenderError> {
        Self::with_detail(scene, width, height, detail_for(width, height))
    }

    pub fn with_detail(
        scene: &Scene,
        width: usize,
        height: usize,
        detail: Detail,
    ) -> Result<Cameras, RenderError> {
        let model = scene.render_model(detail)?;
        let renderer = MjRenderer::builder()
            .width(width as u32)
            .height(height as u32)
            .rgb(true)
            .depth(false)
            .build(&model)
            .map_err(|e| RenderError::Start(format!("{e:?}")))?;
        Ok(Cameras {
            renderer,
            ids: scene.cameras.clone(),
            mirror: Mirror::new(scene, model),
            detail,
            width,
            height,
        })
    }

    /// Shows `drawn`'s lights, surface colours and camera poses from the next frame on, on a copy
    /// of the render model (`None`, or a draw with nothing visual: the scene as built). The
    /// simulated model is not touched.
    pub fn set_look(&mut self, scene: &Scene, drawn: Option<&compiler::perturb::Drawn>) {
        self.mirror.set_look(scene, drawn);
    }

    /// Renders every camera of the task, in task order, with each item's logic state (`logic`, in
    /// task order) on its displays.
    pub fn render(
        &mut self,
        data: &MjData<Arc<MjModel>>,
        logic: &[Logic],
        names: &[String],
    ) -> Result<Vec<Image>, RenderError> {
        self.mirror_state(data, logic)?;
        let mut out = Vec::with_capacity(self.ids.len());
        for (k, name) in names.iter().enumerate().take(self.ids.len()) {
            let camera = MjvCamera::new_fixed(self.ids[k]);
            out.push(self.draw(camera, name)?);
        }
        Ok(out)
    }

    /// The state of `data` seen from a free camera looking at `view.lookat` (no task camera):
    /// `autobio render`'s view from above.
    pub fn render_view(
        &mut self,
        data: &MjData<Arc<MjModel>>,
        logic: &[Logic],
        view: &View,
    ) -> Result<Image, RenderError> {
        self.mirror_state(data, logic)?;
        let camera = MjvCamera {
            type_: MjtCamera::mjCAMERA_FREE as i32,
            lookat: view.lookat,
            distance: view.distance,
            azimuth: view.azimuth_deg,
            elevation: view.elevation_deg,
            ..MjvCamera::default()
        };
        self.draw(camera, &view.name)
    }

    /// The drawn state made `data`'s, the displays that changed uploaded.
    fn mirror_state(
        &mut self,
        data: &MjData<Arc<MjModel>>,
        logic: &[Logic],
    ) -> Result<(), RenderError> {
        let changed = self.mirror.sync(data, logic)?;
        let uploaded = match self.mirror.textures() {
            Some(textures) => changed
                .iter()
                .try_for_each(|&t| self.renderer.update_texture_from(textures, t)),
            None => Ok(()),
        };
        if let Err(e) = uploaded {
            self.mirror.redraw_displays(&changed);
            return Err(RenderError::Display(format!("upload: {e:?}")));
        }
        Ok(())
    }

    /// One frame of the mirrored state from `camera`.
    fn draw(&mut self, camera: MjvCamera, name: &str) -> Result<Image, RenderError> {
        let failed = |why: String| RenderError::Draw {
            camera: name.to_string(),
            why,
        };
        self.renderer.set_camera(camera);
        self.renderer
            .sync_data(self.mirror.data_mut())
            .map_err(|e| failed(format!("sync: {e:?}")))?;
        self.renderer
            .render()
            .map_err(|e| failed(format!("{e:?}")))?;
        let rgb = self
            .renderer
            .rgb_flat()
            .ok_or_else(|| failed("the renderer produced no RGB".into()))?
            .to_vec();
        Ok(Image {
            camera: name.to_string(),
            width: self.width,
            height: self.height,
            rgb,
        })
    }
}
