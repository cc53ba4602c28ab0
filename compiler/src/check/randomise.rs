//! `[randomise.<name>]` tables applied to the lowered specs: a robot's joint offsets (E0021 when
//! more ranges than joints), a labware item's planar shift, yaw and free joints (E0003 for a part
//! with a declared state or a joint the kind lacks, E0021 past half a turn), E0004 for the other
//! target's form and E0013 for a target that names nothing. It draws no values (that is
//! [`crate::task::Task::sample`]) and warns of no implausible shift ([`super::scene`]).

use crate::report::{Cx, hint_for};
use crate::task::{JointJitter, LabwareSpec, RobotSpec};
use dsl::Code;
use dsl::ast::{Protocol, RandomItem, Spanned};

/// Applies each randomisation table, in order, to the robot or labware item it names; a target
/// whose spec was not lowered is skipped (its error is already reported).
pub(super) fn randomise(
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
            randomise_robot(cx, target, &r.items, robot);
        } else if let Some(i) = p.labware.iter().position(|x| x.name.value == target.value) {
            let Some(lw) = labware[i].as_mut() else {
                continue;
            };
            randomise_labware(cx, target, &r.items, lw);
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

/// A robot is randomised only by `low` and `high` joint offsets about its home pose.
fn randomise_robot(
    cx: &mut Cx,
    target: &Spanned<String>,
    items: &[RandomItem],
    robot: &mut RobotSpec,
) {
    for item in items {
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
            RandomItem::Xy(q) | RandomItem::Yaw(q) | RandomItem::PartsRadius(q) => cx.err(
                Code::E0003,
                q.span,
                format!("robot `{}` cannot be moved by randomisation", target.value),
                Some("randomise a robot's `joints`; `xy` and `yaw` apply to labware".into()),
            ),
        }
    }
}

/// A labware item is shifted (`xy`), turned (`yaw`) and has its free joints offset by role.
fn randomise_labware(
    cx: &mut Cx,
    target: &Spanned<String>,
    items: &[RandomItem],
    lw: &mut LabwareSpec,
) {
    for item in items {
        match item {
            RandomItem::Xy(q) => lw.xy_jitter_m = q.value.abs(),
            RandomItem::Yaw(q) => lw.yaw_jitter_rad = q.value.abs(),
            RandomItem::PartsRadius(q) if lw.parts.is_empty() => cx.err(
                Code::E0003,
                q.span,
                format!("`{}` has no part lying apart to draw a place for", target.value),
                Some("`parts_radius` draws where a part given in `parts` lies; give it one, or drop this".into()),
            ),
            RandomItem::PartsRadius(q) => lw.parts_radius_m = q.value.abs(),
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
                for (role, q) in joints {
                    labware_joint(cx, target, kind, role, q, lw);
                }
            }
        }
    }
}

/// One `role = angle` offset of a labware item's joint: only a free joint (a rotor), at most half
/// a turn.
fn labware_joint(
    cx: &mut Cx,
    target: &Spanned<String>,
    kind: &labware::LabwareKind,
    role: &Spanned<String>,
    q: &Spanned<f64>,
    lw: &mut LabwareSpec,
) {
    let roles: Vec<&str> = kind.joints.iter().map(|(j, _)| *j).collect();
    let is_part = kind.parts.iter().any(|p| p.part == role.value);
    if is_part && roles.contains(&role.value.as_str()) {
        // A lid starts in its declared state (`open`, `closed`): the proof and the latch rely
        // on it.
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
            format!(
                "`{}` ({}) has no joints to randomise",
                target.value, lw.kind
            ),
            Some("use `xy` and `yaw` to move the item".into()),
        );
    } else {
        cx.err(
            Code::E0003,
            role.span,
            format!(
                "`{}` ({}) has no joint `{}`",
                target.value, lw.kind, role.value
            ),
            Some(hint_for(&role.value, &roles, "joints")),
        );
    }
}

#[cfg(test)]
mod tests {
    use super::super::testing::*;
    use dsl::Code;

    const CENTRIFUGE: &str =
        "[labware.centrifuge]\nkind = \"centrifuge_5430\"\npose = { pos_m = [0.0, 0.35, 0.824] }\n";

    /// A labware item's shift, turn and free joint are lowered as the ± bounds written.
    #[test]
    fn labware_is_shifted_turned_and_its_rotor_offset_as_written() {
        let src = with(&format!(
            "{CENTRIFUGE}\n[randomise.tube]\nxy_mm = 20\nyaw_deg = 10\n\n[randomise.centrifuge]\njoints_rad = {{ rotor = -0.1 }}\n"
        ));
        lowered(&src, |low, diags| {
            assert!(diags.is_empty(), "{diags:#?}");
            let low = low.unwrap();
            let tube = &low.labware[2];
            assert!((tube.xy_jitter_m - 0.02).abs() < 1e-12);
            assert!((tube.yaw_jitter_rad - 10f64.to_radians()).abs() < 1e-12);
            assert_eq!(low.labware[3].joint_jitter["rotor"], 0.1);
        });
    }

    /// A lid with a declared state, a joint past half a turn, a joint the kind lacks and an item
    /// without joints are each refused at the role; the rotor beside them is still applied.
    #[test]
    fn joints_with_a_declared_state_or_out_of_range_are_refused_at_the_role() {
        let src = with(&format!(
            "{CENTRIFUGE}\n[randomise.centrifuge]\njoints_rad = {{ lid = 0.1, rotor = 4, spindle = 0.1 }}\n\n[randomise.source]\njoints_rad = {{ rotor = 0.1 }}\n"
        ));
        lowered(&src, |low, diags| {
            assert_eq!(
                codes(diags),
                [Code::E0003, Code::E0021, Code::E0003, Code::E0003],
                "{diags:#?}"
            );
            assert_eq!(
                diags[0].message,
                "`centrifuge`'s `lid` starts in its declared state and cannot be randomised"
            );
            assert_eq!(diags[1].message, "± 4 rad is more than half a turn");
            assert_eq!(covered(&src, diags[2].span), "spindle");
            assert_eq!(diags[2].hint.as_deref(), Some("known joints: lid, rotor"));
            assert_eq!(
                diags[3].message,
                "`source` (tube_rack) has no joints to randomise"
            );
            assert!(low.unwrap().labware[3].joint_jitter.is_empty());
        });
    }

    /// A robot is randomised by joint arrays only, no longer than its joints; a target that
    /// names nothing is E0013 with the closest name.
    #[test]
    fn robots_take_joint_arrays_only_and_an_unknown_target_is_e0013() {
        let src = with(
            "[randomise.arm]\nxy_m = 0.01\njoints_rad = { low = [0, 0, 0, 0, 0, 0, 0], high = [0, 0, 0, 0, 0, 0, 0] }\n\n[randomise.tub]\nxy_m = 0.01\n",
        );
        lowered(&src, |low, diags| {
            let d = one(diags, Code::E0003);
            assert_eq!(d.message, "robot `arm` cannot be moved by randomisation");
            assert_eq!(
                one(diags, Code::E0021).message,
                "`arm` has 6 joints, but 7 ranges are given"
            );
            let d = one(diags, Code::E0013);
            assert_eq!(d.message, "nothing named `tub` to randomise");
            assert_eq!(d.hint.as_deref(), Some("did you mean `tube`?"));
            assert_eq!(low.unwrap().robots[0].joint_jitter, None);
        });
        let src = with(
            "[randomise.arm]\njoints_rad = { low = [-0.1, 0, 0, 0, 0, 0], high = [0.1, 0, 0, 0, 0, 0] }\n",
        );
        lowered(&src, |low, diags| {
            assert!(diags.is_empty(), "{diags:#?}");
            let jitter = low.unwrap().robots[0].joint_jitter.clone().unwrap();
            assert_eq!(jitter.low, [-0.1, 0.0, 0.0, 0.0, 0.0, 0.0]);
        });
    }
}
