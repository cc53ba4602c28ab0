//! A seed's initial scene as pictures, without running an episode: every task camera and a view
//! from above that frames every robot base and item (`autobio render`), so that an author sees
//! what a seed draws before waiting on an evaluation; rows of such pictures stacked (a clean
//! scene over its perturbed self). It reads the instance the seed draws and draws; it steps
//! nothing.

use crate::env::{Env, EnvError, EnvOptions};
use crate::render::View;
use compiler::Task;
use results::Image;

/// The task cameras' frames of episode `seed` at its start, then the view from above, each
/// `size` (width, height).
pub fn initial_scene(task: &Task, seed: u64, size: [usize; 2]) -> Result<Vec<Image>, EnvError> {
    let mut env = Env::make(
        task,
        seed,
        EnvOptions {
            image_size: Some(size),
            ..Default::default()
        },
    )?;
    let mut images = env.frames()?.to_vec();
    let view = from_above(task, &env);
    images.push(env.view(&view)?);
    Ok(images)
}

/// Straight down (nearly: -89 degrees keeps MuJoCo's up vector defined) at the middle of every
/// robot base and item, from far enough that the widest of them fits a 45 degree field of view.
fn from_above(task: &Task, env: &Env) -> View {
    let mut points: Vec<[f64; 3]> = task
        .robots
        .iter()
        .map(|r| {
            let t = r.base.translation.vector;
            [t.x, t.y, t.z]
        })
        .collect();
    for p in &env.instance().labware_placement {
        let t = p.translation.vector;
        points.push([t.x, t.y, t.z]);
    }
    let n = points.len().max(1) as f64;
    let mid = |k: usize| points.iter().map(|p| p[k]).sum::<f64>() / n;
    let lookat = [mid(0), mid(1), mid(2)];
    let spread = points
        .iter()
        .map(|p| (p[0] - lookat[0]).hypot(p[1] - lookat[1]))
        .fold(0.0_f64, f64::max);
    // Half the view at distance d spans d * tan(22.5 deg); keep 0.4 m of margin for the arms.
    let distance = ((spread + 0.4) / (22.5_f64).to_radians().tan()).max(1.0);
    View {
        name: "above".into(),
        lookat,
        distance,
        azimuth_deg: 90.0,
        elevation_deg: -89.0,
    }
}

/// The task cameras' frames of episode `seed` at its start drawn by `renderer` (Blender's
/// photoreal frames beside the rasteriser's in `autobio render --renderer blender`).
pub fn initial_frames(
    task: &Task,
    seed: u64,
    size: [usize; 2],
    renderer: crate::cameras::Renderer,
) -> Result<Vec<Image>, EnvError> {
    let mut env = Env::make(
        task,
        seed,
        EnvOptions {
            image_size: Some(size),
            renderer,
        },
    )?;
    Ok(env.frames()?.to_vec())
}

/// Frames of one size side by side, left to right, as one image named after them.
pub fn side_by_side(frames: &[Image]) -> Image {
    let (w, h) = frames.first().map_or((0, 0), |f| (f.width, f.height));
    let mut rgb = vec![0; w * frames.len() * h * 3];
    let row = w * frames.len() * 3;
    for (k, f) in frames.iter().enumerate() {
        for y in 0..h.min(f.height) {
            let src = &f.rgb[y * f.width * 3..(y * f.width + w.min(f.width)) * 3];
            let at = y * row + k * w * 3;
            rgb[at..at + src.len()].copy_from_slice(src);
        }
    }
    Image {
        camera: frames
            .iter()
            .map(|f| f.camera.as_str())
            .collect::<Vec<_>>()
            .join("+"),
        width: w * frames.len(),
        height: h,
        rgb,
    }
}

/// Images of one width stacked top to bottom, as one image named after them (`a / b`).
pub fn stacked(rows: &[Image]) -> Image {
    let w = rows.first().map_or(0, |r| r.width);
    let mut rgb = Vec::new();
    for r in rows {
        for y in 0..r.height {
            let mut line = r.rgb[y * r.width * 3..(y + 1) * r.width * 3].to_vec();
            line.resize(w * 3, 0);
            rgb.extend_from_slice(&line[..w * 3]);
        }
    }
    Image {
        camera: rows
            .iter()
            .map(|r| r.camera.as_str())
            .collect::<Vec<_>>()
            .join(" / "),
        width: w,
        height: rows.iter().map(|r| r.height).sum(),
        rgb,
    }
}
