//! A drawn perturbation made visible: lights, surface colours and cameras changed on the render
//! model's own copy ([`apply_look`]), and the sensor's noise applied to each frame after it is
//! drawn ([`degrade`]). The simulated model is never changed by a look (its only addition, the
//! spare lights a light perturbation may turn on, is built in off and touches no physics), so
//! physics (and the trajectory hash) is the same under any look. What is drawn, and from which seed, is the compiler's
//! (`compiler::perturb`); this module only shows it.

use crate::scene::{Owner, SPARE_LIGHT, Scene};
use compiler::perturb::{CameraDraw, Drawn, LightDraw, NoiseDraw, Tint};
use mujoco_rs::prelude::*;
use rand_chacha::ChaCha8Rng;
use rand_core::{RngCore, SeedableRng};
use results::Image;
use std::collections::BTreeSet;

/// `drawn`'s lights, colours and cameras set on `model`, a copy of `scene`'s render model.
pub(crate) fn apply_look(model: &mut MjModel, scene: &Scene, drawn: &Drawn) {
    if let Some(l) = &drawn.light {
        light(model, l);
    }
    if !drawn.material.is_empty() {
        colours(model, scene, drawn);
    }
    for (name, c) in &drawn.camera {
        if let Some(k) = scene.task().cameras.iter().position(|x| &x.name == name)
            && let Some(&id) = scene.cameras.get(k)
        {
            camera(model, id, c);
        }
    }
}

fn light(model: &mut MjModel, l: &LightDraw) {
    let factor = |c: [f32; 3]| -> [f32; 3] {
        [0, 1, 2].map(|k| ((f64::from(c[k]) * l.scale * l.tint[k]).clamp(0.0, 1.0)) as f32)
    };
    let tilt = nalgebra::Rotation3::from_axis_angle(&nalgebra::Vector3::x_axis(), l.tilt_rad[0])
        * nalgebra::Rotation3::from_axis_angle(&nalgebra::Vector3::y_axis(), l.tilt_rad[1]);
    let names: Vec<Option<String>> = (0..model.ffi().nlight as usize)
        .map(|i| {
            model
                .id_to_name(MjtObjBase::mjOBJ_LIGHT, i)
                .map(str::to_string)
        })
        .collect();
    let mut spares_on = 0;
    for (i, name) in names.iter().enumerate() {
        if name.as_deref().is_some_and(|n| n.starts_with(SPARE_LIGHT)) {
            let on = spares_on + 1 < l.lights;
            model.light_active_mut()[i] = on as mujoco_rs::wrappers::mj_primitive::MjtBool;
            spares_on += 1;
        }
        model.light_diffuse_mut()[i] = factor(model.light_diffuse()[i]);
        model.light_ambient_mut()[i] = factor(model.light_ambient()[i]);
        let d = model.light_dir()[i];
        let turned = tilt * nalgebra::Vector3::new(d[0], d[1], d[2]);
        model.light_dir_mut()[i] = [turned.x, turned.y, turned.z];
    }
    let head = &mut model.vis_mut().headlight;
    head.diffuse = factor(head.diffuse);
    head.ambient = factor(head.ambient);
}

/// Each geom's surface: its owner's name (a robot or an item), else the bench or the room by the
/// geom's name; `None` for what no surface covers.
fn surface_of(scene: &Scene, model: &MjModel, geom: usize) -> Option<String> {
    let body = model.geom_bodyid()[geom] as usize;
    let task = scene.task();
    match scene.body_owner.get(body).copied().flatten() {
        Some(Owner::Robot(r)) => return Some(task.robots[r].name.clone()),
        Some(Owner::Labware(i)) => return Some(task.labware[i].name.clone()),
        None => {}
    }
    let name = model.id_to_name(MjtObjBase::mjOBJ_GEOM, geom)?;
    if name == "table/top" {
        return Some("bench".into());
    }
    if name == "floor" || name.starts_with("room/") {
        return Some("room".into());
    }
    // A robot's pedestal stands in the world, named after the robot.
    let (robot, rest) = name.split_once('/')?;
    (rest == "pedestal").then(|| robot.to_string())
}

fn colours(model: &mut MjModel, scene: &Scene, drawn: &Drawn) {
    let mut done = BTreeSet::new();
    for g in 0..model.ffi().ngeom as usize {
        let Some(tint) = surface_of(scene, model, g).and_then(|s| drawn.material.get(&s).copied())
        else {
            continue;
        };
        let mat = model.geom_matid()[g];
        match usize::try_from(mat) {
            Ok(m) => {
                // A textured material (a display, a label) keeps its look; a shared one is
                // tinted once, for the first surface that uses it.
                let textured = model.mat_texid()[m].iter().any(|&t| t >= 0);
                if textured || !done.insert(m) {
                    continue;
                }
                let c = model.mat_rgba()[m];
                model.mat_rgba_mut()[m] = tinted(c, tint);
            }
            Err(_) => {
                let c = model.geom_rgba()[g];
                model.geom_rgba_mut()[g] = tinted(c, tint);
            }
        }
    }
}

/// `c` with its hue turned, saturation and value scaled (alpha kept).
fn tinted(c: [f32; 4], t: Tint) -> [f32; 4] {
    let [r, g, b] = [c[0], c[1], c[2]].map(f64::from);
    let max = r.max(g).max(b);
    let min = r.min(g).min(b);
    let delta = max - min;
    let hue = if delta <= 0.0 {
        0.0
    } else if max == r {
        ((g - b) / delta).rem_euclid(6.0) / 6.0
    } else if max == g {
        ((b - r) / delta + 2.0) / 6.0
    } else {
        ((r - g) / delta + 4.0) / 6.0
    };
    let sat = if max <= 0.0 { 0.0 } else { delta / max };
    let h = (hue + t.hue).rem_euclid(1.0);
    let s = (sat * t.saturation).clamp(0.0, 1.0);
    let v = (max * t.value).clamp(0.0, 1.0);
    let sector = h * 6.0;
    let x = v * s * (1.0 - (sector.rem_euclid(2.0) - 1.0).abs());
    let chroma = v * s;
    let (r, g, b) = match sector as u32 {
        0 => (chroma, x, 0.0),
        1 => (x, chroma, 0.0),
        2 => (0.0, chroma, x),
        3 => (0.0, x, chroma),
        4 => (x, 0.0, chroma),
        _ => (chroma, 0.0, x),
    };
    let m = v - chroma;
    [(r + m) as f32, (g + m) as f32, (b + m) as f32, c[3]]
}

fn camera(model: &mut MjModel, id: usize, c: &CameraDraw) {
    let p = model.cam_pos()[id];
    model.cam_pos_mut()[id] = [0, 1, 2].map(|k| p[k] + c.shift_m[k]);
    let q = model.cam_quat()[id];
    let own = nalgebra::UnitQuaternion::from_quaternion(nalgebra::Quaternion::new(
        q[0], q[1], q[2], q[3],
    ));
    let turn = nalgebra::UnitQuaternion::from_scaled_axis(nalgebra::Vector3::from(c.turn_rad));
    let t = turn * own;
    model.cam_quat_mut()[id] = [t.w, t.i, t.j, t.k];
    let f = model.cam_fovy()[id];
    model.cam_fovy_mut()[id] = (f + c.fovy_deg).clamp(5.0, 150.0);
}

/// The sensor's noise of `drawn` (if any) on the task cameras' frames (in task order) of
/// control step `step` of episode `seed`: what an environment and a replay both apply.
pub fn degrade_frames(images: &mut [Image], drawn: Option<&Drawn>, seed: u64, step: u64) {
    if let Some(noise) = drawn.and_then(|d| d.noise.as_ref()) {
        for (k, image) in images.iter_mut().enumerate() {
            degrade(image, noise, seed, step, k);
        }
    }
}

/// The sensor's noise on one frame: blur, then Gaussian noise, then JPEG compression, each
/// frame's noise drawn from the episode seed, the control step and the camera's place.
pub fn degrade(image: &mut Image, noise: &NoiseDraw, seed: u64, step: u64, camera: usize) {
    let (w, h) = (image.width, image.height);
    if w == 0 || h == 0 || image.rgb.len() != w * h * 3 {
        return;
    }
    // Within what the compiler allows, whatever a recording says.
    let (blur_px, gaussian) = (
        noise.blur_px.clamp(0.0, 5.0),
        noise.gaussian.clamp(0.0, 0.5),
    );
    if blur_px > 0.0 {
        blur(&mut image.rgb, w, h, blur_px);
    }
    if gaussian > 0.0 {
        let mut rng = ChaCha8Rng::seed_from_u64(seed);
        // Streams 1-8 are the perturbation draws'; each frame's is past them. Its bytes come
        // from a fast generator seeded from that stream (a frame takes 600 kB of them).
        rng.set_stream((1 << 40) | (step << 8) | camera as u64);
        let mut fast = rand_xoshiro::Xoshiro256PlusPlus::seed_from_u64(rng.next_u64());
        grain(&mut image.rgb, gaussian * 255.0, &mut fast);
    }
    if let Some(q) = noise.jpeg_quality {
        compress(&mut image.rgb, w, h, q);
    }
}

/// A separable Gaussian blur of standard deviation `sigma` pixels, edges clamped. Both passes
/// add whole shifted rows at once (contiguous, so the compiler vectorises them).
fn blur(rgb: &mut [u8], w: usize, h: usize, sigma: f64) {
    let radius = (3.0 * sigma).ceil() as usize;
    let weights: Vec<f32> = (0..=2 * radius)
        .map(|i| {
            let x = i as f64 - radius as f64;
            (-x * x / (2.0 * sigma * sigma)).exp() as f32
        })
        .collect();
    let total: f32 = weights.iter().sum();
    let weights: Vec<f32> = weights.iter().map(|x| x / total).collect();
    let row = w * 3;
    // Along rows: each row padded by its edge pixels, then the weighted sum of its shifts.
    let mut across = vec![0f32; rgb.len()];
    let mut padded = vec![0f32; (w + 2 * radius) * 3];
    for y in 0..h {
        let src = &rgb[y * row..(y + 1) * row];
        for (k, px) in padded.chunks_exact_mut(3).enumerate() {
            let x = k.saturating_sub(radius).min(w - 1);
            for c in 0..3 {
                px[c] = f32::from(src[x * 3 + c]);
            }
        }
        let out = &mut across[y * row..(y + 1) * row];
        for (i, &wt) in weights.iter().enumerate() {
            for (o, &p) in out.iter_mut().zip(&padded[i * 3..i * 3 + row]) {
                *o += wt * p;
            }
        }
    }
    // Along columns: each output row the weighted sum of its neighbouring rows.
    let mut acc = vec![0f32; row];
    for y in 0..h {
        acc.fill(0.0);
        for (i, &wt) in weights.iter().enumerate() {
            let sy = (y + i).saturating_sub(radius).min(h - 1);
            for (a, &p) in acc.iter_mut().zip(&across[sy * row..(sy + 1) * row]) {
                *a += wt * p;
            }
        }
        for (d, a) in rgb[y * row..(y + 1) * row].iter_mut().zip(&acc) {
            *d = (a + 0.5).clamp(0.0, 255.0) as u8;
        }
    }
}

/// Zero-mean noise of standard deviation `sigma` (in 8-bit levels) on every channel: the sum of
/// four uniform random bytes, centred and scaled (close to Gaussian), the bytes drawn in bulk.
fn grain(rgb: &mut [u8], sigma: f64, rng: &mut impl RngCore) {
    // Four uniform bytes sum to mean 510 with standard deviation sqrt(4 * (256^2 - 1) / 12).
    let scale = (sigma / (4.0 * (256.0f64 * 256.0 - 1.0) / 12.0).sqrt()) as f32;
    let mut bytes = vec![0u8; rgb.len() * 4];
    rng.fill_bytes(&mut bytes);
    for (px, b) in rgb.iter_mut().zip(bytes.chunks_exact(4)) {
        let sum = i32::from(b[0]) + i32::from(b[1]) + i32::from(b[2]) + i32::from(b[3]);
        let n = (sum - 510) as f32 * scale;
        // Adding a half and truncating rounds (without `round`, which does not vectorise here).
        *px = (f32::from(*px) + n + 0.5).clamp(0.0, 255.0) as u8;
    }
}

/// The frame through a JPEG encoder at `quality` and back.
fn compress(rgb: &mut [u8], w: usize, h: usize, quality: u8) {
    let (Ok(w16), Ok(h16)) = (u16::try_from(w), u16::try_from(h)) else {
        return;
    };
    let mut encoded = Vec::new();
    let enc = jpeg_encoder::Encoder::new(&mut encoded, quality.clamp(1, 100));
    if enc
        .encode(rgb, w16, h16, jpeg_encoder::ColorType::Rgb)
        .is_err()
    {
        return;
    }
    let mut dec = zune_jpeg::JpegDecoder::new(zune_jpeg::zune_core::bytestream::ZCursor::new(
        encoded.as_slice(),
    ));
    if let Ok(decoded) = dec.decode()
        && decoded.len() == rgb.len()
    {
        rgb.copy_from_slice(&decoded);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_tint_of_nothing_keeps_the_colour_and_a_hue_turn_keeps_value() {
        let c = [0.72, 0.66, 0.56, 1.0];
        let same = tinted(
            c,
            Tint {
                hue: 0.0,
                saturation: 1.0,
                value: 1.0,
            },
        );
        for k in 0..4 {
            assert!((same[k] - c[k]).abs() < 1e-5, "{same:?}");
        }
        let turned = tinted(
            c,
            Tint {
                hue: 0.5,
                saturation: 1.0,
                value: 1.0,
            },
        );
        let max = |x: [f32; 4]| x[0].max(x[1]).max(x[2]);
        assert!((max(turned) - max(c)).abs() < 1e-5);
        assert!(
            turned[2] > turned[0],
            "a warm colour turned half way is cool: {turned:?}"
        );
    }

    #[test]
    fn noise_is_seeded_per_frame_and_has_its_strength() {
        let img = |v: u8| Image {
            camera: "c".into(),
            width: 64,
            height: 48,
            rgb: vec![v; 64 * 48 * 3],
        };
        let n = NoiseDraw {
            gaussian: 0.05,
            blur_px: 0.0,
            jpeg_quality: None,
        };
        let (mut a, mut b, mut c) = (img(128), img(128), img(128));
        degrade(&mut a, &n, 7, 3, 0);
        degrade(&mut b, &n, 7, 3, 0);
        degrade(&mut c, &n, 7, 4, 0);
        assert_eq!(a.rgb, b.rgb);
        assert_ne!(a.rgb, c.rgb);
        let mean = a.rgb.iter().map(|&x| f64::from(x)).sum::<f64>() / a.rgb.len() as f64;
        let sd = (a
            .rgb
            .iter()
            .map(|&x| (f64::from(x) - mean).powi(2))
            .sum::<f64>()
            / a.rgb.len() as f64)
            .sqrt();
        assert!(
            (mean - 128.0).abs() < 0.5 && (sd - 0.05 * 255.0).abs() < 0.6,
            "{mean} {sd}"
        );
        // A blur keeps a flat image flat; JPEG keeps it near.
        let mut flat = img(90);
        degrade(
            &mut flat,
            &NoiseDraw {
                gaussian: 0.0,
                blur_px: 1.5,
                jpeg_quality: Some(30),
            },
            0,
            0,
            0,
        );
        assert!(flat.rgb.iter().all(|&x| x.abs_diff(90) <= 2));
    }

    #[test]
    fn a_degraded_frame_is_the_same_bytes_everywhere() {
        // Recordings of noisy frames are compared byte for byte by `leaderboard verify`, on
        // whatever CPU: blur, noise and the JPEG round trip (scalar paths only) must not depend
        // on it. The digest pins this frame's bytes; a change of any of them shows here.
        use sha2::Digest;
        let (w, h) = (64, 48);
        let mut img = Image {
            camera: "c".into(),
            width: w,
            height: h,
            rgb: (0..w * h * 3).map(|i| ((i * 37) % 251) as u8).collect(),
        };
        let n = NoiseDraw {
            gaussian: 0.04,
            blur_px: 1.1,
            jpeg_quality: Some(35),
        };
        degrade(&mut img, &n, 11, 7, 1);
        let digest = hex_of(&sha2::Sha256::digest(&img.rgb));
        assert_eq!(digest, PINNED, "the degraded frame's bytes changed");
    }

    fn hex_of(b: &[u8]) -> String {
        b.iter().map(|x| format!("{x:02x}")).collect()
    }

    const PINNED: &str = "f7b29308d7f676e8c727246b7ed04c4e5339b7a33d1c88c09758c7734b2d8342";
}
