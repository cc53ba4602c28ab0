//! The episode's failure paths on real MuJoCo: a policy error, an empty action chunk, an action of
//! the wrong length and a non-finite action each end the episode as a failure with its reason, at
//! the step where it happened; an unstable simulation ends the control step with its reason (the
//! same error path in the episode loop as the non-finite action). And `scoring::eval::evaluate` writes each
//! finished episode to the journal before the next one starts, with results JSON that carries its
//! schema version.

use crate::common;

use policy::Observation;
use policy::Policy;
use policy::PolicyError;
use scoring::policies::HoldPolicy;

fn task() -> compiler::Task {
    common::compile("protocols/thermal_cycler/close_lid.toml")
}

/// Holds still for `good` calls, then answers with `then`.
struct Faulty<F: FnMut(&Observation) -> Result<Vec<Vec<f64>>, PolicyError>> {
    good: usize,
    then: F,
}

impl<F: FnMut(&Observation) -> Result<Vec<Vec<f64>>, PolicyError>> Policy for Faulty<F> {
    fn name(&self) -> String {
        "faulty".into()
    }

    fn act(&mut self, obs: &Observation) -> Result<Vec<Vec<f64>>, PolicyError> {
        if self.good > 0 {
            self.good -= 1;
            return HoldPolicy.act(obs);
        }
        (self.then)(obs)
    }
}

fn run(policy: impl Policy + 'static) -> results::episode::EpisodeResult {
    common::run_with(&task(), 0, &Default::default(), |_, _, _| Box::new(policy))
}

fn assert_failed_at(r: &results::episode::EpisodeResult, steps: u64, reason: &str) {
    assert!(!r.success && !r.verdict.success, "{r:?}");
    assert_eq!(r.outcome, results::episode::Outcome::PolicyError, "{r:?}");
    assert_eq!(r.control_steps, steps, "ended at the failing step");
    let error = r.error.as_deref().expect("a reason");
    assert!(error.contains(reason), "{error}");
}

#[test]
fn a_policy_error_ends_the_episode_with_its_reason() {
    let r = run(Faulty {
        good: 3,
        then: |_: &Observation| Err(PolicyError::Failed("the model server crashed".into())),
    });
    assert_failed_at(&r, 3, "the policy failed: the model server crashed");
}

#[test]
fn an_empty_chunk_ends_the_episode() {
    let r = run(Faulty {
        good: 2,
        then: |_: &Observation| Ok(vec![]),
    });
    assert_failed_at(&r, 2, "empty action chunk");
}

#[test]
fn an_action_of_the_wrong_length_ends_the_episode() {
    let r = run(Faulty {
        good: 4,
        then: |obs: &Observation| Ok(vec![obs.privileged.ctrl()[..6].to_vec()]),
    });
    assert_failed_at(&r, 4, "action has 6 values, the robots take 7");
}

#[test]
fn a_non_finite_action_ends_the_episode() {
    for bad in [f64::NAN, f64::INFINITY] {
        let r = run(Faulty {
            good: 1,
            then: move |obs: &Observation| {
                let mut a = obs.privileged.ctrl();
                a[2] = bad;
                Ok(vec![a])
            },
        });
        assert_failed_at(
            &r,
            1,
            &format!("action value 2 is not a finite number ({bad})"),
        );
    }
}

#[test]
fn an_unstable_simulation_ends_the_step_with_its_reason() {
    let t = task();
    let (instance, scene) = common::scene(&t, 0);
    let mut ep = runtime::Episode::new(scene, &t, &instance);
    ep.control_step().unwrap();
    // A blown-up velocity, as a diverging integration produces.
    ep.data.qvel_mut()[0] = f64::NAN;
    let err = ep.control_step().unwrap_err();
    assert!(
        matches!(err, runtime::StepError::Unstable { .. }),
        "{err:?}"
    );
    assert!(
        err.to_string().contains("simulation became unstable"),
        "{err}"
    );
}

#[test]
fn the_journal_has_each_episode_before_the_next_starts() {
    let t = task();
    let dir = common::scratch("journal").join("out");
    let opts = scoring::eval::EvalOptions {
        policy: scoring::policies::PolicySpec::Hold,
        episodes: 3,
        seed: 40,
        out: Some(dir.clone()),
        record: false,
        image_every: 0,
        resume: false,
        ..Default::default()
    };
    let journal = dir.join(format!("{}.journal.jsonl", t.id));
    let mut seen = Vec::new();
    let report = scoring::eval::evaluate(&t, &opts, |p| {
        let e = p.result;
        // Called after the journal write and before the next episode.
        let text = std::fs::read_to_string(&journal).unwrap();
        let lines: Vec<&str> = text.lines().collect();
        assert_eq!(lines.len(), seen.len() + 1);
        let last: results::episode::EpisodeResult =
            serde_json::from_str(lines[lines.len() - 1]).unwrap();
        assert_eq!(&last, e);
        seen.push(e.seed);
    })
    .unwrap();
    assert_eq!(seen, [40, 41, 42]);
    assert_eq!(report.summary.successes, 0, "hold scores 0");
    let results: serde_json::Value = serde_json::from_str(
        &std::fs::read_to_string(dir.join(format!("{}.results.json", t.id))).unwrap(),
    )
    .unwrap();
    assert_eq!(
        results["schema_version"].as_u64(),
        Some(u64::from(results::run::RESULTS_SCHEMA_VERSION))
    );
    assert_eq!(results["policy"], "hold");
    assert_eq!(results["episodes"].as_array().unwrap().len(), 3);
    // Every episode is classed, and all are in the denominator.
    assert_eq!(
        results["summary"]["outcomes"],
        serde_json::json!({"time_limit": 3})
    );
    let ci = &results["summary"]["wilson_95"];
    assert_eq!(ci[0], 0.0);
    assert!((ci[1].as_f64().unwrap() - 0.5615).abs() < 1e-3, "{ci}");
    let _ = std::fs::remove_dir_all(&dir);
}

/// An unstable simulation through the real episode loop and evaluation run: a task stepped at a
/// timestep its contacts and actuators cannot take (50 ms: the arm's position servos overshoot
/// and the accelerations blow up) ends each episode as `unstable` with the time it happened, in
/// the journal and the results, and the run goes on to its next episode.
#[test]
fn an_unstable_simulation_is_an_unstable_episode_in_the_results() {
    let mut t = task();
    t.physics.timestep_s = 0.05;
    t.physics.substeps = 1;
    let dir = common::scratch("unstable").join("out");
    let opts = scoring::eval::EvalOptions {
        policy: scoring::policies::PolicySpec::Expert,
        episodes: 2,
        seed: 0,
        out: Some(dir.clone()),
        ..Default::default()
    };
    let report = scoring::eval::evaluate(&t, &opts, |_| {}).unwrap();
    assert_eq!(report.episodes.len(), 2);
    for e in &report.episodes {
        assert_eq!(e.outcome, results::episode::Outcome::Unstable, "{e:?}");
        assert!(!e.success && e.verdict.score == 0.0);
        let error = e.error.as_deref().unwrap();
        assert!(
            error.contains("simulation became unstable at t="),
            "{error}"
        );
        // MuJoCo does not silently reset the state and carry on: the episode ends where it
        // blew up, and says when.
        assert!(e.control_steps > 0, "{e:?}");
        let ran = e.control_steps as f64 * t.physics.timestep_s * t.physics.substeps as f64;
        assert!(
            (e.sim_time_s - ran).abs() < 0.051,
            "{} s after {ran} s of steps",
            e.sim_time_s
        );
        let at: f64 = error
            .split("at t=")
            .nth(1)
            .and_then(|s| s.split(' ').next())
            .and_then(|s| s.parse().ok())
            .unwrap();
        assert!(
            (at - e.sim_time_s).abs() < 0.051,
            "{at} vs {}",
            e.sim_time_s
        );
    }
    let results: serde_json::Value = serde_json::from_str(
        &std::fs::read_to_string(dir.join(format!("{}.results.json", t.id))).unwrap(),
    )
    .unwrap();
    assert_eq!(
        results["summary"]["outcomes"],
        serde_json::json!({"unstable": 2})
    );
    let journal = common::journal(&dir, &t.id);
    assert_eq!(journal.len(), 2);
    assert!(journal.iter().all(|e| e["outcome"] == "unstable"));
    let _ = std::fs::remove_dir_all(&dir);
}
