//! Protocol synthesis (issue 26): `autobio synth` writes protocols that `autobio check` passes
//! with nothing to say, within the asked number of steps, on every bench its sources stand on;
//! the same seed writes the same files and another seed others; a step its source follows with
//! the arm standing back keeps that follow-up; sources with nothing to recombine are a clear
//! error; and the expert runs what it wrote.

use crate::common;

use common::{autobio, autobio_ok, scratch, text};
use std::collections::BTreeMap;
use std::path::Path;

const FROM: &str = "protocols/workflows/stages";

fn synth(out: &Path, seed: &str, count: &str, steps: &str) {
    autobio_ok(&[
        "synth",
        "--from",
        FROM,
        "--count",
        count,
        "--steps",
        steps,
        "--seed",
        seed,
        "--out",
        out.to_str().unwrap(),
    ]);
}

/// The protocol files a run wrote (not the scene copies), by name, with their text.
fn protocols(dir: &Path) -> BTreeMap<String, String> {
    std::fs::read_dir(dir)
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter_map(|p| {
            let text = std::fs::read_to_string(&p).ok()?;
            text.contains("[protocol]")
                .then(|| (p.file_name().unwrap().to_string_lossy().into_owned(), text))
        })
        .collect()
}

#[test]
fn synthesised_protocols_check_clean_and_one_seed_writes_one_set() {
    let (a, b, c) = (scratch("synth-a"), scratch("synth-b"), scratch("synth-c"));
    // Three protocols a run: enough for both benches and two seeds (six took twice as long).
    synth(&a, "3", "3", "4..6");
    synth(&b, "3", "3", "4..6");
    synth(&c, "4", "3", "4..6");
    let (pa, pb, pc) = (protocols(&a), protocols(&b), protocols(&c));
    assert_eq!(pa.len(), 3, "{:?}", pa.keys());
    assert_eq!(pa, pb, "the same seed writes the same files, byte for byte");
    assert_ne!(
        pa.values().collect::<Vec<_>>(),
        pc.values().collect::<Vec<_>>(),
        "another seed writes other protocols"
    );
    // Both benches under the sources are used (the bench is drawn per protocol).
    for bench in ["lab_bench", "centrifuge_bench"] {
        assert!(
            pa.keys().chain(pc.keys()).any(|k| k.starts_with(bench)),
            "no protocol on {bench}: {:?} {:?}",
            pa.keys(),
            pc.keys()
        );
        assert!(
            a.join(format!("{bench}.toml")).is_file(),
            "the scene is copied beside them"
        );
    }
    for (name, body) in &pa {
        let steps = body.matches("[[steps]]").count();
        assert!((4..=6).contains(&steps), "{name}: {steps} steps\n{body}");
        let path = a.join(name);
        let out = autobio(&["check", path.to_str().unwrap()]);
        assert!(
            out.status.success() && text(&out.stderr).is_empty(),
            "{name} does not check clean:\n{}{}\n{body}",
            text(&out.stdout),
            text(&out.stderr)
        );
    }
}

#[test]
fn a_step_keeps_the_arm_standing_back_that_follows_it_in_its_source() {
    // In the centrifuge run's load stage the loader stands back (`retract`) after placing the
    // tube in the rotor, so that the lid can swing shut; `retract` changes nothing the walk can
    // see, so it comes only as that place's follow-up.
    let out = scratch("synth-follow");
    synth(&out, "5", "12", "5..8");
    let mut places = 0;
    for (name, body) in protocols(&out) {
        let steps: Vec<&str> = body.split("[[steps]]").skip(1).collect();
        for (i, s) in steps.iter().enumerate() {
            if s.contains("to = \"centrifuge.") {
                places += 1;
                let next = steps.get(i + 1).copied().unwrap_or_default();
                assert!(
                    next.contains("do = \"retract\"") && next.contains("with = \"loader\""),
                    "{name}: a place into the rotor without the loader standing back after it\n{body}"
                );
            }
        }
        let retracts = body.matches("do = \"retract\"").count();
        assert!(
            retracts <= steps.len() / 2,
            "{name}: retracts are follow-ups, never chosen for themselves\n{body}"
        );
    }
    assert!(places > 0, "no protocol placed a tube in the rotor");
}

#[test]
fn sources_without_a_shared_scene_file_are_a_clear_error() {
    // `protocols/tube` writes each scene inline: nothing to recombine.
    let out = scratch("synth-inline");
    let r = autobio(&[
        "synth",
        "--from",
        "protocols/tube",
        "--out",
        out.to_str().unwrap(),
    ]);
    assert_eq!(r.status.code(), Some(2), "{}", text(&r.stderr));
    let err = text(&r.stderr);
    assert!(err.contains("names a scene file"), "{err}");
    let r = autobio(&["synth", "--from", FROM, "--steps", "5..3", "--out", "x"]);
    assert!(!r.status.success());
    assert!(text(&r.stderr).contains("A <= B"), "{}", text(&r.stderr));
}

#[test]
fn the_expert_runs_a_synthesised_protocol_and_hold_does_not() {
    let out = scratch("synth-run");
    synth(&out, "7", "4", "4..5");
    let (name, _) = protocols(&out)
        .into_iter()
        .find(|(n, _)| n.starts_with("lab_bench"))
        .expect("a protocol on the lab bench");
    let path = out.join(&name);
    let checked = compiler::check_file(&path, None).unwrap();
    let task = checked.task.expect("it compiles");
    let expert = common::run(&task, 0, "expert");
    assert!(expert.error.is_none(), "{name}: {:?}", expert.error);
    assert!(expert.success, "{name}: {:#?}", expert.verdict);
    let hold = common::run(&task, 0, "hold");
    assert!(!hold.success, "{name}: a motionless robot passes");
}
