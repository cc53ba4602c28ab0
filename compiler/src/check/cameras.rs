//! The task's cameras: the fixed camera a `[camera]` table places (its field of view and view
//! direction checked, E0021) and the default set every task gets (the bench camera unless
//! `[camera]` replaces it, and one wrist camera per robot). It renders nothing.

use crate::report::Cx;
use crate::task::{CameraMount, CameraSpec, RobotSpec};
use dsl::Code;

/// The fixed camera of a `[camera]` table: standing at `pos`, looking at `look_at` with the image's
/// up as close to world up as the view allows.
pub(super) fn fixed_camera(cx: &mut Cx, c: &dsl::ast::Camera) -> Option<CameraMount> {
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

#[cfg(test)]
mod tests {
    use super::super::testing::*;
    use crate::task::CameraMount;
    use dsl::Code;

    /// `[camera]` with `pos`, `look_at` and `fovy`.
    fn camera(pos: &str, look_at: &str, fovy: &str) -> String {
        with(&format!(
            "[camera]\npos_m = {pos}\nlook_at_m = {look_at}\nfovy_deg = {fovy}\n"
        ))
    }

    /// The fixed camera looks from `pos` at `look_at`, its image's x level and its up upwards;
    /// the task's cameras are it and the arm's wrist camera.
    #[test]
    fn a_camera_table_places_the_fixed_camera_looking_at_its_point() {
        let (task, diags) = compiled(&camera("[0.0, -0.6, 1.3]", "[0.0, -0.05, 0.92]", "36"));
        assert!(diags.is_empty(), "{diags:#?}");
        let cams = task.unwrap().cameras;
        let names: Vec<&str> = cams.iter().map(|c| c.name.as_str()).collect();
        assert_eq!(names, ["table_front", "arm/wrist"]);
        let CameraMount::Fixed {
            pos,
            xyaxes,
            fovy_deg,
        } = &cams[0].mount
        else {
            panic!("a fixed camera");
        };
        assert_eq!(*pos, [0.0, -0.6, 1.3]);
        assert!((fovy_deg - 36.0).abs() < 1e-9);
        // Looking along +y and down: x is +x, up leans towards +z and +y.
        assert!((xyaxes[0] - 1.0).abs() < 1e-9 && xyaxes[1].abs() < 1e-9);
        assert!(xyaxes[5] > 0.8 && xyaxes[4] > 0.0, "{xyaxes:?}");
        // Without `[camera]`, the bench camera at 45°.
        let (task, _) = compiled(BASE);
        let CameraMount::Fixed { fovy_deg, .. } = &task.unwrap().cameras[0].mount else {
            panic!("a fixed camera");
        };
        assert_eq!(*fovy_deg, 45.0);
    }

    /// A field of view outside 1° to 150°, a camera looking at itself and one looking straight
    /// down are E0021, and no task is made.
    #[test]
    fn a_camera_with_no_usable_view_is_e0021() {
        let cases = [
            (
                "[0.0, -0.6, 1.3]",
                "[0.0, -0.05, 0.92]",
                "200",
                "200",
                "a field of view of 200.0° is no camera's",
            ),
            (
                "[0.0, -0.6, 1.3]",
                "[0.0, -0.6, 1.3]",
                "45",
                "[0.0, -0.6, 1.3]",
                "the camera looks at the point it stands on",
            ),
            (
                "[0.0, 0.0, 1.3]",
                "[0.0, 0.0, 0.9]",
                "45",
                "[0.0, 0.0, 0.9]",
                "the camera looks straight up or down, so its image has no up",
            ),
        ];
        for (pos, look_at, fovy, at, message) in cases {
            let src = camera(pos, look_at, fovy);
            let (task, diags) = compiled(&src);
            assert!(task.is_none());
            let d = one(&diags, Code::E0021);
            assert_eq!(d.message, message);
            assert_eq!(covered(&src, d.span), at, "{message}");
        }
    }
}
