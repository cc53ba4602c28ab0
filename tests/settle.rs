//! Success is a state, not a moment: a stage is done only when its checks have gone on holding for
//! the settle time (`[success] settle`, default `compiler::DEFAULT_SETTLE_S`). A lid flung
//! through "open" and falling back is not opened; one that stays open is, once it has stayed.

use crate::common;

/// The judge over a lid-angle series: (time, lid angle) at the control period.
fn judge(task: &compiler::Task, series: &[(f64, f64)]) -> results::verdict::Verdict {
    let (instance, scene) = common::scene(task, 0);
    let ep = runtime::Episode::new(scene, task, &instance);
    let initial = ep.labware_state();
    let states: Vec<(f64, Vec<labware::LabwareState>)> = series
        .iter()
        .map(|&(t, lid)| {
            let mut s = initial.clone();
            let cycler = s.iter_mut().find(|l| l.name == "cycler").unwrap();
            cycler.joints.insert("lid".into(), lid);
            // Unlatched throughout: only the lid's angle decides.
            let lever = labware::thermal_cycler::Params::default().lever_raised;
            cycler.joints.insert("lever".into(), lever);
            cycler.logic.insert("locked".into(), 0.0);
            (t, s)
        })
        .collect();
    results::verdict::Judge::replay(task, &instance.params, &states)
}

#[test]
fn a_lid_that_passes_through_open_is_not_opened() {
    let task = common::compile("protocols/thermal_cycler/open_lid.toml");
    assert_eq!(task.stages[0].settle_s, compiler::DEFAULT_SETTLE_S);
    let open = labware::thermal_cycler::Params::default().lid_open;
    let closed = labware::thermal_cycler::Params::default().lid_closed;
    let dt = 0.02;
    let at = |k: usize| k as f64 * dt;
    // Closed for 1 s, open for 0.3 s (15 steps), closed again for 2 s.
    let mut flung = Vec::new();
    for k in 0..50 {
        flung.push((at(k), closed));
    }
    for k in 50..65 {
        flung.push((at(k), open));
    }
    for k in 65..165 {
        flung.push((at(k), closed));
    }
    let v = judge(&task, &flung);
    assert!(!v.success && v.score == 0.0, "{v:#?}");
    // Not for another reason: while the lid was open, every check held.
    let mut moment: Vec<(f64, f64)> = (0..50).map(|k| (at(k), closed)).collect();
    moment.push((at(50), open));
    let v = judge(&task, &moment);
    assert!(
        v.stages[0].predicates.iter().all(|p| p.holds) && !v.success,
        "{v:#?}"
    );
    // Open and staying open: done once it has stayed the settle time, not before.
    let mut stays: Vec<(f64, f64)> = (0..50).map(|k| (at(k), closed)).collect();
    stays.extend((50..100).map(|k| (at(k), open)));
    let v = judge(&task, &stays);
    assert!(v.success, "{v:#?}");
    let done = v.stages[0].completed_at_s.unwrap();
    assert!(
        (done - (at(50) + compiler::DEFAULT_SETTLE_S)).abs() < 1e-6,
        "completed at {done} s"
    );
    // With `settle = "0 s"` the moment counts, as it did before settle times.
    let instant = common::compile_edited("protocols/thermal_cycler/open_lid.toml", |s| {
        s.replace("[success]\n", "[success]\nsettle = \"0 s\"\n")
    });
    assert_eq!(instant.stages[0].settle_s, 0.0);
    assert!(judge(&instant, &flung).success);
}

#[test]
fn the_expert_still_wins_with_the_settle_time() {
    let task = common::compile("protocols/thermal_cycler/open_lid.toml");
    let r = common::run(&task, 0, "expert");
    assert!(r.success, "{r:?}");
    let done = r.verdict.stages[0].completed_at_s.unwrap();
    assert!(r.sim_time_s >= done - 1e-9);
}
