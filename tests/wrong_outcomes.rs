//! Wrong outcomes on real MuJoCo fail their checks (the tube transfer's wrong slot is in
//! tests/tube_transfer.rs, every task's no-motion run in tests/hold_control.rs): a lid left shut
//! fails open_lid; a lid shut without pressing the lever fails close_lid on the latch rule; a chain
//! that finishes only its first stage gets partial credit and fails; the two-arm task fails when
//! only the lid is done; every chain (the centrifuges' open-then-close, the thermal cycler's round
//! trips, the workflows) stopped before its last stage fails with partial credit, and one-stage
//! lids stopped part way fail. (The Aloha tasks' wrong outcomes, a tube let go and a cap half
//! unscrewed, are in tests/aloha.rs.)

use crate::common;

use common::{compile, predicate, run, run_with};
use expert::ExpertPolicy;
use policy::Observation;
use policy::Policy;
use policy::PolicyError;
use scoring::policies::HoldPolicy;

fn task(name: &str) -> compiler::Task {
    compile(&format!("protocols/thermal_cycler/{name}"))
}

/// The expert while `keep_going` says so, then no motion.
struct ExpertUntil<F: FnMut(&Observation) -> bool> {
    expert: ExpertPolicy,
    keep_going: F,
}

impl<F: FnMut(&Observation) -> bool> Policy for ExpertUntil<F> {
    fn name(&self) -> String {
        "expert-until".into()
    }

    fn act(&mut self, obs: &Observation) -> Result<Vec<Vec<f64>>, PolicyError> {
        if (self.keep_going)(obs) {
            self.expert.act(obs)
        } else {
            HoldPolicy.act(obs)
        }
    }
}

/// An episode of the expert, stopped (held still) once `keep_going` turns false.
fn expert_until(
    task: &compiler::Task,
    seed: u64,
    keep_going: impl FnMut(&Observation) -> bool + 'static,
) -> results::episode::EpisodeResult {
    run_with(task, seed, &Default::default(), |t, s, i| {
        Box::new(ExpertUntil {
            expert: ExpertPolicy::new(t, s, i).unwrap(),
            keep_going,
        })
    })
}

#[test]
fn open_lid_fails_while_the_lid_stays_shut() {
    let mut t = task("open_lid.toml");
    t.time_limit_s = 2.0;
    let r = run(&t, 2, "hold");
    assert!(!r.success && r.error.is_none(), "{r:?}");
    let open = predicate(&r, "cycler.lid is open");
    assert!(!open.holds, "{open:?}");
    // Still at the closed angle, far outside the open tolerance.
    assert!(
        (open.value - open.target).abs() > 10.0 * open.tolerance,
        "{open:?}"
    );
}

#[test]
fn a_lid_shut_without_pressing_the_lever_is_closed_but_not_locked() {
    let mut t = task("close_lid.toml");
    t.time_limit_s = 2.0;
    // The lid starts shut with the lever raised: the latch has not engaged.
    let cycler = t.labware_index("cycler").unwrap();
    t.labware[cycler]
        .initial
        .insert("lid".into(), "closed".into());
    let r = run(&t, 3, "hold");
    assert!(!r.success && r.error.is_none(), "{r:?}");
    let closed = predicate(&r, "cycler.lid is closed");
    assert!(closed.holds, "the lid is shut: {closed:?}");
    let locked = predicate(&r, "cycler.lid is locked");
    assert!(
        !locked.holds,
        "the latch locked without the lever: {locked:?}"
    );
    assert_eq!(r.verdict.score, 0.0, "binary scoring");
}

#[test]
fn a_chain_that_finishes_only_its_first_stage_fails_with_partial_credit() {
    let t = task("close_then_open.toml");
    let r = expert_until(&t, 4, |obs| obs.stage == 0);
    assert!(!r.success && r.error.is_none(), "{r:?}");
    let [first, second] = &r.verdict.stages[..] else {
        panic!("two stages: {:#?}", r.verdict)
    };
    assert!(first.success && first.completed_at_s.is_some(), "{first:?}");
    assert!(
        !second.success && second.completed_at_s.is_none(),
        "{second:?}"
    );
    assert_eq!(r.verdict.score, 0.5, "one of two stages");
    // The second stage ran out its own time limit, counted from the first stage's end.
    let end = first.completed_at_s.unwrap() + t.stages[1].time_limit_s;
    assert!(
        (r.sim_time_s - end).abs() < 0.05,
        "{} vs {end}",
        r.sim_time_s
    );
}

#[test]
fn the_two_arm_task_fails_when_only_the_lid_is_done() {
    let t = compile("protocols/two_arm/close_lid_and_transfer.toml");
    let cycler = t.labware_index("cycler").unwrap();
    let model = t.labware[cycler].params.clone();
    // Stopped a few control steps after the lid's lock check holds (the lever settled).
    let mut locked_for = 0;
    let r = expert_until(&t, 6, move |obs| {
        let state = &obs.privileged.labware[cycler];
        let m = model.instrument().unwrap();
        if m.measure("lid", "locked", None, state)
            .is_some_and(|m| m.holds)
        {
            locked_for += 1;
        }
        locked_for <= 5
    });
    assert!(!r.success && r.error.is_none(), "{r:?}");
    assert!(predicate(&r, "cycler.lid is locked").holds);
    let moved = r
        .verdict
        .predicates()
        .iter()
        .find(|p| p.text.starts_with("tube in target."))
        .unwrap();
    assert!(!moved.holds, "{moved:?}");
}

/// Stage k of n reached, then stopped: the expert until the chain's last stage starts, then no
/// motion (that stage's limit cut to 3 s, so the run is short): every earlier stage is done at
/// its time, the last is not, a check of it fails on the MuJoCo state, and the chain scores
/// partial credit, no success.
fn stopped_before_the_last_stage(path: &str, seed: u64) {
    let mut t = compile(path);
    let n = t.stages.len();
    assert!(n >= 2, "{path}: {n} stages");
    let cut = t.stages[n - 1].time_limit_s - 3.0;
    t.stages[n - 1].time_limit_s = 3.0;
    t.time_limit_s -= cut;
    let r = expert_until(&t, seed, move |obs| obs.stage < n - 1);
    assert!(!r.success && r.error.is_none(), "{path}: {r:?}");
    assert_eq!(r.verdict.stages.len(), n, "{path}: {:#?}", r.verdict);
    for s in &r.verdict.stages[..n - 1] {
        assert!(s.success && s.completed_at_s.is_some(), "{path}: {s:?}");
    }
    let last = &r.verdict.stages[n - 1];
    assert!(
        !last.success && last.completed_at_s.is_none(),
        "{path}: {last:?}"
    );
    assert!(
        last.predicates
            .iter()
            .any(|p| !p.value.is_nan() && !p.holds),
        "{path}: no measured check of the last stage fails: {last:?}"
    );
    assert!(
        r.verdict.score < 1.0 && r.verdict.score >= (n - 1) as f64 / n as f64 - 1e-9,
        "{path}: score {} for {} of {n} stages",
        r.verdict.score,
        n - 1
    );
}

/// A one-stage task stopped part way: the expert for `after_s` seconds, then no motion until
/// the limit (cut to 3 s later): a measured check fails and the episode scores below 1.
fn stopped_part_way(path: &str, seed: u64, after_s: f64) {
    let mut t = compile(path);
    assert_eq!(t.stages.len(), 1, "{path}");
    t.stages[0].time_limit_s = after_s + 3.0;
    t.time_limit_s = after_s + 3.0;
    let r = expert_until(&t, seed, move |obs| obs.time < after_s);
    assert!(!r.success && r.error.is_none(), "{path}: {r:?}");
    assert!(
        r.verdict
            .predicates()
            .iter()
            .any(|p| !p.value.is_nan() && !p.holds),
        "{path}: no measured check fails: {:#?}",
        r.verdict
    );
    assert!(r.verdict.score < 1.0, "{path}: {:#?}", r.verdict);
    // And the same seed, run to the end, wins: the stop is what failed it.
    let full = compile(path);
    assert!(run(&full, seed, "expert").success, "{path}: seed {seed}");
}

#[test]
fn centrifuge_open_then_close_chains_fail_with_the_lid_left_open() {
    for path in [
        "protocols/centrifuge_5430/open_then_close.toml",
        "protocols/centrifuge_5910/open_then_close.toml",
        "protocols/centrifuge_mini/open_then_close.toml",
    ] {
        stopped_before_the_last_stage(path, 1);
    }
}

#[test]
fn thermal_cycler_round_trips_fail_when_the_second_half_is_not_done() {
    // A chain of two stages, stopped once the first is done.
    stopped_before_the_last_stage("protocols/thermal_cycler/open_then_close.toml", 2);
    // One stage of two lab steps (open, then close), stopped after about the first step.
    stopped_part_way("protocols/thermal_cycler/open_and_close.toml", 2, 10.0);
}

#[test]
fn workflows_fail_when_their_last_stage_is_not_done() {
    for path in [
        "protocols/workflows/bench_run.toml",
        "protocols/workflows/centrifuge_run.toml",
        "protocols/workflows/mixer_cycle.toml",
        "protocols/workflows/mixer_run.toml",
    ] {
        stopped_before_the_last_stage(path, 3);
    }
}

#[test]
fn lids_stopped_part_way_fail() {
    stopped_part_way("protocols/centrifuge_5910/close_lid_riser.toml", 4, 5.0);
    stopped_part_way("protocols/centrifuge_mini/open_lid.toml", 5, 5.0);
}
