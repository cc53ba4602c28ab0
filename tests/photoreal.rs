//! Photoreal frames (runtime/src/blender, docs/photoreal.md): Blender draws the state the
//! rasteriser draws. Every body's silhouette in Blender's frame of a task camera matches the
//! rasteriser's (mask IoU at least 0.95 for every body covering 50 pixels or more in either) on two tasks,
//! fixed and wrist cameras; the agreement fails where the states differ (a check that can fail);
//! a photoreal dataset holds the same episode as the rasteriser's (its frames' table byte for
//! byte), names its renderer and loads in the real LeRobot; `replay --render --renderer blender`
//! redraws a recording.

use crate::common::{self, autobio_ok};
use runtime::blender::{self, Settings};
use runtime::render::masks;
use std::sync::Arc;

/// The fewest reference pixels for a body to count as visible: below it a body is a sliver at
/// the frame's edge or behind another, where a pixel's rounding decides the ratio.
const VISIBLE: usize = 50;

/// Each camera's masks of `seed`'s start of `path` from both renderers (raster first).
fn masks_of(
    path: &str,
    seed: u64,
    blender_seed: u64,
) -> Vec<(String, results::Image, results::Image)> {
    let task = common::compile(path);
    let size = [224, 224];
    let names: Vec<String> = task.cameras.iter().map(|c| c.name.clone()).collect();
    let start = |seed: u64| {
        let instance = task.sample(seed);
        let scene = Arc::new(runtime::Scene::build(&task, &instance).unwrap());
        let ep = runtime::Episode::new(scene.clone(), &task, &instance);
        (scene, ep)
    };
    let (scene, ep) = start(seed);
    let raster = masks::raster(&scene, None, &ep.data, ep.logic(), size).unwrap();
    let (bscene, bep) = start(blender_seed);
    let settings = Settings {
        samples: 1,
        denoise: false,
        ..Settings::default()
    };
    let mut cams = blender::Cameras::new(&bscene, size[0], size[1], settings).unwrap();
    let drawn = cams.masks(&bep.data, bep.logic(), &names).unwrap();
    names
        .into_iter()
        .zip(raster.into_iter().zip(drawn))
        .map(|(n, (r, b))| (n, r, b))
        .collect()
}

/// The visible bodies' agreement: (camera, body, IoU, reference pixels).
fn agreement(path: &str, seed: u64, blender_seed: u64) -> Vec<(String, usize, f64, usize)> {
    let mut out = Vec::new();
    for (camera, raster, drawn) in masks_of(path, seed, blender_seed) {
        let bodies = masks::agreement(&raster, &drawn);
        // Visible in either: what only Blender draws fails as what only the rasteriser draws.
        let visible = |b: &&masks::BodyAgreement| b.reference.max(b.other) >= VISIBLE;
        assert!(
            bodies.iter().filter(visible).count() >= 3,
            "{path} {camera}: too few visible bodies to compare"
        );
        for b in bodies.iter().filter(visible) {
            out.push((camera.clone(), b.body, b.iou, b.reference));
        }
    }
    out
}

#[test]
fn every_visible_body_has_the_same_silhouette_in_both_renderers() {
    for path in [
        "protocols/thermal_cycler/close_lid.toml",
        "protocols/tube/transfer.toml",
    ] {
        let bodies = agreement(path, 0, 0);
        let worst = bodies.iter().min_by(|a, b| a.2.total_cmp(&b.2)).unwrap();
        assert!(
            worst.2 >= 0.95,
            "{path}: camera {} body {} agrees only {:.3} ({} px)",
            worst.0,
            worst.1,
            worst.2,
            worst.3
        );
        // Both cameras, the fixed one and the wrist's among the fingers.
        let cameras: std::collections::BTreeSet<&str> =
            bodies.iter().map(|b| b.0.as_str()).collect();
        assert!(cameras.len() >= 2, "{path}: {cameras:?}");
    }
}

#[test]
fn silhouettes_of_different_states_disagree() {
    // Seed 1 moves the racks and the tube: Blender drawing seed 1 against the rasteriser's seed
    // 0 must fail the agreement the test above asserts.
    let bodies = agreement("protocols/tube/transfer.toml", 0, 1);
    let worst = bodies.iter().map(|b| b.2).fold(1.0, f64::min);
    assert!(worst < 0.95, "a moved layout still agrees ({worst:.3})");
}

#[test]
fn a_photoreal_dataset_holds_the_same_episode_and_loads_in_lerobot() {
    let dir = common::scratch("photoreal-dataset");
    // `demo` of the tube pick-up (the shortest task: about 200 control steps) as a v3.0 dataset
    // of `episodes` at 32x24, into `out`.
    let args = |out: &std::path::Path, episodes: &'static str, extra: &[&'static str]| {
        let mut a: Vec<String> = [
            "demo",
            "--protocol",
            "protocols/tube/pick_up.toml",
            "--format",
            "lerobot-v30",
            "--codec",
            "h264",
            "--episodes",
            episodes,
            "--size",
            "32x24",
            "--out",
        ]
        .iter()
        .map(|s| s.to_string())
        .collect();
        a.push(out.to_str().unwrap().to_string());
        a.extend(extra.iter().map(|s| s.to_string()));
        a
    };
    let demo = |name: &str, extra: &[&'static str]| {
        let out = dir.join(name);
        let a = args(&out, "1", extra);
        autobio_ok(&a.iter().map(String::as_str).collect::<Vec<_>>());
        out
    };
    let raster = demo("raster", &[]);
    let photoreal = demo(
        "blender",
        &["--renderer", "blender", "--samples", "1", "--no-denoise"],
    );
    // The same episode whoever draws its frames: the frames' table (states, actions, times)
    // byte for byte; only the videos differ.
    let table =
        |d: &std::path::Path| std::fs::read(d.join("data/chunk-000/file-000.parquet")).unwrap();
    assert_eq!(table(&raster), table(&photoreal));
    let videos = |d: &std::path::Path| {
        let mut v = Vec::new();
        for cam in std::fs::read_dir(d.join("videos")).unwrap() {
            let f = cam.unwrap().path().join("chunk-000/file-000.mp4");
            v.push(std::fs::read(f).unwrap());
        }
        v
    };
    let (rv, bv) = (videos(&raster), videos(&photoreal));
    assert_eq!(rv.len(), bv.len());
    assert!(rv.iter().zip(&bv).all(|(r, b)| r != b));
    // The dataset names its renderer and settings per episode; the rasteriser's names none.
    let line = |d: &std::path::Path| -> serde_json::Value {
        let t = std::fs::read_to_string(d.join("meta/autobio.jsonl")).unwrap();
        serde_json::from_str(t.lines().next().unwrap()).unwrap()
    };
    assert!(line(&raster).get("renderer").is_none());
    let named = &line(&photoreal)["renderer"];
    assert_eq!(named["renderer"], "blender");
    assert_eq!(named["engine"], "cycles");
    assert_eq!(named["samples"], 1);
    assert_eq!(named["denoiser"], "none");
    // Resumed with the rasteriser, or with other samples, it is refused: a dataset has one look.
    for other in [&[][..], &["--renderer", "blender", "--samples", "2"][..]] {
        let mut a = args(&photoreal, "2", other);
        a.push("--resume".into());
        let a: Vec<&str> = a.iter().map(String::as_str).collect();
        let out = common::autobio(&a);
        assert!(!out.status.success(), "{other:?}");
        let err = common::text(&out.stderr);
        assert!(err.contains("same --renderer"), "{other:?}: {err}");
    }
    // The real LeRobot loads it and decodes its photoreal videos.
    let root = std::path::Path::new(env!("CARGO_MANIFEST_DIR"));
    let out = std::process::Command::new(root.join(".deps/lerobot-env/bin/python"))
        .arg(root.join("tests/datasets/load_lerobot.py"))
        .arg(&photoreal)
        .output()
        .unwrap();
    assert!(out.status.success(), "{}", common::text(&out.stderr));
    let loaded: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    assert_eq!(loaded["episodes"], 1);
    let cameras = loaded["cameras"].as_object().unwrap();
    assert_eq!(cameras.len(), 2, "{loaded}");
    for (key, c) in cameras {
        assert_eq!(c["shape"], serde_json::json!([3, 24, 32]), "{key}");
        assert!(c["mean"].as_f64().unwrap() > 0.05, "{key}: a black frame");
    }
}

#[test]
fn replay_redraws_a_recording_with_blender() {
    let dir = common::scratch("photoreal-replay");
    autobio_ok(&[
        "eval",
        "--protocol",
        "protocols/centrifuge_5430/close_lid.toml",
        "--episodes",
        "1",
        "--record",
        "--image-every",
        "10",
        "--size",
        "48x36",
        "--out",
        dir.to_str().unwrap(),
    ]);
    let recording = dir.join("centrifuge_5430.close_lid_seed0.mcap");
    let redrawn = dir.join("redrawn.mcap");
    let said = autobio_ok(&[
        "replay",
        recording.to_str().unwrap(),
        "--render",
        "--renderer",
        "blender",
        "--samples",
        "1",
        "--no-denoise",
        "--every",
        "40",
        "--out",
        redrawn.to_str().unwrap(),
    ]);
    assert!(said.contains("re-scored: success"), "{said}");
    let open = |p: &std::path::Path| scoring::replay::Recording::open(p).unwrap();
    let (before, after) = (open(&recording), open(&redrawn));
    for camera in before.task.cameras.iter().map(|c| c.name.as_str()) {
        let frames = scoring::replay::recorded_frames(&after, camera).unwrap();
        assert_eq!(frames.len(), before.steps().div_ceil(40), "{camera}");
        assert_eq!([frames[0].1.width, frames[0].1.height], [48, 36]);
        assert!(
            common::spread(&frames[0].1.rgb) > 10.0,
            "{camera}: a blank frame"
        );
        // Not the rasteriser's frame of the same step.
        let raster = scoring::replay::recorded_frames(&before, camera).unwrap();
        assert_ne!(raster[0].1.rgb, frames[0].1.rgb, "{camera}");
    }
}

#[test]
fn a_missing_blender_is_named_with_its_remedy() {
    let out = common::autobio_env(
        &[
            "render",
            "protocols/tube/transfer.toml",
            "--renderer",
            "blender",
            "--png",
            common::scratch("no-blender")
                .join("x.png")
                .to_str()
                .unwrap(),
        ],
        &[("AUTOBIO_BLENDER_PYTHON", "/nonexistent/python")],
    );
    assert!(!out.status.success());
    let err = common::text(&out.stderr);
    assert!(
        err.contains("/nonexistent/python") && err.contains("make setup"),
        "{err}"
    );
}

#[test]
fn blender_shows_a_perturbed_look_and_takes_a_new_one_in_the_same_worker() {
    let task = common::compile("protocols/tube/transfer.toml");
    let looks: Vec<compiler::perturb::Preset> = ["light:2", "material:2", "camera:2"]
        .iter()
        .map(|p| p.parse().unwrap())
        .collect();
    let shaken = task
        .clone()
        .with_perturb(&compiler::perturb::Preset::combine(&looks));
    let instance = shaken.sample(0);
    let scene = Arc::new(runtime::Scene::build(&shaken, &instance).unwrap());
    let ep = runtime::Episode::new(scene.clone(), &shaken, &instance);
    let names: Vec<String> = task.cameras.iter().map(|c| c.name.clone()).collect();
    let settings = Settings {
        samples: 1,
        denoise: false,
        ..Settings::default()
    };
    let mut cams = blender::Cameras::new(&scene, 32, 24, settings).unwrap();
    let clean = cams.render(&ep.data, ep.logic(), &names).unwrap();
    let drawn = instance.perturbation.as_ref();
    assert!(drawn.is_some());
    cams.set_look(&scene, drawn).unwrap();
    let shown = cams.render(&ep.data, ep.logic(), &names).unwrap();
    // The bench camera moved, the lights and colours changed: a different frame.
    assert_ne!(clean[0].rgb, shown[0].rgb);
    // Back to the clean look: the scene is built again in the same worker and draws as before.
    cams.set_look(&scene, None).unwrap();
    let again = cams.render(&ep.data, ep.logic(), &names).unwrap();
    assert_eq!(clean.len(), again.len());
    for (a, b) in clean.iter().zip(&again) {
        let differing = a
            .rgb
            .iter()
            .zip(&b.rgb)
            .filter(|(x, y)| x.abs_diff(**y) > 8)
            .count();
        assert!(
            differing * 50 < a.rgb.len(),
            "{}: {differing} values differ",
            a.camera
        );
    }
}
