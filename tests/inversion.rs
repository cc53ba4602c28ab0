//! Issue 49, part 4: `invert` (mixing by inversion) on real MuJoCo. The expert takes the capped
//! tube out of the rack, turns it upside down and back four times and puts it back; the judge
//! counts each turn over and back from the tube's measured tilt, so a robot that turns it fewer
//! times, or lifts it and sets it back unturned, fails with the count as the predicate's value,
//! and a motionless one counts none.

use crate::common;
use expert::ExpertPolicy;

const PATH: &str = "protocols/lab/mix_by_inversion.toml";

/// The shipped protocol judged, acted by an expert whose plan is the protocol edited by `edit`.
fn acted_by(seed: u64, edit: impl FnOnce(String) -> String) -> results::episode::EpisodeResult {
    let judged = common::compile(PATH);
    let acting = common::compile_edited(PATH, |s| {
        edit(s).replace("\"lysate inverted 4 times\", ", "")
    });
    common::run_with(&judged, seed, &Default::default(), |_, s, i| {
        Box::new(ExpertPolicy::new(&acting, s, i).unwrap())
    })
}

#[test]
fn four_inversions_are_counted_and_fewer_fail() {
    let task = common::compile(PATH);
    let r = common::run(&task, 0, "expert");
    assert!(r.success, "{:#?}", r.verdict);
    assert_eq!(common::predicate(&r, "lysate inverted 4 times").value, 4.0);

    let hold = common::run(&task, 0, "hold");
    assert!(!hold.success);
    assert_eq!(
        common::predicate(&hold, "lysate inverted 4 times").value,
        0.0
    );

    // Turned over twice, put back where it belongs: the place holds, the count does not.
    let r = acted_by(1, |s| s.replace("times = 4", "times = 2"));
    assert!(!r.success);
    let count = common::predicate(&r, "lysate inverted 4 times");
    assert_eq!((count.value, count.holds), (2.0, false), "{count:?}");

    // Lifted and set back without turning it: nothing counted.
    let r = acted_by(2, |s| {
        s.replace(
            "[[steps]]\ndo = \"invert\"\non = \"lysate\"\ntimes = 4\nwith = \"arm\"\n\n",
            "",
        )
    });
    assert!(!r.success);
    assert_eq!(common::predicate(&r, "lysate inverted 4 times").value, 0.0);
    let placed = r
        .verdict
        .predicates()
        .iter()
        .find(|p| p.text.starts_with("lysate in rack."))
        .cloned()
        .unwrap();
    assert!(placed.holds, "the tube went back: {placed:?}");
}
