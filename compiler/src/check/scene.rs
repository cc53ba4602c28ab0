//! Whole-scene checks that need no lowering: one namespace for robots, labware and parameters
//! (E0015), and values that parse and type-check but are almost certainly mistakes: a placement
//! off the bench or in the wrong unit (E0024), a randomised shift off any bench (W0003), a time
//! limit shorter than a control step or longer than a day (W0004), weights that binary scoring
//! ignores (W0005). It resolves no kind, builds no spec and changes nothing in the protocol.

use crate::report::Cx;
use dsl::ast::{Protocol, RandomItem, Spanned};
use dsl::{Code, Diagnostic};
use std::collections::BTreeMap;

/// How far from the bench's centre (the world origin) anything of a task can sensibly be, in
/// metres: a lab room. Beyond it a position is almost certainly in the wrong unit.
const ROOM: f64 = 5.0;
/// Longest randomisation offset in the plane that still keeps an item on a bench, in metres.
const BENCH_OFFSET: f64 = 1.0;
/// How far past the bench's edge an item may stand and still count as on it (m): a rack
/// overhanging the edge, an instrument's footprint.
const ITEM_MARGIN: f64 = 0.3;
/// Longest time limit that is not a unit slip, in seconds: a day.
const LONGEST_TIME_LIMIT: f64 = 86_400.0;

/// E0015 for a name declared twice among robots, labware and parameters (one namespace).
pub(super) fn duplicates(cx: &mut Cx, p: &Protocol) {
    let mut seen: BTreeMap<&str, &str> = BTreeMap::new();
    let names = p
        .robots
        .iter()
        .map(|r| (&r.name, "robot"))
        .chain(p.labware.iter().map(|l| (&l.name, "labware")))
        .chain(p.params.iter().map(|x| (&x.name, "parameter")));
    for (name, what) in names {
        if let Some(first) = seen.insert(&name.value, what) {
            cx.err(
                Code::E0015,
                name.span,
                format!(
                    "`{}` is declared twice (as a {first} and a {what})",
                    name.value
                ),
                Some("robots, labware and parameters share one namespace; rename one".into()),
            );
        }
    }
}

/// Values that parse and type-check but are almost certainly mistakes, in this order:
/// placements, randomised shifts, the time limit, ignored weights.
pub(super) fn implausible(cx: &mut Cx, p: &Protocol) {
    placements(cx, p);
    shifts(cx, p);
    if let Some(t) = &p.meta.time_limit {
        time_limit_warning(cx, t);
    }
    if let Some(w) = &p.success.weights
        && p.success.scoring.as_ref().map(|s| s.value.as_str()) != Some("progress")
    {
        cx.push(
            Diagnostic::new(
                Code::W0005,
                w.span,
                "binary scoring ignores these weights".to_string(),
            )
            .with_hint("weights apply under `scoring = \"progress\"`; remove them or set it"),
        );
    }
}

fn in_room([x, y, z]: [f64; 3]) -> bool {
    x.abs() <= ROOM && y.abs() <= ROOM && (-1.0..=ROOM).contains(&z)
}

/// E0024 for a robot out of the room, or an item neither over the bench nor within a robot's
/// reach; the hint says so when the numbers read as millimetres.
fn placements(cx: &mut Cx, p: &Protocol) {
    // Where each robot stands and how far it reaches, for the labware poses below.
    let arms: Vec<([f64; 3], f64)> = p
        .robots
        .iter()
        .filter_map(|r| {
            let model = robots::model(&r.model.as_ref()?.value)?;
            Some((r.base.pos.as_ref()?.value, model.reach))
        })
        .collect();
    let within_reach = |q: [f64; 3]| {
        arms.iter().any(|(b, reach)| {
            ((q[0] - b[0]).powi(2) + (q[1] - b[1]).powi(2) + (q[2] - b[2]).powi(2)).sqrt() <= *reach
        })
    };
    let poses = p
        .robots
        .iter()
        .map(|r| (&r.name, &r.base, true))
        .chain(p.labware.iter().map(|l| (&l.name, &l.pose, false)));
    for (name, pose, robot) in poses {
        let Some(pos) = &pose.pos else { continue };
        let [x, y, z] = pos.value;
        // A robot may stand anywhere in the room; an item must stand where a task can use it:
        // over the bench, or within a robot's reach (on a riser beside it).
        let usable = in_room(pos.value)
            && (robot
                || crate::bench::over_bench(x, y, ITEM_MARGIN)
                || arms.is_empty()
                || within_reach(pos.value));
        if usable {
            continue;
        }
        let metres = [x / 1000.0, y / 1000.0, z / 1000.0];
        let hint = if !in_room(pos.value) && in_room(metres) {
            format!(
                "`pos_m` is in metres; this reads as millimetres: write `pos_mm = [{x}, {y}, {z}]` or `pos_m = [{}, {}, {}]`",
                metres[0], metres[1], metres[2]
            )
        } else {
            "`pos_m` is in metres; place it over the bench (1.8 x 1.3 m about the origin, its top at 0.824 m) or within a robot's reach".to_string()
        };
        let what = if in_room(pos.value) {
            "off the bench and out of every robot's reach"
        } else {
            "metres away from the bench"
        };
        cx.push(
            Diagnostic::new(
                Code::E0024,
                pos.span,
                format!("`{}` is placed at ({x}, {y}, {z}) m, {what}", name.value),
            )
            .with_hint(hint),
        );
    }
}

/// W0003 for an `xy` randomisation that may shift an item off any bench.
fn shifts(cx: &mut Cx, p: &Protocol) {
    for r in &p.randomise {
        for item in &r.items {
            if let RandomItem::Xy(q) = item
                && q.value.abs() > BENCH_OFFSET
            {
                cx.push(
                    Diagnostic::new(
                        Code::W0003,
                        q.span,
                        format!(
                            "`{}` is shifted by up to {} m, off any bench",
                            r.target.value, q.value
                        ),
                    )
                    .with_hint("`xy_m` is in metres; write millimetres as `xy_mm` or \"10 mm\""),
                );
            }
        }
    }
}

/// W0004 for a time limit shorter than one control period or longer than a day.
pub(crate) fn time_limit_warning(cx: &mut Cx, t: &Spanned<f64>) {
    let physics = crate::physics();
    let period = physics.timestep_s * physics.substeps as f64;
    if t.value > 0.0 && t.value < period {
        cx.push(
            Diagnostic::new(
                Code::W0004,
                t.span,
                format!(
                    "a time limit of {} s ends the episode before one control step ({period} s)",
                    t.value
                ),
            )
            .with_hint(format!(
                "give at least one control step ({} ms), e.g. \"30 s\"; check the value's unit",
                period * 1e3
            )),
        );
    } else if t.value > LONGEST_TIME_LIMIT {
        cx.push(
            Diagnostic::new(
                Code::W0004,
                t.span,
                format!("a time limit of {} s is longer than a day", t.value),
            )
            .with_hint("check the unit: `time_limit_ms` and \"min\" are easy to mix up"),
        );
    }
}

#[cfg(test)]
mod tests {
    use super::super::testing::*;
    use dsl::Code;

    /// Robots, labware and parameters share one namespace: the second declaration is the error.
    #[test]
    fn a_name_shared_by_a_robot_and_a_parameter_is_e0015_at_the_second() {
        let src = edited(&[("[params.row]", "[params.arm]")]);
        lowered(&src, |_, diags| {
            let d = one(diags, Code::E0015);
            assert_eq!(
                d.message,
                "`arm` is declared twice (as a robot and a parameter)"
            );
            assert_eq!(covered(&src, d.span), "arm");
            assert!(d.span.start > src.find("[params.").unwrap());
        });
    }

    /// A rack written in millimetres under `pos_m` is metres away: E0024, and the hint gives the
    /// position both ways.
    #[test]
    fn a_position_written_in_millimetres_is_e0024_with_both_spellings() {
        let src = edited(&[("pos_m = [0.3, 0.2, 0.854]", "pos_m = [300, 200, 854]")]);
        lowered(&src, |_, diags| {
            let d = one(diags, Code::E0024);
            assert_eq!(
                d.message,
                "`target` is placed at (300, 200, 854) m, metres away from the bench"
            );
            assert_eq!(covered(&src, d.span), "[300, 200, 854]");
            let hint = d.hint.as_deref().unwrap();
            assert!(
                hint.contains("`pos_mm = [300, 200, 854]` or `pos_m = [0.3, 0.2, 0.854]`"),
                "{hint}"
            );
        });
        // In the room but off the bench and out of the arm's reach: the other message.
        let src = edited(&[("pos_m = [0.3, 0.2, 0.854]", "pos_m = [3.0, 3.0, 0.854]")]);
        lowered(&src, |_, diags| {
            assert!(
                one(diags, Code::E0024)
                    .message
                    .ends_with("off the bench and out of every robot's reach")
            );
        });
    }

    /// W0004 below one control step (20 ms) and above a day; a plain limit gets none.
    #[test]
    fn time_limits_shorter_than_a_control_step_or_longer_than_a_day_warn() {
        let short = edited(&[("time_limit = \"15 s\"", "time_limit = \"10 ms\"")]);
        lowered(&short, |_, diags| {
            let d = one(diags, Code::W0004);
            assert!(d.message.contains("before one control step"), "{d:?}");
            assert_eq!(covered(&short, d.span), "\"10 ms\"");
        });
        let long = edited(&[("time_limit = \"15 s\"", "time_limit = \"2000 min\"")]);
        lowered(&long, |_, diags| {
            assert_eq!(
                one(diags, Code::W0004).message,
                "a time limit of 120000 s is longer than a day"
            );
        });
        lowered(BASE, |_, diags| assert!(diags.is_empty(), "{diags:#?}"));
    }

    /// W0003 for a shift of more than a metre; W0005 for weights under binary scoring, and none
    /// once scoring is `progress`.
    #[test]
    fn a_shift_off_the_bench_and_weights_binary_scoring_ignores_warn() {
        let src = with("[randomise.tube]\nxy_m = 2\n");
        lowered(&src, |_, diags| {
            assert_eq!(
                one(diags, Code::W0003).message,
                "`tube` is shifted by up to 2 m, off any bench"
            );
        });
        let binary = edited(&[("all = [", "weights = [1.0]\nall = [")]);
        lowered(&binary, |_, diags| {
            let d = one(diags, Code::W0005);
            assert_eq!(covered(&binary, d.span), "[1.0]");
        });
        let progress = edited(&[(
            "all = [",
            "scoring = \"progress\"\nweights = [1.0]\nall = [",
        )]);
        lowered(&progress, |_, diags| {
            assert!(diags.is_empty(), "{diags:#?}")
        });
    }
}
