//! Name resolution, state tracing and lowering from the AST to a [`Task`].

use crate::primitives;
use crate::robots;
use crate::task::*;
use dsl::ast::{Protocol, RandomItem, Spanned};
use dsl::{Code, Diagnostic, Span, did_you_mean};
use labware::{Pose, thermal_cycler};
use std::collections::BTreeMap;

/// Checks a parsed protocol and lowers it. Returns a task only when no error was found; the
/// diagnostics are complete either way.
pub fn compile(p: &Protocol, file: &str) -> (Option<Task>, Vec<Diagnostic>) {
    let mut cx = Cx { diags: Vec::new() };
    let task = cx.lower(p, file);
    let ok = !cx.diags.iter().any(|d| d.is_error());
    (task.filter(|_| ok), cx.diags)
}

struct Cx {
    diags: Vec<Diagnostic>,
}

fn hint_for(input: &str, candidates: &[&str], what: &str) -> String {
    match did_you_mean(input, candidates.iter().copied()) {
        Some(s) => format!("did you mean `{s}`?"),
        None => format!("known {what}: {}", candidates.join(", ")),
    }
}

impl Cx {
    fn err(&mut self, code: Code, span: Span, msg: String, hint: Option<String>) {
        let mut d = Diagnostic::error(code, span, msg);
        d.hint = hint;
        self.diags.push(d);
    }

    fn lower(&mut self, p: &Protocol, file: &str) -> Option<Task> {
        let mut robots = self.robots(p);
        let mut labware = self.labware(p);
        self.randomise(p, &mut robots, &mut labware);
        let plan = self.plan(p, &labware);
        let success = self.success(p, &labware);
        let m = &p.meta;
        let robots: Vec<RobotSpec> = robots.into_iter().flatten().collect();
        let labware: Vec<LabwareSpec> = labware.into_iter().flatten().collect();
        let cameras = default_cameras(&robots);
        Some(Task {
            schema_version: TASK_SCHEMA_VERSION,
            id: m.id.as_ref()?.value.clone(),
            version: m.version.as_ref().map(|v| v.value).unwrap_or(1),
            level: m
                .level
                .as_ref()
                .map(|l| l.value.clone())
                .unwrap_or_else(|| "easy".into()),
            instruction: m.instruction.as_ref()?.value.clone(),
            source: file.to_string(),
            time_limit_s: m.time_limit.as_ref()?.value,
            physics: Physics {
                timestep_s: 0.002,
                substeps: 10,
            },
            robots,
            labware,
            cameras,
            plan: plan?,
            success,
        })
    }

    fn robots(&mut self, p: &Protocol) -> Vec<Option<RobotSpec>> {
        let names: Vec<&str> = robots::MODELS.iter().map(|m| m.name).collect();
        p.robots
            .iter()
            .map(|r| {
                let model = r.model.as_ref()?;
                let Some(m) = robots::model(&model.value) else {
                    let hint = hint_for(&model.value, &names, "robot models");
                    self.err(
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

    fn labware(&mut self, p: &Protocol) -> Vec<Option<LabwareSpec>> {
        let kinds: Vec<&str> = labware::KINDS.iter().map(|k| k.name).collect();
        p.labware
            .iter()
            .map(|l| {
                let kind = l.kind.as_ref()?;
                let Some(k) = labware::kind(&kind.value) else {
                    let hint = hint_for(&kind.value, &kinds, "labware kinds");
                    self.err(
                        Code::E0010,
                        kind.span,
                        format!("unknown labware kind `{}`", kind.value),
                        Some(hint),
                    );
                    return None;
                };
                let mut initial = BTreeMap::new();
                for part in k.parts {
                    initial.insert(part.part.to_string(), part.initial[0].to_string());
                }
                for (part, state) in &l.state {
                    let Some(ps) = k.parts.iter().find(|ps| ps.part == part.value) else {
                        let parts: Vec<&str> = k.parts.iter().map(|ps| ps.part).collect();
                        self.err(
                            Code::E0003,
                            part.span,
                            format!("`{}` has no part `{}`", k.name, part.value),
                            Some(hint_for(&part.value, &parts, "parts")),
                        );
                        continue;
                    };
                    if !ps.initial.contains(&state.value.as_str()) {
                        self.err(
                            Code::E0021,
                            state.span,
                            format!("`{}` cannot start `{}`", part.value, state.value),
                            Some(hint_for(&state.value, ps.initial, "initial states")),
                        );
                        continue;
                    }
                    initial.insert(part.value.clone(), state.value.clone());
                }
                // The catalogue holds one kind so far; new kinds add their arm here.
                let params = LabwareParams::ThermalCycler(thermal_cycler::Params::default());
                Some(LabwareSpec {
                    name: l.name.value.clone(),
                    kind: k.name.into(),
                    placement: pose(&l.pose),
                    xy_jitter_m: 0.0,
                    yaw_jitter_rad: 0.0,
                    initial,
                    params,
                })
            })
            .collect()
    }

    fn randomise(
        &mut self,
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
                                self.err(
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
                        RandomItem::Xy(q) | RandomItem::Yaw(q) => {
                            self.err(
                                Code::E0003,
                                q.span,
                                format!(
                                    "robot `{}` cannot be moved by randomisation",
                                    target.value
                                ),
                                Some(
                                    "randomise a robot's `joints`; `xy` and `yaw` apply to labware"
                                        .into(),
                                ),
                            );
                        }
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
                        RandomItem::Joints { span, .. } => {
                            self.err(
                                Code::E0003,
                                *span,
                                format!("labware `{}` has no joints to randomise", target.value),
                                Some("use `xy` and `yaw` for labware".into()),
                            );
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
                self.err(
                    Code::E0013,
                    target.span,
                    format!("nothing named `{}` to randomise", target.value),
                    Some(hint_for(&target.value, &names, "robots and labware")),
                );
            }
        }
    }

    fn plan(&mut self, p: &Protocol, labware: &[Option<LabwareSpec>]) -> Option<Vec<PlannedStep>> {
        let names: Vec<&str> = primitives::CATALOGUE.iter().map(|p| p.name).collect();
        let labware_names: Vec<&str> = p.labware.iter().map(|l| l.name.value.as_str()).collect();
        let robot_names: Vec<&str> = p.robots.iter().map(|r| r.name.value.as_str()).collect();
        let mut states: BTreeMap<String, BTreeMap<String, String>> = labware
            .iter()
            .flatten()
            .map(|l| (l.name.clone(), l.initial.clone()))
            .collect();
        let mut plan = Vec::new();
        let mut ok = true;
        for step in &p.steps {
            let Some(prim_name) = &step.primitive else {
                ok = false;
                continue;
            };
            let Some(prim) = primitives::primitive(&prim_name.value) else {
                self.err(
                    Code::E0012,
                    prim_name.span,
                    format!("unknown lab primitive `{}`", prim_name.value),
                    Some(hint_for(&prim_name.value, &names, "primitives")),
                );
                ok = false;
                continue;
            };
            let on = self.reference(step.on.as_ref(), step.span, "on", &labware_names, "labware");
            let with = self.reference(
                step.with.as_ref(),
                step.span,
                "with",
                &robot_names,
                "robots",
            );
            let (Some(on), Some(with)) = (on, with) else {
                ok = false;
                continue;
            };
            let Some(spec) = labware.iter().flatten().find(|l| l.name == on.value) else {
                ok = false;
                continue;
            };
            let kind = labware::kind(&spec.kind).expect("kinds resolved above");
            if !kind.primitives.contains(&prim.name) {
                self.err(
                    Code::E0014,
                    prim_name.span,
                    format!(
                        "`{}` cannot be applied to `{}` (a {})",
                        prim.name, on.value, kind.name
                    ),
                    Some(format!(
                        "a {} supports: {}",
                        kind.name,
                        kind.primitives.join(", ")
                    )),
                );
                ok = false;
                continue;
            }
            let state = states
                .get_mut(&on.value)
                .and_then(|s| s.get_mut(prim.part))
                .expect("every part has an initial state");
            if !prim.requires.contains(&state.as_str()) {
                self.err(
                    Code::E0031,
                    prim_name.span,
                    format!(
                        "`{}` needs `{}.{}` to be {}, but here it is `{}`",
                        prim.name,
                        on.value,
                        prim.part,
                        prim.requires.join(" or "),
                        state
                    ),
                    Some(format!(
                        "remove this step or add one before it that leaves the {} {}",
                        prim.part, prim.requires[0]
                    )),
                );
                ok = false;
                continue;
            }
            plan.push(PlannedStep {
                primitive: prim.name.into(),
                labware: on.value.clone(),
                robot: with.value.clone(),
                from_state: state.clone(),
                to_state: prim.leaves.into(),
            });
            *state = prim.leaves.to_string();
        }
        ok.then_some(plan)
    }

    fn reference<'a>(
        &mut self,
        r: Option<&'a Spanned<String>>,
        step: Span,
        key: &str,
        names: &[&str],
        what: &str,
    ) -> Option<&'a Spanned<String>> {
        let Some(r) = r else {
            self.err(
                Code::E0002,
                step,
                format!("step has no `{key}`"),
                Some(format!(
                    "name one of the declared {what}: {}",
                    names.join(", ")
                )),
            );
            return None;
        };
        if !names.contains(&r.value.as_str()) {
            self.err(
                Code::E0013,
                r.span,
                format!("no {what} named `{}`", r.value),
                Some(hint_for(&r.value, names, what)),
            );
            return None;
        }
        Some(r)
    }

    fn success(&mut self, p: &Protocol, labware: &[Option<LabwareSpec>]) -> Vec<Predicate> {
        let mut out = Vec::new();
        for pred in &p.success {
            let text = pred.value.trim();
            let parsed = text.split_once(" is ").and_then(|(lhs, state)| {
                lhs.trim()
                    .split_once('.')
                    .map(|(l, part)| (l.trim(), part.trim(), state.trim()))
            });
            let Some((name, part, state)) = parsed else {
                self.err(
                    Code::E0030,
                    pred.span,
                    format!("cannot read predicate `{text}`"),
                    Some(
                        "write `<labware>.<part> is <state>`, e.g. \"cycler.lid is closed\"".into(),
                    ),
                );
                continue;
            };
            let Some(spec) = labware.iter().flatten().find(|l| l.name == name) else {
                let names: Vec<&str> = p.labware.iter().map(|l| l.name.value.as_str()).collect();
                if !names.contains(&name) {
                    self.err(
                        Code::E0013,
                        pred.span,
                        format!("no labware named `{name}`"),
                        Some(hint_for(name, &names, "labware")),
                    );
                }
                continue;
            };
            let kind = labware::kind(&spec.kind).expect("kinds resolved above");
            let Some(ps) = kind.parts.iter().find(|ps| ps.part == part) else {
                let parts: Vec<&str> = kind.parts.iter().map(|ps| ps.part).collect();
                self.err(
                    Code::E0030,
                    pred.span,
                    format!("a {} has no part `{part}`", kind.name),
                    Some(hint_for(part, &parts, "parts")),
                );
                continue;
            };
            if !ps.states.contains(&state) {
                self.err(
                    Code::E0030,
                    pred.span,
                    format!("`{part}` has no state `{state}`"),
                    Some(hint_for(state, ps.states, "states")),
                );
                continue;
            }
            let LabwareParams::ThermalCycler(params) = &spec.params;
            let tolerance = match state {
                "closed" => params.closed_tolerance,
                "locked" => params.locked_tolerance,
                "open" => params.open_tolerance,
                _ => params.unlocked_tolerance,
            };
            out.push(Predicate {
                text: text.into(),
                labware: name.into(),
                part: part.into(),
                state: state.into(),
                tolerance,
            });
        }
        out
    }
}

fn pose(p: &dsl::ast::Pose) -> Pose {
    let pos = p.pos.as_ref().map(|s| s.value).unwrap_or([0.0; 3]);
    Pose::yaw(pos, p.yaw.as_ref().map(|y| y.value).unwrap_or(0.0))
}

/// The fixed bench camera (in front of the bench, looking across it and 20° down) and one wrist
/// camera per robot, all 224x224.
fn default_cameras(robots: &[RobotSpec]) -> Vec<CameraSpec> {
    let (s, c) = 20f64.to_radians().sin_cos();
    let mut cams = vec![CameraSpec {
        name: "table_front".into(),
        width: 224,
        height: 224,
        mount: CameraMount::Fixed {
            pos: [0.0, -1.2, 1.65],
            xyaxes: [1.0, 0.0, 0.0, 0.0, s, c],
            fovy_deg: 45.0,
        },
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
