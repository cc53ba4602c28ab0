//! Every shipped protocol's first frame from its fixed camera (224x224, as a VLA sees it): not
//! blank, not one flat colour, and showing its labware: hiding the labware (every labware geom
//! made transparent) changes at least 0.5% of the frame (the least: the paper's screw tasks, a
//! rack and one tube from upstream's front camera 1.5 m away, 0.8%; the mini centrifuge's tasks
//! place their own camera, having been 2.2% from the bench camera). Frames that must differ between draws (the mixer's
//! display, the rotor's loaded slot) are tested with their tasks.

use crate::common;

use robots::Detail;
use runtime::Owner;
use runtime::render::Cameras;
use std::collections::HashMap;
use std::sync::Arc;

/// The first frame of `path`'s seed-0 episode from its fixed camera (full detail), with its
/// labware drawn or every labware geom made transparent.
/// `None` where the scene is not simulated (its start is refused).
fn first_frame(path: &str, labware: bool) -> Option<Vec<u8>> {
    let task = common::compile(path);
    let instance = task.sample(0);
    let mut scene = runtime::Scene::build(&task, &instance).ok()?;
    if !labware {
        let owners = scene.body_owner.clone();
        let model = Arc::get_mut(&mut scene.model).expect("a fresh scene's model is its own");
        let bodies: Vec<i32> = model.geom_bodyid().to_vec();
        for (g, body) in bodies.iter().enumerate() {
            if matches!(owners[*body as usize], Some(Owner::Labware(_))) {
                model.geom_rgba_mut()[g][3] = 0.0;
            }
        }
    }
    let ep = runtime::Episode::new(Arc::new(scene), &task, &instance);
    // Every camera, the fixed one first.
    let names: Vec<String> = task.cameras.iter().map(|c| c.name.clone()).collect();
    let mut cams = Cameras::with_detail(&ep.scene, 224, 224, Detail::Full).unwrap();
    Some(
        cams.render(&ep.data, ep.logic(), &names)
            .unwrap()
            .remove(0)
            .rgb,
    )
}

#[test]
fn every_task_opens_on_a_frame_that_shows_its_labware() {
    let mut unsimulated = Vec::new();
    for path in common::shipped_protocols() {
        let path = path.display().to_string();
        let Some(frame) = first_frame(&path, true) else {
            unsimulated.push(path);
            continue;
        };
        assert!(common::spread(&frame) > 10.0, "{path}: a blank first frame");
        let mut counts: HashMap<&[u8], usize> = HashMap::new();
        for px in frame.chunks(3) {
            *counts.entry(px).or_default() += 1;
        }
        let flat = counts.values().max().copied().unwrap_or(0) as f64 / (224.0 * 224.0);
        assert!(
            flat < 0.5,
            "{path}: {:.0}% of the frame is one colour",
            100.0 * flat
        );
        let bare = first_frame(&path, false).expect("built once");
        let changed = frame
            .chunks(3)
            .zip(bare.chunks(3))
            .filter(|(a, b)| a != b)
            .count();
        // Upstream's front camera, 1.5 m from a rack and one tube (the screw tasks), sees them
        // on 0.8% of the frame: half a percent is a camera that sees the work.
        assert!(
            changed > 224 * 224 / 200,
            "{path}: the labware covers {changed} pixels of the first frame"
        );
    }
    // Every shipped task's scene builds (a refused scene would be drawn by nothing).
    assert!(unsimulated.is_empty(), "{unsimulated:?}");
}
