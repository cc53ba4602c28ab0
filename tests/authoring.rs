//! What a protocol author meets when running a protocol (issue 29, first part): a trivial task
//! (success holds before the first step) is refused by `eval` and `demo` unless allowed, with
//! `check`'s warnings shown; an episode that ends in an error scores 0, so an all-error run
//! reports success 0 and mean score 0; results name the real results file and carry predicates
//! with the seed's values filled in; failure lines name what the seed drew and number steps from
//! 1; `autobio render` draws a seed's initial scene.

use crate::common;
use common::{autobio, autobio_ok, scratch, text};

const TRIVIAL: &str = "tests/corpus/warnings/success_holds_at_start.toml";

/// The results JSON a tube-transfer run wrote into `dir`.
fn transfer_results(dir: &std::path::Path) -> serde_json::Value {
    let path = dir.join("tube.transfer.results.json");
    serde_json::from_str(&std::fs::read_to_string(path).unwrap()).unwrap()
}

#[test]
fn a_trivial_protocol_is_refused_by_eval_and_demo_and_runs_when_allowed() {
    let dir = scratch("trivial");
    let out_dir = dir.display().to_string();
    for args in [
        vec![
            "eval",
            "--protocol",
            TRIVIAL,
            "--episodes",
            "1",
            "--policy",
            "hold",
        ],
        vec![
            "demo",
            "--protocol",
            TRIVIAL,
            "--episodes",
            "1",
            "--out",
            &out_dir,
        ],
    ] {
        let out = autobio(&args);
        let said = text(&out.stderr);
        assert_eq!(out.status.code(), Some(2), "{args:?}: {said}");
        assert!(
            said.contains("warning[W0001]") && said.contains(":52:8"),
            "{args:?}: check's warning, at its place: {said}"
        );
        assert!(said.contains("--allow-trivial"), "{said}");
    }
    // Allowed, it runs; the no-motion control wins it, which is why it is refused.
    let out = autobio_ok(&[
        "eval",
        "--protocol",
        TRIVIAL,
        "--episodes",
        "2",
        "--policy",
        "hold",
        "--allow-trivial",
    ]);
    assert!(out.contains("100.0%"), "{out}");
    // A protocol with no warning runs as before, printing none.
    let out = autobio(&[
        "eval",
        "--protocol",
        "protocols/tube/transfer.toml",
        "--episodes",
        "1",
        "--policy",
        "hold",
    ]);
    assert!(out.status.success());
    assert!(
        !text(&out.stderr).contains("warning["),
        "{}",
        text(&out.stderr)
    );
}

#[test]
fn an_all_error_run_scores_zero_even_on_a_task_whose_checks_hold() {
    let dir = scratch("all-errors");
    let empty = dir.join("no-recordings");
    std::fs::create_dir_all(&empty).unwrap();
    let policy = format!("replay:{}", empty.display());
    let out = dir.join("run");
    autobio_ok(&[
        "eval",
        "--protocol",
        TRIVIAL,
        "--episodes",
        "3",
        "--policy",
        &policy,
        "--allow-trivial",
        "--out",
        out.to_str().unwrap(),
    ]);
    let results = transfer_results(&out);
    let episodes = results["episodes"].as_array().unwrap();
    assert!(!episodes.is_empty(), "{results}");
    for e in episodes {
        assert_eq!(e["outcome"], "policy_error", "{e}");
        assert_eq!(e["verdict"]["score"], 0.0, "{e}");
        // The checks did hold: what scores 0 is the error, not the state.
        assert_eq!(e["verdict"]["stages"][0]["predicates"][0]["holds"], true);
    }
    let summary = &results["summary"];
    assert_eq!(summary["success_rate"], 0.0, "{summary}");
    assert_eq!(summary["mean_score"], 0.0, "{summary}");
}

#[test]
fn results_name_the_real_file_and_the_filled_in_predicate() {
    let dir = scratch("filled");
    let out = autobio_ok(&[
        "eval",
        "--protocol",
        "protocols/tube/transfer.toml",
        "--episodes",
        "2",
        "--policy",
        "hold",
        "--out",
        dir.to_str().unwrap(),
    ]);
    let path = dir.join("tube.transfer.results.json");
    assert!(
        out.contains(&format!("results: {}", path.display())),
        "{out}"
    );
    assert!(!out.contains("<task>"), "{out}");
    let results: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&path).unwrap()).unwrap();
    let task = common::compile("protocols/tube/transfer.toml");
    let episodes = results["episodes"].as_array().unwrap();
    assert_eq!(episodes.len(), 2, "{results}");
    for e in episodes {
        let drawn = task.sample(e["seed"].as_u64().unwrap()).params;
        let want = format!("tube in target.{}{}", drawn["row"], drawn["col"]);
        let text = &e["verdict"]["stages"][0]["predicates"][0]["text"];
        assert_eq!(text, &serde_json::Value::String(want), "{e}");
    }
}

#[test]
fn failure_lines_name_the_seeds_draw_and_count_steps_from_one() {
    let protocol = scratch("hand-over").join("hand_over.toml");
    std::fs::write(&protocol, common::HAND_OVER).unwrap();
    let path = protocol.to_str().unwrap();
    let out = autobio(&["eval", "--protocol", path, "--episodes", "1", "--seed", "4"]);
    let said = text(&out.stderr);
    let task = common::compile(path);
    let slot = &task.sample(4).params["slot"];
    assert!(
        said.contains(&format!("seed 4 (run 0; drew slot={slot})")),
        "{said}"
    );
    // The protocol's second step (`hand_over`; the first is `pick`) is step 2.
    assert!(said.contains("step 2 `hand_over`"), "{said}");
}

#[test]
fn render_draws_a_seeds_initial_scene_and_seeds_differ() {
    let dir = scratch("render");
    let png = |seed: &str| {
        let path = dir.join(format!("seed{seed}.png"));
        let out = autobio_ok(&[
            "render",
            "protocols/tube/transfer.toml",
            "--seed",
            seed,
            "--png",
            path.to_str().unwrap(),
            "--size",
            "96x64",
        ]);
        assert!(out.contains("table_front, arm/wrist, above"), "{out}");
        assert!(out.contains("drew col="), "{out}");
        results::Image::from_png("sheet", &std::fs::read(&path).unwrap()).unwrap()
    };
    let (a, b, a_again) = (png("1"), png("2"), png("1"));
    assert_eq!((a.width, a.height), (96 * 3, 64));
    assert!(common::spread(&a.rgb) > 10.0, "a picture, not a blank");
    assert_ne!(
        a.rgb, b.rgb,
        "two seeds of a randomised task draw two scenes"
    );
    assert_eq!(a.rgb, a_again.rgb, "the same seed draws the same picture");
}

#[test]
fn a_parameter_driven_slot_sums_up_its_bad_values_in_one_diagnostic() {
    let checked = compiler::check_file(
        std::path::Path::new("tests/corpus/multi/parameter_slots.toml"),
        None,
    )
    .unwrap();
    assert_eq!(checked.diagnostics.len(), 2, "{:#?}", checked.diagnostics);
    for d in &checked.diagnostics {
        assert!(
            d.message.contains("`row = C` (any `col`)")
                && d.message.contains("`col = 6` (any `row`)"),
            "{}",
            d.message
        );
        assert!(
            d.hint
                .as_deref()
                .is_some_and(|h| h.contains("2x5 grid, A1..B5")),
            "{:?}",
            d.hint
        );
        // The summary depends on the parameters; it names no single combination.
        assert!(d.notes.is_empty(), "{:?}", d.notes);
    }
}

#[test]
fn names_units_and_state_words_get_what_the_author_meant() {
    let checked = compiler::check_file(
        std::path::Path::new("tests/corpus/multi/keys_and_states.toml"),
        None,
    )
    .unwrap();
    let hint = |code: &str, message: &str| -> String {
        checked
            .diagnostics
            .iter()
            .find(|d| d.code.as_str() == code && d.message.contains(message))
            .and_then(|d| d.hint.clone())
            .unwrap_or_else(|| panic!("no {code} `{message}` in {:#?}", checked.diagnostics))
    };
    assert!(hint("E0003", "time_limit_sec").contains("did you mean `time_limit_s`?"));
    assert!(hint("E0003", "`action`").contains("do = \"close_lid\""));
    let state = hint("E0017", "unlocked");
    assert!(state.starts_with("declare `closed`"), "{state}");
    let units = compiler::check_file(
        std::path::Path::new("tests/corpus/multi/units_and_slots.toml"),
        None,
    )
    .unwrap();
    let messages: Vec<&str> = units
        .diagnostics
        .iter()
        .map(|d| d.message.as_str())
        .collect();
    for (unit, meant) in [("RPM", "rpm"), ("C", "°C"), ("secs", "s")] {
        assert!(
            messages
                .iter()
                .any(|m| m.contains(&format!("unknown unit `{unit}`"))
                    && m.ends_with(&format!("did you mean `{meant}`?"))),
            "{messages:?}"
        );
    }
}

#[test]
fn a_failing_slot_predicate_says_which_part_failed_and_by_how_much() {
    let dir = scratch("parts");
    let out = autobio(&[
        "eval",
        "--protocol",
        "protocols/tube/transfer.toml",
        "--episodes",
        "1",
        "--policy",
        "hold",
        "--out",
        dir.to_str().unwrap(),
    ]);
    let said = text(&out.stderr);
    assert!(
        said.contains("failed (in-plane distance ") && said.contains("mm, within 15.0 mm)"),
        "{said}"
    );
    let results = transfer_results(&dir);
    let p = &results["episodes"][0]["verdict"]["stages"][0]["predicates"][0];
    let parts = p["parts"].as_array().unwrap();
    let names: Vec<&str> = parts.iter().map(|q| q["name"].as_str().unwrap()).collect();
    assert_eq!(names, ["in-plane distance", "height", "tilt"]);
    // The tube stands upright in the other rack, at the racks' common height: only the distance
    // fails, and it is the predicate's own value.
    let holds: Vec<bool> = parts
        .iter()
        .map(|q| q["holds"].as_bool().unwrap())
        .collect();
    assert_eq!(holds, [false, true, true], "{parts:?}");
    assert_eq!(parts[0]["value"], p["value"]);
    // A predicate that holds carries no parts.
    let dir = scratch("parts-expert");
    autobio_ok(&[
        "eval",
        "--protocol",
        "protocols/tube/transfer.toml",
        "--episodes",
        "1",
        "--out",
        dir.to_str().unwrap(),
    ]);
    let results = transfer_results(&dir);
    let p = &results["episodes"][0]["verdict"]["stages"][0]["predicates"][0];
    assert_eq!(p["holds"], true);
    assert!(p.get("parts").is_none(), "{p}");
}

/// A round trip in one protocol: "was open" remembers a state seen at some control step, so the
/// lid that starts closed, is opened and is closed again is a task a motionless arm fails.
#[test]
fn a_round_trip_with_the_history_predicate_checks_clean_fails_hold_and_the_expert_wins_it() {
    let file = "protocols/thermal_cycler/open_and_close.toml";
    let checked = compiler::check_file(std::path::Path::new(file), None).unwrap();
    assert!(checked.diagnostics.is_empty(), "{:#?}", checked.diagnostics);
    let task = checked.task.unwrap();
    for seed in [0, 7] {
        let expert = common::run(&task, seed, "expert");
        assert!(expert.success, "seed {seed}: {:?}", expert.verdict);
        let was = &expert.verdict.predicates()[0];
        assert!(was.text == "cycler.lid was open" && was.holds, "{was:?}");
        // At the end the lid is shut: what holds is the memory of it open, not the state now.
        assert!((was.value - was.target).abs() > was.tolerance, "{was:?}");
        let hold = common::run(&task, seed, "hold");
        assert!(
            !hold.success && hold.verdict.score == 0.0,
            "{:?}",
            hold.verdict
        );
        assert!(!hold.verdict.predicates()[0].holds);
    }
    // Without the history predicate the same protocol is trivial (its success holds at the
    // start) and refused.
    let dir = scratch("round-trip");
    let trivial = dir.join("trivial.toml");
    std::fs::write(
        &trivial,
        std::fs::read_to_string(file)
            .unwrap()
            .replace("\"cycler.lid was open\", ", ""),
    )
    .unwrap();
    let out = autobio(&[
        "eval",
        "--protocol",
        trivial.to_str().unwrap(),
        "--episodes",
        "1",
    ]);
    assert_eq!(out.status.code(), Some(2));
    assert!(text(&out.stderr).contains("W0001"), "{}", text(&out.stderr));
}

#[test]
fn describe_with_a_seed_shows_everything_the_seed_draws() {
    let file = "protocols/tube/transfer.toml";
    let out = autobio_ok(&["describe", file, "--seed", "3"]);
    let drawn = common::compile(file).sample(3);
    let joints: Vec<String> = drawn.robot_q[0].iter().map(|v| format!("{v:.3}")).collect();
    assert!(
        out.contains(&format!("robot arm joints [{}] rad", joints.join(", "))),
        "{out}"
    );
    assert!(
        out.contains("labware target at (0.300, 0.200, 0.854) m"),
        "{out}"
    );
    assert!(
        out.contains(&format!("labware tube in source.{}", drawn.params["from"])),
        "{out}"
    );
    // Another seed draws another start.
    let other = autobio_ok(&["describe", file, "--seed", "4"]);
    let line = |s: &str| {
        s.lines()
            .find(|l| l.contains("robot arm joints"))
            .map(String::from)
    };
    assert_ne!(line(&out), line(&other));
}

/// A tube whose cap starts off is built open (walls on a base, no cap): `check` says nothing
/// about it (W0007 is for starts a model cannot set up) and the catalogue marks no state of the
/// cap as unsimulated.
#[test]
fn a_tube_whose_cap_starts_off_is_simulated_open() {
    let catalogue = autobio_ok(&["describe", "--catalogue"]);
    assert!(
        catalogue.contains("part cap: on | off | apart (may start on | off | apart)\n"),
        "{catalogue}"
    );
    assert!(!catalogue.contains("not simulated yet"), "{catalogue}");
    let out = autobio(&["check", "protocols/pipette/aspirate.toml"]);
    assert!(out.status.success());
    assert!(
        !text(&out.stderr).contains("W0007"),
        "{}",
        text(&out.stderr)
    );
}
