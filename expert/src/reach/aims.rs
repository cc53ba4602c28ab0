//! The targets the reach pass checks in one layout ([`aims`]): each step's first target as the
//! expert resolves it, the path it then follows holding a part, the standoff it comes in from,
//! a carried item's seat and a held tool's places, with the labware's joints as earlier steps
//! leave them. It does not solve them (the pass does, in `mod.rs`).

use super::*;
use compiler::primitives::Expanded;

/// The targets the pass checks, step by step: each step's first target where the step's item is
/// where it started; and for an item a robot picked up, the seat it is then placed on, with the
/// item held as the pick grasped it (the seat's tool pose depends on that).
pub(super) fn aims(
    task: &Task,
    scene: &Scene,
    states: &mut [LabwareState],
    params: &compiler::params::Bindings,
    kins: &mut [ArmKinematics],
    start: &[Vec<f64>],
) -> Vec<Aim> {
    // Items in a hand since a pick (by which robot, grasped with the tool where), and items
    // that have been put somewhere else.
    let mut held: BTreeMap<String, (usize, Pose)> = BTreeMap::new();
    let mut placed = BTreeSet::new();
    // Whether an earlier step has moved some labware's joints (a lid opened).
    let mut moved_joints = false;
    let mut out = Vec::new();
    for (i, (_, step)) in task.steps().enumerate() {
        let Some(robot) = task.robot_index(&step.robot) else {
            continue;
        };
        let Some(Expanded { args, motions }) = Expanded::of(task, i, step, params) else {
            continue;
        };
        let on = args.get("on").cloned();
        // The labware as earlier steps left its joints (a lid opened).
        let owned = states.to_vec();
        let lab = &Lab::new(task, &owned, params);
        let seats: Vec<&Motion> = motions
            .iter()
            .filter(|m| {
                matches!(
                    m,
                    Motion::Reach {
                        target: Target::Seat { .. }
                    } | Motion::Transit {
                        target: Target::Seat { .. }
                    }
                )
            })
            .collect();
        // A pick puts its item itself in the hand (an unscrewing lifts the cap, not the tube).
        let picks = step.primitive == "pick";
        let g = scene.robots[robot].model.gripper;
        if let Some(item) = &on {
            if placed.contains(item) {
                continue;
            }
            if !seats.is_empty() {
                placed.insert(item.clone());
                // Placed by the robot that picked it: the seat as that grasp carries the item.
                let Some((_, grasp)) = held.remove(item).filter(|(r, _)| *r == robot) else {
                    continue;
                };
                let frame =
                    StepFrame::new(&motions, lab, &grasp, Some(item), g.finger_reach, g.enclose);
                let Ok(frame) = frame else { continue };
                out.extend(seat_aims(i, robot, &seats, &frame, lab));
                continue;
            }
            if held.contains_key(item) {
                continue;
            }
        }
        let tcp = primitives::Kinematics::tcp(&mut kins[robot], &start[robot]);
        let Ok(frame) = StepFrame::new(
            &motions,
            lab,
            &tcp,
            on.as_deref(),
            g.finger_reach,
            g.enclose,
        ) else {
            continue;
        };
        // A held tool brought onto an opening.
        if matches!(first_target(&motions), Some(Target::Bring { .. })) {
            let as_started = !moved_joints && held.values().all(|(r, _)| *r != robot);
            out.extend(bring_aims(
                i, robot, &motions, &frame, lab, &tcp, as_started,
            ));
            continue;
        }
        let Ok(Some(pose)) = frame.first_pose(&motions, lab) else {
            continue;
        };
        if picks && let Some(item) = &on {
            held.insert(item.clone(), (robot, pose));
        }
        // The lid (and lever) where the grip takes it, then each grasp's path.
        if let Some(Target::Affordance { labware, goals, .. }) = first_target(&motions) {
            set_goals(task, states, params, labware, goals);
        }
        let as_started = !moved_joints && held.values().all(|(r, _)| *r != robot);
        // A lift after the grasp (a pick's, a cap's): straight up, holding what was gripped.
        let lift = motions.iter().find_map(|m| match m {
            Motion::Lift { height } => Some(*height),
            _ => None,
        });
        let lifted = |at: &Pose, mut path: Vec<Pose>| {
            path.extend(lift.map(|h| labware::frame::translation([0.0, 0.0, h]) * at));
            path
        };
        // Either of a symmetric affordance's grasps, as the expert may take them.
        let grasps: Vec<(Pose, Vec<Pose>)> = frame
            .symmetric_grasps()
            .filter_map(|f| {
                let at = f.first_pose(&motions, lab).ok().flatten()?;
                let path = follow(task, states, params, &f, &motions, &at);
                Some((at, lifted(&at, path)))
            })
            .collect();
        // Where the step leaves the labware's joints, for the steps after it.
        for m in &motions {
            if let Motion::Follow { labware, goals, .. } = m {
                set_goals(task, states, params, labware, goals);
                moved_joints = true;
            }
        }
        let approach = approach_aim(i, robot, &motions, &grasps, as_started);
        // The way in first, as the arm comes: the target's aim is then the arm's last solution
        // for the steps after it (the end of its arc or lift).
        out.extend(approach);
        out.push(Aim {
            step: i,
            robot,
            target: target_name(&motions),
            grasps,
            as_started,
        });
    }
    out
}

/// The aims of placing a carried item: each seat motion's pose with the item as `frame` (the
/// pick's grasp) carries it.
fn seat_aims(i: usize, robot: usize, seats: &[&Motion], frame: &StepFrame, lab: &Lab) -> Vec<Aim> {
    seats
        .iter()
        .filter_map(|m| {
            let pose = frame.first_pose(std::slice::from_ref(*m), lab).ok()??;
            Some(Aim {
                step: i,
                robot,
                target: target_name(std::slice::from_ref(*m)),
                grasps: vec![(pose, Vec::new())],
                as_started: false,
            })
        })
        .collect()
}

/// The aims of a held tool brought onto an opening (a pipette's tip over a tube's mouth, then
/// under its surface): each place it is brought to, as the tool sits in the hand at the start
/// (`tcp`), at any heading about the opening's axis the expert may take.
fn bring_aims(
    i: usize,
    robot: usize,
    motions: &[Motion],
    frame: &StepFrame,
    lab: &Lab,
    tcp: &Pose,
    as_started: bool,
) -> Vec<Aim> {
    let mut out = Vec::new();
    let mut seen: Vec<&Target> = Vec::new();
    for m in motions {
        let Motion::Reach { target } = m else {
            continue;
        };
        if seen.contains(&target) {
            continue;
        }
        seen.push(target);
        // The headings the expert tries where its first is blocked.
        let grasps: Vec<(Pose, Vec<Pose>)> = frame
            .headings()
            .filter_map(|f| f.pose_toward(target, lab, tcp).ok())
            .map(|p| (p, Vec::new()))
            .collect();
        if !grasps.is_empty() {
            out.push(Aim {
                step: i,
                robot,
                target: target_name(std::slice::from_ref(m)),
                grasps,
                as_started,
            });
        }
    }
    out
}

/// Where the arm comes in from: the standoff back along the target's axis (4 cm above a tube's
/// grasp), for each of `grasps`; `None` for a step with no approach.
fn approach_aim(
    i: usize,
    robot: usize,
    motions: &[Motion],
    grasps: &[(Pose, Vec<Pose>)],
    as_started: bool,
) -> Option<Aim> {
    let d = motions.iter().find_map(|m| match m {
        Motion::Approach { standoff, .. } => Some(*standoff),
        _ => None,
    })?;
    let back = labware::frame::translation([0.0, 0.0, -d]);
    Some(Aim {
        step: i,
        robot,
        target: format!(
            "{} (coming in {:.0} cm back along it)",
            target_name(motions),
            d * 100.0
        ),
        grasps: grasps.iter().map(|(g, _)| (g * back, Vec::new())).collect(),
        as_started,
    })
}

/// The tool poses of a step's `Follow` motions in order, from its grasp at `from` with `frame`,
/// each from where the one before leaves the labware's joints (`states` as the grip takes it).
fn follow(
    task: &Task,
    states: &[LabwareState],
    params: &compiler::params::Bindings,
    frame: &StepFrame,
    motions: &[Motion],
    from: &Pose,
) -> Vec<Pose> {
    let mut states = states.to_vec();
    let mut path = Vec::new();
    let mut tcp = *from;
    for m in motions {
        let Motion::Follow { labware, goals, .. } = m else {
            continue;
        };
        let lab = Lab::new(task, &states, params);
        let Ok(poses) = frame.poses(m, &lab, &tcp) else {
            return path;
        };
        path.extend(poses.iter().skip(1).copied());
        tcp = *poses.last().unwrap_or(&tcp);
        set_goals(task, &mut states, params, labware, goals);
    }
    path
}

/// Sets `labware`'s joints to `goals` as the expert resolves them (`Lab::at_goals`: roles it
/// lacks, a lever on a lid without one, are skipped); a goal it cannot resolve leaves it as is.
fn set_goals(
    task: &Task,
    states: &mut [LabwareState],
    params: &compiler::params::Bindings,
    labware: &str,
    goals: &compiler::motion::Goals,
) {
    let Some(i) = task.labware_index(labware) else {
        return;
    };
    let owned = states.to_vec();
    if let Ok(at) = Lab::new(task, &owned, params).at_goals(labware, goals) {
        states[i] = at;
    }
}

/// What a step's motions aim at first, for a reader.
fn target_name(motions: &[Motion]) -> String {
    match first_target(motions) {
        Some(Target::Affordance { labware, name, .. }) => format!("`{labware}`'s `{name}`"),
        Some(Target::Button { labware, param, .. }) => {
            format!("the button that sets `{labware}.{param}`")
        }
        Some(Target::Seat { location, above }) if *above > 0.0 => {
            format!("{:.0} mm above the seat `{location}`", above * 1000.0)
        }
        Some(Target::Seat { location, .. }) => format!("the seat `{location}`"),
        Some(Target::Carry { labware, to, .. }) => format!("`{labware}`'s `{to}`"),
        Some(Target::Bring {
            carried,
            from,
            labware,
            to,
            ..
        }) => format!("`{carried}`'s `{from}` onto `{labware}`'s `{to}`"),
        None => "its target".into(),
    }
}
