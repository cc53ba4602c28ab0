//! Photoreal frames (runtime/src/blender): Blender draws the same state as the rasteriser.

use crate::common;
use runtime::blender::{self, Settings};
use runtime::render::masks;
use std::sync::Arc;

/// The worst agreement of a visible body between the two renderers' silhouettes of `path`'s
/// seed-0 start, camera by camera, printing every body's.
fn silhouettes(path: &str, size: [usize; 2]) -> Vec<(String, String, f64, usize)> {
    let task = common::compile(path);
    let instance = task.sample(0);
    let scene = Arc::new(runtime::Scene::build(&task, &instance).unwrap());
    let ep = runtime::Episode::new(scene.clone(), &task, &instance);
    let names: Vec<String> = task.cameras.iter().map(|c| c.name.clone()).collect();
    let raster = masks::raster(&scene, None, &ep.data, ep.logic(), size).unwrap();
    let settings = Settings {
        samples: 4,
        ..Settings::default()
    };
    let mut cams = blender::Cameras::new(&scene, size[0], size[1], settings).unwrap();
    let drawn = cams.masks(&ep.data, ep.logic(), &names).unwrap();
    let photo = cams.render(&ep.data, ep.logic(), &names).unwrap();
    let dir = common::scratch("photoreal");
    let mut out = Vec::new();
    for ((r, b), p) in raster.iter().zip(&drawn).zip(&photo) {
        let stem = format!("{}_{}", task.id, r.camera.replace('/', "_"));
        std::fs::write(dir.join(format!("{stem}_raster.png")), r.to_png().unwrap()).unwrap();
        std::fs::write(dir.join(format!("{stem}_blender.png")), b.to_png().unwrap()).unwrap();
        std::fs::write(dir.join(format!("{stem}_photo.png")), p.to_png().unwrap()).unwrap();
        for a in masks::agreement(r, b) {
            let name = scene
                .model
                .id_to_name(mujoco_rs::prelude::MjtObjBase::mjOBJ_BODY, a.body)
                .unwrap_or("?")
                .to_string();
            eprintln!(
                "{} {} {name}: {:.4} ({} / {} px)",
                task.id, r.camera, a.iou, a.reference, a.other
            );
            out.push((r.camera.clone(), name, a.iou, a.reference));
        }
    }
    eprintln!("pictures in {}", dir.display());
    out
}

#[test]
fn blender_draws_every_body_where_the_rasteriser_does() {
    for path in [
        "protocols/thermal_cycler/close_lid.toml",
        "protocols/tube/transfer.toml",
    ] {
        silhouettes(path, [224, 224]);
    }
}
