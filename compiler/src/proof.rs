//! The state proof: traces every stage's steps through the abstract [`World`], from the declared
//! initial state, for every parameter combination (or a deterministic sample when there are too
//! many), and reports each step whose precondition fails, each stage whose plan cannot reach its
//! success condition, and success conditions that hold before anything happens.

use crate::check::{CheckedPredicate, CheckedStep};
use crate::params::{Bindings, ParamSpec, proof_assignments, render};
use crate::predicates;
use crate::primitives::{self, BoundStep, Env};
use crate::report::Cx;
use crate::task::LabwareSpec;
use crate::world::{Hand, Location, World};
use dsl::{Code, Diagnostic, Dimension, Span};
use labware::LabwareKind;
use std::collections::BTreeMap;

/// One stage as the proof sees it.
pub(crate) struct ProofStage<'a> {
    pub id: String,
    pub file: Option<String>,
    pub steps: &'a [CheckedStep<'a>],
    pub predicates: &'a [CheckedPredicate],
    /// A later chain stage's own file, whose start declarations the chain ignores (W0008 where
    /// they differ from the state carried over); `None` for a first stage or a lone protocol.
    pub declared: Option<&'a dsl::ast::Protocol>,
    /// The stage's time limit (s), as the chain may override it.
    pub time_limit_s: f64,
}

/// The scene the stages share.
pub(crate) struct ProofScene<'a> {
    pub labware: &'a [LabwareSpec],
    pub kinds: &'a BTreeMap<String, &'static LabwareKind>,
    pub robots: Vec<String>,
    /// Where to point for a labware's initial placement (first stage's file).
    pub labware_spans: &'a BTreeMap<String, Span>,
    pub file: Option<String>,
    /// Where each parameter is declared: its file (`None`: the file being checked) and span.
    pub param_places: BTreeMap<String, (Option<String>, Span)>,
}

fn describe(bound: &Bindings) -> Option<String> {
    (!bound.is_empty()).then(|| {
        let parts: Vec<String> = bound.iter().map(|(k, v)| format!("{k} = {v}")).collect();
        format!("with {}", parts.join(", "))
    })
}

fn initial_world(cx: &mut Cx, scene: &ProofScene, bound: &Bindings) -> Option<World> {
    let mut w = World::default();
    let env = Env {
        kinds: scene.kinds,
        robots: &scene.robots,
    };
    cx.file = scene.file.clone();
    let mut ok = true;
    for spec in scene.labware {
        let span = scene
            .labware_spans
            .get(&spec.name)
            .copied()
            .unwrap_or_default();
        let kind = scene.kinds[&spec.name];
        for (part, state) in &spec.initial {
            w.set_part(&spec.name, part, state);
        }
        if let Some(at) = &spec.at {
            let at = render(at, bound).unwrap_or_else(|_| at.clone());
            match primitives::resolve_location(&env, &at) {
                Ok((holder, slot, hkind)) => {
                    let accepts = hkind.slots.map(|s| s.accepts).unwrap_or(&[]);
                    if !accepts.contains(&kind.name) {
                        let mut d = Diagnostic::new(
                            Code::E0016,
                            span,
                            format!(
                                "a slot of `{holder}` (a {}) does not take a {}",
                                hkind.name, kind.name
                            ),
                        )
                        .with_hint(format!("it takes: {}", accepts.join(", ")));
                        d.notes.extend(describe(bound));
                        cx.push(d);
                        ok = false;
                    } else if let Some(other) = w.occupant(&holder, &slot) {
                        let mut d = Diagnostic::new(
                            Code::E0016,
                            span,
                            format!("`{}` and `{other}` both start in `{at}`", spec.name),
                        )
                        .with_hint("draw the slot with `slot = .., free = true` or exclude the other's slot");
                        d.notes.extend(describe(bound));
                        cx.push(d);
                        ok = false;
                    } else {
                        w.locations
                            .insert(spec.name.clone(), Location::Slot { holder, slot });
                    }
                }
                Err(m) => {
                    cx.push(Diagnostic::new(Code::E0016, span, m.to_string()));
                    ok = false;
                }
            }
        } else if let Some(robot) = &spec.held_by {
            if let Some(other) = w.hands.get(robot).and_then(|h| match h {
                Hand::Item(i) => Some(i.clone()),
                _ => None,
            }) {
                cx.push(
                    Diagnostic::new(
                        Code::E0016,
                        span,
                        format!(
                            "`{}` and `{other}` both start in `{robot}`'s hand",
                            spec.name
                        ),
                    )
                    .with_hint("a hand holds one item"),
                );
                ok = false;
            } else {
                w.locations.insert(
                    spec.name.clone(),
                    Location::Held {
                        robot: robot.clone(),
                    },
                );
                w.hands.insert(robot.clone(), Hand::Item(spec.name.clone()));
            }
        } else if kind.movable {
            w.locations.insert(spec.name.clone(), Location::Bench);
        }
        if let Some(v) = &spec.volume {
            match predicates::quantity(v, bound, Dimension::Volume) {
                Ok(x) if x <= kind.capacity_ul.unwrap_or(0.0) && x >= 0.0 => {
                    w.volumes.insert(spec.name.clone(), x);
                    if let Some(liquid) = &spec.liquid {
                        w.contents
                            .entry(spec.name.clone())
                            .or_default()
                            .insert(liquid.clone(), x);
                    }
                }
                Ok(x) => {
                    let mut d = Diagnostic::new(
                        Code::E0021,
                        span,
                        format!(
                            "`{}` starts with {x} µL, but holds at most {} µL",
                            spec.name,
                            kind.capacity_ul.unwrap_or(0.0)
                        ),
                    );
                    d.notes.extend(describe(bound));
                    cx.push(d);
                    ok = false;
                }
                Err(m) => {
                    cx.push(Diagnostic::new(Code::E0020, span, m.to_string()));
                    ok = false;
                }
            }
        }
        for (param, v) in &spec.panel {
            let Some(p) = kind.panel_param(param) else {
                continue;
            };
            if let Ok(x) = predicates::quantity(v, bound, primitives::panel_dimension(p.unit)) {
                w.panel
                    .insert((spec.name.clone(), param.clone()), p.set_value(x));
            }
        }
    }
    for r in &scene.robots {
        w.hands.entry(r.clone()).or_insert(Hand::Empty);
    }
    ok.then_some(w)
}

/// W0008 at each start state or place a later stage's file declares that differs from what the
/// chain carries into it from the stage before: the chain ignores the declaration, and an author
/// who wrote it likely expects something else.
fn carried_over(cx: &mut Cx, w: &World, ast: &dsl::ast::Protocol, bound: &Bindings, origin: &str) {
    for l in &ast.labware {
        let name = &l.name.value;
        for (key, value) in &l.state {
            let declared = value.value.text();
            if let Some(now) = w.part(name, &key.value)
                && now != declared
            {
                cx.push(
                    Diagnostic::new(
                        Code::W0008,
                        value.span,
                        format!(
                            "`{name}.{}` starts `{declared}` in this file, but the chain carries it over `{now}`",
                            key.value
                        ),
                    )
                    .with_note(origin.to_string())
                    .with_hint("in a chain this stage starts where the one before ended; declare that state, or drop this one"),
                );
            }
        }
        if let Some(at) = &l.at {
            let declared = render(&at.value, bound).unwrap_or_else(|_| at.value.clone());
            let now = match w.locations.get(name) {
                Some(Location::Slot { holder, slot }) => Some(format!("{holder}.{slot}")),
                Some(other) => Some(other.to_string()),
                None => None,
            };
            if let Some(now) = now
                && now != declared
            {
                let mut d = Diagnostic::new(
                    Code::W0008,
                    at.span,
                    format!(
                        "`{name}` starts in `{declared}` in this file, but the chain carries it over {}",
                        match w.locations.get(name) {
                            Some(Location::Slot { .. }) => format!("in `{now}`"),
                            _ => now.clone(),
                        }
                    ),
                )
                .with_note(origin.to_string())
                .with_hint("in a chain this stage starts where the one before ended");
                d.notes.extend(describe(bound));
                cx.push(d);
            }
        }
    }
}

/// W0009 at the step whose panel setting takes the stage's button holding past its time limit:
/// the instrument cannot show the value in time even if every motion took no time at all.
fn slow_panel(
    cx: &mut Cx,
    step: &CheckedStep,
    args: &BTreeMap<String, String>,
    held_before: f64,
    w: &World,
    limit_s: f64,
    bound: &Bindings,
) {
    let this = w.panel_hold_s - held_before;
    let what = match (args.get("on"), args.get("param"), args.get("value")) {
        (Some(on), Some(param), Some(value)) => format!("setting `{on}.{param}` to {value}"),
        _ => format!("`{}`", step.primitive.name),
    };
    let span = step
        .ast
        .arg("value")
        .map(|a| a.span)
        .unwrap_or(step.ast.span);
    let mut d = Diagnostic::new(
        Code::W0009,
        span,
        if held_before > 0.0 {
            format!(
                "{what} holds its button {this:.1} s; with the stage's earlier panel steps, {:.1} s, past its time limit of {limit_s} s",
                w.panel_hold_s
            )
        } else {
            format!("{what} holds its button {this:.1} s, past the stage's time limit of {limit_s} s")
        },
    )
    .with_hint(format!(
        "raise `time_limit` above {:.0} s (the motions need time too), or set a value nearer the start",
        w.panel_hold_s.ceil()
    ));
    if step
        .ast
        .arg("value")
        .is_some_and(|v| v.value.text().contains('{'))
    {
        d.notes.extend(describe(bound));
    }
    cx.push(d);
}

/// What the proof knows of each predicate's time constraint in one stage: whether its form has
/// held, since when it holds (on the stage's clock of waits and runs), and the least time it
/// has held so far.
struct Dwelling {
    ever: Vec<bool>,
    /// The world could not tell, at some point, whether the form held (a run under way): the
    /// judge measures it.
    unknown: Vec<bool>,
    since: Vec<Option<f64>>,
    least: Vec<f64>,
}

impl Dwelling {
    fn new(holds: &[Option<bool>]) -> Dwelling {
        Dwelling {
            ever: holds.iter().map(|h| *h == Some(true)).collect(),
            unknown: holds.iter().map(Option::is_none).collect(),
            since: holds
                .iter()
                .map(|h| (*h == Some(true)).then_some(0.0))
                .collect(),
            least: vec![0.0; holds.len()],
        }
    }

    /// After a step that left the clock at `clock` and the form of predicate `k` at `now`.
    fn step(&mut self, k: usize, now: Option<bool>, clock: f64) {
        self.unknown[k] |= now.is_none();
        match (now, self.since[k]) {
            (Some(true), None) => {
                self.ever[k] = true;
                self.since[k] = Some(clock);
            }
            (Some(false), Some(from)) => {
                self.least[k] += clock - from;
                self.since[k] = None;
            }
            _ => {}
        }
    }

    /// E0039 for the first predicate whose form holds longer than its constraint allows, even
    /// if every motion took no time.
    fn broken(&self, predicates: &[CheckedPredicate], clock: f64) -> Option<Diagnostic> {
        predicates.iter().enumerate().find_map(|(k, p)| {
            let most = p.predicate.dwell?.at_most_s?;
            let least = self.least[k] + self.since[k].map_or(0.0, |from| clock - from);
            (least > most + 1e-9).then(|| {
                Diagnostic::new(
                    Code::E0039,
                    p.span,
                    format!(
                        "`{}` cannot be kept: the waits and runs while it holds take at least {least:.0} s, more than {most:.0} s",
                        p.predicate.text
                    ),
                )
                .with_hint("shorten the waits or runs between the step that makes it true and the one that ends it")
            })
        })
    }
}

/// Runs the proof and reports into `cx`. Stops tracing a combination at its first failure.
/// E0039 for the first timed step (`within`) whose waits and runs since the step it is timed
/// from already take longer than its time, on the stage's clock after each step.
fn late_step(steps: &[CheckedStep], clock_after: &[f64]) -> Option<Diagnostic> {
    let ids: BTreeMap<&str, usize> = steps
        .iter()
        .enumerate()
        .filter_map(|(i, s)| s.ast.id.as_ref().map(|id| (id.value.as_str(), i)))
        .collect();
    for (i, s) in steps.iter().enumerate() {
        let Some(within) = &s.ast.within else {
            continue;
        };
        let Ok(q) = dsl::parse_quantity(&within.value) else {
            continue;
        };
        let from = match &s.ast.after {
            Some(a) => ids.get(a.value.as_str()).copied(),
            None => i.checked_sub(1),
        };
        let Some(from) = from else { continue };
        let (Some(a), Some(b)) = (clock_after.get(from), clock_after.get(i)) else {
            continue;
        };
        if b - a > q.si + 1e-9 {
            return Some(
                Diagnostic::new(
                    Code::E0039,
                    within.span,
                    format!(
                        "the waits and runs from step {} to this `{}` take at least {:.0} s, more than `within = \"{}\"`",
                        from + 1,
                        s.primitive.name,
                        b - a,
                        within.value
                    ),
                )
                .with_hint(format!(
                    "allow at least {:.0} s (and time for the motions), or time this step from a later one",
                    (b - a).ceil()
                )),
            );
        }
    }
    None
}

pub(crate) fn prove(cx: &mut Cx, scene: &ProofScene, stages: &[ProofStage], params: &[ParamSpec]) {
    let (assignments, complete) = proof_assignments(params);
    if !complete {
        // Point at the parameter with the most values: narrowing it helps most.
        let widest = params.iter().max_by_key(|p| p.size());
        let (file, span) = widest
            .and_then(|p| scene.param_places.get(&p.name).cloned())
            .unwrap_or((scene.file.clone(), Span::default()));
        let sizes: Vec<String> = params
            .iter()
            .map(|p| format!("`{}` has {}", p.name, p.size()))
            .collect();
        cx.file = file;
        cx.push(
            Diagnostic::new(
                Code::W0002,
                span,
                format!(
                    "the state proof traced {} sampled parameter combinations, not all",
                    assignments.len()
                ),
            )
            .with_note(format!("values per parameter: {}", sizes.join(", ")))
            .with_hint("narrow the parameter domains for an exhaustive proof"),
        );
    }
    let env = Env {
        kinds: scene.kinds,
        robots: &scene.robots,
    };
    let mut warned_trivial = vec![false; stages.len()];
    'combination: for bound in &assignments {
        let Some(mut w) = initial_world(cx, scene, bound) else {
            continue;
        };
        for (si, stage) in stages.iter().enumerate() {
            cx.file = stage.file.clone();
            let origin = (si > 0).then(|| {
                format!(
                    "stage {} (`{}`) starts where stage {} (`{}`) ends",
                    si + 1,
                    stage.id,
                    si,
                    stages[si - 1].id
                )
            });
            if let (Some(ast), Some(origin)) = (stage.declared, &origin) {
                carried_over(cx, &w, ast, bound, origin);
            }
            w.panel_hold_s = 0.0;
            w.clock_s = 0.0;
            // The judge counts a stage's inversions from its start, and so does the proof.
            w.inversions.clear();
            for p in stage.predicates {
                if let Some(e) = p.predicate.check.target_error(bound) {
                    let mut d = Diagnostic::new(Code::E0020, p.span, e.to_string())
                        .with_hint("a parameter used as a quantity must render with its unit");
                    d.notes.extend(describe(bound));
                    cx.push(d);
                    continue 'combination;
                }
            }
            let holds: Vec<Option<bool>> = stage
                .predicates
                .iter()
                .map(|p| p.predicate.check.eval_abstract(&w, bound))
                .collect();
            // `was` checks remember a state seen after any step of the stage.
            let mut seen: Vec<bool> = holds.iter().map(|h| *h == Some(true)).collect();
            // Time constraints: the least time each form has held (the waits and runs while
            // it held), and since when on the stage's clock it holds now.
            let mut dwell = Dwelling::new(&holds);
            if !warned_trivial[si]
                && !holds.is_empty()
                && holds.iter().all(|h| *h == Some(true))
                && let Some(first) = stage.predicates.first()
            {
                warned_trivial[si] = true;
                let mut d = Diagnostic::new(
                    Code::W0001,
                    first.span,
                    "every success predicate already holds before the first step".to_string(),
                )
                .with_hint(
                    "check the initial `state` and the predicates; state a round trip with `was` \
                     (`cycler.lid was open` beside `cycler.lid is closed`) or as a chain; `eval` \
                     and `demo` refuse this task unless `--allow-trivial`",
                );
                d.notes.extend(describe(bound));
                d.notes.extend(origin.clone());
                cx.push(d);
            }
            // The stage's clock after each step: what a step's `within` is proved against.
            let mut clock_after: Vec<f64> = Vec::with_capacity(stage.steps.len());
            for step in stage.steps {
                let mut args = BTreeMap::new();
                for (k, v) in &step.planned.args {
                    args.insert(k.clone(), render(v, bound).unwrap_or_else(|_| v.clone()));
                }
                let bound_step = BoundStep {
                    primitive: step.primitive,
                    robot: &step.planned.robot,
                    args: &args,
                };
                let held_before = w.panel_hold_s;
                if let Err(v) = primitives::apply(&mut w, &env, &bound_step) {
                    let span = v
                        .arg
                        .and_then(|a| step.ast.arg(a))
                        .map(|a| a.span)
                        .or(step.ast.primitive.as_ref().map(|p| p.span))
                        .unwrap_or(step.ast.span);
                    let mut d = Diagnostic::new(v.code, span, v.message);
                    d.hint = v.hint;
                    d.notes.extend(describe(bound));
                    d.notes.extend(origin.clone());
                    cx.push(d);
                    continue 'combination;
                }
                if w.clock_s > stage.time_limit_s {
                    let span = step
                        .ast
                        .primitive
                        .as_ref()
                        .map(|p| p.span)
                        .unwrap_or(step.ast.span);
                    let mut d = Diagnostic::new(
                        Code::E0039,
                        span,
                        format!(
                            "the stage's waits and runs up to this `{}` take at least {:.0} s, past its time limit of {} s",
                            step.primitive.name, w.clock_s, stage.time_limit_s
                        ),
                    )
                    .with_hint(format!(
                        "raise `time_limit` above {:.0} s (the motions need time too)",
                        w.clock_s.ceil()
                    ));
                    d.notes.extend(describe(bound));
                    cx.push(d);
                    continue 'combination;
                }
                if w.panel_hold_s > stage.time_limit_s && held_before <= stage.time_limit_s {
                    slow_panel(cx, step, &args, held_before, &w, stage.time_limit_s, bound);
                }
                for (k, p) in stage.predicates.iter().enumerate() {
                    let now = p.predicate.check.eval_abstract(&w, bound);
                    if p.predicate.check.is_history() && now == Some(true) {
                        seen[k] = true;
                    }
                    dwell.step(k, now, w.clock_s);
                }
                clock_after.push(w.clock_s);
            }
            if let Some(mut d) = late_step(stage.steps, &clock_after) {
                d.notes.extend(describe(bound));
                cx.push(d);
                continue 'combination;
            }
            if let Some(d) = dwell.broken(stage.predicates, w.clock_s) {
                let mut d = d;
                d.notes.extend(describe(bound));
                cx.push(d);
                continue 'combination;
            }
            for (k, p) in stage.predicates.iter().enumerate() {
                if p.predicate.since.is_some() {
                    // A timed step's outcome is the judge's to time; the plan's share is
                    // `late_step`'s.
                    continue;
                }
                let now = if let Some(constraint) = &p.predicate.dwell {
                    // Never held: no time at all, which breaks a least time; else the judge's
                    // to measure.
                    let needs_time = constraint.at_least_s.is_some_and(|lo| lo > 0.0);
                    (needs_time && !dwell.ever[k] && !dwell.unknown[k]).then_some(false)
                } else if p.predicate.check.is_history() {
                    Some(seen[k])
                } else {
                    p.predicate.check.eval_abstract(&w, bound)
                };
                if now == Some(false) {
                    let mut d = Diagnostic::new(
                        Code::E0033,
                        p.span,
                        format!("after the last step, `{}` is false", p.predicate.text),
                    )
                    .with_hint("add the steps that make it true, or fix the predicate");
                    d.notes.extend(describe(bound));
                    cx.push(d);
                    continue 'combination;
                }
            }
        }
    }
}
