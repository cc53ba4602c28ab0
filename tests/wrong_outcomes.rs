//! Wrong outcomes on real MuJoCo fail their checks, for every simulated thermal-cycler task and
//! the chain (the tube transfer's wrong slot is in tests/tube_transfer.rs): the lid left locked
//! fails open_lid; a lid shut without pressing the lever fails close_lid on the latch rule; a chain
//! that finishes only its first stage gets partial credit and fails; the two-arm task fails when
//! only the lid is done. (The tube-unscrewing task has no expert motions yet: its control is the
//! no-motion run in tests/hold_control.rs.)

use scoring::episode::{EpisodeOptions, run_episode};
use scoring::expert::ExpertPolicy;
use scoring::{HoldPolicy, Observation, Policy, PolicyError};
use std::sync::Arc;

fn task(name: &str) -> compiler::Task {
    let path = format!("protocols/thermal_cycler/{name}");
    let (task, diags) = compiler::compile_source(&std::fs::read_to_string(&path).unwrap(), &path);
    task.unwrap_or_else(|| panic!("{diags:#?}"))
}

fn run(task: &compiler::Task, seed: u64, policy: &mut dyn Policy) -> scoring::EpisodeResult {
    let instance = task.sample(seed);
    let scene = Arc::new(runtime::Scene::build(task, &instance).unwrap());
    run_episode(task, &scene, &instance, policy, &EpisodeOptions::default()).unwrap()
}

fn predicate<'a>(r: &'a scoring::EpisodeResult, text: &str) -> &'a scoring::PredicateValue {
    r.verdict
        .predicates()
        .iter()
        .find(|p| p.text == text)
        .unwrap_or_else(|| panic!("no `{text}` in {:#?}", r.verdict))
}

#[test]
fn open_lid_fails_while_the_lid_stays_locked() {
    let mut t = task("open_lid.toml");
    t.time_limit_s = 2.0;
    let r = run(&t, 2, &mut HoldPolicy);
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
    let r = run(&t, 3, &mut HoldPolicy);
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

/// The expert for the first stage, then no motion.
struct FirstStageOnly(ExpertPolicy);

impl Policy for FirstStageOnly {
    fn name(&self) -> String {
        "first-stage-only".into()
    }

    fn act(&mut self, obs: &Observation) -> Result<Vec<Vec<f64>>, PolicyError> {
        if obs.stage == 0 {
            self.0.act(obs)
        } else {
            Ok(vec![obs.privileged.ctrl()])
        }
    }
}

#[test]
fn a_chain_that_finishes_only_its_first_stage_fails_with_partial_credit() {
    let t = task("close_then_open.toml");
    let seed = 4;
    let instance = t.sample(seed);
    let scene = Arc::new(runtime::Scene::build(&t, &instance).unwrap());
    let mut policy = FirstStageOnly(ExpertPolicy::new(&t, &scene, &instance).unwrap());
    let r = run_episode(
        &t,
        &scene,
        &instance,
        &mut policy,
        &EpisodeOptions::default(),
    )
    .unwrap();
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

/// The expert until the cycler's `lid is locked` check holds, then no motion.
struct UntilLocked {
    expert: ExpertPolicy,
    cycler: usize,
    model: labware::Model,
    locked_for: usize,
}

impl Policy for UntilLocked {
    fn name(&self) -> String {
        "until-locked".into()
    }

    fn act(&mut self, obs: &Observation) -> Result<Vec<Vec<f64>>, PolicyError> {
        let state = &obs.privileged.labware[self.cycler];
        let model = self.model.instrument().unwrap();
        if model
            .measure("lid", "locked", None, state)
            .is_some_and(|m| m.holds)
        {
            self.locked_for += 1;
        }
        // A few control steps after it holds, so that the lever has settled in its notch.
        if self.locked_for > 5 {
            Ok(vec![obs.privileged.ctrl()])
        } else {
            self.expert.act(obs)
        }
    }
}

#[test]
fn the_two_arm_task_fails_when_only_the_lid_is_done() {
    let path = "protocols/two_arm/close_lid_and_transfer.toml";
    let (t, diags) = compiler::compile_source(&std::fs::read_to_string(path).unwrap(), path);
    let t = t.unwrap_or_else(|| panic!("{diags:#?}"));
    let instance = t.sample(6);
    let scene = Arc::new(runtime::Scene::build(&t, &instance).unwrap());
    let cycler = t.labware_index("cycler").unwrap();
    let mut policy = UntilLocked {
        expert: ExpertPolicy::new(&t, &scene, &instance).unwrap(),
        cycler,
        model: t.labware[cycler].params.clone(),
        locked_for: 0,
    };
    let r = run_episode(
        &t,
        &scene,
        &instance,
        &mut policy,
        &EpisodeOptions::default(),
    )
    .unwrap();
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
