//! Issue 49: the PCR set-up, 0.2 mL tubes standing in Opentrons' 96-well aluminium block (made
//! from its published definition) filled from a master mix by a P200, on real MuJoCo. Each tube
//! is judged by how much of the named mix it holds: the expert fills all three, a motionless
//! robot none, and a plan that serves one tube twice fails at the tube it missed and at the one
//! it filled twice. The PCR tube's 20 mm bore is a narrow opening: the tip goes only half way
//! down it, brought over the mouth again while it misses that point by more than half a
//! millimetre (at most four tries) before it goes in. `lab.pcr` sets the same reaction up in
//! the `thermal_cycler_96`'s block and runs the cycler over it.

use crate::common;
use expert::ExpertPolicy;
use std::path::Path;

const PATH: &str = "protocols/lab/pcr_setup.toml";
const TUBES: [&str; 3] = ["pcr1", "pcr2", "pcr3"];

fn check(tube: &str) -> String {
    format!("{tube}.volume of master_mix = 25 µL")
}

#[test]
fn the_expert_fills_each_pcr_tube_and_hold_fills_none() {
    let task = common::compile(PATH);
    let r = common::run(&task, 0, "expert");
    assert!(r.success, "{:#?}", r.verdict);
    for tube in TUBES {
        let p = common::predicate(&r, &check(tube));
        assert!((p.value - 25.0).abs() <= 1.0, "{tube}: {p:?}");
    }
    let mix = common::predicate(&r, "mix.volume = 925 µL");
    assert!(mix.holds, "{mix:?}");
    let hold = common::run(&task, 0, "hold");
    assert!(!hold.success);
    for tube in TUBES {
        assert_eq!(common::predicate(&hold, &check(tube)).value, 0.0, "{tube}");
    }
}

#[test]
fn a_tube_served_twice_and_one_missed_fail_their_checks() {
    let judged = common::compile(PATH);
    // The same plan with the loop's list wrong: the first tube twice, the second never (its
    // success lines dropped so that the plan proves).
    let acting = common::compile_edited(PATH, |s| {
        s.replace(
            "tube = [\"pcr1\", \"pcr2\", \"pcr3\"]",
            "tube = [\"pcr1\", \"pcr1\", \"pcr3\"]",
        )
        .replace("  \"pcr1.volume of master_mix = 25 µL\",\n", "")
        .replace("  \"pcr2.volume of master_mix = 25 µL\",\n", "")
    });
    let r = common::run_with(&judged, 0, &Default::default(), |_, s, i| {
        Box::new(ExpertPolicy::new(&acting, s, i).unwrap())
    });
    assert!(!r.success, "a tube filled twice passed");
    let twice = common::predicate(&r, &check("pcr1"));
    assert!(
        !twice.holds && (twice.value - 50.0).abs() <= 2.0,
        "{twice:?}"
    );
    let missed = common::predicate(&r, &check("pcr2"));
    assert!(!missed.holds && missed.value == 0.0, "{missed:?}");
    assert!(common::predicate(&r, &check("pcr3")).holds);
}

/// The PCR from set-up to the end of its run (`lab.pcr`): the P200 fills the three tubes standing
/// in the `thermal_cycler_96`'s block, its arm takes the pipette home, the other arm shuts and
/// locks the lid over the tubes (which starts the profile) and opens it once the run is done;
/// every tube is still in its well at the end.
#[test]
fn the_pcr_is_set_up_in_the_cyclers_block_and_run() {
    let task = common::compile("protocols/lab/pcr.toml");
    let r = common::run(&task, 0, "expert");
    assert!(r.success, "{:#?}", r.verdict);
    for tube in TUBES {
        let p = common::predicate(&r, &check(tube));
        assert!((p.value - 25.0).abs() <= 1.0, "{tube}: {p:?}");
    }
    let run = common::predicate(&r, "cycler.run is done");
    assert!(run.holds && run.value == 2.0, "{run:?}");
    // The profile's lab time (about 1 h 24 min) passed, jumped over while only the cycler ran.
    assert!(r.sim_time_s > 4800.0, "{} s", r.sim_time_s);
    // Each tube stands in its well, its base within 1.5 mm of the seat in the plane.
    let seated: Vec<_> = r
        .verdict
        .predicates()
        .iter()
        .filter(|p| p.text.contains(" in cycler."))
        .collect();
    assert_eq!(seated.len(), 3);
    for p in seated {
        assert!(p.holds && p.value < 0.0015, "{p:?}");
    }
}

/// `retract` takes a pipette home in the hand that pipettes with it; any other carried item
/// must still be set down first (E0031, naming the hand).
#[test]
fn retract_takes_a_pipette_home_but_not_a_tube() {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("protocols/tube/transfer.toml");
    let source = std::fs::read_to_string(path).unwrap();
    let edited = source.replacen(
        "[[steps]]\ndo = \"place\"",
        "[[steps]]\ndo = \"retract\"\nwith = \"arm\"\n\n[[steps]]\ndo = \"place\"",
        1,
    );
    assert_ne!(edited, source);
    let (task, diags) = compiler::compile_source(&edited, "transfer.toml");
    assert!(task.is_none());
    let e = diags
        .iter()
        .find(|d| d.code == dsl::Code::E0031)
        .expect("an E0031");
    assert!(
        e.message.contains("`retract` needs `arm`'s hand empty"),
        "{}",
        e.message
    );
}
