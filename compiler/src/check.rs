//! Name resolution and lowering of one protocol to a scene plus a [`Stage`], collecting every
//! diagnostic. The state proof over the stages lives in [`crate::proof`]; chains in
//! [`crate::chain`].

use crate::params::{Domain, ParamSpec, placeholders};
use crate::predicates::{self, Check, Cmp, Form, Tolerance};
use crate::primitives::{self, LabPrimitive, resolve_location};
pub(crate) use crate::report::{Cx, hint_for};
use crate::task::*;
use dsl::ast::{ParamDomain, Protocol, RandomItem, Scalar, Spanned, Step};
use dsl::{Code, Diagnostic, Dimension, Span, did_you_mean, parse_quantity};
use labware::{LabwareKind, Model, Pose};
use std::collections::{BTreeMap, BTreeSet};

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

/// Checks one protocol's names, arguments, parameters and predicates and lowers it. Returns
/// `None` when something needed for a task is missing; the diagnostics are complete either way.
pub(crate) fn lower<'a>(cx: &mut Cx, p: &'a Protocol, file: &str) -> Option<Lowered<'a>> {
    duplicates(cx, p);
    implausible(cx, p);
    let robots = lower_robots(cx, p);
    let (labware, kinds) = lower_labware(cx, p);
    let mut robots_ok: Vec<Option<RobotSpec>> = robots;
    let mut labware_ok: Vec<Option<LabwareSpec>> = labware;
    randomise(cx, p, &mut robots_ok, &mut labware_ok);
    let params = lower_params(cx, p, &kinds, &labware_ok);
    // Every declared parameter counts for placeholders, also one whose domain had an error (that
    // error is reported once, at the parameter).
    let param_names: Vec<&str> = p.params.iter().map(|p| p.name.value.as_str()).collect();
    if let Some(i) = &p.meta.instruction {
        check_placeholders(cx, i, &param_names);
    }
    for l in &p.labware {
        if let Some(at) = &l.at {
            check_placeholders(cx, at, &param_names);
        }
        for (_, v) in &l.state {
            if let Scalar::Str(s) = &v.value {
                check_placeholders(cx, &Spanned::new(s.clone(), v.span), &param_names);
            }
        }
    }
    let robot_names: Vec<String> = p.robots.iter().map(|r| r.name.value.clone()).collect();
    let steps = check_steps(cx, p, &robot_names, &param_names);
    let declared: Vec<&str> = p.labware.iter().map(|l| l.name.value.as_str()).collect();
    let predicates = lower_predicates(cx, p, &kinds, &robot_names, &param_names, &declared);
    crate::sweep::check(
        cx,
        &sweep_uses(p, &kinds, &predicates),
        &kinds,
        &declared,
        &robot_names,
        &params,
    );
    let m = &p.meta;
    let labware_spans = p
        .labware
        .iter()
        .map(|l| {
            let span =
                l.at.as_ref()
                    .or(l.held_by.as_ref())
                    .map(|a| a.span)
                    .unwrap_or(l.name.span);
            (l.name.value.clone(), span)
        })
        .collect();
    let scoring = match p.success.scoring.as_ref().map(|s| s.value.as_str()) {
        Some("progress") => Scoring::Progress,
        _ => Scoring::Binary,
    };
    let camera = p.camera.as_ref().and_then(|c| fixed_camera(cx, c));
    let id = m.id.as_ref()?.value.clone();
    let stage = Stage {
        id: id.clone(),
        source: file.to_string(),
        instruction: m.instruction.as_ref()?.value.clone(),
        time_limit_s: m.time_limit.as_ref()?.value,
        plan: steps.iter().map(|s| s.planned.clone()).collect(),
        success: predicates.iter().map(|p| p.predicate.clone()).collect(),
        scoring,
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

/// Every place the protocol names a slot or a quantity, for [`crate::sweep::check`]: each
/// labware's `at`, each step's location arguments (the item being the step's `on`), volumes and
/// panel values, each `in` predicate and each volume or panel predicate's target.
fn sweep_uses(
    p: &Protocol,
    kinds: &KindMap,
    predicates: &[CheckedPredicate],
) -> Vec<crate::sweep::Use> {
    use crate::sweep::{Use, What};
    let item = |name: &str| kinds.get(name).map(|k| (name.to_string(), *k));
    let mut uses: Vec<Use> = p
        .labware
        .iter()
        .filter_map(|l| {
            l.at.as_ref().map(|at| Use {
                span: at.span,
                template: at.value.clone(),
                what: What::Slot {
                    item: item(&l.name.value),
                    start: true,
                },
            })
        })
        .collect();
    for step in &p.steps {
        let Some(prim) = step
            .primitive
            .as_ref()
            .and_then(|n| primitives::primitive(&n.value))
        else {
            continue;
        };
        let on = step.arg("on").map(|v| v.value.text());
        let panel = on
            .as_deref()
            .and_then(|o| kinds.get(o))
            .zip(step.arg("param").map(|v| v.value.text()))
            .and_then(|(k, param)| k.panel_param(&param));
        for a in prim.args {
            let Some(v) = step.arg(a.name) else {
                continue;
            };
            let what = match a.kind {
                primitives::ArgKind::Location => What::Slot {
                    item: on.as_deref().and_then(item),
                    start: false,
                },
                primitives::ArgKind::Volume => What::Quantity(Dimension::Volume),
                primitives::ArgKind::PanelValue => match panel {
                    Some(pp) => What::Quantity(primitives::panel_dimension(pp.unit)),
                    None => continue,
                },
                _ => continue,
            };
            uses.push(Use {
                span: v.span,
                template: v.value.text(),
                what,
            });
        }
    }
    for cp in predicates {
        let (template, what) = match &cp.predicate.check {
            Check::InSlot {
                item: name,
                location,
                ..
            } => (
                location.clone(),
                What::Slot {
                    item: item(name),
                    start: false,
                },
            ),
            Check::Volume { value, .. } => (value.clone(), What::Quantity(Dimension::Volume)),
            Check::Panel { value, unit, .. } => (
                value.clone(),
                What::Quantity(primitives::panel_dimension(unit)),
            ),
            _ => continue,
        };
        uses.push(Use {
            span: cp.span,
            template,
            what,
        });
    }
    uses
}

/// What to declare for a state word a part cannot start in: the word an author means by a
/// negation or another form (`unlocked` is `closed`: shut, not latched), else the closest word.
fn state_hint(word: &str, initial: &[&str]) -> String {
    let meant = match word.to_lowercase().as_str() {
        "unlocked" | "shut" | "close" | "unlatched" => Some("closed"),
        "opened" => Some("open"),
        "lock" | "latched" => Some("locked"),
        "removed" => Some("off"),
        "screwed" | "capped" => Some("on"),
        _ => None,
    };
    match meant.filter(|m| initial.contains(m)) {
        Some(m) => format!(
            "declare `{m}`; the states it can start in: {}",
            initial.join(", ")
        ),
        None => hint_for(word, initial, "initial states"),
    }
}

/// The fixed camera of a `[camera]` table: standing at `pos`, looking at `look_at` with the image's
/// up as close to world up as the view allows.
fn fixed_camera(cx: &mut Cx, c: &dsl::ast::Camera) -> Option<CameraMount> {
    let (pos, at) = (c.pos.as_ref()?, c.look_at.as_ref()?);
    let fovy = c
        .fovy
        .as_ref()
        .map(|f| f.value)
        .unwrap_or(45f64.to_radians());
    if let Some(f) = &c.fovy
        && !(1.0..=150.0).contains(&f.value.to_degrees())
    {
        cx.err(
            Code::E0021,
            f.span,
            format!(
                "a field of view of {:.1}° is no camera's",
                f.value.to_degrees()
            ),
            Some("use 1° to 150°; 45° is the bench camera's".into()),
        );
        return None;
    }
    let v = |a: [f64; 3]| nalgebra::Vector3::new(a[0], a[1], a[2]);
    let forward = v(at.value) - v(pos.value);
    let right = forward.cross(&nalgebra::Vector3::z());
    if forward.norm() < 1e-3 || right.norm() < 1e-6 * forward.norm() {
        let msg = if forward.norm() < 1e-3 {
            "the camera looks at the point it stands on"
        } else {
            "the camera looks straight up or down, so its image has no up"
        };
        cx.err(
            Code::E0021,
            at.span,
            msg.into(),
            Some("look at a point at least 1 mm away, not straight above or below".into()),
        );
        return None;
    }
    let x = right.normalize();
    let y = x.cross(&forward.normalize());
    Some(CameraMount::Fixed {
        pos: pos.value,
        xyaxes: [x.x, x.y, x.z, y.x, y.y, y.z],
        fovy_deg: fovy.to_degrees(),
    })
}

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

/// Warnings for values that parse and type-check but are almost certainly mistakes.
/// Checks a scene file alone (`autobio check scene.toml`): its names, robots, labware, start
/// states and randomisation, as a protocol standing in it would have them checked.
pub(crate) fn check_scene(cx: &mut Cx, p: &Protocol) {
    duplicates(cx, p);
    implausible(cx, p);
    let mut robots = lower_robots(cx, p);
    let (mut labware, _) = lower_labware(cx, p);
    randomise(cx, p, &mut robots, &mut labware);
}

fn implausible(cx: &mut Cx, p: &Protocol) {
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
    let in_room =
        |[x, y, z]: [f64; 3]| x.abs() <= ROOM && y.abs() <= ROOM && (-1.0..=ROOM).contains(&z);
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

fn duplicates(cx: &mut Cx, p: &Protocol) {
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

fn lower_robots(cx: &mut Cx, p: &Protocol) -> Vec<Option<RobotSpec>> {
    let names: Vec<&str> = robots::MODELS.iter().map(|m| m.name).collect();
    p.robots
        .iter()
        .map(|r| {
            let model = r.model.as_ref()?;
            let Some(m) = robots::model(&model.value) else {
                let hint = hint_for(&model.value, &names, "robot models");
                cx.err(
                    Code::E0011,
                    model.span,
                    format!("unknown robot model `{}`", model.value),
                    Some(hint),
                );
                return None;
            };
            Some(RobotSpec {
                name: r.name.value.clone(),
                model: m.name.into(),
                base: pose(&r.base),
                home: m.home.to_vec(),
                joint_jitter: None,
            })
        })
        .collect()
}

type KindMap = BTreeMap<String, &'static LabwareKind>;

/// A predicate's tolerance before overrides: name, default value, and what it bounds.
type NamedTolerance = (String, f64, Dimension);

fn lower_labware(cx: &mut Cx, p: &Protocol) -> (Vec<Option<LabwareSpec>>, KindMap) {
    let kinds: Vec<&str> = labware::KINDS.iter().map(|k| k.name).collect();
    let mut map = KindMap::new();
    let specs = p
        .labware
        .iter()
        .map(|l| {
            let kind = l.kind.as_ref()?;
            let Some(k) = labware::kind(&kind.value) else {
                let hint = hint_for(&kind.value, &kinds, "labware kinds");
                cx.err(
                    Code::E0010,
                    kind.span,
                    format!("unknown labware kind `{}`", kind.value),
                    Some(hint),
                );
                return None;
            };
            map.insert(l.name.value.clone(), k);
            let mut spec = LabwareSpec {
                name: l.name.value.clone(),
                kind: k.name.into(),
                placement: pose(&l.pose),
                xy_jitter_m: 0.0,
                yaw_jitter_rad: 0.0,
                joint_jitter: BTreeMap::new(),
                initial: k
                    .parts
                    .iter()
                    .map(|ps| (ps.part.to_string(), ps.initial[0].to_string()))
                    .collect(),
                at: l.at.as_ref().map(|a| a.value.clone()),
                held_by: None,
                volume: None,
                panel: BTreeMap::new(),
                params: Model::for_kind(k.name).unwrap_or(Model::Unmodelled),
            };
            if let Some(robot) = &l.held_by {
                let robots: Vec<&str> = p.robots.iter().map(|r| r.name.value.as_str()).collect();
                if !robots.contains(&robot.value.as_str()) {
                    cx.err(
                        Code::E0013,
                        robot.span,
                        format!("no robot named `{}`", robot.value),
                        Some(hint_for(&robot.value, &robots, "robots")),
                    );
                } else if !k.movable {
                    cx.err(
                        Code::E0016,
                        robot.span,
                        format!("`{}` (a {}) cannot be held", l.name.value, k.name),
                        Some("place it with `pose` instead".into()),
                    );
                } else if l.at.is_some() {
                    cx.err(
                        Code::E0016,
                        robot.span,
                        format!("`{}` starts both in a slot and in a hand", l.name.value),
                        Some("keep `at` or `held_by`, not both".into()),
                    );
                } else {
                    spec.held_by = Some(robot.value.clone());
                }
            }
            if let Some(at) = &l.at
                && !k.movable
            {
                cx.err(
                    Code::E0016,
                    at.span,
                    format!("`{}` (a {}) cannot stand in a slot", l.name.value, k.name),
                    Some("place it with `pose` instead".into()),
                );
            }
            for (key, value) in &l.state {
                initial_state(cx, k, &mut spec, key, value);
            }
            spec.params = spec.params.for_start(&spec.initial);
            // A start the language allows but the item's model cannot set up yet: said here,
            // not first by `eval` when it builds the scene.
            if let Some(why) = spec
                .params
                .instrument()
                .and_then(|m| m.unsupported_start(&spec.initial))
            {
                let span = l
                    .state
                    .first()
                    .map_or(l.name.span, |(_, v)| v.span);
                cx.push(
                    Diagnostic::new(
                        Code::W0007,
                        span,
                        format!("the simulator cannot start `{}` this way yet", l.name.value),
                    )
                    .with_note(why)
                    .with_hint("the protocol checks and compiles; `eval` and `demo` cannot build its scene"),
                );
            }
            Some(spec)
        })
        .collect();
    (specs, map)
}

/// One `state = { key = value }` entry: a part state, the volume, or a panel value.
fn initial_state(
    cx: &mut Cx,
    k: &'static LabwareKind,
    spec: &mut LabwareSpec,
    key: &Spanned<String>,
    value: &Spanned<Scalar>,
) {
    let text = value.value.text();
    if let Some(ps) = k.part(&key.value) {
        if !ps.initial.contains(&text.as_str()) {
            cx.err(
                Code::E0017,
                value.span,
                format!("`{}` cannot start `{text}`", key.value),
                Some(state_hint(&text, ps.initial)),
            );
        } else {
            spec.initial.insert(key.value.clone(), text);
        }
        return;
    }
    let dim = if key.value == "volume" && k.capacity_ul.is_some() {
        Some(Dimension::Volume)
    } else {
        k.panel_param(&key.value)
            .map(|p| primitives::panel_dimension(p.unit))
    };
    let Some(dim) = dim else {
        let mut keys: Vec<&str> = k.parts.iter().map(|p| p.part).collect();
        if k.capacity_ul.is_some() {
            keys.push("volume");
        }
        keys.extend(k.panel.iter().map(|p| p.name));
        cx.err(
            Code::E0017,
            key.span,
            format!("a {} has no state `{}`", k.name, key.value),
            Some(hint_for(&key.value, &keys, "state keys")),
        );
        return;
    };
    let Scalar::Str(s) = &value.value else {
        cx.err(
            Code::E0020,
            value.span,
            format!("`{}` needs a unit", key.value),
            Some(format!(
                "write it as a string such as \"{text} {}\"",
                dim.canonical_unit()
            )),
        );
        return;
    };
    if placeholders(s).is_empty() {
        match parse_quantity(s) {
            Ok(q) if q.dimension != dim => {
                cx.err(
                    Code::E0020,
                    value.span,
                    format!(
                        "`{s}` is a {}, but `{}` is a {}",
                        q.dimension.name(),
                        key.value,
                        dim.name()
                    ),
                    Some(format!("use one of: {}", dim.example_units())),
                );
                return;
            }
            Err(e) => {
                cx.err(Code::E0020, value.span, e, None);
                return;
            }
            Ok(q) => {
                let range = if key.value == "volume" {
                    Some((0.0, k.capacity_ul.unwrap_or(0.0), "µL"))
                } else {
                    k.panel_param(&key.value).map(|p| (p.min, p.max, p.unit))
                };
                if let Some((lo, hi, unit)) = range
                    && !(lo..=hi).contains(&q.si)
                {
                    cx.err(
                        Code::E0021,
                        value.span,
                        format!(
                            "`{}` of a {} ranges {lo}..{hi} {unit}, found `{s}`",
                            key.value, k.name
                        ),
                        None,
                    );
                    return;
                }
            }
        }
    }
    if key.value == "volume" {
        spec.volume = Some(s.clone());
    } else {
        spec.panel.insert(key.value.clone(), s.clone());
    }
}

fn randomise(
    cx: &mut Cx,
    p: &Protocol,
    robots: &mut [Option<RobotSpec>],
    labware: &mut [Option<LabwareSpec>],
) {
    for r in &p.randomise {
        let target = &r.target;
        if let Some(i) = p.robots.iter().position(|x| x.name.value == target.value) {
            let Some(robot) = robots[i].as_mut() else {
                continue;
            };
            for item in &r.items {
                match item {
                    RandomItem::Joints { low, high, span } => {
                        if low.value.len() > robot.home.len() {
                            cx.err(
                                Code::E0021,
                                *span,
                                format!(
                                    "`{}` has {} joints, but {} ranges are given",
                                    target.value,
                                    robot.home.len(),
                                    low.value.len()
                                ),
                                None,
                            );
                            continue;
                        }
                        robot.joint_jitter = Some(JointJitter {
                            low: low.value.clone(),
                            high: high.value.clone(),
                        });
                    }
                    RandomItem::LabwareJoints { span, .. } => cx.err(
                        Code::E0004,
                        *span,
                        format!(
                            "robot `{}`'s joints are randomised by `low` and `high` arrays",
                            target.value
                        ),
                        Some("e.g. `joints = { low = [-0.1, 0, 0, 0, 0, 0], high = [0.1, 0, 0, 0, 0, 0] }`; `role = angle` pairs are for labware joints".into()),
                    ),
                    RandomItem::Xy(q) | RandomItem::Yaw(q) => cx.err(
                        Code::E0003,
                        q.span,
                        format!("robot `{}` cannot be moved by randomisation", target.value),
                        Some(
                            "randomise a robot's `joints`; `xy` and `yaw` apply to labware".into(),
                        ),
                    ),
                }
            }
        } else if let Some(i) = p.labware.iter().position(|x| x.name.value == target.value) {
            let Some(lw) = labware[i].as_mut() else {
                continue;
            };
            for item in &r.items {
                match item {
                    RandomItem::Xy(q) => lw.xy_jitter_m = q.value.abs(),
                    RandomItem::Yaw(q) => lw.yaw_jitter_rad = q.value.abs(),
                    RandomItem::Joints { span, .. } => cx.err(
                        Code::E0004,
                        *span,
                        format!(
                            "labware `{}`'s joints are randomised by role, not by `low` and `high` arrays",
                            target.value
                        ),
                        Some("e.g. `joints = { rotor = \"0.1 rad\" }` (± that angle), or `xy` and `yaw` to move the item".into()),
                    ),
                    RandomItem::LabwareJoints { joints, .. } => {
                        let Some(kind) = labware::kind(&lw.kind) else {
                            continue;
                        };
                        let roles: Vec<&str> = kind.joints.iter().map(|(j, _)| *j).collect();
                        for (role, q) in joints {
                            let is_part = kind.parts.iter().any(|p| p.part == role.value);
                            if is_part && roles.contains(&role.value.as_str()) {
                                // A lid starts in its declared state (`open`, `closed`): the proof
                                // and the latch rely on it.
                                cx.err(
                                    Code::E0003,
                                    role.span,
                                    format!(
                                        "`{}`'s `{}` starts in its declared state and cannot be randomised",
                                        target.value, role.value
                                    ),
                                    Some(format!(
                                        "set it with `state = {{ {} = \"...\" }}`; free joints (a rotor) can be randomised",
                                        role.value
                                    )),
                                );
                            } else if roles.contains(&role.value.as_str()) {
                                if q.value.abs() > std::f64::consts::PI {
                                    cx.err(
                                        Code::E0021,
                                        q.span,
                                        format!("± {} rad is more than half a turn", q.value.abs()),
                                        Some("a joint offset is drawn from ±this angle; at most π".into()),
                                    );
                                } else {
                                    lw.joint_jitter.insert(role.value.clone(), q.value.abs());
                                }
                            } else if roles.is_empty() {
                                cx.err(
                                    Code::E0003,
                                    role.span,
                                    format!("`{}` ({}) has no joints to randomise", target.value, lw.kind),
                                    Some("use `xy` and `yaw` to move the item".into()),
                                );
                            } else {
                                cx.err(
                                    Code::E0003,
                                    role.span,
                                    format!("`{}` ({}) has no joint `{}`", target.value, lw.kind, role.value),
                                    Some(hint_for(&role.value, &roles, "joints")),
                                );
                            }
                        }
                    }
                }
            }
        } else {
            let names: Vec<&str> = p
                .robots
                .iter()
                .map(|r| r.name.value.as_str())
                .chain(p.labware.iter().map(|l| l.name.value.as_str()))
                .collect();
            cx.err(
                Code::E0013,
                target.span,
                format!("nothing named `{}` to randomise", target.value),
                Some(hint_for(&target.value, &names, "robots and labware")),
            );
        }
    }
}

fn lower_params(
    cx: &mut Cx,
    p: &Protocol,
    kinds: &KindMap,
    labware: &[Option<LabwareSpec>],
) -> Vec<ParamSpec> {
    let mut out: Vec<ParamSpec> = Vec::new();
    for param in &p.params {
        let earlier: Vec<&str> = out.iter().map(|p| p.name.as_str()).collect();
        let Some(domain) = &param.domain else {
            continue;
        };
        let domain = match domain {
            // Reported by the parser.
            ParamDomain::Choice(values) if values.is_empty() => continue,
            ParamDomain::Choice(values) => {
                // One type per domain: numbers (integers and decimals) or strings or booleans.
                // The first value sets it; a value of another type is the mistake, reported
                // where it is written, not where the parameter is later used.
                let class = |v: &Scalar| match v {
                    Scalar::Int(_) | Scalar::Float(_) => ("a number", "numbers"),
                    Scalar::Str(_) => ("a string", "strings"),
                    Scalar::Bool(_) => ("a boolean", "booleans"),
                };
                let first = class(&values[0].value);
                let mut mixed = false;
                for v in &values[1..] {
                    let this = class(&v.value);
                    if this != first {
                        cx.err(
                            Code::E0004,
                            v.span,
                            format!(
                                "`{}`'s choices are {}, but `{}` is {}",
                                param.name.value,
                                first.1,
                                v.value.text(),
                                this.0
                            ),
                            Some(format!(
                                "every value of one `choice` has the same type: write `{}` as {}, or quote every value",
                                v.value.text(),
                                first.0
                            )),
                        );
                        mixed = true;
                    }
                }
                if mixed {
                    continue;
                }
                let mut seen = BTreeSet::new();
                for v in values {
                    if !seen.insert(v.value.text()) {
                        cx.err(
                            Code::E0022,
                            v.span,
                            format!("`{}` is listed twice", v.value.text()),
                            None,
                        );
                    }
                }
                Domain::Choice {
                    values: values.iter().map(|v| v.value.text()).collect(),
                }
            }
            ParamDomain::Int { low, high, step } => {
                let step_v = step.as_ref().map(|s| s.value).unwrap_or(1);
                if low.value > high.value {
                    cx.err(
                        Code::E0022,
                        low.span,
                        format!("`int` range [{}, {}] is empty", low.value, high.value),
                        Some("write the low end first".into()),
                    );
                    continue;
                }
                if step_v <= 0 {
                    let span = step.as_ref().map(|s| s.span).unwrap_or(param.span);
                    cx.err(Code::E0022, span, "`step` must be positive".into(), None);
                    continue;
                }
                Domain::Int {
                    low: low.value,
                    high: high.value,
                    step: step_v,
                }
            }
            ParamDomain::Real { low, high } => {
                let (lo, hi) = match (parse_quantity(&low.value), parse_quantity(&high.value)) {
                    (Ok(a), Ok(b)) if a.dimension == b.dimension => (a, b),
                    (Ok(a), Ok(b)) => {
                        cx.err(
                            Code::E0020,
                            high.span,
                            format!(
                                "`real` bounds differ in kind: a {} and a {}",
                                a.dimension.name(),
                                b.dimension.name()
                            ),
                            None,
                        );
                        continue;
                    }
                    (Err(e), _) => {
                        cx.err(Code::E0020, low.span, e, None);
                        continue;
                    }
                    (_, Err(e)) => {
                        cx.err(Code::E0020, high.span, e, None);
                        continue;
                    }
                };
                if lo.si > hi.si {
                    cx.err(
                        Code::E0022,
                        low.span,
                        format!("`real` range [`{}`, `{}`] is empty", low.value, high.value),
                        None,
                    );
                    continue;
                }
                if let Some(e) = param.exclude.first() {
                    cx.err(
                        Code::E0022,
                        e.span,
                        "a `real` parameter cannot exclude values".into(),
                        Some("exclusions apply to `choice`, `int` and `slot` parameters".into()),
                    );
                }
                Domain::Real {
                    low: lo.si,
                    high: hi.si,
                    unit: lo.dimension.canonical_unit().into(),
                }
            }
            ParamDomain::Slot { of, free, opposite } => {
                let Some(kind) = kinds.get(&of.value) else {
                    let names: Vec<&str> = kinds.keys().map(String::as_str).collect();
                    cx.err(
                        Code::E0013,
                        of.span,
                        format!("no labware named `{}`", of.value),
                        Some(hint_for(&of.value, &names, "labware")),
                    );
                    continue;
                };
                let Some(slots) = kind.slots else {
                    cx.err(
                        Code::E0016,
                        of.span,
                        format!("`{}` (a {}) has no slots", of.value, kind.name),
                        None,
                    );
                    continue;
                };
                if let Some(o) = opposite {
                    let labware::SlotLayout::Ring { n } = slots.layout else {
                        cx.err(
                            Code::E0016,
                            o.span,
                            format!(
                                "`{}` has no opposite slots: its slots form a {}",
                                of.value,
                                slots.layout.describe()
                            ),
                            None,
                        );
                        continue;
                    };
                    let same_holder = out.iter().any(|x| {
                        x.name == o.value && matches!(&x.domain, Domain::Slot { holder, .. } if *holder == of.value)
                    });
                    if !same_holder {
                        cx.err(
                            Code::E0023,
                            o.span,
                            format!(
                                "`opposite` needs an earlier slot parameter of `{}`, found `{}`",
                                of.value, o.value
                            ),
                            Some(hint_for(&o.value, &earlier, "earlier parameters")),
                        );
                        continue;
                    }
                    Domain::Opposite {
                        holder: of.value.clone(),
                        of: o.value.clone(),
                        ring: n,
                    }
                } else {
                    let occupied: Vec<String> = labware
                        .iter()
                        .flatten()
                        .filter_map(|l| l.at.as_deref())
                        .filter(|a| placeholders(a).is_empty())
                        .filter_map(|a| a.split_once('.'))
                        .filter(|(h, _)| *h == of.value)
                        .map(|(_, s)| s.to_string())
                        .collect();
                    Domain::Slot {
                        holder: of.value.clone(),
                        slots: slots
                            .layout
                            .names()
                            .into_iter()
                            .filter(|s| !(*free && occupied.contains(s)))
                            .collect(),
                    }
                }
            }
        };
        for e in &param.exclude {
            if let Scalar::Str(s) = &e.value {
                for (_, name) in placeholders(s) {
                    if !earlier.contains(&name.as_str()) {
                        cx.err(
                            Code::E0023,
                            e.span,
                            format!(
                                "`exclude` uses `{{{name}}}`, which is not an earlier parameter"
                            ),
                            Some(hint_for(&name, &earlier, "earlier parameters")),
                        );
                    }
                }
            }
        }
        let spec = ParamSpec {
            name: param.name.value.clone(),
            domain,
            exclude: param.exclude.iter().map(|e| e.value.text()).collect(),
        };
        out.push(spec);
        let (assignments, _) = crate::params::proof_assignments(&out);
        if assignments.is_empty() {
            out.pop();
            cx.err(
                Code::E0022,
                param.name.span,
                format!("parameter `{}` has no value left to draw", param.name.value),
                Some("its exclusions (or `free = true`) remove every value".into()),
            );
        }
    }
    out
}

/// Reports `{name}` placeholders that name no parameter.
fn check_placeholders(cx: &mut Cx, text: &Spanned<String>, params: &[&str]) {
    for (offset, name) in placeholders(&text.value) {
        if !params.contains(&name.as_str()) {
            // +1 skips the opening quote of a basic string; exact for strings without escapes.
            let start = text.span.start + 1 + offset;
            let span = Span::new(start, (start + name.len() + 2).min(text.span.end));
            cx.err(
                Code::E0023,
                span,
                format!("unknown placeholder `{{{name}}}`"),
                Some(hint_for(&name, params, "parameters")),
            );
        }
    }
}

fn check_steps<'a>(
    cx: &mut Cx,
    p: &'a Protocol,
    robots: &[String],
    params: &[&str],
) -> Vec<CheckedStep<'a>> {
    let prim_names: Vec<&str> = primitives::CATALOGUE.iter().map(|p| p.name).collect();
    let robot_names: Vec<&str> = robots.iter().map(String::as_str).collect();
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
        let mut ok = true;
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
                ok = false;
            }
            Some(w) if !robots.contains(&w.value) => {
                cx.err(
                    Code::E0013,
                    w.span,
                    format!("no robot named `{}`", w.value),
                    Some(hint_for(&w.value, &robot_names, "robots")),
                );
                ok = false;
            }
            Some(_) => {}
        }
        let together = step.together.as_ref().is_some_and(|t| t.value);
        if let Some(t) = step.together.as_ref().filter(|t| t.value) {
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
                        "`together` starts a step with the step before it, and this is the first step".into(),
                        Some("remove `together`; a stage's first step starts when the stage does".into()),
                    );
                    ok = false;
                }
                (_, Some(robot)) => {
                    cx.err(
                        Code::E0021,
                        t.span,
                        format!("`together` joins a step of `{robot}`'s to a group where `{robot}` already has one: one robot does one step at a time"),
                        Some("give one of the two steps to another robot, or remove `together`".into()),
                    );
                    ok = false;
                }
                _ => {}
            }
        }
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
        for a in prim.args {
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
        if !ok {
            continue;
        }
        let args: BTreeMap<String, String> = step
            .args
            .iter()
            .map(|(k, v)| (k.value.clone(), v.value.text()))
            .collect();
        out.push(CheckedStep {
            ast: step,
            primitive: prim,
            planned: PlannedStep {
                primitive: prim.name.into(),
                robot: step
                    .with
                    .as_ref()
                    .map(|w| w.value.clone())
                    .unwrap_or_default(),
                labware: args.get("on").cloned(),
                args,
                together,
            },
        });
    }
    out
}

fn lower_predicates(
    cx: &mut Cx,
    p: &Protocol,
    kinds: &KindMap,
    robots: &[String],
    params: &[&str],
    declared: &[&str],
) -> Vec<CheckedPredicate> {
    let overrides: BTreeMap<&str, (&Spanned<String>, &Spanned<String>)> = p
        .tolerances
        .iter()
        .map(|(n, v)| (n.value.as_str(), (n, v)))
        .collect();
    let weights = p.success.weights.as_ref();
    if let Some(w) = weights
        && w.value.len() != p.success.all.len()
    {
        cx.err(
            Code::E0021,
            w.span,
            format!(
                "{} weights for {} predicates",
                w.value.len(),
                p.success.all.len()
            ),
            Some("give one weight per predicate in `all`".into()),
        );
    }
    if let Some(w) = weights
        && w.value.iter().sum::<f64>() <= 0.0
    {
        cx.err(Code::E0021, w.span, "the weights sum to zero".into(), None);
    }
    let mut used_tolerances: BTreeMap<String, Dimension> = BTreeMap::new();
    let mut out = Vec::new();
    for (i, text) in p.success.all.iter().enumerate() {
        check_placeholders(cx, text, params);
        let parsed = match predicates::parse(&text.value) {
            Ok(x) => x,
            Err(e) => {
                cx.err(
                    Code::E0030,
                    text.span,
                    format!("cannot read predicate `{}`: {e}", text.value),
                    Some("forms: `<lw>.<part> is <state>`, `<lw>.<part> was <state>` (at some step), `<item> in <holder>.<slot>`, `<lw>.volume = <q>`, `<lw>.<value> = <q>`, `<robot> touches <item>`, `<lw>.<joint> in [lo, hi] <unit>`, `<item> near [x, y, z] m`".into()),
                );
                continue;
            }
        };
        let Some((check, dim)) = resolve_check(cx, text, &parsed.form, kinds, robots, declared)
        else {
            continue;
        };
        let check = apply_tolerance(
            cx,
            text,
            check,
            dim,
            parsed.within,
            &overrides,
            &mut used_tolerances,
        );
        let weight = weights.and_then(|w| w.value.get(i).copied()).unwrap_or(1.0);
        out.push(CheckedPredicate {
            span: text.span,
            predicate: Predicate {
                text: text.value.clone(),
                check,
                weight,
            },
        });
    }
    for (name, (n, v)) in &overrides {
        let Some(dim) = used_tolerances.get(*name) else {
            let used: Vec<&str> = used_tolerances.keys().map(String::as_str).collect();
            cx.err(
                Code::E0035,
                n.span,
                format!("no predicate uses a tolerance named `{name}`"),
                Some(hint_for(name, &used, "tolerances in use")),
            );
            continue;
        };
        match parse_quantity(&v.value) {
            Ok(q) if q.dimension == *dim => {}
            Ok(q) => cx.err(
                Code::E0035,
                v.span,
                format!(
                    "tolerance `{name}` bounds a {}, but `{}` is a {}",
                    dim.name(),
                    v.value,
                    q.dimension.name()
                ),
                Some(format!("use one of: {}", dim.example_units())),
            ),
            Err(e) => cx.err(Code::E0020, v.span, e, None),
        }
    }
    out
}

/// Resolves a predicate's names. Returns the check (tolerance not yet applied) and the dimension
/// its tolerance bounds.
fn resolve_check(
    cx: &mut Cx,
    text: &Spanned<String>,
    form: &Form,
    kinds: &KindMap,
    robots: &[String],
    declared: &[&str],
) -> Option<(Check, Option<NamedTolerance>)> {
    let labware_names: Vec<&str> = kinds.keys().map(String::as_str).collect();
    let lookup = |cx: &mut Cx, name: &str| -> Option<&'static LabwareKind> {
        if !placeholders(name).is_empty() {
            cx.err(
                Code::E0030,
                text.span,
                format!("`{name}`: labware names in predicates cannot be parameters"),
                Some("parameters may stand for slots and values".into()),
            );
            return None;
        }
        let k = kinds.get(name).copied();
        // Declared with an unknown kind: that was reported at the kind.
        if k.is_none() && !declared.contains(&name) {
            cx.err(
                Code::E0013,
                text.span,
                format!("no labware named `{name}`"),
                Some(hint_for(name, &labware_names, "labware")),
            );
        }
        k
    };
    match form {
        Form::State {
            labware: lw,
            part,
            state,
            ever,
        } => {
            let kind = lookup(cx, lw)?;
            let Some(ps) = kind.part(part) else {
                let parts: Vec<&str> = kind.parts.iter().map(|p| p.part).collect();
                cx.err(
                    Code::E0030,
                    text.span,
                    format!("a {} has no part `{part}`", kind.name),
                    Some(hint_for(part, &parts, "parts")),
                );
                return None;
            };
            if !ps.states.contains(&state.as_str()) {
                cx.err(
                    Code::E0030,
                    text.span,
                    format!("`{part}` has no state `{state}`"),
                    Some(hint_for(state, ps.states, "states")),
                );
                return None;
            }
            let name = format!("{part}_{state}");
            // A part that moves on a joint is measured in the joint's unit (a lid's angle); a
            // loose part (a tube's cap) by its distance from where the state puts it.
            let dimension = match kind.joints.iter().find(|(j, _)| j == part) {
                Some((_, "m")) | None => Dimension::Length,
                Some(_) => Dimension::Angle,
            };
            let tol = kind.tolerance(&name).map(|v| (name, v, dimension));
            Some((
                Check::State {
                    labware: lw.clone(),
                    part: part.clone(),
                    state: state.clone(),
                    tolerance: None,
                    ever: *ever,
                },
                tol,
            ))
        }
        Form::JointRange {
            labware: lw,
            joint,
            low,
            high,
        } => {
            let kind = lookup(cx, lw)?;
            if !kind.joints.iter().any(|(j, _)| j == joint) {
                let joints: Vec<&str> = kind.joints.iter().map(|(j, _)| *j).collect();
                cx.err(
                    Code::E0030,
                    text.span,
                    format!("a {} has no joint `{joint}`", kind.name),
                    Some(hint_for(joint, &joints, "joints")),
                );
                return None;
            }
            Some((
                Check::JointRange {
                    labware: lw.clone(),
                    joint: joint.clone(),
                    low: *low,
                    high: *high,
                },
                None,
            ))
        }
        Form::InSlot { item, location } => {
            let kind = lookup(cx, item)?;
            if !kind.movable {
                cx.err(
                    Code::E0030,
                    text.span,
                    format!("`{item}` (a {}) never moves into a slot", kind.name),
                    None,
                );
                return None;
            }
            let holder = location.split_once('.').map(|(h, _)| h).unwrap_or("");
            let hkind = lookup(cx, holder)?;
            if hkind.slots.is_none() {
                cx.err(
                    Code::E0016,
                    text.span,
                    format!("`{holder}` (a {}) has no slots", hkind.name),
                    None,
                );
                return None;
            }
            if placeholders(location).is_empty() {
                let env_kinds = kinds.clone();
                let env = primitives::Env {
                    kinds: &env_kinds,
                    robots,
                };
                if let Err(m) = resolve_location(&env, location) {
                    cx.err(Code::E0016, text.span, m, None);
                    return None;
                }
            }
            let v = kind.tolerance("slot_xy").unwrap_or(0.015);
            Some((
                Check::InSlot {
                    item: item.clone(),
                    location: location.clone(),
                    tolerance: Tolerance {
                        name: "slot_xy".into(),
                        value: v,
                    },
                    height: kind.tolerance("slot_z").unwrap_or(0.005),
                    tilt: crate::predicates::SLOT_TILT,
                },
                Some(("slot_xy".into(), v, Dimension::Length)),
            ))
        }
        Form::Compare {
            labware: lw,
            field,
            cmp,
            value,
        } => {
            let kind = lookup(cx, lw)?;
            if field == "volume" && kind.capacity_ul.is_some() {
                // A value with placeholders is read per parameter combination by the proof.
                if placeholders(value).is_empty()
                    && let Err(e) =
                        predicates::quantity(value, &Default::default(), Dimension::Volume)
                {
                    cx.err(
                        Code::E0020,
                        text.span,
                        e,
                        Some("compare a volume with a quantity: \"tube.volume = 200 µL\"".into()),
                    );
                    return None;
                }
                let v = kind.tolerance("volume").unwrap_or(1.0);
                return Some((
                    Check::Volume {
                        container: lw.clone(),
                        cmp: *cmp,
                        value: value.clone(),
                        tolerance: Tolerance {
                            name: "volume".into(),
                            value: v,
                        },
                    },
                    Some(("volume".into(), v, Dimension::Volume)),
                ));
            }
            let Some(p) = kind.panel_param(field) else {
                let mut fields: Vec<&str> = kind.panel.iter().map(|p| p.name).collect();
                if kind.capacity_ul.is_some() {
                    fields.push("volume");
                }
                cx.err(
                    Code::E0030,
                    text.span,
                    format!("a {} has no value `{field}` to compare", kind.name),
                    Some(hint_for(field, &fields, "values")),
                );
                return None;
            };
            if *cmp != Cmp::Eq {
                cx.err(
                    Code::E0030,
                    text.span,
                    "a panel value is compared with `=`".into(),
                    None,
                );
                return None;
            }
            let dim = primitives::panel_dimension(p.unit);
            if placeholders(value).is_empty()
                && let Err(e) = predicates::quantity(value, &Default::default(), dim)
            {
                cx.err(Code::E0020, text.span, e, None);
                return None;
            }
            let v = kind.tolerance("display").unwrap_or(1e-6);
            Some((
                Check::Panel {
                    instrument: lw.clone(),
                    param: field.clone(),
                    unit: p.unit.into(),
                    initial: p.initial,
                    value: value.clone(),
                    tolerance: Tolerance {
                        name: "display".into(),
                        value: v,
                    },
                },
                Some(("display".into(), v, dim)),
            ))
        }
        Form::Contact { robot, item } => {
            if !robots.contains(robot) {
                let names: Vec<&str> = robots.iter().map(String::as_str).collect();
                cx.err(
                    Code::E0013,
                    text.span,
                    format!("no robot named `{robot}`"),
                    Some(hint_for(robot, &names, "robots")),
                );
                return None;
            }
            lookup(cx, item)?;
            Some((
                Check::Contact {
                    robot: robot.clone(),
                    item: item.clone(),
                },
                None,
            ))
        }
        Form::Near { item, pos } => {
            let kind = lookup(cx, item)?;
            let v = kind.tolerance("position").unwrap_or(0.005);
            Some((
                Check::Position {
                    item: item.clone(),
                    pos: *pos,
                    tolerance: Tolerance {
                        name: "position".into(),
                        value: v,
                    },
                },
                Some(("position".into(), v, Dimension::Length)),
            ))
        }
        Form::Lifted { item, height } => {
            lookup(cx, item)?;
            Some((
                Check::Lifted {
                    item: item.clone(),
                    height: *height,
                },
                None,
            ))
        }
    }
}

/// Fills in the tolerance: inline `within`, else a `[tolerances]` override, else the kind's default.
fn apply_tolerance(
    cx: &mut Cx,
    text: &Spanned<String>,
    mut check: Check,
    tol: Option<NamedTolerance>,
    within: Option<(f64, Dimension)>,
    overrides: &BTreeMap<&str, (&Spanned<String>, &Spanned<String>)>,
    used: &mut BTreeMap<String, Dimension>,
) -> Check {
    let Some((name, default, dim)) = tol else {
        if within.is_some() {
            cx.err(
                Code::E0035,
                text.span,
                "this predicate takes no tolerance".into(),
                Some("remove `within ..`".into()),
            );
        }
        return check;
    };
    used.insert(name.clone(), dim);
    let mut value = default;
    if let Some((_, v)) = overrides.get(name.as_str())
        && let Ok(q) = parse_quantity(&v.value)
        && q.dimension == dim
    {
        value = q.si;
    }
    if let Some((v, d)) = within {
        if d == dim {
            value = v;
        } else {
            cx.err(
                Code::E0035,
                text.span,
                format!(
                    "`within` gives a {}, but this predicate's tolerance is a {}",
                    d.name(),
                    dim.name()
                ),
                Some(format!("use one of: {}", dim.example_units())),
            );
        }
    }
    let t = Tolerance { name, value };
    match &mut check {
        Check::State { tolerance, .. } => *tolerance = Some(t),
        Check::InSlot { tolerance, .. }
        | Check::Volume { tolerance, .. }
        | Check::Panel { tolerance, .. }
        | Check::Position { tolerance, .. } => *tolerance = t,
        Check::JointRange { .. } | Check::Contact { .. } | Check::Lifted { .. } => {}
    }
    check
}

pub(crate) fn pose(p: &dsl::ast::Pose) -> Pose {
    let pos = p.pos.as_ref().map(|s| s.value).unwrap_or([0.0; 3]);
    labware::frame::yaw(pos, p.yaw.as_ref().map(|y| y.value).unwrap_or(0.0))
}

/// The fixed camera (`fixed`, else the bench camera in front of the bench, looking across it and
/// 20° down) and one wrist camera per robot, all 224x224.
pub(crate) fn default_cameras(
    robots: &[RobotSpec],
    fixed: Option<&CameraMount>,
) -> Vec<CameraSpec> {
    let (s, c) = 20f64.to_radians().sin_cos();
    let bench = CameraMount::Fixed {
        pos: [0.0, -1.2, 1.65],
        xyaxes: [1.0, 0.0, 0.0, 0.0, s, c],
        fovy_deg: 45.0,
    };
    let mut cams = vec![CameraSpec {
        name: "table_front".into(),
        width: 224,
        height: 224,
        mount: fixed.cloned().unwrap_or(bench),
    }];
    for r in robots {
        cams.push(CameraSpec {
            name: format!("{}/wrist", r.name),
            width: 224,
            height: 224,
            mount: CameraMount::Wrist {
                robot: r.name.clone(),
            },
        });
    }
    cams
}
