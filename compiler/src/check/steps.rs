//! `[[steps]]` checked one by one against the primitive catalogue: a known primitive (E0012), a
//! declared robot in `with` (E0002, E0013), `together` only where it can join the step before
//! (E0021), the primitive's arguments and none other (E0032), and placeholders naming parameters
//! (E0023). A step that passes becomes a [`PlannedStep`]. It does not check what the arguments
//! name (slots, quantities: [`crate::sweep`]) or whether a step's preconditions hold
//! ([`crate::proof`]).

use super::CheckedStep;
use super::parameters::check_placeholders;
use crate::primitives::{self, LabPrimitive};
use crate::report::{Cx, hint_for};
use crate::task::PlannedStep;
use dsl::ast::{Protocol, Scalar, Spanned, Step};
use dsl::{Code, did_you_mean};
use std::collections::BTreeMap;

/// Each step that passes its checks, in order; a step with an error is left out after it.
pub(super) fn check_steps<'a>(
    cx: &mut Cx,
    p: &'a Protocol,
    robots: &[String],
    params: &[&str],
) -> Vec<CheckedStep<'a>> {
    let prim_names: Vec<&str> = primitives::CATALOGUE.iter().map(|p| p.name).collect();
    let mut out = Vec::new();
    for (i, step) in p.steps.iter().enumerate() {
        let Some(prim_name) = &step.primitive else {
            continue;
        };
        let Some(prim) = primitives::primitive(&prim_name.value) else {
            cx.err(
                Code::E0012,
                prim_name.span,
                format!("unknown lab primitive `{}`", prim_name.value),
                Some(hint_for(&prim_name.value, &prim_names, "primitives")),
            );
            continue;
        };
        // Every check runs (`&=` does not short-circuit), so one pass reports all of a step's
        // mistakes.
        let mut ok = check_robot(cx, step, robots);
        ok &= check_together(cx, p, i, step);
        ok &= check_args(cx, step, prim, params);
        ok &= check_required_args(cx, step, prim, prim_name);
        ok &= check_fixed_programme(cx, step, prim);
        if !ok {
            continue;
        }
        out.push(CheckedStep {
            ast: step,
            primitive: prim,
            planned: planned_step(step, prim),
        });
    }
    out
}

/// `with` names a declared robot.
fn check_robot(cx: &mut Cx, step: &Step, robots: &[String]) -> bool {
    let robot_names: Vec<&str> = robots.iter().map(String::as_str).collect();
    match &step.with {
        None => {
            cx.err(
                Code::E0002,
                step.span,
                "step has no `with`".into(),
                Some(format!(
                    "name the robot that does it: {}",
                    robot_names.join(", ")
                )),
            );
            false
        }
        Some(w) if !robots.contains(&w.value) => {
            cx.err(
                Code::E0013,
                w.span,
                format!("no robot named `{}`", w.value),
                Some(hint_for(&w.value, &robot_names, "robots")),
            );
            false
        }
        Some(_) => true,
    }
}

/// `together = true` joins step `i` to the group of the step before it: not on the first step,
/// and not on a robot that already has a step in that group.
fn check_together(cx: &mut Cx, p: &Protocol, i: usize, step: &Step) -> bool {
    let Some(t) = step.together.as_ref().filter(|t| t.value) else {
        return true;
    };
    // The robots of the group this step joins: the step before it and, while those were
    // marked `together` too, the steps before them.
    let mut group: Vec<&str> = Vec::new();
    for j in (0..i).rev() {
        if let Some(w) = &p.steps[j].with {
            group.push(&w.value);
        }
        if !p.steps[j].together.as_ref().is_some_and(|t| t.value) {
            break;
        }
    }
    let same = step
        .with
        .as_ref()
        .and_then(|w| group.iter().find(|g| **g == w.value));
    match (i, same) {
        (0, _) => {
            cx.err(
                Code::E0021,
                t.span,
                "`together` starts a step with the step before it, and this is the first step"
                    .into(),
                Some("remove `together`; a stage's first step starts when the stage does".into()),
            );
            false
        }
        (_, Some(robot)) => {
            cx.err(
                Code::E0021,
                t.span,
                format!("`together` joins a step of `{robot}`'s to a group where `{robot}` already has one: one robot does one step at a time"),
                Some("give one of the two steps to another robot, or remove `together`".into()),
            );
            false
        }
        _ => true,
    }
}

/// Each written argument is one of the primitive's (E0032) and its placeholders name parameters
/// (E0023).
fn check_args(cx: &mut Cx, step: &Step, prim: &LabPrimitive, params: &[&str]) -> bool {
    let mut ok = true;
    let arg_names: Vec<&str> = prim.args.iter().map(|a| a.name).collect();
    for (key, value) in &step.args {
        if !arg_names.contains(&key.value.as_str()) {
            let hint = match did_you_mean(&key.value, arg_names.iter().copied()) {
                Some(s) => format!("did you mean `{s}`? `{}`", prim.signature()),
                None => format!("`{}`", prim.signature()),
            };
            cx.err(
                Code::E0032,
                key.span,
                format!("`{}` takes no argument `{}`", prim.name, key.value),
                Some(hint),
            );
            ok = false;
        }
        if let Scalar::Str(s) = &value.value {
            let before = cx.diags.len();
            check_placeholders(cx, &Spanned::new(s.clone(), value.span), params);
            ok &= cx.diags.len() == before;
        }
    }
    ok
}

/// Every argument of the primitive but its optional ones is given (E0032, at the primitive's
/// name).
fn check_required_args(
    cx: &mut Cx,
    step: &Step,
    prim: &LabPrimitive,
    prim_name: &Spanned<String>,
) -> bool {
    let mut ok = true;
    for a in prim.args.iter().filter(|a| !a.optional) {
        if step.arg(a.name).is_none() {
            cx.err(
                Code::E0032,
                prim_name.span,
                format!("`{}` needs `{}` ({})", prim.name, a.name, a.doc),
                Some(format!("`{}`", prim.signature())),
            );
            ok = false;
        }
    }
    ok
}

/// A run step's programme is fixed when the task compiles (the instrument's model carries it):
/// no placeholder in its arguments but `on`.
fn check_fixed_programme(cx: &mut Cx, step: &Step, prim: &LabPrimitive) -> bool {
    if primitives::run::programme(prim.name, &BTreeMap::new(), None).is_none() {
        return true;
    }
    let mut ok = true;
    for (k, v) in &step.args {
        if k.value != "on" && v.value.text().contains('{') {
            cx.err(
                Code::E0031,
                v.span,
                format!(
                    "`{}`'s `{}` is a placeholder, but a run's programme is fixed when the task compiles",
                    prim.name, k.value
                ),
                Some("write the value itself; draw the run's settings in another protocol per value".into()),
            );
            ok = false;
        }
    }
    ok
}

/// A checked step as the task plans it: its arguments as written, `on` as its labware.
fn planned_step(step: &Step, prim: &LabPrimitive) -> PlannedStep {
    let args: BTreeMap<String, String> = step
        .args
        .iter()
        .map(|(k, v)| (k.value.clone(), v.value.text()))
        .collect();
    PlannedStep {
        primitive: prim.name.into(),
        robot: step
            .with
            .as_ref()
            .map(|w| w.value.clone())
            .unwrap_or_default(),
        labware: args.get("on").cloned(),
        args,
        together: step.together.as_ref().is_some_and(|t| t.value),
        span: crate::task::StepSpan(step.with.as_ref().map(|w| w.span).unwrap_or(step.span)),
    }
}

#[cfg(test)]
mod tests {
    use super::super::testing::*;
    use dsl::Code;

    const PICK: &str = "do = \"pick\"\non = \"tube\"\nwith = \"arm\"";

    /// A step without `with`, or naming no robot, is reported and left out of the plan.
    #[test]
    fn a_step_without_a_declared_robot_is_reported_and_left_out() {
        let src = edited(&[(PICK, "do = \"pick\"\non = \"tube\"")]);
        lowered(&src, |low, diags| {
            assert_eq!(one(diags, Code::E0002).message, "step has no `with`");
            assert_eq!(low.unwrap().steps.len(), 1);
        });
        let src = edited(&[(PICK, "do = \"pick\"\non = \"tube\"\nwith = \"arn\"")]);
        lowered(&src, |low, diags| {
            let d = one(diags, Code::E0013);
            assert_eq!(covered(&src, d.span), "\"arn\"");
            assert_eq!(d.hint.as_deref(), Some("did you mean `arm`?"));
            assert_eq!(low.unwrap().stage.plan[0].primitive, "place");
        });
    }

    /// `together` cannot start the first step, nor join a step to a group where its robot
    /// already has one.
    #[test]
    fn together_joins_another_robots_step_only() {
        let first = edited(&[(PICK, &format!("{PICK}\ntogether = true"))]);
        lowered(&first, |_, diags| {
            let d = one(diags, Code::E0021);
            assert!(d.message.contains("this is the first step"), "{d:?}");
            assert_eq!(covered(&first, d.span), "true");
        });
        let same = edited(&[(
            "to = \"target.{row}1\"",
            "to = \"target.{row}1\"\ntogether = true",
        )]);
        lowered(&same, |low, diags| {
            assert!(one(diags, Code::E0021).message.starts_with(
                "`together` joins a step of `arm`'s to a group where `arm` already has one"
            ));
            assert_eq!(low.unwrap().steps.len(), 1);
        });
    }

    /// An argument the primitive does not take is E0032 with the closest one; a missing one is
    /// E0032 at the primitive's name.
    #[test]
    fn a_steps_arguments_are_the_primitives_own_and_all_given() {
        let src = edited(&[("to = \"target.{row}1\"", "tto = \"target.{row}1\"")]);
        lowered(&src, |low, diags| {
            let wrong: Vec<_> = diags.iter().filter(|d| d.code == Code::E0032).collect();
            assert_eq!(wrong.len(), 2, "{diags:#?}");
            assert_eq!(wrong[0].message, "`place` takes no argument `tto`");
            assert!(
                wrong[0]
                    .hint
                    .as_deref()
                    .unwrap()
                    .starts_with("did you mean `to`?")
            );
            assert!(wrong[1].message.starts_with("`place` needs `to` ("));
            assert_eq!(covered(&src, wrong[1].span), "\"place\"");
            assert_eq!(low.unwrap().steps.len(), 1);
        });
    }

    /// A checked step is planned with its robot, its `on` and its arguments as written.
    #[test]
    fn a_checked_step_is_planned_with_its_arguments_as_written() {
        lowered(BASE, |low, _| {
            let plan = &low.unwrap().stage.plan;
            assert_eq!(plan[1].primitive, "place");
            assert_eq!(plan[1].robot, "arm");
            assert_eq!(plan[1].labware.as_deref(), Some("tube"));
            assert_eq!(plan[1].args["to"], "target.{row}1");
            assert_eq!(plan[1].args["on"], "tube");
            assert!(!plan[1].together);
        });
    }
}
