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
    /// The render model as the scene built it.
    base: Arc<MjModel>,
    /// Whether the mirror's model is a perturbed copy of `base` ([`Cameras::set_look`]).
    looked: bool,
    /// The renderer's own data: the drawn state, positions computed from its `qpos`, on `base`
    /// or on a perturbed copy of it.
    mirror: MjData<Arc<MjModel>>,
    /// Instrument displays, and a copy of the render model whose texture pixels they are drawn
    /// into (uploads read textures from it; nothing else uses it).
    screens: Vec<Screen>,
    textures: Option<MjModel>,
    /// Items whose liquid is drawn (`labware::liquid_view`).
    liquids: Vec<LiquidView>,
    pub detail: Detail,
    pub width: usize,
    pub height: usize,
}

/// An item whose liquid surface is drawn: its bore, its root body and its discs' mocap indices.
struct LiquidView {
    item: usize,
    bore: physics::liquid::Container,
    root: usize,
    discs: Vec<usize>,
}

/// One instrument display: whose it is, its texture, and the values it was last drawn with.
struct Screen {
    item: usize,
    index: usize,
    model: labware::Model,
    texture: usize,
    width: usize,
    height: usize,
    shows: Vec<String>,
    drawn: Option<Vec<f64>>,
    scratch: Vec<u8>,
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
        let mut screens = Vec::new();
        for (item, ids) in scene.labware.iter().enumerate() {
            let spec = &scene.task().labware[item];
            let Some(instrument) = spec.params.instrument() else {
                continue;
            };
            let displays = instrument.panel().map(|p| p.displays(&spec.name));
            for (index, (d, &texture)) in displays
                .unwrap_or_default()
                .into_iter()
                .zip(&ids.displays)
                .enumerate()
            {
                screens.push(Screen {
                    item,
                    index,
                    model: spec.params.clone(),
                    texture,
                    width: d.width,
                    height: d.height,
                    shows: d.shows,
                    drawn: None,
                    scratch: vec![0; d.width * d.height * 3],
                });
            }
        }
        let mut liquids = Vec::new();
        for (item, ids) in scene.labware.iter().enumerate() {
            let spec = &scene.task().labware[item];
            let Some(instrument) = spec.params.instrument() else {
                continue;
            };
            let Some(liquid) = instrument.liquid() else {
                continue;
            };
            let (bodies, Some(bore)) = (liquid.liquid_bodies(&spec.name), liquid.interior()) else {
                continue;
            };
            let discs: Vec<usize> = bodies
                .iter()
                .filter_map(|b| {
                    let body = model.name_to_id(MjtObjBase::mjOBJ_BODY, b)?;
                    usize::try_from(model.body_mocapid()[body]).ok()
                })
                .collect();
            if !discs.is_empty() {
                liquids.push(LiquidView {
                    item,
                    bore,
                    root: ids.root_body,
                    discs,
                });
            }
        }
        let textures = (!screens.is_empty()).then(|| (*model).clone());
        let mirror = MjData::new(model.clone());
        Ok(Cameras {
            renderer,
            ids: scene.cameras.clone(),
            base: model,
            looked: false,
            mirror,
            screens,
            textures,
            liquids,
            detail,
            width,
            height,
        })
    }

    /// Shows `drawn`'s lights, surface colours and camera poses from the next frame on, on a copy
    /// of the render model (`None`, or a draw with nothing visual: the scene as built). The
    /// simulated model is not touched.
    pub fn set_look(&mut self, scene: &Scene, drawn: Option<&compiler::perturb::Drawn>) {
        let visual =
            drawn.filter(|d| d.light.is_some() || !d.material.is_empty() || !d.camera.is_empty());
        if visual.is_none() && !self.looked {
            return;
        }
        let model = match visual {
            Some(d) => {
                let mut m = (*self.base).clone();
                crate::perturb::apply_look(&mut m, scene, d);
                Arc::new(m)
            }
            None => self.base.clone(),
        };
        self.mirror = MjData::new(model);
        self.looked = visual.is_some();
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

    /// The drawn state made `data`'s: its displays redrawn where they changed, its positions
    /// recomputed from `qpos` and the mocap poses.
    fn mirror_state(
        &mut self,
        data: &MjData<Arc<MjModel>>,
        logic: &[Logic],
    ) -> Result<(), RenderError> {
        self.update_screens(logic)?;
        let m = &mut self.mirror;
        m.qpos_mut().copy_from_slice(data.qpos());
        m.mocap_pos_mut().copy_from_slice(data.mocap_pos());
        m.mocap_quat_mut().copy_from_slice(data.mocap_quat());
        m.kinematics();
        if !self.liquids.is_empty() {
            // Each liquid's surface where its volume stands in the item as drawn.
            for l in &self.liquids {
                let at = labware::frame::pose(
                    m.xpos()[l.root],
                    labware::frame::from_wxyz(m.xquat()[l.root]),
                );
                let ul = logic
                    .get(l.item)
                    .and_then(|g| g.get(labware::process::VOLUME_UL))
                    .copied()
                    .unwrap_or(0.0);
                for (&mocap, disc) in l
                    .discs
                    .iter()
                    .zip(labware::liquid_view::discs(&l.bore, &at, ul))
                {
                    m.mocap_pos_mut()[mocap] = labware::frame::position(&disc);
                    m.mocap_quat_mut()[mocap] = labware::frame::wxyz(&disc.rotation);
                }
            }
            m.kinematics();
        }
        m.camlight();
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
            .sync_data(&mut self.mirror)
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

    /// Redraws and uploads the displays whose shown values changed since they were last drawn.
    fn update_screens(&mut self, logic: &[Logic]) -> Result<(), RenderError> {
        let bad = |why: &str| RenderError::Display(why.to_string());
        let Some(textures) = self.textures.as_mut() else {
            return Ok(());
        };
        for s in &mut self.screens {
            let state = logic
                .get(s.item)
                .ok_or_else(|| bad("no logic state for a display's item"))?;
            let values: Vec<f64> = s
                .shows
                .iter()
                .map(|k| state.get(k).copied().unwrap_or(f64::NAN))
                .collect();
            // NaN never equals itself: compare bit patterns, so an unset value is drawn once.
            let same = s.drawn.as_ref().is_some_and(|d| {
                d.len() == values.len()
                    && d.iter()
                        .zip(&values)
                        .all(|(a, b)| a.to_bits() == b.to_bits())
            });
            if same {
                continue;
            }
            let instrument = s
                .model
                .instrument()
                .ok_or_else(|| bad("a display without a model"))?;
            if let Some(panel) = instrument.panel() {
                panel.draw_display(s.index, state, &mut s.scratch);
            }
            let adr = usize::try_from(textures.tex_adr()[s.texture])
                .map_err(|_| bad("a display texture is not stored in the model"))?;
            let channels = textures.tex_nchannel()[s.texture] as usize;
            let size = (
                textures.tex_width()[s.texture] as usize,
                textures.tex_height()[s.texture] as usize,
            );
            if size != (s.width, s.height) || channels < 3 {
                return Err(RenderError::Display(format!(
                    "display texture is {}x{}x{channels}, the model draws {}x{} RGB",
                    size.0, size.1, s.width, s.height
                )));
            }
            let pixels = &mut textures.tex_data_mut()[adr..adr + s.width * s.height * channels];
            for (dst, src) in pixels
                .chunks_exact_mut(channels)
                .zip(s.scratch.chunks_exact(3))
            {
                dst[..3].copy_from_slice(src);
            }
            self.renderer
                .update_texture_from(textures, s.texture)
                .map_err(|e| RenderError::Display(format!("upload: {e:?}")))?;
            s.drawn = Some(values);
        }
        Ok(())
    }
}
