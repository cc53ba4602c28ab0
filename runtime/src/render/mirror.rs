//! The drawn state: a renderer's own copy of the simulated state, on the scene's render model (or
//! a perturbed copy of it), with the instrument displays drawn into texture pixels and each
//! liquid's surface placed where its volume stands. Both renderers draw from it (the rasteriser
//! in [`super::Cameras`], Blender in [`crate::blender`]); it draws nothing itself.
//!
//! Every sync copies the simulated `qpos` and mocap poses and recomputes positions
//! (`mj_kinematics`, `mj_camlight`), whichever the model: a frame shows exactly the state it is
//! reported with, and a replay that sets a recorded state draws the same frame.
//!
//! Displays are retained: a display is redrawn only when a value it shows changes, and
//! [`Mirror::sync`] says which textures changed so a renderer uploads only those.

use super::RenderError;
use crate::scene::Scene;
use labware::Logic;
use mujoco_rs::prelude::*;
use std::sync::Arc;

pub struct Mirror {
    /// The render model as the scene built it.
    base: Arc<MjModel>,
    /// Whether `data`'s model is a perturbed copy of `base` ([`Mirror::set_look`]).
    looked: bool,
    /// The drawn state, positions computed from its `qpos`, on `base` or a perturbed copy.
    data: MjData<Arc<MjModel>>,
    screens: Vec<Screen>,
    /// A copy of the render model whose texture pixels the displays are drawn into.
    textures: Option<MjModel>,
    /// Items whose liquid is drawn (`labware::liquid_view`).
    liquids: Vec<LiquidView>,
}

/// An item whose liquid surface is drawn: its bore, its root body and its discs' mocap indices.
struct LiquidView {
    item: usize,
    bore: physics::liquid::Container,
    root: usize,
    discs: Vec<usize>,
    /// The discs' bodies.
    bodies: Vec<usize>,
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

impl Mirror {
    /// The drawn state of `scene` on `model`, one of its render models.
    pub fn new(scene: &Scene, model: Arc<MjModel>) -> Mirror {
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
            let (discs, bodies): (Vec<usize>, Vec<usize>) = bodies
                .iter()
                .filter_map(|b| {
                    let body = model.name_to_id(MjtObjBase::mjOBJ_BODY, b)?;
                    Some((usize::try_from(model.body_mocapid()[body]).ok()?, body))
                })
                .unzip();
            if !discs.is_empty() {
                liquids.push(LiquidView {
                    item,
                    bore,
                    root: ids.root_body,
                    discs,
                    bodies,
                });
            }
        }
        let textures = (!screens.is_empty()).then(|| (*model).clone());
        Mirror {
            data: MjData::new(model.clone()),
            base: model,
            looked: false,
            screens,
            textures,
            liquids,
        }
    }

    /// Shows `drawn`'s lights, surface colours and camera poses from the next sync on, on a copy
    /// of the render model (`None`, or a draw with nothing visual: the scene as built). The
    /// simulated model is not touched. Whether the drawn model changed.
    pub fn set_look(&mut self, scene: &Scene, drawn: Option<&compiler::perturb::Drawn>) -> bool {
        let visual =
            drawn.filter(|d| d.light.is_some() || !d.material.is_empty() || !d.camera.is_empty());
        if visual.is_none() && !self.looked {
            return false;
        }
        let model = match visual {
            Some(d) => {
                let mut m = (*self.base).clone();
                crate::perturb::apply_look(&mut m, scene, d);
                Arc::new(m)
            }
            None => self.base.clone(),
        };
        self.data = MjData::new(model);
        self.looked = visual.is_some();
        true
    }

    /// The drawn state.
    pub fn data(&self) -> &MjData<Arc<MjModel>> {
        &self.data
    }

    pub fn data_mut(&mut self) -> &mut MjData<Arc<MjModel>> {
        &mut self.data
    }

    /// The model the state is drawn on.
    pub fn model(&self) -> &MjModel {
        self.data.model()
    }

    /// The model whose texture pixels hold the displays as last drawn (`None`: no display).
    pub fn textures(&self) -> Option<&MjModel> {
        self.textures.as_ref()
    }

    /// The bodies that draw liquid surfaces.
    pub fn liquid_bodies(&self) -> impl Iterator<Item = usize> + '_ {
        self.liquids.iter().flat_map(|l| l.bodies.iter().copied())
    }

    /// The display textures (ids in the render model).
    pub fn display_textures(&self) -> impl Iterator<Item = usize> + '_ {
        self.screens.iter().map(|s| s.texture)
    }

    /// The drawn state made `data`'s: its displays redrawn where they changed, its positions
    /// recomputed from `qpos` and the mocap poses. The textures redrawn.
    pub fn sync(
        &mut self,
        data: &MjData<Arc<MjModel>>,
        logic: &[Logic],
    ) -> Result<Vec<usize>, RenderError> {
        let changed = self.update_screens(logic)?;
        let m = &mut self.data;
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
        Ok(changed)
    }

    /// Redraws the displays whose shown values changed since they were last drawn; their
    /// textures.
    fn update_screens(&mut self, logic: &[Logic]) -> Result<Vec<usize>, RenderError> {
        let bad = |why: &str| RenderError::Display(why.to_string());
        let Some(textures) = self.textures.as_mut() else {
            return Ok(Vec::new());
        };
        let mut changed = Vec::new();
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
            s.drawn = Some(values);
            changed.push(s.texture);
        }
        Ok(changed)
    }

    /// Forgets that these display textures were drawn, so the next sync redraws them and says
    /// so: for a renderer that failed to take them (an upload, a Blender request).
    pub fn redraw_displays(&mut self, textures: &[usize]) {
        for s in self
            .screens
            .iter_mut()
            .filter(|s| textures.contains(&s.texture))
        {
            s.drawn = None;
        }
    }

    /// A display texture's pixels as last drawn: width, height and RGB rows (MuJoCo's order).
    pub fn display_pixels(&self, texture: usize) -> Option<(usize, usize, &[u8])> {
        let s = self.screens.iter().find(|s| s.texture == texture)?;
        Some((s.width, s.height, &s.scratch))
    }
}
