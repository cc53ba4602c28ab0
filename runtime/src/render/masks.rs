//! Silhouettes: each body of the scene in a flat colour of its own ([`mask_colour`])
//! on black, drawn by the rasteriser from a copy of the render model (no lights, no materials,
//! no multisampling: a pixel is the body at its centre), and the agreement of two such masks
//! body by body (intersection over union). Blender draws the same masks
//! (`blender::Cameras::masks`); the two renderers' silhouettes are compared in tests/photoreal.rs
//! and `autobio bench`.

use super::{Mirror, RenderError};
use crate::scene::Scene;
use labware::Logic;
use mujoco_rs::prelude::*;
use mujoco_rs::renderer::MjRenderer;
use results::Image;
use robots::Detail;
use std::collections::BTreeMap;
use std::sync::Arc;

/// MuJoCo's default geom colour: a geom with a material and this colour shows the material's.
const DEFAULT_RGBA: [f32; 4] = [0.5, 0.5, 0.5, 1.0];

/// A geom's colour as the rasteriser draws it.
pub fn rgba(model: &MjModel, g: usize) -> [f32; 4] {
    let own = model.geom_rgba()[g];
    match usize::try_from(model.geom_matid()[g]) {
        Ok(m) if own == DEFAULT_RGBA => model.mat_rgba()[m],
        _ => own,
    }
}

/// Whether the rasteriser draws geom `g` and Blender can build it.
pub fn drawn(model: &MjModel, g: usize) -> bool {
    let visible_group = (0..3).contains(&model.geom_group()[g]);
    let shape = model.geom_type()[g];
    let buildable = !matches!(shape, MjtGeomBase::mjGEOM_SDF | MjtGeomBase::mjGEOM_HFIELD);
    visible_group && buildable && rgba(model, g)[3] > 0.0
}

/// A body's colour in a silhouette mask: 16 levels a channel, 17 apart, so an 8-bit value
/// rounded either way still names its body (`None` for the background).
pub fn mask_colour(body: usize) -> [u8; 3] {
    let i = body + 1;
    [i % 16, (i / 16) % 16, (i / 256) % 16].map(|v| (v * 17) as u8)
}

/// The body a mask pixel names (`None`: the background, black).
pub fn mask_body(rgb: [u8; 3]) -> Option<usize> {
    let [r, g, b] = rgb.map(|v| ((v as usize + 8) / 17).min(15));
    (r + 16 * g + 256 * b).checked_sub(1)
}

/// The rasteriser's masks of every task camera, in task order, of `data`'s state under the
/// episode's look (its cameras and lights; colours are the masks').
pub fn raster(
    scene: &Scene,
    look: Option<&compiler::perturb::Drawn>,
    data: &MjData<Arc<MjModel>>,
    logic: &[Logic],
    size: [usize; 2],
) -> Result<Vec<Image>, RenderError> {
    let mut model = (*scene.render_model(Detail::Full)?).clone();
    if let Some(d) = look {
        crate::perturb::apply_look(&mut model, scene, d);
    }
    flat(&mut model);
    let mut renderer = MjRenderer::builder()
        .width(size[0] as u32)
        .height(size[1] as u32)
        .rgb(true)
        .depth(false)
        .build(&model)
        .map_err(|e| RenderError::Start(format!("{e:?}")))?;
    renderer.opts_mut().sitegroup = [0; 6];
    let mut mirror = Mirror::new(scene, Arc::new(model));
    mirror.sync(data, logic)?;
    let mut out = Vec::new();
    for (k, &cam) in scene.cameras.iter().enumerate() {
        let name = scene
            .task()
            .cameras
            .get(k)
            .map_or_else(|| format!("camera{k}"), |c| c.name.clone());
        let failed = |why: String| RenderError::Draw {
            camera: name.clone(),
            why,
        };
        renderer.set_camera(MjvCamera::new_fixed(cam));
        renderer
            .sync_data(mirror.data_mut())
            .map_err(|e| failed(format!("sync: {e:?}")))?;
        renderer.render().map_err(|e| failed(format!("{e:?}")))?;
        let rgb = renderer
            .rgb_flat()
            .ok_or_else(|| failed("no RGB".into()))?
            .to_vec();
        out.push(Image {
            camera: name.clone(),
            width: size[0],
            height: size[1],
            rgb,
        });
    }
    Ok(out)
}

/// Every drawn geom in its body's mask colour, lit by an ambient headlight alone.
fn flat(model: &mut MjModel) {
    for g in 0..model.ffi().ngeom as usize {
        let shown = drawn(model, g);
        let c = mask_colour(model.geom_bodyid()[g] as usize).map(|v| v as f32 / 255.0);
        model.geom_rgba_mut()[g] = if shown {
            [c[0], c[1], c[2], 1.0]
        } else {
            [0.0; 4]
        };
        // SAFETY: -1 (no material) is always a valid material id.
        unsafe { model.geom_matid_mut()[g] = -1 };
    }
    for l in 0..model.ffi().nlight as usize {
        model.light_active_mut()[l] = false;
    }
    let vis = model.vis_mut();
    vis.headlight.active = 1;
    vis.headlight.ambient = [1.0; 3];
    vis.headlight.diffuse = [0.0; 3];
    vis.headlight.specular = [0.0; 3];
    vis.quality.offsamples = 0;
}

/// One body's silhouettes in two masks.
#[derive(Clone, Debug, PartialEq)]
pub struct BodyAgreement {
    pub body: usize,
    /// Its pixels in the reference mask and in the other.
    pub reference: usize,
    pub other: usize,
    pub intersection: usize,
    pub iou: f64,
}

/// Each body seen in either mask, by body id: its pixels in each and their intersection over
/// union. The masks must be the same size.
pub fn agreement(reference: &Image, other: &Image) -> Vec<BodyAgreement> {
    let mut count: BTreeMap<usize, [usize; 3]> = BTreeMap::new();
    for (a, b) in reference.rgb.chunks_exact(3).zip(other.rgb.chunks_exact(3)) {
        let a = mask_body([a[0], a[1], a[2]]);
        let b = mask_body([b[0], b[1], b[2]]);
        if let Some(a) = a {
            count.entry(a).or_default()[0] += 1;
        }
        if let Some(b) = b {
            count.entry(b).or_default()[1] += 1;
        }
        if let (Some(a), Some(b)) = (a, b)
            && a == b
        {
            count.entry(a).or_default()[2] += 1;
        }
    }
    count
        .into_iter()
        .map(|(body, [r, o, i])| BodyAgreement {
            body,
            reference: r,
            other: o,
            intersection: i,
            iou: i as f64 / (r + o - i).max(1) as f64,
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_body_has_its_own_mask_colour_and_reads_back_through_rounding() {
        for body in 0..4000 {
            let c = mask_colour(body);
            assert_eq!(mask_body(c), Some(body));
            // An 8-bit value off by a few still names the same body.
            let off = c.map(|v| v.saturating_add(3));
            assert_eq!(mask_body(off), Some(body), "{c:?}");
        }
        assert_eq!(mask_body([0, 0, 0]), None);
        assert_eq!(mask_body([2, 1, 0]), None);
    }
}
