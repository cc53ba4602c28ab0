//! `autobio bench --only photoreal`: Blender's frames/s at 224x224 on one scene (every task
//! camera, one control step between frame sets), with Cycles on the CPU at 8, 16 and 32 samples
//! denoised and at 16 without the denoiser, and with Eevee (headless on Mesa's software OpenGL
//! here) at 16, each as a ratio of the rasteriser's full-detail rate measured in the same run;
//! and the two renderers' silhouette agreement on the scene's start (the least IoU of a visible
//! body). Blender's threads are the machine's cores.

use anyhow::Result;
use runtime::blender::{self, Engine, Settings};
use std::sync::Arc;
use std::time::Instant;

/// Blender's settings measured, with the frame sets timed for each (the first is not: it warms
/// the scene and, for Eevee, compiles its shaders).
const RUNS: [(Engine, u32, bool, usize); 5] = [
    (Engine::Cycles, 8, true, 3),
    (Engine::Cycles, 16, true, 3),
    (Engine::Cycles, 32, true, 2),
    (Engine::Cycles, 16, false, 3),
    (Engine::Eevee, 16, false, 1),
];

pub(crate) fn figures(task: &compiler::Task) -> Result<()> {
    if !blender::installed() {
        outln!(
            "photoreal (skipped: no Blender at {}; `make setup` installs it)",
            blender::worker::python().display()
        );
        return Ok(());
    }
    let instance = task.sample(0);
    let scene = Arc::new(runtime::Scene::build(task, &instance)?);
    let names: Vec<String> = task.cameras.iter().map(|c| c.name.clone()).collect();
    let mut ep = runtime::Episode::new(scene.clone(), task, &instance);
    let size = [224, 224];
    // The rasteriser at full detail (Blender draws the full meshes), 20 frame sets.
    let mut raster =
        runtime::render::Cameras::with_detail(&scene, size[0], size[1], robots::Detail::Full)?;
    raster.render(&ep.data, ep.logic(), &names)?;
    let t = Instant::now();
    for _ in 0..20 {
        ep.control_step()?;
        raster.render(&ep.data, ep.logic(), &names)?;
    }
    let raster_rate = (20 * names.len()) as f64 / t.elapsed().as_secs_f64();
    outln!(
        "photoreal {} ({} cameras at 224x224); the rasteriser at full detail: {raster_rate:.1} frames/s",
        task.id,
        names.len()
    );
    let threads = std::thread::available_parallelism().map_or(1, |n| n.get());
    for (engine, samples, denoise, sets) in RUNS {
        let settings = Settings {
            engine,
            samples,
            denoise,
            threads,
        };
        let mut cams = blender::Cameras::new(&scene, size[0], size[1], settings)?;
        cams.render(&ep.data, ep.logic(), &names)?;
        let t = Instant::now();
        for _ in 0..sets {
            ep.control_step()?;
            cams.render(&ep.data, ep.logic(), &names)?;
        }
        let rate = (sets * names.len()) as f64 / t.elapsed().as_secs_f64();
        outln!(
            "photoreal {:<6} {samples:>3} samples {:<9} {rate:>8.3} frames/s   ratio {:.4}x the rasteriser ({:.2} s a frame, {threads} threads)",
            format!("{engine:?}").to_lowercase(),
            if denoise { "denoised" } else { "raw" },
            rate / raster_rate,
            1.0 / rate
        );
    }
    let raster_masks = runtime::render::masks::raster(&scene, None, &ep.data, ep.logic(), size)?;
    let mut cams = blender::Cameras::new(
        &scene,
        size[0],
        size[1],
        Settings {
            samples: 1,
            denoise: false,
            threads,
            ..Settings::default()
        },
    )?;
    let drawn = cams.masks(&ep.data, ep.logic(), &names)?;
    let mut worst = (1.0f64, String::new());
    let mut bodies = 0;
    for (r, b) in raster_masks.iter().zip(&drawn) {
        for a in runtime::render::masks::agreement(r, b) {
            if a.reference.max(a.other) >= 50 {
                bodies += 1;
                if a.iou < worst.0 {
                    worst = (a.iou, r.camera.clone());
                }
            }
        }
    }
    outln!(
        "photoreal silhouettes  least IoU {:.4} over {bodies} visible bodies (camera {}; target >= 0.95)",
        worst.0,
        worst.1
    );
    Ok(())
}
