//! Perturbations (docs/robustness.md): each dimension changes what it should (the frames, the
//! instruction, the start pose, the layout, the items on the bench) and nothing else; the visual
//! ones and the wording leave the expert's trajectory as it was, hash for hash, while frames are
//! drawn every step; under start-pose, layout and distractor perturbations the expert still wins
//! and the motionless robot still fails; a dimension's draw does not depend on which others are on; and `autobio demo
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
        ..Default::default()
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
                // Racks stood at the bench's free places: bodies of the scene, in view or not
                // (one rack may stand at the frame's edge).
                Dimension::Distractors => {
                    let drawn = inst.perturbation.as_ref().unwrap();
                    assert!(!drawn.distractors.is_empty());
                    let bodies = |t: &Task, i: &SceneInstance| {
                        runtime::Scene::build(t, i).unwrap().model.ffi().nbody
                    };
                    assert!(bodies(&t, &inst) > bodies(&task, &clean), "{d}:{strength}");
                    assert!(share > 0.0, "{d}:{strength} changed no pixel");
                }
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
                    // Drawn after the layout, clear of the items where they then stand.
                    Dimension::Distractors => true,
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
            ..Default::default()
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
        ..Default::default()
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
fn under_start_pose_layout_and_distractor_perturbations_the_expert_wins_and_hold_fails() {
    for path in [PICK_UP, "protocols/thermal_cycler/close_lid.toml"] {
        let task = common::compile(path);
        for d in [
            Dimension::RobotStart,
            Dimension::Layout,
            Dimension::Distractors,
        ] {
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
fn an_empty_table_perturbs_nothing_and_leaves_the_task_as_it_was() {
    let clean = common::compile(PICK_UP);
    let empty = common::compile_edited(PICK_UP, |s| s + "\n[perturb]\n");
    assert_eq!(empty, clean);
}

#[test]
fn presets_the_task_cannot_take_are_refused_and_named_ones_rename_the_task() {
    // A narrow bench camera: the strong camera shake could swing its aim off the work.
    let dir = common::scratch("perturb-refused");
    let narrow = dir.join("narrow.toml");
    let text = std::fs::read_to_string(PICK_UP)
        .unwrap()
        .replace("fovy_deg = 45", "fovy_deg = 12");
    std::fs::write(&narrow, text).unwrap();
    let out = common::autobio(&[
        "eval",
        "--protocol",
        narrow.to_str().unwrap(),
        "--perturb",
        "camera:2",
    ]);
    assert_eq!(out.status.code(), Some(2), "{}", common::text(&out.stderr));
    assert!(
        common::text(&out.stderr)
            .contains("its perturbations cannot be run: camera `table_front` could lose the work"),
        "{}",
        common::text(&out.stderr)
    );
    // A preset the task can take names itself in the task's id, so its results stand apart.
    let runs = dir.join("runs");
    let said = common::autobio_ok(&[
        "eval",
        "--protocol",
        PICK_UP,
        "--perturb",
        "noise:2",
        "--perturb",
        "layout",
        "--episodes",
        "1",
        "--out",
        runs.to_str().unwrap(),
    ]);
    assert!(said.contains("tube.pick_up@noise-2+layout-1"), "{said}");
    assert!(
        runs.join("tube.pick_up@noise-2+layout-1.results.json")
            .exists()
    );
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

mod forged {
    //! Bundles of the shipped `robustness-smoke` suite (the thermal cycler's close, clean, under
    //! `light:2` and under `layout:1`), genuine and with a perturbation removed or altered,
    //! verified from a folder outside the checkout with the shipped suites compiled in.

    use crate::common::{self, scratch, text};
    use crate::leaderboard::{members, pack, rewrite};
    use serde_json::Value;
    use std::collections::BTreeMap;
    use std::path::{Path, PathBuf};
    use std::sync::OnceLock;

    const LIGHT: &str = "thermal_cycler.close_lid@light-2";
    const LAYOUT: &str = "thermal_cycler.close_lid@layout-1";
    const CLEAN: &str = "thermal_cycler.close_lid";

    pub(super) fn genuine() -> &'static (PathBuf, BTreeMap<String, Vec<u8>>) {
        static G: OnceLock<(PathBuf, BTreeMap<String, Vec<u8>>)> = OnceLock::new();
        G.get_or_init(|| {
            let root = scratch("perturb-forgeries");
            let suite = Path::new(env!("CARGO_MANIFEST_DIR")).join("suites/robustness-smoke.toml");
            let run = root.join("run");
            common::eval_suite(&suite, &run, &["--policy", "expert"]);
            let bundle = root.join("expert.tar.zst");
            common::submit(&run, "scripted expert", &bundle, &[]);
            let away = root.join("elsewhere");
            std::fs::create_dir_all(&away).unwrap();
            (away, members(&bundle))
        })
    }

    /// Packs `m` (rehashed, as a forger would) and verifies it away: exit code, refusals, all said.
    fn verify(name: &str, m: &BTreeMap<String, Vec<u8>>) -> (i32, Vec<String>, String) {
        let out = scratch(name).join("b.tar.zst");
        pack(m, &out, true);
        let o = std::process::Command::new(env!("CARGO_BIN_EXE_autobio"))
            .args(["leaderboard", "verify", out.to_str().unwrap()])
            .current_dir(&genuine().0)
            .output()
            .unwrap();
        let said = text(&o.stdout) + &text(&o.stderr);
        let refusals = said
            .lines()
            .filter_map(|l| l.strip_prefix("refused: "))
            .map(str::to_string)
            .collect();
        (o.status.code().unwrap(), refusals, said)
    }

    /// The recording of `task`'s seed 0 with its `/task` message edited.
    fn edit_task_message(m: &mut BTreeMap<String, Vec<u8>>, task: &str, edit: impl Fn(&mut Value)) {
        let key = format!("runs/0/{task}_seed0.mcap");
        let dir = scratch("perturb-forged-recording");
        let (src, dst) = (dir.join("in.mcap"), dir.join("out.mcap"));
        std::fs::write(&src, &m[&key]).unwrap();
        rewrite(&src, &dst, |topic, data| {
            (topic == "/task").then(|| {
                let mut v: Value = serde_json::from_slice(data).unwrap();
                edit(&mut v);
                serde_json::to_vec(&v).unwrap()
            })
        });
        m.insert(key, std::fs::read(&dst).unwrap());
    }

    fn refused_for(name: &str, m: &BTreeMap<String, Vec<u8>>, task: &str, why: &str) {
        let (code, refusals, said) = verify(name, m);
        assert_eq!(code, 1, "{name}: {said}");
        assert!(
            refusals.iter().any(|r| r.contains(task) && r.contains(why)),
            "{name}: no refusal of {task} for `{why}` in {refusals:#?}"
        );
    }

    #[test]
    fn forged_perturbations_are_refused() {
        let (_, genuine) = genuine();
        // The control: the genuine run, repacked, verifies; it holds each preset's task.
        let (code, refusals, said) = verify("perturb-control", genuine);
        assert_eq!((code, refusals.len()), (0, 0), "{said}");
        for t in [CLEAN, LIGHT, LAYOUT] {
            assert!(
                genuine.contains_key(&format!("runs/0/{t}.manifest.json")),
                "{t}"
            );
        }

        // The light perturbation removed from what the recording says the episode was.
        let mut m = genuine.clone();
        edit_task_message(&mut m, LIGHT, |v| {
            v["task"].as_object_mut().unwrap().remove("perturb");
            v["instance"]
                .as_object_mut()
                .unwrap()
                .remove("perturbation");
        });
        refused_for(
            "perturb-removed",
            &m,
            LIGHT,
            "`/task` message 0 (at 0 s) is not the episode's",
        );

        // The light perturbation altered (a dimmer draw claimed).
        let mut m = genuine.clone();
        edit_task_message(&mut m, LIGHT, |v| {
            v["instance"]["perturbation"]["light"]["scale"] = Value::from(1.0);
        });
        refused_for(
            "perturb-altered",
            &m,
            LIGHT,
            "`/task` message 0 (at 0 s) is not the episode's",
        );

        // The manifest claims the clean task's content for the perturbed task's run.
        let mut m = genuine.clone();
        let clean: Value =
            serde_json::from_slice(&m[&format!("runs/0/{CLEAN}.manifest.json")]).unwrap();
        let key = format!("runs/0/{LIGHT}.manifest.json");
        let mut manifest: Value = serde_json::from_slice(&m[&key]).unwrap();
        manifest["task_content_sha256"] = clean["task_content_sha256"].clone();
        m.insert(key, serde_json::to_vec_pretty(&manifest).unwrap());
        refused_for(
            "perturb-clean-content",
            &m,
            LIGHT,
            "under the suite's `light:2`",
        );

        // The layout run's recording replaced by the clean run's (renamed): its actions, made
        // for the clean layout, are re-enacted on the perturbed one.
        let mut m = genuine.clone();
        let clean_rec = m[&format!("runs/0/{CLEAN}_seed0.mcap")].clone();
        m.insert(format!("runs/0/{LAYOUT}_seed0.mcap"), clean_rec);
        refused_for(
            "perturb-layout-swapped",
            &m,
            LAYOUT,
            "re-enacted from its seed and recorded actions",
        );

        // The suite's presets dropped from the index: not the shipped suite.
        let mut m = genuine.clone();
        let mut index: Value = serde_json::from_slice(&m["index.json"]).unwrap();
        index["suite"].as_object_mut().unwrap().remove("perturb");
        m.insert(
            "index.json".into(),
            serde_json::to_vec_pretty(&index).unwrap(),
        );
        let (code, refusals, said) = verify("perturb-suite-edited", &m);
        assert_eq!(code, 1, "{said}");
        assert!(
            refusals
                .iter()
                .any(|r| r.contains("is not the suite file it names")),
            "{refusals:#?}"
        );
    }
}

mod site {
    use super::forged_fixture;
    use crate::common::{self, scratch};
    use serde_json::Value;

    #[test]
    fn the_site_shows_success_per_preset_beside_clean_with_the_drop() {
        let bundles = scratch("perturb-site").join("bundles");
        std::fs::create_dir_all(&bundles).unwrap();
        crate::leaderboard::pack(forged_fixture(), &bundles.join("expert.tar.zst"), true);
        let site = scratch("perturb-site").join("site");
        common::autobio_ok(&[
            "leaderboard",
            "build",
            bundles.to_str().unwrap(),
            "--out",
            site.to_str().unwrap(),
        ]);
        let html = std::fs::read_to_string(site.join("index.html")).unwrap();
        assert!(
            html.contains("Robustness") && html.contains("<th>layout:1</th>"),
            "{html}"
        );
        let json: Value =
            serde_json::from_slice(&std::fs::read(site.join("robustness.json")).unwrap()).unwrap();
        let (group, table) = json.as_object().unwrap().iter().next().unwrap();
        assert!(group.contains("robustness-smoke"), "{group}");
        assert_eq!(table["presets"], serde_json::json!(["light:2", "layout:1"]));
        let row = &table["rows"][0];
        // The expert wins every episode, clean and perturbed: no drop, an interval about it.
        assert_eq!(row["clean"][0], 100.0);
        for cell in row["cells"].as_array().unwrap() {
            assert_eq!(cell["success"], 100.0);
            assert_eq!(cell["drop"], 0.0);
            let [lo, hi] = [0, 1].map(|k| cell["drop_interval"][k].as_f64().unwrap());
            assert!(lo < 0.0 && hi > 0.0, "{cell}");
        }
        let md = std::fs::read_to_string(site.join("ranking.md")).unwrap();
        assert!(
            md.contains("| model | clean % | light:2 | layout:1 |"),
            "{md}"
        );
    }
}

/// The genuine `robustness-smoke` run's bundle members (shared with the site test).
fn forged_fixture() -> &'static std::collections::BTreeMap<String, Vec<u8>> {
    &forged::genuine().1
}

/// A `[perturb]` table and paraphrases with every dimension, mutated 600 ways (values swapped for
/// others of every type and size, keys misspelt, units changed, lines dropped): compiling never
/// panics, every diagnostic lies inside the file, and a task that compiles draws and shows its
/// perturbations for two seeds without a panic.
#[test]
fn mutated_perturb_tables_never_panic_and_point_inside_themselves() {
    use rand_chacha::ChaCha8Rng;
    use rand_core::{RngCore, SeedableRng};
    let base = std::fs::read_to_string("protocols/thermal_cycler/close_lid.toml").unwrap()
        + r#"
[perturb]
light = { intensity = [0.5, 1.5], direction_deg = 20, colour = 0.2, lights = [1, 3] }
material = { of = ["bench", "robots"], hue = 0.1, saturation = 0.2, value = 0.2 }
camera = { shift_m = 0.02, turn_deg = 2, fovy_deg = 3, cameras = ["table_front"] }
noise = { gaussian = 0.02, blur_px = 0.5, jpeg_quality = [40, 80] }
language = { rewrite = 2 }
robot_start = { joints_rad = 0.03 }
layout = { shift_mm = 10, turn_deg = 5 }
distractors = { count = [1, 2], kinds = ["tube_rack"] }
"#;
    let values = [
        "0",
        "-1",
        "1e9",
        "nan",
        "\"x\"",
        "[]",
        "[1]",
        "[3, 1]",
        "[1, 2, 3]",
        "{}",
        "true",
        "\"5 deg\"",
        "[\"bench\", 2]",
        "0.5",
        "2",
        "3",
        "[0, 4]",
        "[1e300, 1e301]",
    ];
    let lines: Vec<&str> = base.lines().collect();
    let first = lines.iter().position(|l| *l == "[perturb]").unwrap();
    let mut rng = ChaCha8Rng::seed_from_u64(51);
    let mut compiled = 0;
    for _ in 0..600 {
        let mut out: Vec<String> = lines.iter().map(|l| l.to_string()).collect();
        for _ in 0..1 + rng.next_u32() % 3 {
            let at = first + 1 + (rng.next_u32() as usize) % (lines.len() - first - 1);
            let line = out[at].clone();
            let v = values[(rng.next_u32() as usize) % values.len()];
            out[at] = match rng.next_u32() % 5 {
                // A value replaced.
                0 => match line.find("= ") {
                    Some(i) => {
                        let rest = &line[i + 2..];
                        let end = rest.find([',', '}']).unwrap_or(rest.len());
                        format!("{}= {v}{}", &line[..i], &rest[end..])
                    }
                    None => line,
                },
                // The whole dimension replaced by a value.
                1 => match line.split_once(" = ") {
                    Some((k, _)) => format!("{k} = {v}"),
                    None => line,
                },
                // A key misspelt or its unit changed.
                2 => line
                    .replacen("_deg", "_rad", 1)
                    .replacen("shift", "shfit", 1),
                3 => String::new(),
                _ => line.replacen('[', "", 1),
            };
        }
        let text = out.join("\n");
        let (task, diags) = compiler::compile_source(&text, "mutated.toml");
        for d in &diags {
            assert!(d.span.end <= text.len(), "{d:?} outside:\n{text}");
        }
        if let Some(t) = task {
            compiled += 1;
            let _ = compiler::perturb::problems(&t);
            for seed in [0, 1] {
                let i = t.sample(seed);
                assert_eq!(i, t.sample(seed));
            }
        }
    }
    assert!(
        compiled > 50,
        "only {compiled} of 600 compiled: the mutations test nothing drawn"
    );
}
