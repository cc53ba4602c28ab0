//! Reach before any episode (`expert::reach`, E0036), on the real robot models and MuJoCo: every
//! shipped protocol's steps are reached; a robot stood too far from its work, a slot placed out of
//! its reach, or a lid's arc it gives out along, gets the error at the step, and the base its hint
//! names makes the protocol check clean (and the expert win it, for the grasp, slot and press
//! point cases), for
//! an arm with a closed-form IK (the ViperX) and one solved by the QP (the UR5e). A slot out of
//! reach in only some layouts is W0010, naming the seeds whose episodes then fail at planning.
//! The corpus's arc, joint-limit and partial-range cases (and the shipped protocols edited out of
//! reach for a grasp, a slot and a press point above) each get a hinted base from which the file
//! checks with no reach diagnostic and the expert wins.

use crate::common;

use common::run;
use std::path::Path;

/// The protocol at `path` with the line `from` replaced by `to`, checked as `autobio check`
/// checks it.
fn checked(path: &str, from: &str, to: &str, tag: &str) -> compiler::Checked {
    let source = std::fs::read_to_string(path).unwrap();
    assert!(source.contains(from), "{path} has no `{from}`");
    check_as(path, &source.replacen(from, to, 1), &format!("reach-{tag}"))
}

/// `source` written as `path`'s file name in a scratch folder named `scratch`, checked as
/// `autobio check` checks it (the compiler, then reach).
fn check_as(path: &str, source: &str, scratch: &str) -> compiler::Checked {
    let file = common::scratch(scratch).join(Path::new(path).file_name().unwrap());
    std::fs::write(&file, source).unwrap();
    let mut c = compiler::check_file(&file, None).unwrap();
    expert::reach::check(&mut c, &expert::reach::Store::none());
    c
}

/// The base the hint of `c`'s E0036 names, as written in it.
fn hinted_base(c: &compiler::Checked) -> String {
    hint_of(c, dsl::Code::E0036).1
}

/// The hint of `c`'s first `code` diagnostic, and the base it names as written in it.
fn hint_of(c: &compiler::Checked, code: dsl::Code) -> (String, String) {
    let d = c
        .diagnostics
        .iter()
        .find(|d| d.code == code)
        .unwrap_or_else(|| panic!("no {code:?} in {:#?}", c.diagnostics));
    let hint = d.hint.clone().unwrap();
    let start = hint
        .find("pos_m = [")
        .unwrap_or_else(|| panic!("no base in the hint: {hint}"))
        + "pos_m = ".len();
    let end = start + hint[start..].find(']').unwrap() + 1;
    let base = hint[start..end].to_string();
    (hint, base)
}

#[test]
fn every_shipped_protocol_reaches_its_targets_in_every_sampled_layout() {
    // Every file under `protocols/`, the workflows' stage files and scenes included.
    let mut files = Vec::new();
    let mut dirs = vec![std::path::PathBuf::from("protocols")];
    while let Some(d) = dirs.pop() {
        for f in std::fs::read_dir(d).unwrap() {
            let path = f.unwrap().path();
            if path.is_dir() {
                dirs.push(path);
            } else {
                files.push(path);
            }
        }
    }
    assert!(files.len() > 30, "{files:?}");
    {
        for path in files {
            let mut c = compiler::check_file(&path, None).unwrap();
            expert::reach::check(&mut c, &expert::reach::Store::none());
            let errors: Vec<_> = c
                .diagnostics
                .iter()
                .filter(|d| d.code.as_str().starts_with('E'))
                .collect();
            assert!(errors.is_empty(), "{}: {errors:#?}", path.display());
            let missed: Vec<_> = c
                .diagnostics
                .iter()
                .filter(|d| matches!(d.code, dsl::Code::E0036 | dsl::Code::W0010))
                .collect();
            assert!(missed.is_empty(), "{}: {missed:#?}", path.display());
        }
    }
}

/// With `from` written `far`, the arm misses step `step`'s target; stood where the hint says, the
/// protocol checks clean and the expert wins seed 0. `base` is the robot's base line.
fn the_hint_fixes(path: &str, base: &str, (from, far): (&str, &str), step: usize, tag: &str) {
    let too_far = checked(path, from, far, &format!("{tag}-far"));
    assert!(too_far.task.is_none());
    // One report at the step, saying how close the best solve came.
    let at_step = format!("cannot reach step {step}'s target");
    let reports: Vec<&dsl::Diagnostic> = too_far
        .diagnostics
        .iter()
        .filter(|d| d.code == dsl::Code::E0036 && d.message.contains(&at_step))
        .collect();
    assert_eq!(reports.len(), 1, "{:#?}", too_far.diagnostics);
    assert!(
        reports[0].message.contains(" rad off"),
        "{}",
        reports[0].message
    );
    let hinted = hinted_base(&too_far);
    // The edit that put it out of reach, and the robot where the hint stands it.
    let stood = format!("base = {{ pos_m = {hinted} }}");
    let source = std::fs::read_to_string(path)
        .unwrap()
        .replacen(from, far, 1);
    let robot_now = if from == base { far } else { base };
    let source = source.replacen(robot_now, &stood, 1);
    let fixed = check_as(path, &source, &format!("reach-{tag}-hinted"));
    assert!(
        fixed.diagnostics.iter().all(|d| !d.is_error()),
        "{hinted}: {:#?}",
        fixed.diagnostics
    );
    let r = run(fixed.task.as_ref().unwrap(), 0, "expert");
    assert!(r.success, "from {hinted}: {:#?}", r.verdict);
}

#[test]
fn an_aloha_stood_out_of_reach_gets_e0036_and_its_hint_base_works() {
    let base = "base = { pos_m = [-0.1, 0.0, 0.824] }";
    let far = "base = { pos_m = [-0.75, 0.0, 0.824] }";
    the_hint_fixes("protocols/tube/pick_up.toml", base, (base, far), 1, "aloha");
}

#[test]
fn a_ur5e_stood_out_of_reach_gets_e0036_and_its_hint_base_works() {
    let base = "base = { pos_m = [-0.1, 0.0, 0.824] }";
    let far = "base = { pos_m = [-0.9, 0.0, 0.824] }";
    the_hint_fixes("protocols/tube/transfer.toml", base, (base, far), 1, "ur5e");
}

/// The slot a tube is placed in, out of reach: the seat is solved with the tube held as the
/// pick grasped it.
#[test]
fn a_place_out_of_reach_gets_e0036_at_its_step_and_its_hint_base_works() {
    let base = "base = { pos_m = [-0.1, 0.0, 0.824] }";
    let target = "pose = { pos_m = [0.3, 0.2, 0.854], yaw_deg = 90 }";
    let far = "pose = { pos_m = [0.5, 0.8, 0.854], yaw_deg = 90 }";
    the_hint_fixes(
        "protocols/tube/transfer.toml",
        base,
        (target, far),
        2,
        "seat",
    );
}

/// The rack of tubes stood past the pipetting arm's reach: the pipette's tip, as the hand holds
/// it, cannot be brought over the source tube's mouth (nor under its surface), E0036 says so at
/// the aspirate, and from the hinted base the transfer is made.
#[test]
fn a_tube_out_of_the_pipettes_reach_gets_e0036_and_its_hint_base_works() {
    let base = "base = { pos_m = [0.0, -0.5, 0.824] }";
    let target = "pose = { pos_m = [0.0, 0.0, 0.854] }";
    let far = "pose = { pos_m = [0.0, 0.5, 0.854] }";
    the_hint_fixes(
        "protocols/pipette/transfer.toml",
        base,
        (target, far),
        1,
        "pipette",
    );
}

/// The thermal mixer stood past the arm's reach: the first button the panel steps need (the
/// press point, and the point 4 cm back along it where the finger comes in from) is out of
/// reach, E0036 says so at that step, and from the hinted base the panel is set.
#[test]
fn a_press_point_out_of_reach_gets_e0036_and_its_hint_base_works() {
    let base = "base = { pos_m = [0.0, 0.5, 0.824] }";
    let target = "pose = { pos_m = [-0.05, 0.0, 0.824], yaw_deg = 180 }";
    let far = "pose = { pos_m = [-0.05, -0.35, 0.824], yaw_deg = 180 }";
    the_hint_fixes(
        "protocols/thermal_mixer/set_parameters.toml",
        base,
        (target, far),
        1,
        "press",
    );
}

/// The 5910 opened from a riser moved about: too low, its lid bar is reached but not the bar's
/// arc, and E0036 says where along the arc the arm gives out (no base at that height is clear
/// of the centrifuge: the hint raises the arm, and from there the protocol checks clean); moved
/// aside, the key and bar are out of reach, and from the hinted base the protocol checks clean. (The expert then plans
/// the run, but does not yet swing the lid open from there: reach is not success.)
#[test]
fn a_lid_out_of_reach_is_found_along_its_arc_and_a_hinted_base_checks_clean() {
    let dir = common::scratch("reach-arc");
    let riser = std::fs::read_to_string("protocols/centrifuge_5910/riser.toml").unwrap();
    let stands = "base = { pos_m = [0.4, 0.25, 1.45], yaw_deg = -90 }";
    assert!(riser.contains(stands));
    std::fs::copy(
        "protocols/centrifuge_5910/open_lid.toml",
        dir.join("open_lid.toml"),
    )
    .unwrap();
    let check = |base: &str| {
        std::fs::write(dir.join("riser.toml"), riser.replacen(stands, base, 1)).unwrap();
        let mut c = compiler::check_file(&dir.join("open_lid.toml"), None).unwrap();
        expert::reach::check(&mut c, &expert::reach::Store::none());
        c
    };
    let low = check("base = { pos_m = [0.4, 0.25, 1.0], yaw_deg = -90 }");
    let arc = low
        .diagnostics
        .iter()
        .find(|d| d.code == dsl::Code::E0036 && d.message.contains("step 2's target"))
        .unwrap_or_else(|| panic!("{:#?}", low.diagnostics));
    assert!(
        arc.message
            .contains("`lid_open` and along the path it then follows, at pose"),
        "{}",
        arc.message
    );
    // No base at that height is clear of the centrifuge: the hint raises the arm, and stood
    // there the protocol checks clean.
    assert!(
        arc.hint.as_deref().unwrap().contains("higher: on a riser"),
        "{arc:?}"
    );
    let aside = check("base = { pos_m = [0.55, 0.25, 1.45], yaw_deg = -90 }");
    assert!(aside.task.is_none());
    for hinted in [hinted_base(&low), hinted_base(&aside)] {
        let fixed = check(&format!("base = {{ pos_m = {hinted}, yaw_deg = -90 }}"));
        assert!(
            fixed.diagnostics.iter().all(|d| !d.is_error()),
            "{hinted}: {:#?}",
            fixed.diagnostics
        );
    }
}

/// A target rack at the arm's edge: W0010 names the seeds whose drawn slot is out of reach, and
/// the expert fails at planning on exactly those while it wins the others.
#[test]
fn a_slot_out_of_reach_in_some_layouts_is_a_warning_naming_the_seeds_that_fail() {
    let c = checked(
        "protocols/tube/transfer.toml",
        "pose = { pos_m = [0.3, 0.2, 0.854], yaw_deg = 90 }",
        "pose = { pos_m = [0.5, 0.6, 0.854], yaw_deg = 90 }",
        "partial",
    );
    let task = c.task.as_ref().expect("a warning, not an error");
    let seeds = expert::reach::partly_unreachable(task, &expert::reach::Store::none());
    assert_eq!(seeds.get(&1), Some(&vec![4, 5]), "{seeds:?}");
    let w = c
        .diagnostics
        .iter()
        .find(|d| d.code == dsl::Code::W0010)
        .unwrap();
    assert!(w.message.contains("step 2's target") && w.message.contains("(seeds 4, 5)"));
    assert!(!run(task, 4, "expert").success);
    assert!(run(task, 1, "expert").success);
}

/// The 5430's opening with its arm stood `y` metres from the centrifuge's centre line: the lid
/// task's own files, copied with the scene's base moved.
fn opening_from(y: f64) -> compiler::Task {
    let dir = common::scratch(&format!("margin-{y}"));
    for f in ["scene.toml", "open_lid.toml"] {
        let text = std::fs::read_to_string(format!("protocols/centrifuge_5430/{f}")).unwrap();
        let from = "base = { pos_m = [0.0, 0.5, 0.824] }";
        let text = if f == "scene.toml" {
            assert!(text.contains(from));
            text.replace(from, &format!("base = {{ pos_m = [0.0, {y}, 0.824] }}"))
        } else {
            text
        };
        std::fs::write(dir.join(f), text).unwrap();
    }
    compiler::check_file(&dir.join("open_lid.toml"), None)
        .unwrap()
        .task
        .unwrap()
}

#[test]
fn a_steps_reach_margin_shrinks_as_its_robot_stands_back_and_is_none_out_of_reach() {
    // `describe`'s figure for step 2 (the lid lifted along its arc): the 5430's own layout has
    // its arc at the edge of the arm's reach.
    let margin = |y: f64| {
        let m = expert::reach::margins(&opening_from(y));
        assert_eq!(m.len(), 2, "{m:?}");
        assert_eq!((m[1].step, m[1].robot.as_str()), (1, "arm"));
        m[1].margin
    };
    let near = margin(0.4).expect("reached from 0.4 m");
    let shipped = margin(0.5).expect("reached from the shipped 0.5 m");
    assert!(near > shipped + 0.05, "{near} vs {shipped}");
    assert!(
        shipped < 0.05,
        "the shipped arc is near the edge: {shipped}"
    );
    assert_eq!(margin(0.6), None, "out of reach from 0.6 m");
    // And the step the arm reaches easily (the key on the panel) keeps room at any of these.
    let key = expert::reach::margins(&opening_from(0.6))[0]
        .margin
        .unwrap();
    assert!(key > 0.1, "{key}");
}

#[test]
fn a_target_in_reach_only_past_a_joint_range_names_the_joint_and_a_lower_shelf_checks_clean() {
    // The rack on a shelf above the bench, close in front of the ViperX: coming down onto the
    // tube needs the wrist bent past its range, which is the reason given, not a distance.
    let shelf = "pose = { pos_m = [0.15, 0.0, 1.15], yaw_deg = 90 }";
    let rack = "pose = { pos_m = [0.3, 0.0, 0.854], yaw_deg = 90 }";
    let high = checked("protocols/tube/pick_up.toml", rack, shelf, "joint-high");
    let e = high
        .diagnostics
        .iter()
        .find(|d| d.code == dsl::Code::E0036)
        .unwrap_or_else(|| panic!("{:#?}", high.diagnostics));
    assert!(
        e.message
            .contains("within the arm's reach, but only past joint `wrist_angle`'s range"),
        "{}",
        e.message
    );
    assert!(!e.message.contains("closest solve"), "{}", e.message);
    // 18 cm lower the wrist has room, for the grasp, the way in and the lift: clean.
    let lower = "pose = { pos_m = [0.15, 0.0, 0.97], yaw_deg = 90 }";
    let low = checked("protocols/tube/pick_up.toml", rack, lower, "joint-low");
    assert!(
        !low.diagnostics.iter().any(|d| d.code == dsl::Code::E0036),
        "{:#?}",
        low.diagnostics
    );
}

/// The corpus case at `path` (one robot) gets `code` with a hinted base; with the robot's base
/// line rewritten to it, the file checks with no error and no reach warning at all (the hint
/// covers every sampled layout), and the expert wins each of `seeds`.
fn the_corpus_hint_fixes(path: &str, code: dsl::Code, seeds: &[u64], tag: &str) -> String {
    let source = std::fs::read_to_string(path).unwrap();
    let mut c = compiler::check_file(Path::new(path), None).unwrap();
    expert::reach::check(&mut c, &expert::reach::Store::none());
    let (hint, hinted) = hint_of(&c, code);
    let line = source
        .lines()
        .find(|l| l.starts_with("base = { pos_m = ["))
        .unwrap();
    let stood = source.replacen(line, &format!("base = {{ pos_m = {hinted} }}"), 1);
    let fixed = check_as(path, &stood, &format!("reach-corpus-{tag}"));
    assert!(
        fixed
            .diagnostics
            .iter()
            .all(|d| !d.is_error() && d.code != dsl::Code::W0010),
        "{hinted}: {:#?}",
        fixed.diagnostics
    );
    let task = fixed.task.as_ref().unwrap();
    for &seed in seeds {
        let r = run(task, seed, "expert");
        assert!(r.success, "seed {seed} from {hinted}: {:#?}", r.verdict);
    }
    hint
}

/// The arc case: the 5430's lid bar is taken but its arc runs out of reach; from the hinted base
/// the file checks clean and the expert opens the lid.
#[test]
fn the_arc_corpus_case_hints_a_base_from_which_the_lid_is_opened() {
    the_corpus_hint_fixes(
        "tests/corpus/faulty/lid_arc_out_of_reach.toml",
        dsl::Code::E0036,
        &[0],
        "arc",
    );
}

/// The joint-limit case: no base at the arm's height brings the wrist within its range over the
/// shelf, so the hint raises the arm (a riser), from where the expert picks the tube up.
#[test]
fn the_joint_limit_corpus_case_hints_a_raised_base_from_which_the_tube_is_picked() {
    let hint = the_corpus_hint_fixes(
        "tests/corpus/faulty/step_past_joint_limit.toml",
        dsl::Code::E0036,
        &[0],
        "joint",
    );
    assert!(hint.contains("higher: on a riser"), "{hint}");
}

/// The partial-range case: W0010's hint names a base from which the slots every sampled layout
/// draws are reached, and the expert wins the seeds that failed at planning before.
#[test]
fn the_partial_range_corpus_case_hints_a_base_that_reaches_every_layout() {
    the_corpus_hint_fixes(
        "tests/corpus/warnings/place_partly_out_of_reach.toml",
        dsl::Code::W0010,
        &[4, 5],
        "partial",
    );
}

/// `autobio check FILE` with its reach outcomes kept under `cache`: stdout and stderr.
fn check_cached(file: &str, cache: &Path) -> String {
    let out = std::process::Command::new(env!("CARGO_BIN_EXE_autobio"))
        .args(["check", file])
        .env("AUTOBIO_CACHE_DIR", cache)
        .env("NO_COLOR", "1")
        .output()
        .unwrap();
    format!("{}{}", common::text(&out.stdout), common::text(&out.stderr))
}

/// The files a reach store holds.
fn kept(cache: &Path) -> Vec<std::path::PathBuf> {
    std::fs::read_dir(cache.join("reach"))
        .map(|d| d.map(|e| e.unwrap().path()).collect())
        .unwrap_or_default()
}

#[test]
fn kept_reach_outcomes_give_the_same_diagnostics_and_an_edit_is_solved_afresh() {
    let cache = common::scratch("reach-store");
    // A step out of reach (E0036 with its base hint) and a clean protocol: each checked with an
    // empty store, then answered from it, then with its entries corrupted.
    for file in [
        "tests/corpus/faulty/step_out_of_reach.toml",
        "protocols/thermal_cycler/close_lid.toml",
    ] {
        let cold = check_cached(file, &cache);
        let entries = kept(&cache).len();
        assert!(entries > 0, "{file}: nothing kept");
        let warm = check_cached(file, &cache);
        assert_eq!(warm, cold, "{file}: answered from the store");
        assert_eq!(kept(&cache).len(), entries, "{file}: solved again");
        for f in kept(&cache) {
            std::fs::write(f, "{ not json").unwrap();
        }
        assert_eq!(
            check_cached(file, &cache),
            cold,
            "{file}: a corrupt entry is a miss"
        );
        // What the store says is what was solved: the faulty file's error is in it.
        if file.contains("faulty") {
            assert!(cold.contains("E0036"), "{cold}");
        }
    }
    // An edited protocol (its robot moved out of reach) is solved afresh: new entries, and the
    // error the edit causes, not the clean outcome kept for the file before it.
    let source = std::fs::read_to_string("protocols/thermal_cycler/close_lid.toml").unwrap();
    let moved = common::scratch("reach-store-edit").join("close_lid.toml");
    let edited = source.replacen(
        "base = { pos_m = [0.0, 0.5, 0.824] }",
        "base = { pos_m = [0.0, 1.1, 0.824] }",
        1,
    );
    assert_ne!(edited, source, "the edit did not apply");
    std::fs::write(&moved, edited).unwrap();
    let before = kept(&cache).len();
    let out = check_cached(moved.to_str().unwrap(), &cache);
    assert!(out.contains("E0036"), "{out}");
    assert!(
        kept(&cache).len() > before,
        "the edited task was not solved"
    );
    // An empty AUTOBIO_CACHE_DIR keeps nothing (not even in the home folder's cache).
    let home = common::scratch("reach-store-home");
    let none = std::process::Command::new(env!("CARGO_BIN_EXE_autobio"))
        .args(["check", "protocols/thermal_cycler/close_lid.toml"])
        .env("AUTOBIO_CACHE_DIR", "")
        .env("HOME", &home)
        .env_remove("XDG_CACHE_HOME")
        .output()
        .unwrap();
    assert!(none.status.success());
    assert!(!home.join(".cache").exists());
}

/// A loop's expansions are steps of their own: where the third expansion of a `for_each`
/// places its tube out of reach, E0036 names that expanded step (the plan's 6th) and points at
/// the loop body's step that wrote it, not at a top-level step of the file by the plan's index
/// (there is none: the file has one, the loop).
#[test]
fn a_for_each_whose_third_expansion_is_out_of_reach_points_at_the_loops_step() {
    let path = "protocols/tube/transfer.toml";
    let shipped = std::fs::read_to_string(path).unwrap();
    let steps = shipped.find("[[steps]]").unwrap();
    let mut head = shipped[..steps].to_string();
    for (from, to) in [
        ("\n[params.row]\nchoice = [\"A\", \"B\"]\n", "\n"),
        ("\n[params.col]\nint = [1, 5]\n", "\n"),
        ("\n[params.from]\nslot = \"source\"\n", "\n"),
        (
            ", row {row}, col {col}",
            ", and two more, the last into the far rack",
        ),
        (
            "[labware.tube]\nkind = \"tube_50ml\"\nat = \"source.{from}\"\n",
            "",
        ),
    ] {
        assert!(head.contains(from), "{path} has no {from:?}");
        head = head.replacen(from, to, 1);
    }
    let mut source = head;
    for (tube, at) in [("t1", "A1"), ("t2", "A3"), ("t3", "A5")] {
        source += &format!("[labware.{tube}]\nkind = \"tube_50ml\"\nat = \"source.{at}\"\n\n");
    }
    source += "[labware.far]\nkind = \"tube_rack\"\npose = { pos_m = [0.5, 0.8, 0.854], yaw_deg = 90 }\n\n\
[[steps]]\nfor_each = { tube = [\"t1\", \"t2\", \"t3\"], slot = [\"target.A1\", \"target.B3\", \"far.A1\"] }\n\n\
[[steps.body]]\ndo = \"pick\"\non = \"{tube}\"\nwith = \"arm\"\n\n\
[[steps.body]]\ndo = \"place\"\non = \"{tube}\"\nto = \"{slot}\"\nwith = \"arm\"\n\n\
[success]\nall = [\"t1 in target.A1\", \"t2 in target.B3\", \"t3 in far.A1\"]\n";
    let c = check_as(path, &source, "reach-for-each");
    let reach: Vec<&dsl::Diagnostic> = c
        .diagnostics
        .iter()
        .filter(|d| d.code == dsl::Code::E0036)
        .collect();
    assert_eq!(reach.len(), 1, "{:#?}", c.diagnostics);
    assert!(
        reach[0].message.contains("cannot reach step 6's target"),
        "{}",
        reach[0].message
    );
    // At the body's `place`, its `with`: the last `with = "arm"` of the file.
    let with = source.rfind("with = \"arm\"").unwrap() + "with = ".len();
    assert_eq!(
        &source[reach[0].span.start..reach[0].span.end],
        "\"arm\"",
        "{:#?}",
        reach[0]
    );
    assert_eq!(reach[0].span.start, with, "{:#?}", reach[0]);
    assert!(c.task.is_none());
}
