//! Reach before any episode (`scoring::reach`, E0036), on the real robot models and MuJoCo: every
//! shipped protocol's steps are reached; a robot stood too far from its work gets the error at
//! the step, and the base its hint names makes the protocol check clean and the expert win it,
//! for an arm with a closed-form IK (the ViperX) and one solved by the QP (the UR5e).

mod common;

use common::run;
use std::path::Path;

/// The protocol at `path` with its first robot's base line replaced, checked as `autobio check`
/// checks it.
fn checked(path: &str, from: &str, to: &str, tag: &str) -> compiler::Checked {
    let source = std::fs::read_to_string(path).unwrap();
    assert!(source.contains(from), "{path} has no `{from}`");
    let edited = source.replacen(from, to, 1);
    let dir = common::scratch(&format!("reach-{tag}"));
    let file = dir.join(Path::new(path).file_name().unwrap());
    std::fs::write(&file, edited).unwrap();
    let mut c = compiler::check_file(&file, None).unwrap();
    scoring::reach::check(&mut c);
    c
}

/// The base the hint of `c`'s E0036 names, as written in it.
fn hinted_base(c: &compiler::Checked) -> String {
    let d = c
        .diagnostics
        .iter()
        .find(|d| d.code == dsl::Code::E0036)
        .unwrap_or_else(|| panic!("no E0036 in {:#?}", c.diagnostics));
    let hint = d.hint.as_deref().unwrap();
    let start = hint.find("pos_m = [").unwrap() + "pos_m = ".len();
    let end = start + hint[start..].find(']').unwrap() + 1;
    hint[start..end].to_string()
}

#[test]
fn every_shipped_protocol_reaches_its_targets() {
    for dir in std::fs::read_dir("protocols").unwrap() {
        for f in std::fs::read_dir(dir.unwrap().path()).unwrap() {
            let path = f.unwrap().path();
            let mut c = compiler::check_file(&path, None).unwrap();
            scoring::reach::check(&mut c);
            let missed: Vec<_> = c
                .diagnostics
                .iter()
                .filter(|d| d.code == dsl::Code::E0036)
                .collect();
            assert!(missed.is_empty(), "{}: {missed:#?}", path.display());
        }
    }
}

/// Stood `far`, the arm misses step 1's grasp; stood where the hint says, the protocol checks
/// clean and the expert wins seed 0.
fn the_hint_fixes(path: &str, base: &str, far: &str, tag: &str) {
    let too_far = checked(path, base, far, &format!("{tag}-far"));
    assert!(too_far.task.is_none());
    let d = too_far
        .diagnostics
        .iter()
        .find(|d| d.code == dsl::Code::E0036)
        .unwrap();
    assert!(
        d.message.contains("cannot reach step 1's target") && d.message.contains("mm off"),
        "{}",
        d.message
    );
    let hinted = hinted_base(&too_far);
    let fixed = checked(
        path,
        base,
        &format!("base = {{ pos_m = {hinted} }}"),
        &format!("{tag}-hinted"),
    );
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
    the_hint_fixes(
        "protocols/tube/pick_up.toml",
        "base = { pos_m = [-0.1, 0.0, 0.824] }",
        "base = { pos_m = [-0.75, 0.0, 0.824] }",
        "aloha",
    );
}

#[test]
fn a_ur5e_stood_out_of_reach_gets_e0036_and_its_hint_base_works() {
    the_hint_fixes(
        "protocols/tube/transfer.toml",
        "base = { pos_m = [-0.1, 0.0, 0.824] }",
        "base = { pos_m = [-0.9, 0.0, 0.824] }",
        "ur5e",
    );
}
