//! What the Blender worker is told: the scene once (every drawn geom's shape, finish and body,
//! the meshes, the display textures, the lights and the cameras' fields of view, all read from
//! the render model as the rasteriser draws it), then each frame's poses. It sends nothing and
//! draws nothing.
//!
//! A geom is drawn when the rasteriser draws it: groups 0-2 (MuJoCo's visible groups), not
//! fully transparent, a shape Blender can build (SDF and height-field geoms are collision
//! geometry here). Its colour is the rasteriser's (the material's unless the geom sets its own).

use super::Settings;
use crate::render::Mirror;
use crate::render::masks::{drawn, mask_colour, rgba};
use mujoco_rs::prelude::*;
use serde_json::{Value, json};
use std::collections::BTreeSet;

/// How a surface looks in Blender, read from how the rasteriser draws it: no instrument kind is
/// named here.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Finish {
    /// Translucent in the rasteriser (tubes' walls, windows): glass-like clear plastic.
    Clear,
    /// A liquid's surface disc (`labware::liquid_view`): water.
    Liquid,
    /// An instrument display: its texture, emissive.
    Display,
    /// Pale, unsaturated, and specular by its material (a robot's links): brushed metal.
    Metal,
    /// Near black: rubber (grippers' pads, feet).
    Rubber,
    /// Saturated colours: moulded plastic (caps, racks, knobs).
    Plastic,
    /// Everything else: painted housings.
    Painted,
    /// The bench top: laminate with a faint grain.
    Bench,
}

impl Finish {
    pub fn name(self) -> &'static str {
        match self {
            Finish::Clear => "clear",
            Finish::Liquid => "liquid",
            Finish::Display => "display",
            Finish::Metal => "metal",
            Finish::Rubber => "rubber",
            Finish::Plastic => "plastic",
            Finish::Painted => "painted",
            Finish::Bench => "bench",
        }
    }
}

/// The bench top's geom (`crate::scene`).
const BENCH_GEOM: &str = "table/top";

fn shape_name(t: MjtGeomBase) -> &'static str {
    match t {
        MjtGeomBase::mjGEOM_PLANE => "plane",
        MjtGeomBase::mjGEOM_SPHERE => "sphere",
        MjtGeomBase::mjGEOM_CAPSULE => "capsule",
        MjtGeomBase::mjGEOM_ELLIPSOID => "ellipsoid",
        MjtGeomBase::mjGEOM_CYLINDER => "cylinder",
        MjtGeomBase::mjGEOM_MESH => "mesh",
        _ => "box",
    }
}

/// The texture a geom's material shows, if any.
fn texture(model: &MjModel, g: usize) -> Option<usize> {
    let m = usize::try_from(model.geom_matid()[g]).ok()?;
    model.mat_texid()[m]
        .iter()
        .find_map(|&t| usize::try_from(t).ok())
}

fn finish(model: &MjModel, g: usize, liquids: &BTreeSet<usize>, displays: &[usize]) -> Finish {
    let body = model.geom_bodyid()[g] as usize;
    if liquids.contains(&body) {
        return Finish::Liquid;
    }
    if texture(model, g).is_some_and(|t| displays.contains(&t)) {
        return Finish::Display;
    }
    if model.id_to_name(MjtObjBase::mjOBJ_GEOM, g) == Some(BENCH_GEOM) {
        return Finish::Bench;
    }
    let [r, gr, b, a] = rgba(model, g);
    if a < 0.95 {
        return Finish::Clear;
    }
    let max = r.max(gr).max(b);
    let min = r.min(gr).min(b);
    let saturation = if max > 0.0 { (max - min) / max } else { 0.0 };
    // Only a material asks for shine: a bare geom (walls, housings) is paint.
    let specular = usize::try_from(model.geom_matid()[g])
        .map(|m| model.mat_specular()[m].max(model.mat_reflectance()[m]))
        .unwrap_or(0.0);
    if max < 0.12 {
        Finish::Rubber
    } else if saturation >= 0.25 {
        Finish::Plastic
    } else if specular >= 0.5 && (0.6..=0.92).contains(&max) {
        Finish::Metal
    } else {
        Finish::Painted
    }
}

/// A growing blob with typed parts, each described as `{"offset", "len"}` in bytes.
#[derive(Default)]
pub struct Blob(pub Vec<u8>);

impl Blob {
    pub fn f32s(&mut self, values: impl IntoIterator<Item = f32>) -> Value {
        let offset = self.0.len();
        for v in values {
            self.0.extend_from_slice(&v.to_le_bytes());
        }
        json!({"offset": offset, "len": self.0.len() - offset})
    }

    pub fn u32s(&mut self, values: impl IntoIterator<Item = u32>) -> Value {
        let offset = self.0.len();
        for v in values {
            self.0.extend_from_slice(&v.to_le_bytes());
        }
        json!({"offset": offset, "len": self.0.len() - offset})
    }

    pub fn bytes(&mut self, b: &[u8]) -> Value {
        let offset = self.0.len();
        self.0.extend_from_slice(b);
        json!({"offset": offset, "len": b.len()})
    }
}

/// The scene as drawn: which geoms, cameras and lights Blender was given, in its order.
pub struct Stage {
    pub geoms: Vec<usize>,
    pub cameras: Vec<usize>,
    pub lights: Vec<usize>,
}

impl Stage {
    /// The `scene` request for `mirror`'s model and the task cameras `cameras`.
    pub fn request(
        mirror: &Mirror,
        cameras: &[usize],
        size: [usize; 2],
        settings: &Settings,
    ) -> (Stage, Value, Vec<u8>) {
        let model = mirror.model();
        let liquids: BTreeSet<usize> = mirror.liquid_bodies().collect();
        let displays: Vec<usize> = mirror.display_textures().collect();
        let geoms: Vec<usize> = (0..model.ffi().ngeom as usize)
            .filter(|&g| drawn(model, g))
            .collect();
        let mut blob = Blob::default();
        // Meshes, each once, in first use order.
        let mut meshes: Vec<usize> = Vec::new();
        for &g in &geoms {
            if model.geom_type()[g] == MjtGeomBase::mjGEOM_MESH {
                let m = model.geom_dataid()[g] as usize;
                if !meshes.contains(&m) {
                    meshes.push(m);
                }
            }
        }
        let (mut verts, mut faces, mut mesh_parts) = (Vec::new(), Vec::new(), Vec::new());
        for &m in &meshes {
            let (va, vn) = (
                model.mesh_vertadr()[m] as usize,
                model.mesh_vertnum()[m] as usize,
            );
            let (fa, fnum) = (
                model.mesh_faceadr()[m] as usize,
                model.mesh_facenum()[m] as usize,
            );
            mesh_parts.push(json!({
                "vert": verts.len() / 3, "nvert": vn, "face": faces.len() / 3, "nface": fnum,
            }));
            verts.extend(model.mesh_vert()[va..va + vn].iter().flatten().copied());
            faces.extend(
                model.mesh_face()[fa..fa + fnum]
                    .iter()
                    .flatten()
                    .map(|&i| i as u32),
            );
        }
        let verts_part = blob.f32s(verts);
        let faces_part = blob.u32s(faces);
        let mut textures = Vec::new();
        let mut pixels = Vec::new();
        for t in &displays {
            if let Some((w, h, rgb)) = mirror.display_pixels(*t) {
                textures.push(json!({"id": t, "width": w, "height": h, "offset": pixels.len()}));
                pixels.extend_from_slice(rgb);
            }
        }
        let pixels_part = blob.bytes(&pixels);
        let geom_specs: Vec<Value> = geoms
            .iter()
            .map(|&g| {
                let kind = shape_name(model.geom_type()[g]);
                let mesh = (kind == "mesh")
                    .then(|| {
                        meshes
                            .iter()
                            .position(|&m| m == model.geom_dataid()[g] as usize)
                    })
                    .flatten();
                let finish = finish(model, g, &liquids, &displays);
                json!({
                    "kind": kind,
                    "size": model.geom_size()[g],
                    "mesh": mesh,
                    "rgba": rgba(model, g),
                    "finish": finish.name(),
                    "texture": (finish == Finish::Display).then(|| texture(model, g)).flatten(),
                    "mask": mask_colour(model.geom_bodyid()[g] as usize),
                })
            })
            .collect();
        // The rasteriser's clipping planes: a wrist camera among the fingers sees what it sees.
        let extent = model.stat().extent as f32;
        let (near, far) = (
            model.vis().map.znear * extent,
            model.vis().map.zfar * extent,
        );
        let camera_specs: Vec<Value> = cameras
            .iter()
            .map(|&c| json!({"fovy_deg": model.cam_fovy()[c], "near": near, "far": far}))
            .collect();
        let lights: Vec<usize> = (0..model.ffi().nlight as usize)
            .filter(|&l| model.light_active()[l])
            .collect();
        let light_specs: Vec<Value> = lights
            .iter()
            .map(|&l| {
                let d = model.light_diffuse()[l];
                let peak = d.iter().copied().fold(0.0f32, f32::max).max(1e-6);
                json!({
                    "intensity": (d[0] + d[1] + d[2]) / 3.0,
                    "color": d.map(|c| c / peak),
                    "directional": model.light_type()[l] == MjtLightType::mjLIGHT_DIRECTIONAL,
                })
            })
            .collect();
        let header = json!({
            "op": "scene",
            "settings": settings.describe(),
            "size": size,
            "verts": verts_part,
            "faces": faces_part,
            "pixels": pixels_part,
            "meshes": mesh_parts,
            "textures": textures,
            "geoms": geom_specs,
            "cameras": camera_specs,
            "lights": light_specs,
        });
        (
            Stage {
                geoms,
                cameras: cameras.to_vec(),
                lights,
            },
            header,
            blob.0,
        )
    }

    /// The `frame` request: every drawn geom's, camera's and light's pose in the mirrored
    /// state, the displays redrawn since the last frame, and which cameras to draw.
    pub fn frame(
        &self,
        mirror: &Mirror,
        changed: &[usize],
        draw: &[usize],
        mode: &str,
    ) -> (Value, Vec<u8>) {
        let d = mirror.data();
        let mut blob = Blob::default();
        let pose = |p: [f64; 3], r: [f64; 9]| p.into_iter().chain(r).map(|v| v as f32);
        let geoms = blob.f32s(
            self.geoms
                .iter()
                .flat_map(|&g| pose(d.geom_xpos()[g], d.geom_xmat()[g])),
        );
        let cameras = blob.f32s(
            self.cameras
                .iter()
                .flat_map(|&c| pose(d.cam_xpos()[c], d.cam_xmat()[c])),
        );
        let lights = blob.f32s(self.lights.iter().flat_map(|&l| {
            d.light_xpos()[l]
                .into_iter()
                .chain(d.light_xdir()[l])
                .map(|v| v as f32)
        }));
        let mut textures = Vec::new();
        let mut pixels = Vec::new();
        for t in changed {
            if let Some((w, h, rgb)) = mirror.display_pixels(*t) {
                textures.push(json!({"id": t, "width": w, "height": h, "offset": pixels.len()}));
                pixels.extend_from_slice(rgb);
            }
        }
        let pixels = blob.bytes(&pixels);
        (
            json!({
                "op": "frame",
                "mode": mode,
                "geoms": geoms,
                "cameras": cameras,
                "lights": lights,
                "textures": textures,
                "pixels": pixels,
                "draw": draw,
            }),
            blob.0,
        )
    }
}
