//! Issue 49, part 4: racks made from Opentrons' published labware definitions hold tubes where
//! the definition puts its wells, on real MuJoCo; named liquids (`state = { liquid = ".." }`,
//! Opentrons' `loadLiquid`) move with the pipette in proportion and are judged by name: the
//! dilution protocol's expert delivers the stock, a motionless robot does not, and a robot that
//! brings the right volume of the wrong liquid fails the check that names the liquid.

use crate::common;
use expert::ExpertPolicy;

/// A scene of tubes standing in the corner places of the definition racks from the start (the
/// two tube racks and the aluminium block's PCR tubes), and capped PCR tubes in the corner wells
/// of the `thermal_cycler_96`'s block under its locked lid.
const RACKS: &str = r#"format = 1
[protocol]
id = "test.definition_racks"
level = "easy"
instruction = "nothing to do"
time_limit = "2 s"

[robots.arm]
model = "ur5e_2f85"
base = { pos_m = [0.0, 0.5, 0.824] }

[labware.small]
kind = "tuberack_24_1_5ml"
pose = { pos_m = [0.3, 0.0, 0.8545] }

[labware.large]
kind = "tuberack_6_50ml"
pose = { pos_m = [-0.2, 0.0, 0.8559], yaw_deg = 30 }

[labware.s1]
kind = "tube_1_5ml"
at = "small.A1"

[labware.s2]
kind = "tube_1_5ml"
at = "small.D6"

[labware.block]
kind = "aluminium_block_96_pcr"
pose = { pos_m = [0.05, -0.2, 0.83173], yaw_deg = -15 }

[labware.p1]
kind = "tube_0_2ml"
at = "block.A1"

[labware.p2]
kind = "tube_0_2ml"
at = "block.H12"

[labware.cycler]
kind = "thermal_cycler_96"
pose = { pos_m = [-0.3, -0.4, 0.824], yaw_deg = 20 }
state = { lid = "locked" }

[labware.c1]
kind = "tube_0_2ml"
at = "cycler.A1"

[labware.c2]
kind = "tube_0_2ml"
at = "cycler.H12"

[labware.l1]
kind = "tube_50ml"
at = "large.A1"

[labware.l2]
kind = "tube_50ml"
at = "large.B3"

[[steps]]
do = "wait"
duration = "1 s"
with = "arm"

[success]
all = [
  "s1 in small.A1", "s2 in small.D6", "l1 in large.A1", "l2 in large.B3", "p1 in block.A1",
  "p2 in block.H12", "c1 in cycler.A1", "c2 in cycler.H12", "cycler.lid is locked",
]
"#;

/// Tubes set in a definition rack's places settle there: after a second of physics each is
/// still upright in its place, its base within 1 mm of the seat the definition gives in the plane
/// (the well's x and y) and within the tube kind's height tolerance of the well's bottom. The
/// cycler's capped tubes stand so under its shut lid, which stays locked over them.
#[test]
fn tubes_stand_in_definition_racks_where_the_definition_puts_the_wells() {
    let (task, diags) = compiler::compile_source(RACKS, "racks.toml");
    let task = task.unwrap_or_else(|| panic!("{diags:#?}"));
    let r = common::run(&task, 0, "hold");
    for p in r.verdict.predicates() {
        assert!(p.holds, "{}: {p:?}", p.text);
        if p.text.contains(".lid") {
            continue;
        }
        assert!(
            p.value.abs() < 0.001,
            "{}: {} m from its seat",
            p.text,
            p.value
        );
    }
}

/// The dilution with a third tube of water in the rack, the stock and the target drawn among the
/// other places.
fn with_a_second_water(text: String) -> String {
    text.replace(
        "[labware.pipette]",
        "[labware.water]\nkind = \"tube_50ml\"\nat = \"rack.B3\"\nstate = { cap = \"off\", volume = \"20 mL\", liquid = \"water\" }\n\n[labware.pipette]",
    )
    .replace(
        "[params.from]\nslot = \"rack\"\n",
        "[params.from]\nslot = \"rack\"\nexclude = [\"B3\"]\n",
    )
    .replace("exclude = [\"{from}\"]", "exclude = [\"{from}\", \"B3\"]")
}

#[test]
fn the_dilution_delivers_the_stock_by_name_and_the_wrong_liquid_fails() {
    let path = "protocols/lab/dilution.toml";
    let task = common::compile(path);
    let r = common::run(&task, 0, "expert");
    assert!(r.success, "{:#?}", r.verdict);
    let stock = common::predicate(&r, "diluted.volume of pbs_10x = 500 µL");
    assert!((stock.value - 500.0).abs() <= 1.0, "{stock:?}");
    let hold = common::run(&task, 0, "hold");
    assert!(!hold.success);
    assert_eq!(
        common::predicate(&hold, "diluted.volume of pbs_10x = 500 µL").value,
        0.0
    );

    // Judged as the protocol asks, acted by an expert whose plan draws from the other water.
    let judged = common::compile_edited(path, with_a_second_water);
    let acting = common::compile_edited(path, |s| {
        with_a_second_water(s)
            .replace("on = \"stock\"", "on = \"water\"")
            .replace("  \"diluted.volume of pbs_10x = 500 µL\",\n", "")
    });
    for seed in [0, 1] {
        let r = common::run_with(&judged, seed, &Default::default(), |_, s, i| {
            Box::new(ExpertPolicy::new(&acting, s, i).unwrap())
        });
        assert!(!r.success, "seed {seed}: the wrong liquid passed");
        let total = common::predicate(&r, "diluted.volume = 5 mL");
        assert!(total.holds, "seed {seed}: the volume arrived: {total:?}");
        let named = common::predicate(&r, "diluted.volume of pbs_10x = 500 µL");
        assert!(!named.holds && named.value == 0.0, "seed {seed}: {named:?}");
    }
}
