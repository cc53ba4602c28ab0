//! Wrong outcomes on real MuJoCo fail their checks (the tube transfer's wrong slot is in
//! tests/tube_transfer.rs, every task's no-motion run in tests/hold_control.rs): a lid left shut
//! fails open_lid; a lid shut without pressing the lever fails close_lid on the latch rule; a chain
//! that finishes only its first stage gets partial credit and fails; the two-arm task fails when
//! only the lid is done. (The Aloha tasks' wrong outcomes, a tube let go and a cap half
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
