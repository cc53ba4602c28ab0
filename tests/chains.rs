//! Long-horizon chains and the language's CLI on real files: both thermal-cycler chains run with
//! the expert to success stage by stage on real MuJoCo, an impossible chain is rejected at compile
//! time at the offending step, progress scoring gives partial credit, and `describe` / `explain`
//! / `check --json` work as processes.

use expert::ExpertPolicy;
use scoring::episode::{EpisodeOptions, run_episode};
use std::path::Path;
use std::process::Command;
use std::sync::Arc;

fn compile(path: &str) -> compiler::Task {
    let source = std::fs::read_to_string(path).unwrap();
    let (task, diags) = compiler::compile_source(&source, path);
    task.unwrap_or_else(|| panic!("{path}: {diags:#?}"))
}

fn expert(task: &compiler::Task, seed: u64) -> results::episode::EpisodeResult {
    let instance = task.sample(seed);
    let scene = Arc::new(runtime::Scene::build(task, &instance).unwrap());
    let mut policy = ExpertPolicy::new(task, &scene, &instance).unwrap();
    run_episode(
        task,
        &scene,
        &instance,
        &mut policy,
        &EpisodeOptions::default(),
    )
    .unwrap()
}

#[test]
fn every_inverse_chain_runs_to_success_stage_by_stage() {
    for (path, first, second) in [
        (
            "protocols/thermal_cycler/close_then_open.toml",
            "thermal_cycler.close_lid",
            "thermal_cycler.open_lid",
        ),
        (
            "protocols/thermal_cycler/open_then_close.toml",
            "thermal_cycler.open_lid",
            "thermal_cycler.close_lid",
        ),
        // The opener's retreat from the raised lid is planned here: a lone open_lid episode ends
        // at success, before it.
        (
            "protocols/centrifuge_5430/open_then_close.toml",
            "centrifuge_5430.open_lid",
            "centrifuge_5430.close_lid",
        ),
        (
            "protocols/centrifuge_mini/open_then_close.toml",
            "centrifuge_mini.open_lid",
            "centrifuge_mini.close_lid",
        ),
        (
            "protocols/centrifuge_5910/open_then_close.toml",
            "centrifuge_5910.open_lid",
            "centrifuge_5910.close_lid_riser",
        ),
    ] {
        let task = compile(path);
        assert_eq!(task.stages.len(), 2);
        assert_eq!(
            task.time_limit_s,
            task.stages[0].time_limit_s + task.stages[1].time_limit_s
        );
        let r = expert(&task, 21);
        assert!(r.success, "{path}: {:?} {:#?}", r.error, r.verdict);
        let v = &r.verdict;
        assert_eq!(v.stages.len(), 2);
        assert_eq!(
            (v.stages[0].id.as_str(), v.stages[1].id.as_str()),
            (first, second)
        );
        let (t1, t2) = (
            v.stages[0].completed_at_s.unwrap(),
            v.stages[1].completed_at_s.unwrap(),
        );
        assert!(0.0 < t1 && t1 < t2, "{t1} {t2}");
        assert_eq!(v.score, 1.0);
    }
}

#[test]
fn a_chain_that_closes_a_closed_lid_is_rejected_at_the_step() {
    let path = "tests/corpus/faulty/chain_close_twice.toml";
    // The chain names shipped protocols, outside its own folder: the repository is its root.
    let checked = compiler::check_file(Path::new(path), Some(Path::new("."))).unwrap();
    assert!(checked.task.is_none());
    let d = checked
        .diagnostics
        .iter()
        .find(|d| d.code == dsl::Code::E0031)
        .unwrap();
    let file = d.file.as_deref().unwrap();
    assert!(file.ends_with("close_lid.toml"), "{file}");
    let text = std::fs::read_to_string(file).unwrap();
    assert_eq!(&text[d.span.start..d.span.end], "\"close_lid\"");
    assert!(
        d.notes.iter().any(|n| n.contains("starts where stage 1")),
        "{d:?}"
    );
    // The note names the chain line that included the stage.
    assert!(
        d.notes
            .iter()
            .any(|n| n == &format!("in stage 1, included from {path}:8:12")),
        "{:?}",
        d.notes
    );
    // Without a wider root the chain may not read them at all.
    let confined = compiler::check_file(Path::new(path), None).unwrap();
    assert!(
        !confined.diagnostics.is_empty()
            && confined
                .diagnostics
                .iter()
                .all(|d| d.code == dsl::Code::E0009 && d.file.is_none()),
        "{:?}",
        confined.diagnostics
    );
    // And the CLI renders it against the stage's file.
    let out = Command::new(env!("CARGO_BIN_EXE_autobio"))
        .args(["check", "--root", ".", path])
        .output()
        .unwrap();
    assert_eq!(out.status.code(), Some(1));
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(err.contains("error[E0031]"), "{err}");
    assert!(err.contains("close_lid.toml:25:6"), "{err}");
}

#[test]
fn progress_scoring_gives_partial_credit() {
    let source = std::fs::read_to_string("protocols/thermal_cycler/close_lid.toml")
        .unwrap()
        .replace("time_limit = \"31.5 s\"", "time_limit = \"7 s\"")
        .replace(
            "all = [\"cycler.lid is closed\", \"cycler.lid is locked\"]",
            "all = [\"cycler.lid is closed\", \"cycler.lid is locked\"]\nscoring = \"progress\"\nweights = [3, 1]",
        );
    let (task, diags) = compiler::compile_source(&source, "close_lid_progress.toml");
    let task = task.unwrap_or_else(|| panic!("{diags:#?}"));
    assert_eq!(task.stages[0].scoring, compiler::Scoring::Progress);
    let r = expert(&task, 5);
    assert!(!r.success, "7 s is too short to close and lock");
    let v = &r.verdict.stages[0];
    let closed = &v.predicates[0];
    assert!(closed.progress > 0.1 && closed.progress < 1.0, "{closed:?}");
    let expected = (3.0 * closed.progress + v.predicates[1].progress) / 4.0;
    assert!((v.score - expected).abs() < 1e-12, "{v:?}");
    assert!(r.verdict.score > 0.0 && r.verdict.score < 1.0);
}

#[test]
fn describe_explain_and_json_check_as_processes() {
    let bin = env!("CARGO_BIN_EXE_autobio");
    let out = Command::new(bin)
        .args(["describe", "protocols/thermal_mixer/set_parameters.toml"])
        .output()
        .unwrap();
    assert!(out.status.success());
    let sheet = String::from_utf8_lossy(&out.stdout);
    for needle in [
        "{rpm} integer 300..=1500 step 50, never 900",
        "set_parameter(on = mixer, param = speed, value = {rpm} rpm) with arm",
        "mixer.temperature = {temp} °C [display = 0.000001] (weight 0.5)",
        "progress scoring",
    ] {
        assert!(sheet.contains(needle), "{needle} not in\n{sheet}");
    }
    let out = Command::new(bin)
        .args(["describe", "--catalogue"])
        .output()
        .unwrap();
    let cat = String::from_utf8_lossy(&out.stdout);
    for p in compiler::primitives::CATALOGUE {
        assert!(cat.contains(&p.signature()), "{}", p.name);
    }
    let out = Command::new(bin)
        .args(["explain", "e0031"])
        .output()
        .unwrap();
    assert!(String::from_utf8_lossy(&out.stdout).contains("precondition"));
    let out = Command::new(bin)
        .args(["explain", "--all"])
        .output()
        .unwrap();
    assert_eq!(
        String::from_utf8_lossy(&out.stdout).lines().count(),
        dsl::Code::ALL.len()
    );
    let out = Command::new(bin)
        .args(["check", "--json", "tests/corpus/faulty/unknown_level.toml"])
        .output()
        .unwrap();
    assert_eq!(out.status.code(), Some(1));
    let line: serde_json::Value =
        serde_json::from_str(String::from_utf8_lossy(&out.stdout).lines().next().unwrap()).unwrap();
    assert_eq!(line["code"], "E0021");
    assert_eq!(
        (line["line"].as_u64(), line["column"].as_u64()),
        (Some(7), Some(9))
    );
}

#[test]
fn unmodelled_labware_is_refused_by_the_runtime_with_a_reason() {
    // Every catalogue kind has a model now; a compiled task (JSON from an older build, or a kind
    // added to the catalogue before its model) can still carry none.
    let source = r#"
format = 1

[protocol]
id = "pipette.pick"
instruction = "pick up the pipette"
time_limit = "10 s"

[robots.arm]
model = "ur5e_2f85"
base = { pos_m = [0.0, 0.5, 0.824] }

[labware.pipette]
kind = "pipette"
pose = { pos_m = [0.0, 0.0, 0.83] }

[[steps]]
do = "pick"
on = "pipette"
with = "arm"

[success]
all = ["arm touches pipette"]
"#;
    let (task, diags) = compiler::compile_source(source, "pipette.toml");
    let mut task = task.unwrap_or_else(|| panic!("{diags:#?}"));
    assert!(runtime::Scene::build(&task, &task.sample(0)).is_ok());
    task.labware[0].params = labware::Model::Unmodelled;
    let err = runtime::Scene::build(&task, &task.sample(0))
        .err()
        .expect("a task whose item has no model");
    assert!(err.to_string().contains("no simulation model yet"), "{err}");
}

/// What a later stage says about its own start, randomisation and camera is ignored by the
/// chain, and each place it differs from what the chain carries is a warning there.
#[test]
fn a_later_stage_start_that_the_chain_ignores_is_warned_at_each_place() {
    let path = "tests/corpus/warnings/chain_stage_start_differs.toml";
    let checked = compiler::check_file(Path::new(path), Some(Path::new("."))).unwrap();
    assert!(checked.task.is_some(), "{:#?}", checked.diagnostics);
    let mut found: Vec<(usize, usize, String)> = checked
        .diagnostics
        .iter()
        .map(|d| {
            assert_eq!(d.code, dsl::Code::W0008, "{d:?}");
            let (file, text) = checked.text_of(d).unwrap();
            assert!(file.ends_with("cycler_close_start_differs.toml"), "{file}");
            let (line, col) = dsl::render::line_col(&text, d.span.start);
            (line, col, text[d.span.start..d.span.end].to_string())
        })
        .collect();
    found.sort();
    assert_eq!(
        found,
        [
            (19, 17, "\"closed\"".to_string()),
            (21, 12, "arm".to_string()),
            (24, 1, "[camera]".to_string()),
        ]
    );
    // The shipped chains declare one scene in every stage: not a word.
    for chain in [
        "protocols/thermal_cycler/open_then_close.toml",
        "protocols/thermal_cycler/close_then_open.toml",
        "protocols/centrifuge_5430/open_then_close.toml",
        "protocols/centrifuge_mini/open_then_close.toml",
        "protocols/centrifuge_5910/open_then_close.toml",
    ] {
        let checked = compiler::check_file(Path::new(chain), None).unwrap();
        assert!(
            checked.diagnostics.is_empty(),
            "{chain}: {:#?}",
            checked.diagnostics
        );
    }
}

/// `eval` with the expert says which stage's time limit is tight: a chain's later stage starts
/// where the one before left the robot. The shipped chain, with its own limits, draws no word.
#[test]
fn the_expert_run_warns_of_a_tight_stage_time_limit() {
    let run = |path: &str| {
        let out = tempfile_dir(path);
        let o = Command::new(env!("CARGO_BIN_EXE_autobio"))
            .args([
                "eval",
                "--root",
                ".",
                "--protocol",
                path,
                "--policy",
                "expert",
            ])
            .args(["--episodes", "2", "--workers", "2", "--out", &out])
            .output()
            .unwrap();
        assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
        String::from_utf8_lossy(&o.stderr).to_string()
    };
    let said = run("tests/data/chains/tight_close.toml");
    let warning = said
        .lines()
        .find(|l| {
            l.starts_with("warning: stage 2 `thermal_cycler.close_lid` has a tight time limit")
        })
        .unwrap_or_else(|| panic!("{said}"));
    assert!(warning.contains("of its 10.5 s"), "{warning}");
    assert!(
        said.contains("starts where stage 1 left the robot"),
        "{said}"
    );
    assert!(!said.contains("stage 1 `"), "{said}");
    let shipped = run("protocols/thermal_cycler/open_then_close.toml");
    assert!(!shipped.contains("tight time limit"), "{shipped}");
}

fn tempfile_dir(name: &str) -> String {
    let dir = std::env::temp_dir().join(format!(
        "autobio-chains-{}-{}",
        std::process::id(),
        name.replace('/', "_")
    ));
    let _ = std::fs::remove_dir_all(&dir);
    dir.display().to_string()
}
