//! `[perturb]` and `[protocol] paraphrases` checked and lowered: each dimension's preset or its
//! fields (those not given are the mild preset's), every value against its range (E0021), a
//! camera named that the task lacks or a fixed camera shaken off the work (E0045), and each
//! paraphrase against the instruction's placeholders (E0045).

use super::{CameraShake, Dimension, MAX_DISTRACTORS, MAX_LIGHTS, Perturb, STRENGTHS, Surface};
use crate::report::{Cx, hint_for};
use crate::task::{CameraMount, Task};
use dsl::Code;
use dsl::ast::{self, PerturbSetting, PerturbValue, Spanned};
use std::collections::BTreeSet;

/// The task's perturbations from its `[perturb]` table; `None` when a value is refused (reported).
pub(crate) fn lower(cx: &mut Cx, table: &ast::Perturb, task: &Task) -> Option<Perturb> {
    let mut out = Perturb::default();
    let mut ok = true;
    for dim in &table.dimensions {
        let Some(d) = Dimension::from_name(&dim.name.value) else {
            continue; // the parser reported it
        };
        let p = match &dim.setting {
            PerturbSetting::Strength(s) => {
                let strength = u8::try_from(s.value).ok().filter(|x| STRENGTHS.contains(x));
                let Some(strength) = strength else {
                    cx.err(
                        Code::E0021,
                        s.span,
                        format!("`{}` has no strength {}", d, s.value),
                        Some(format!(
                            "1 is mild, 2 strong (docs/robustness.md lists each preset); or give a table: `{d} = {{ .. }}`"
                        )),
                    );
                    ok = false;
                    continue;
                };
                Perturb::preset(d, strength)
            }
            PerturbSetting::Fields(fields) => {
                let mut p = Perturb::preset(d, 1);
                for f in fields {
                    ok &= field(cx, &mut p, d, &f.key.value, &f.value, task);
                }
                p
            }
        };
        out = out.overlay(&p);
    }
    if let Some(c) = &out.camera
        && ok
    {
        ok &= camera_keeps_the_work(cx, c, table, task);
    }
    if let Some(d) = &out.distractors
        && ok
        && d.count[1] > 0
        && super::distractors::room(task, d) == 0
    {
        let span = table
            .dimensions
            .iter()
            .find(|d| d.name.value == "distractors")
            .map_or(table.span, |d| d.name.span);
        cx.err(
            Code::E0045,
            span,
            super::distractors::NO_ROOM.into(),
            Some("move items closer together, or leave distractors out of this task".into()),
        );
        ok = false;
    }
    ok.then_some(out)
}

/// Reports a value outside `[lo, hi]`; whether it was inside.
fn within(
    cx: &mut Cx,
    v: &Spanned<PerturbValue>,
    what: &str,
    lo: f64,
    hi: f64,
    unit: &str,
) -> bool {
    let bad = match &v.value {
        PerturbValue::Number(x) => !(lo..=hi).contains(x),
        PerturbValue::Range([a, b]) => !(lo..=hi).contains(a) || !(lo..=hi).contains(b),
        PerturbValue::Texts(_) => false,
    };
    if bad {
        cx.err(
            Code::E0021,
            v.span,
            format!("`{what}` must lie within {lo}{unit} to {hi}{unit}"),
            Some("docs/robustness.md gives each field's range and the presets' values".into()),
        );
    }
    !bad
}

/// An angle field in degrees (the parser gave radians), and whether it lies within 0 to `hi`°.
fn degrees(cx: &mut Cx, v: &Spanned<PerturbValue>, what: &str, hi: f64) -> (f64, bool) {
    let x = number(v).to_degrees();
    let ok = within(
        cx,
        &Spanned::new(PerturbValue::Number(x), v.span),
        what,
        0.0,
        hi,
        "°",
    );
    (x, ok)
}

fn number(v: &Spanned<PerturbValue>) -> f64 {
    match v.value {
        PerturbValue::Number(x) => x,
        _ => f64::NAN,
    }
}

fn range(v: &Spanned<PerturbValue>) -> [f64; 2] {
    match v.value {
        PerturbValue::Range(r) => r,
        PerturbValue::Number(x) => [x, x],
        PerturbValue::Texts(_) => [f64::NAN; 2],
    }
}

/// Whether every element of a range is a whole number.
fn whole(cx: &mut Cx, v: &Spanned<PerturbValue>, what: &str) -> bool {
    let r = range(v);
    if r.iter().all(|x| x.fract() == 0.0) {
        return true;
    }
    cx.err(
        Code::E0021,
        v.span,
        format!("`{what}` counts whole numbers"),
        None,
    );
    false
}

/// Sets one field of dimension `d` in `p`; whether its value was accepted.
fn field(
    cx: &mut Cx,
    p: &mut Perturb,
    d: Dimension,
    key: &str,
    v: &Spanned<PerturbValue>,
    task: &Task,
) -> bool {
    let what = format!("perturb.{d}.{key}");
    match (d, key) {
        (Dimension::Light, "intensity") => {
            let ok = within(cx, v, &what, 0.05, 4.0, "");
            if let Some(l) = p.light.as_mut().filter(|_| ok) {
                l.intensity = range(v);
            }
            ok
        }
        (Dimension::Light, "direction") => {
            let (x, ok) = degrees(cx, v, &what, 80.0);
            if let Some(l) = p.light.as_mut().filter(|_| ok) {
                l.direction_deg = x;
            }
            ok
        }
        (Dimension::Light, "colour") => {
            let ok = within(cx, v, &what, 0.0, 1.0, "");
            if let Some(l) = p.light.as_mut().filter(|_| ok) {
                l.colour = number(v);
            }
            ok
        }
        (Dimension::Light, "lights") => {
            let ok = within(cx, v, &what, 1.0, f64::from(MAX_LIGHTS), "") && whole(cx, v, &what);
            if let Some(l) = p.light.as_mut().filter(|_| ok) {
                l.lights = range(v).map(|x| x as u32);
            }
            ok
        }
        (Dimension::Material, "of") => {
            let PerturbValue::Texts(names) = &v.value else {
                return false;
            };
            let known = Surface::ALL.map(Surface::name);
            let mut of = BTreeSet::new();
            for n in names {
                match Surface::ALL.into_iter().find(|s| s.name() == n.value) {
                    Some(s) => {
                        of.insert(s);
                    }
                    None => {
                        cx.err(
                            Code::E0021,
                            n.span,
                            format!("`{what}` names `{}`, which is no surface", n.value),
                            Some(hint_for(&n.value, &known, "surfaces")),
                        );
                        return false;
                    }
                }
            }
            if let Some(m) = p.material.as_mut() {
                m.of = of.into_iter().collect();
            }
            true
        }
        (Dimension::Material, "hue" | "saturation" | "value") => {
            let hi = if key == "hue" { 0.5 } else { 0.9 };
            let ok = within(cx, v, &what, 0.0, hi, "");
            if let Some(m) = p.material.as_mut().filter(|_| ok) {
                let x = number(v);
                match key {
                    "hue" => m.hue = x,
                    "saturation" => m.saturation = x,
                    _ => m.value = x,
                }
            }
            ok
        }
        (Dimension::Camera, "shift") => {
            let ok = within(cx, v, &what, 0.0, 0.2, " m");
            if let Some(c) = p.camera.as_mut().filter(|_| ok) {
                c.shift_m = number(v);
            }
            ok
        }
        (Dimension::Camera, "turn" | "fovy") => {
            let (x, ok) = degrees(cx, v, &what, 30.0);
            if let Some(c) = p.camera.as_mut().filter(|_| ok) {
                if key == "turn" {
                    c.turn_deg = x;
                } else {
                    c.fovy_deg = x;
                }
            }
            ok
        }
        (Dimension::Camera, "cameras") => {
            let PerturbValue::Texts(names) = &v.value else {
                return false;
            };
            let known: Vec<&str> = task.cameras.iter().map(|c| c.name.as_str()).collect();
            for n in names {
                if !known.contains(&n.value.as_str()) {
                    cx.err(
                        Code::E0045,
                        n.span,
                        format!(
                            "`{what}` names `{}`, which is not one of the task's cameras",
                            n.value
                        ),
                        Some(hint_for(&n.value, &known, "cameras")),
                    );
                    return false;
                }
            }
            if let Some(c) = p.camera.as_mut() {
                c.cameras = names.iter().map(|n| n.value.clone()).collect();
            }
            true
        }
        (Dimension::Noise, "gaussian") => {
            let ok = within(cx, v, &what, 0.0, 0.5, "");
            if let Some(n) = p.noise.as_mut().filter(|_| ok) {
                n.gaussian = number(v);
            }
            ok
        }
        (Dimension::Noise, "blur_px") => {
            let ok = within(cx, v, &what, 0.0, 5.0, " px");
            if let Some(n) = p.noise.as_mut().filter(|_| ok) {
                n.blur_px = number(v);
            }
            ok
        }
        (Dimension::Noise, "jpeg_quality") => {
            let ok = within(cx, v, &what, 1.0, 100.0, "") && whole(cx, v, &what);
            if let Some(n) = p.noise.as_mut().filter(|_| ok) {
                n.jpeg_quality = Some(range(v).map(|x| x as u8));
            }
            ok
        }
        (Dimension::Language, "rewrite") => {
            let x = number(v);
            let ok = x == 1.0 || x == 2.0;
            if !ok {
                cx.err(
                    Code::E0021,
                    v.span,
                    format!("`{what}` is 1 (a paraphrase or a framing) or 2 (and synonyms)"),
                    None,
                );
            }
            if let Some(l) = p.language.as_mut().filter(|_| ok) {
                l.rewrite = x as u8;
            }
            ok
        }
        (Dimension::RobotStart, "joints") => {
            let ok = within(cx, v, &what, 0.0, 0.5, " rad");
            if let Some(r) = p.robot_start.as_mut().filter(|_| ok) {
                r.joints_rad = number(v);
            }
            ok
        }
        (Dimension::Layout, "shift") => {
            let ok = within(cx, v, &what, 0.0, 0.1, " m");
            if let Some(l) = p.layout.as_mut().filter(|_| ok) {
                l.shift_m = number(v);
            }
            ok
        }
        (Dimension::Layout, "turn") => {
            let (x, ok) = degrees(cx, v, &what, 45.0);
            if let Some(l) = p.layout.as_mut().filter(|_| ok) {
                l.turn_deg = x;
            }
            ok
        }
        (Dimension::Distractors, "count") => {
            let ok =
                within(cx, v, &what, 0.0, f64::from(MAX_DISTRACTORS), "") && whole(cx, v, &what);
            if let Some(d) = p.distractors.as_mut().filter(|_| ok) {
                d.count = range(v).map(|x| x as u32);
            }
            ok
        }
        (Dimension::Distractors, "kinds") => {
            let PerturbValue::Texts(names) = &v.value else {
                return false;
            };
            let known = labware::distractor_kinds();
            for n in names {
                if !known.contains(&n.value.as_str()) {
                    cx.err(
                        Code::E0021,
                        n.span,
                        format!("`{what}` names `{}`, which is no kind that stands alone unused (a rack or a block)", n.value),
                        Some(hint_for(&n.value, &known, "such kinds")),
                    );
                    return false;
                }
            }
            if let Some(d) = p.distractors.as_mut() {
                d.kinds = names.iter().map(|n| n.value.clone()).collect();
            }
            true
        }
        // The parser admits only the fields above.
        _ => true,
    }
}

/// The share of a camera's narrowest half view its aim may swing through: the middle of the
/// clean frame stays in the middle half of the shaken one.
const KEEP_IN_VIEW: f64 = 0.5;

/// Reports (E0045, at the `camera` dimension) a shake that could lose the work; whether none could.
fn camera_keeps_the_work(cx: &mut Cx, c: &CameraShake, table: &ast::Perturb, task: &Task) -> bool {
    let Some(problem) = camera_problem(task, c) else {
        return true;
    };
    let span = table
        .dimensions
        .iter()
        .find(|d| d.name.value == "camera")
        .map_or(table.span, |d| d.name.span);
    cx.err(
        Code::E0045,
        span,
        problem,
        Some(
            "narrow `turn_deg`, `shift_m` or `fovy_deg`, or name the cameras to shake in `cameras`"
                .into(),
        ),
    );
    false
}

/// Whether a camera shake keeps the work each fixed camera of `task` frames: the clean view's
/// centre (what the camera was aimed at) stays within the inner half of the shaken view at the
/// shake's extremes (the largest turn, plus the angle the largest shift subtends at the items'
/// middle, with the field of view at its narrowest). `None` when it does, else what goes wrong.
/// Wrist cameras move with the arm and are not checked.
pub fn camera_problem(task: &Task, c: &CameraShake) -> Option<String> {
    let v = |a: [f64; 3]| nalgebra::Vector3::new(a[0], a[1], a[2]);
    let places: Vec<_> = task
        .labware
        .iter()
        .map(|l| l.placement.translation.vector)
        .collect();
    if places.is_empty() {
        return None;
    }
    let middle = places.iter().sum::<nalgebra::Vector3<f64>>() / places.len() as f64;
    for cam in &task.cameras {
        if !c.cameras.is_empty() && !c.cameras.contains(&cam.name) {
            continue;
        }
        let CameraMount::Fixed { pos, fovy_deg, .. } = &cam.mount else {
            continue;
        };
        let distance = (middle - v(*pos)).norm().max(0.05);
        let worst = c.turn_deg + (c.shift_m / distance).atan().to_degrees();
        let half = (fovy_deg - c.fovy_deg).max(1.0) / 2.0;
        if worst > KEEP_IN_VIEW * half {
            return Some(format!(
                "camera `{}` could lose the work: turned {:.1}° and moved {:.0} mm ({:.0} mm from the items), its aim could swing {worst:.1}°, past {:.1}° (half of half its narrowest view)",
                cam.name,
                c.turn_deg,
                c.shift_m * 1000.0,
                distance * 1000.0,
                KEEP_IN_VIEW * half,
            ));
        }
    }
    None
}

/// Each paraphrase names exactly the instruction's placeholders (E0045 for one dropped or added).
pub(crate) fn check_paraphrases(cx: &mut Cx, paraphrases: &[Spanned<String>], instruction: &str) {
    let names = |t: &str| -> BTreeSet<String> {
        crate::params::placeholders(t)
            .into_iter()
            .map(|(_, n)| n)
            .collect()
    };
    let want = names(instruction);
    for p in paraphrases {
        let have = names(&p.value);
        let dropped: Vec<&String> = want.difference(&have).collect();
        let added: Vec<&String> = have.difference(&want).collect();
        let list = |v: &[&String]| {
            v.iter()
                .map(|n| format!("`{{{n}}}`"))
                .collect::<Vec<_>>()
                .join(", ")
        };
        let msg = match (dropped.is_empty(), added.is_empty()) {
            (true, true) => continue,
            (false, _) => format!(
                "the paraphrase drops {} that the instruction names",
                list(&dropped)
            ),
            (true, false) => format!(
                "the paraphrase names {}, which the instruction does not",
                list(&added)
            ),
        };
        cx.err(
            Code::E0045,
            p.span,
            msg,
            Some("a paraphrase says the same task in other words: it names every `{param}` the instruction names, and no other".into()),
        );
    }
}
