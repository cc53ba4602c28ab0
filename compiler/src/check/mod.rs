//! Name resolution and lowering of one protocol to a scene plus a [`Stage`], collecting every
//! diagnostic. [`lower`] runs the passes of its submodules in a fixed order (that order is the
//! order of the diagnostics) and assembles a [`Lowered`]; [`check_scene`] runs the scene's share
//! of them on a scene file alone. The passes: [`scene`] (one namespace, implausible values),
//! [`items`] (robots, labware and their start states), [`randomise`], [`parameters`] (domains and
//! placeholders), [`steps`], [`success`] with [`resolve`] (predicates and tolerances),
//! [`timing`] (steps' `within`, lowered to predicates),
//! [`sweep_uses`] (what the slot and quantity sweep reads) and [`cameras`]. This module holds
//! what the passes share and decides no diagnostic of its own. The state proof over the stages
//! lives in [`crate::proof`]; chains in [`crate::chain`].

mod cameras;
mod items;
mod parameters;
mod randomise;
mod resolve;
mod scene;
mod steps;
mod success;
mod sweep_uses;
mod timing;

pub(crate) use cameras::default_cameras;
pub(crate) use scene::time_limit_warning;

use crate::params::ParamSpec;
use crate::primitives::LabPrimitive;
use crate::report::Cx;
use crate::task::*;
use dsl::ast::{Protocol, Scalar, Spanned, Step};
use dsl::{Dimension, Span};
use labware::LabwareKind;
use std::collections::BTreeMap;

/// A step after static checks, kept with its AST for the proof's diagnostics.
pub(crate) struct CheckedStep<'a> {
    pub ast: &'a Step,
    pub primitive: &'static LabPrimitive,
    pub planned: PlannedStep,
}

/// A predicate after static checks, with its span.
pub(crate) struct CheckedPredicate {
    pub span: Span,
    pub predicate: Predicate,
}

/// One protocol lowered: its scene, its stage, and what the proof needs.
pub(crate) struct Lowered<'a> {
    pub id: String,
    pub version: i64,
    pub level: String,
    pub robots: Vec<RobotSpec>,
    pub labware: Vec<LabwareSpec>,
    pub kinds: BTreeMap<String, &'static LabwareKind>,
    pub params: Vec<ParamSpec>,
    pub stage: Stage,
    pub steps: Vec<CheckedStep<'a>>,
    pub predicates: Vec<CheckedPredicate>,
    /// Spans to point at, by labware name (the `at` value or the name).
    pub labware_spans: BTreeMap<String, Span>,
    /// The fixed camera's mount when `[camera]` places it.
    pub camera: Option<CameraMount>,
}

/// Each declared labware item's kind, by name (items whose kind is unknown left out).
type KindMap = BTreeMap<String, &'static LabwareKind>;

/// A predicate's tolerance before overrides: name, default value, and what it bounds.
type NamedTolerance = (String, f64, Dimension);

/// Checks one protocol's names, arguments, parameters and predicates and lowers it. Returns
/// `None` when something needed for a task is missing; the diagnostics are complete either way.
pub(crate) fn lower<'a>(cx: &mut Cx, p: &'a Protocol, file: &str) -> Option<Lowered<'a>> {
    scene::duplicates(cx, p);
    scene::implausible(cx, p);
    let mut robots_ok = items::lower_robots(cx, p);
    let (mut labware_ok, kinds) = items::lower_labware(cx, p);
    randomise::randomise(cx, p, &mut robots_ok, &mut labware_ok);
    let params = parameters::lower_params(cx, p, &kinds, &labware_ok);
    // Every declared parameter counts for placeholders, also one whose domain had an error (that
    // error is reported once, at the parameter).
    let param_names: Vec<&str> = p.params.iter().map(|p| p.name.value.as_str()).collect();
    scene_placeholders(cx, p, &param_names);
    let robot_names: Vec<String> = p.robots.iter().map(|r| r.name.value.clone()).collect();
    let steps = steps::check_steps(cx, p, &robot_names, &param_names);
    let declared: Vec<&str> = p.labware.iter().map(|l| l.name.value.as_str()).collect();
    let mut predicates =
        success::lower_predicates(cx, p, &kinds, &robot_names, &param_names, &declared);
    predicates.extend(timing::lower_timing(
        cx,
        &steps,
        &kinds,
        &robot_names,
        &declared,
    ));
    crate::sweep::check(
        cx,
        &sweep_uses::sweep_uses(p, &kinds, &predicates),
        &kinds,
        &declared,
        &robot_names,
        &params,
    );
    let m = &p.meta;
    if let Some(i) = &m.instruction {
        crate::perturb::check_paraphrases(cx, &m.paraphrases, &i.value);
    }
    let labware_spans = labware_spans(p);
    let camera = p.camera.as_ref().and_then(|c| cameras::fixed_camera(cx, c));
    let id = m.id.as_ref()?.value.clone();
    let stage = Stage {
        id: id.clone(),
        source: file.to_string(),
        instruction: m.instruction.as_ref()?.value.clone(),
        time_limit_s: m.time_limit.as_ref()?.value,
        plan: steps.iter().map(|s| s.planned.clone()).collect(),
        success: predicates.iter().map(|p| p.predicate.clone()).collect(),
        scoring: scoring(p),
        settle_s: p
            .success
            .settle
            .as_ref()
            .map_or(DEFAULT_SETTLE_S, |s| s.value),
    };
    Some(Lowered {
        id,
        version: m.version.as_ref().map(|v| v.value).unwrap_or(1),
        level: m
            .level
            .as_ref()
            .map(|l| l.value.clone())
            .unwrap_or_else(|| "easy".into()),
        robots: robots_ok.into_iter().collect::<Option<Vec<_>>>()?,
        labware: labware_ok.into_iter().collect::<Option<Vec<_>>>()?,
        kinds,
        params,
        stage,
        steps,
        predicates,
        labware_spans,
        camera,
    })
}

/// Checks a scene file alone (`autobio check scene.toml`): its names, robots, labware, start
/// states and randomisation, as a protocol standing in it would have them checked.
pub(crate) fn check_scene(cx: &mut Cx, p: &Protocol) {
    scene::duplicates(cx, p);
    scene::implausible(cx, p);
    let mut robots = items::lower_robots(cx, p);
    let (mut labware, _) = items::lower_labware(cx, p);
    randomise::randomise(cx, p, &mut robots, &mut labware);
}

/// E0023 for the `{name}` placeholders outside steps and predicates that name no parameter: in
/// the instruction, in each labware's `at` and in its string start states.
fn scene_placeholders(cx: &mut Cx, p: &Protocol, param_names: &[&str]) {
    if let Some(i) = &p.meta.instruction {
        parameters::check_placeholders(cx, i, param_names);
    }
    for l in &p.labware {
        if let Some(at) = &l.at {
            parameters::check_placeholders(cx, at, param_names);
        }
        for (_, v) in &l.state {
            if let Scalar::Str(s) = &v.value {
                parameters::check_placeholders(cx, &Spanned::new(s.clone(), v.span), param_names);
            }
        }
    }
}

/// Where the proof points for each labware item: its `at`, else its `held_by`, else its name.
fn labware_spans(p: &Protocol) -> BTreeMap<String, Span> {
    p.labware
        .iter()
        .map(|l| {
            let span =
                l.at.as_ref()
                    .or(l.held_by.as_ref())
                    .map(|a| a.span)
                    .unwrap_or(l.name.span);
            (l.name.value.clone(), span)
        })
        .collect()
}

/// `scoring = "progress"` is progress scoring; anything else (or nothing) is binary.
fn scoring(p: &Protocol) -> Scoring {
    match p.success.scoring.as_ref().map(|s| s.value.as_str()) {
        Some("progress") => Scoring::Progress,
        _ => Scoring::Binary,
    }
}

/// What the tests of the passes share: one small protocol that compiles clean, edited per test,
/// and the ways to run it through the parser and the compiler.
#[cfg(test)]
mod testing {
    use super::{Lowered, lower};
    use crate::report::Cx;
    use dsl::ast::Document;
    use dsl::{Code, Diagnostic};

    /// One arm moving a tube between two racks to a drawn row: no diagnostic at all (tested).
    pub(super) const BASE: &str = r#"format = 1

[protocol]
id = "test.transfer"
instruction = "move the tube to the other rack, row {row}"
time_limit = "15 s"

[robots.arm]
model = "ur5e_2f85"
base = { pos_m = [-0.1, 0.0, 0.824] }

[labware.source]
kind = "tube_rack"
pose = { pos_m = [0.3, -0.2, 0.854], yaw_deg = 90 }

[labware.target]
kind = "tube_rack"
pose = { pos_m = [0.3, 0.2, 0.854], yaw_deg = 90 }

[labware.tube]
kind = "tube_50ml"
at = "source.A1"

[params.row]
choice = ["A", "B"]

[[steps]]
do = "pick"
on = "tube"
with = "arm"

[[steps]]
do = "place"
on = "tube"
to = "target.{row}1"
with = "arm"

[success]
all = ["tube in target.{row}1"]
"#;

    /// [`BASE`] with each `(from, to)` replaced once, in order. A `from` that is not there fails
    /// the test: an edit never silently leaves the protocol as it was.
    pub(super) fn edited(edits: &[(&str, &str)]) -> String {
        let mut s = BASE.to_string();
        for (from, to) in edits {
            assert!(s.contains(from), "`{from}` is not in the protocol:\n{s}");
            s = s.replacen(from, to, 1);
        }
        s
    }

    /// [`BASE`] with `more` appended (further tables).
    pub(super) fn with(more: &str) -> String {
        format!("{BASE}\n{more}")
    }

    /// Parses `src` and runs [`lower`] on it (the checks of this module, no state proof): `f`
    /// gets the lowered protocol, if any, and every diagnostic, the parser's first.
    pub(super) fn lowered<R>(
        src: &str,
        f: impl FnOnce(Option<&Lowered<'_>>, &[Diagnostic]) -> R,
    ) -> R {
        let (doc, mut diags) = dsl::parse(src);
        let Document::Protocol(p) = doc else {
            panic!("not a protocol: {diags:#?}");
        };
        let mut cx = Cx::new(None);
        let low = lower(&mut cx, &p, "test.toml");
        diags.extend(cx.diags);
        f(low.as_ref(), &diags)
    }

    /// The whole compiler on `src`: the task, if any, and every diagnostic.
    pub(super) fn compiled(src: &str) -> (Option<crate::Task>, Vec<Diagnostic>) {
        crate::compile_source(src, "test.toml")
    }

    /// The one diagnostic of `code`; fails when there is none or more than one.
    pub(super) fn one(diags: &[Diagnostic], code: Code) -> &Diagnostic {
        let found: Vec<&Diagnostic> = diags.iter().filter(|d| d.code == code).collect();
        assert_eq!(found.len(), 1, "one {code:?} expected: {diags:#?}");
        found[0]
    }

    /// Every diagnostic's code, in order.
    pub(super) fn codes(diags: &[Diagnostic]) -> Vec<Code> {
        diags.iter().map(|d| d.code).collect()
    }

    /// The source text a span covers (a diagnostic's: `covered(src, d.span)`).
    pub(super) fn covered(src: &str, span: dsl::Span) -> &str {
        &src[span.start..span.end]
    }
}

#[cfg(test)]
mod tests {
    use super::testing::*;
    use crate::task::Scoring;
    use dsl::Code;

    /// The protocol every other test edits compiles with no diagnostic at all, so each error a
    /// test finds comes from its edit.
    #[test]
    fn the_base_protocol_compiles_clean_and_lowers_its_stage() {
        let (task, diags) = compiled(BASE);
        assert!(diags.is_empty(), "{diags:#?}");
        let task = task.expect("a task");
        let stage = &task.stages[0];
        assert_eq!(stage.id, "test.transfer");
        assert_eq!(stage.time_limit_s, 15.0);
        assert_eq!(stage.scoring, Scoring::Binary);
        assert_eq!(stage.plan.len(), 2);
        assert_eq!(stage.success[0].text, "tube in target.{row}1");
        assert_eq!(task.level, "easy");
        assert_eq!(task.version, 1);
        lowered(BASE, |low, _| {
            let low = low.expect("lowered");
            // The proof points at a slotted item's `at`, at a placed item's name.
            assert_eq!(covered(BASE, low.labware_spans["tube"]), "\"source.A1\"");
            assert_eq!(covered(BASE, low.labware_spans["source"]), "source");
        });
    }

    /// A protocol without the keys a stage needs is checked all the same, and lowers to nothing.
    #[test]
    fn a_protocol_missing_its_id_lowers_to_nothing_after_every_check() {
        let src = edited(&[
            ("id = \"test.transfer\"\n", ""),
            ("kind = \"tube_50ml\"", "kind = \"tube_5oml\""),
        ]);
        lowered(&src, |low, diags| {
            assert!(low.is_none());
            // The parser's E0002 for the missing id, then the unknown kind.
            assert!(codes(diags).contains(&Code::E0002), "{diags:#?}");
            assert_eq!(
                one(diags, Code::E0010).hint.as_deref(),
                Some("did you mean `tube_50ml`?")
            );
        });
    }

    /// A scene file alone gets the scene's checks: names, kinds, randomisation targets.
    #[test]
    fn a_scene_file_alone_gets_the_scene_checks_in_order() {
        let src = r#"format = 1

[scene]
description = "a bench"

[robots.arm]
model = "ur5e_2f85"
base = { pos_m = [0.0, 0.5, 0.824] }

[labware.arm]
kind = "centrifuge_543"
pose = { pos_m = [-0.1, 0.0, 0.824] }

[randomise.rack]
xy_m = 0.01
"#;
        let (task, diags) = compiled(src);
        assert!(task.is_none());
        assert_eq!(
            codes(&diags),
            [Code::E0015, Code::E0010, Code::E0013],
            "{diags:#?}"
        );
    }
}
