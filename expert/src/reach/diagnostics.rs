//! The reach pass as diagnostics on a checked protocol file: E0036 for a step out of reach in
//! seed 0's layout (with its base hint), W0010 for a step missed only in some of the next
//! layouts. It does not solve anything itself (the pass in `mod.rs` does, through its store).

use super::hint::{HINT_RADIUS, HINT_RISE, HINT_RISES};
use super::*;

/// E0036 for every unreachable step of a single protocol file that checked clean, at the step's
/// `with`; appended to `checked`, whose task is then dropped, as for any other error.
pub fn check(checked: &mut Checked, store: &Store) {
    let Some(task) = &checked.task else {
        return;
    };
    // A position metres off any bench (W0003) is a unit slip to fix first, not a reach to judge.
    if checked.diagnostics.iter().any(|d| d.code == Code::W0003) {
        return;
    }
    // A chain's stages are checked in their own files, not across the chain.
    if task.stages.iter().any(|s| s.source != task.source) {
        return;
    }
    // Each planned step's own span (a loop's expansions point at the loop's body step).
    let spans: Vec<dsl::Span> = task.steps().map(|(_, s)| s.span.0).collect();
    let missed = unreachable(task, store);
    if missed.is_empty() {
        partly(checked, &spans, store);
        return;
    }
    for m in &missed {
        let Some(&span) = spans.get(m.step) else {
            continue;
        };
        let [x, y, z] = m.at;
        let how = match (&m.limit, m.short_by) {
            (Some(l), _) => format!(
                ": within the arm's reach, but only past joint `{}`'s range (it would need {:.2} rad; its range is {:.2}..{:.2} rad)",
                l.joint, l.needed, l.range.0, l.range.1
            ),
            (None, Some((p, r))) => format!(
                ", the closest solve {:.0} mm and {r:.2} rad off",
                p * 1000.0
            ),
            (None, None) => String::new(),
        };
        let mut d = Diagnostic::new(
            Code::E0036,
            span,
            format!(
                "`{}` cannot reach step {}'s target, {}, at ({x:.3}, {y:.3}, {z:.3}) m{how}",
                m.robot,
                m.step + 1,
                m.target
            ),
        )
        .with_note("checked in seed 0's layout, from the robot's start pose and its home");
        d = match m.base_hint {
            Some(hint) => d.with_hint(format!(
                "stand `{}` at {}: every target checked for it, in all {SAMPLED_LAYOUTS} sampled layouts, solves from there",
                m.robot,
                stand_at(hint, m.base)
            )),
            None => d.with_hint(format!(
                "no base found within {HINT_RADIUS} m of `{}`'s (or up to {:.1} m above it) that reaches every target checked for it in all {SAMPLED_LAYOUTS} sampled layouts; move the labware or the robot",
                m.robot,
                HINT_RISE * HINT_RISES as f64
            )),
        };
        checked.diagnostics.push(d);
    }
    checked.task = None;
}

/// A hinted base as the hint writes it: the position, how far it is from `base` in the plane,
/// and how much higher, where it is.
fn stand_at([hx, hy, hz]: [f64; 3], [bx, by, bz]: [f64; 3]) -> String {
    let dist = ((hx - bx).powi(2) + (hy - by).powi(2)).sqrt();
    let rise = hz - bz;
    // To the millimetre written, without a "-0.000".
    let mm = |v: f64| (v * 1000.0).round() / 1000.0 + 0.0;
    let (hx, hy, hz) = (mm(hx), mm(hy), mm(hz));
    let raised = if rise > 1e-9 {
        format!(", {rise:.2} m higher: on a riser")
    } else {
        String::new()
    };
    format!("pos_m = [{hx:.3}, {hy:.3}, {hz:.3}] ({dist:.3} m from where it is{raised})")
}

/// W0010 for every step reached in seed 0's layout but not in some of the next ones, at the
/// step's `with`: the task checks, but some episodes will fail at planning.
fn partly(checked: &mut Checked, spans: &[dsl::Span], store: &Store) {
    let Some(task) = &checked.task else {
        return;
    };
    let planned: Vec<&compiler::PlannedStep> = task.steps().map(|(_, s)| s).collect();
    // Called where seed 0's layout misses nothing: only the next seeds are left to solve.
    let mut hints: BTreeMap<usize, Option<[f64; 3]>> = BTreeMap::new();
    for (i, seeds) in beyond_seed_0(task, &BTreeSet::new(), store) {
        let (Some(&span), Some(planned)) = (spans.get(i), planned.get(i)) else {
            continue;
        };
        let list: Vec<String> = seeds.iter().map(u64::to_string).collect();
        let first = seeds[0];
        let drawn: Vec<String> = task
            .sample(first)
            .params
            .iter()
            .map(|(k, v)| format!("{k} = {v}"))
            .collect();
        let mut d = Diagnostic::new(
            Code::W0010,
            span,
            format!(
                "`{}` reaches step {}'s target in seed 0's layout but not in {} of the next {} (seeds {})",
                planned.robot,
                i + 1,
                seeds.len(),
                SAMPLED_LAYOUTS - 1,
                list.join(", ")
            ),
        );
        if !drawn.is_empty() {
            d = d.with_note(format!("seed {first} draws {}", drawn.join(", ")));
        }
        let robot = task.robots.iter().position(|r| r.name == planned.robot);
        let found = robot.and_then(|r| {
            let hint = *hints
                .entry(r)
                .or_insert_with(|| base_for_every_layout(task, r));
            hint.map(|h| (r, h))
        });
        let hint = match found {
            Some((r, hint)) => {
                let base = task.robots[r].base.translation.vector;
                format!(
                    "stand `{}` at {}: its targets in all {SAMPLED_LAYOUTS} sampled layouts solve from there; or narrow what the seeds draw (`[params]`, `[randomise]`); `autobio render FILE --seed {first}` draws that layout",
                    planned.robot,
                    stand_at(hint, [base.x, base.y, base.z])
                )
            }
            None => format!(
                "narrow what the seeds draw (`[params]`, `[randomise]`) or stand `{}` nearer; `autobio render FILE --seed {first}` draws that layout",
                planned.robot
            ),
        };
        checked.diagnostics.push(d.with_hint(hint));
    }
}
