//! Perturbations (docs/robustness.md): each dimension changes what it should (the frames, the
//! instruction, the start pose, the layout) and nothing else; the visual ones and the wording
//! leave the expert's trajectory as it was, hash for hash, while frames are drawn every step;
//! under start-pose and layout perturbations the expert still wins and the motionless robot
//! still fails; a dimension's draw does not depend on which others are on; and `autobio demo
//! --perturb` writes what each episode drew into the dataset, which LeRobot's readers load.

use crate::common;

use compiler::perturb::{Dimension, Perturb, Preset};
use compiler::{SceneInstance, Task};
use std::path::Path;

const TRANSFER: &str = "protocols/tube/transfer.toml";
const PICK_UP: &str = "protocols/tube/pick_up.toml";

fn under(task: &Task, d: Dimension, strength: u8) -> Task {
    task.clone().with_perturb(&Perturb::preset(d, strength))
}

/// The task cameras' first frames of episode `seed`, small.
fn first_frames(task: &Task, seed: u64) -> Vec<results::Image> {
    let opts = runtime::EnvOptions {
        image_size: Some([96, 72]),
    };
    let mut env = runtime::Env::make(task, seed, opts).unwrap();
    env.frames().unwrap().to_vec()
}

/// The share of pixel values that differ between two sets of frames.
fn changed(a: &[results::Image], b: &[results::Image]) -> f64 {
    let (mut diff, mut all) = (0usize, 0usize);
    for (x, y) in a.iter().zip(b) {
        assert_eq!(x.rgb.len(), y.rgb.len());
        diff += x
            .rgb
            .iter()
            .zip(&y.rgb)
            .filter(|(p, q)| p.abs_diff(**q) > 2)
            .count();
        all += x.rgb.len();
    }
    diff as f64 / all as f64
}

/// What a dimension may change of an instance: (robot start, layout, instruction).
fn expected(d: Dimension) -> (bool, bool, bool) {
    match d {
        Dimension::RobotStart => (true, false, false),
        Dimension::Layout => (false, true, false),
        Dimension::Language => (false, false, true),
        _ => (false, false, false),
    }
}

fn differs(a: &SceneInstance, b: &SceneInstance) -> (bool, bool, bool) {
    (
        a.robot_q != b.robot_q,
        a.labware_placement != b.labware_placement,
        a.instruction != b.instruction || a.stage_instructions != b.stage_instructions,
    )
}

#[test]
fn each_dimension_changes_what_it_should_and_nothing_else() {
    let task = common::compile(TRANSFER);
    let seed = 3;
    let clean = task.sample(seed);
    assert!(clean.perturbation.is_none());
    let clean_frames = first_frames(&task, seed);
    let everything = Preset::combine(&Dimension::ALL.map(|d| Preset {
        dimension: d,
        strength: 2,
    }));
    let all_on = task.clone().with_perturb(&everything).sample(seed);
    for d in Dimension::ALL {
        for strength in [1, 2] {
            let t = under(&task, d, strength);
            let inst = t.sample(seed);
            assert_eq!(inst, t.sample(seed), "{d}:{strength} draws the same twice");
            assert_eq!(inst.params, clean.params, "{d}: the task's own draws stay");
            assert_eq!(differs(&clean, &inst), expected(d), "{d}:{strength}");
            let frames = first_frames(&t, seed);
            let share = changed(&clean_frames, &frames);
            match d {
                // Only words change: the same pixels.
                Dimension::Language => assert_eq!(share, 0.0, "{d}"),
                _ => assert!(share > 0.02, "{d}:{strength} changed {share} of the pixels"),
            }
            // A dimension draws the same whether the others are on or not.
            if strength == 2 {
                let alone = inst.perturbation.clone().unwrap();
                let with_all = all_on.perturbation.clone().unwrap();
                let same = match d {
                    Dimension::Light => alone.light == with_all.light,
                    Dimension::Material => alone.material == with_all.material,
                    Dimension::Camera => alone.camera == with_all.camera,
                    Dimension::Noise => alone.noise == with_all.noise,
                    Dimension::Language => alone.language == with_all.language,
                    Dimension::RobotStart => alone.robot_start == with_all.robot_start,
                    Dimension::Layout => alone.layout == with_all.layout,
                };
                assert!(same, "{d} draws differently beside the others");
            }
        }
    }
    // Another seed draws another look.
    let t = under(&task, Dimension::Light, 2);
    assert_ne!(t.sample(4).perturbation, t.sample(seed).perturbation);
}

#[test]
fn the_expert_trajectory_is_the_same_under_every_look_and_wording() {
    let task = common::compile(PICK_UP);
    let dir = common::scratch("perturb-hash");
    let seed = 1;
    // Frames are drawn at every step (a recording with images), so the perturbed renderer runs
    // beside the simulation all episode long.
    let run = |t: &Task, name: &str| {
        let opts = scoring::episode::EpisodeOptions {
            record: Some(dir.join(format!("{name}.mcap"))),
            image_every: 1,
            image_size: Some([64, 64]),
        };
        common::run_with(t, seed, &opts, |t, s, i| {
            scoring::policies::make("expert", t, s, i).unwrap()
        })
    };
    let clean = run(&task, "clean");
    assert!(clean.success, "{:#?}", clean.verdict);
    let looks: Vec<Dimension> = Dimension::ALL
        .into_iter()
        .filter(|d| d.leaves_physics())
        .collect();
    assert_eq!(looks.len(), 5);
    for d in &looks {
        let r = run(&under(&task, *d, 2), d.name());
        assert_eq!(
            r.trajectory_hash, clean.trajectory_hash,
            "{d} moved the robot"
        );
        assert!(r.success);
    }
    let all = task.clone().with_perturb(&Preset::combine(
        &looks
            .iter()
            .map(|&d| Preset {
                dimension: d,
                strength: 2,
            })
            .collect::<Vec<_>>(),
    ));
    let r = run(&all, "all");
    assert_eq!(r.trajectory_hash, clean.trajectory_hash);
    // The recording keeps what was drawn, and a replay redraws the perturbed frames as the
    // episode showed them, noise included.
    let rec = scoring::replay::Recording::open(&dir.join("all.mcap")).unwrap();
    assert_eq!(rec.instance.perturbation, all.sample(seed).perturbation);
    let recorded: Vec<results::Image> = rec
        .summary
        .images
        .iter()
        .map(|(camera, frames)| results::Image::from_png(camera, &frames[5].1).unwrap())
        .collect();
    let mut redrawn = Vec::new();
    let opts = scoring::replay::FrameOptions {
        size: None,
        detail: None,
        every: Some(5),
    };
    scoring::replay::frames(&rec, &opts, |k, _, images| {
        if k == 5 {
            redrawn = images;
        }
        Ok(())
    })
    .unwrap();
    let by_name =
        |v: &[results::Image], name: &str| v.iter().find(|i| i.camera == name).unwrap().rgb.clone();
    for r in &recorded {
        assert_eq!(by_name(&redrawn, &r.camera), r.rgb, "{}", r.camera);
    }
}

#[test]
fn under_start_pose_and_layout_perturbations_the_expert_wins_and_hold_fails() {
    for path in [PICK_UP, "protocols/thermal_cycler/close_lid.toml"] {
        let task = common::compile(path);
        for d in [Dimension::RobotStart, Dimension::Layout] {
            let t = under(&task, d, 2);
            for seed in 0..3 {
                let r = common::run(&t, seed, "expert");
                assert!(r.success, "{path} {d}:2 seed {seed}: {:#?}", r.verdict);
            }
        }
        // A motionless robot fails under every perturbation.
        for d in Dimension::ALL {
            let r = common::run(&under(&task, d, 2), 0, "hold");
            assert!(!r.success, "{path}: hold passes under {d}");
        }
    }
}

#[test]
fn perturbed_datasets_record_each_episodes_draw_and_load_in_lerobots_readers() {
    let dir = common::scratch("perturb-dataset").join("ds");
    let out = common::autobio(&[
        "demo",
        "--protocol",
        PICK_UP,
        "--format",
        "lerobot-v30",
        "--codec",
        "h264",
        "--episodes",
        "2",
        "--size",
        "64x64",
        "--perturb",
        "noise:1",
        "--perturb",
        "layout",
        "--out",
        dir.to_str().unwrap(),
    ]);
    assert!(out.status.success(), "{}", common::text(&out.stderr));
    let lines: Vec<serde_json::Value> = std::fs::read_to_string(dir.join("meta/autobio.jsonl"))
        .unwrap()
        .lines()
        .map(|l| serde_json::from_str(l).unwrap())
        .collect();
    assert_eq!(lines.len(), 2);
    let task = common::compile(PICK_UP).with_perturb(&Preset::combine(&[
        "noise:1".parse().unwrap(),
        "layout:1".parse().unwrap(),
    ]));
    for (k, line) in lines.iter().enumerate() {
        let drawn = serde_json::to_value(task.sample(k as u64).perturbation.unwrap()).unwrap();
        assert_eq!(line["perturbation"], drawn, "episode {k}");
        assert!(line["perturbation"]["noise"]["jpeg_quality"].is_u64());
    }
    assert_ne!(lines[0]["perturbation"], lines[1]["perturbation"]);
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let check = std::process::Command::new(root.join(".deps/servers/bin/python"))
        .arg(root.join("tests/datasets/check_lerobot.py"))
        .arg(&dir)
        .arg("v3.0")
        .output()
        .unwrap();
    assert!(check.status.success(), "{}", common::text(&check.stderr));
}

#[test]
fn render_shows_the_clean_scene_over_the_perturbed_one() {
    let dir = common::scratch("perturb-render");
    let png = dir.join("camera.png");
    let said = common::autobio_ok(&[
        "render",
        TRANSFER,
        "--seed",
        "2",
        "--size",
        "64x48",
        "--perturb",
        "camera:2",
        "--png",
        png.to_str().unwrap(),
    ]);
    assert!(
        said.contains("clean above, perturbed below") && said.contains("\"camera\""),
        "{said}"
    );
    let sheet = results::Image::from_png("sheet", &std::fs::read(&png).unwrap()).unwrap();
    // Three views (the bench camera, the wrist, from above) wide, two rows high.
    assert_eq!((sheet.width, sheet.height), (3 * 64, 2 * 48));
    let said = common::autobio_ok(&[
        "render",
        TRANSFER,
        "--size",
        "64x48",
        "--perturb",
        "language:2",
        "--png",
        png.to_str().unwrap(),
    ]);
    assert!(said.contains("instruction: \""), "{said}");
    let bad = common::autobio(&[
        "render",
        TRANSFER,
        "--perturb",
        "lighting",
        "--png",
        "x.png",
    ]);
    assert_eq!(bad.status.code(), Some(2));
    assert!(
        common::text(&bad.stderr).contains("robot_start"),
        "{}",
        common::text(&bad.stderr)
    );
}
