//! Quasi-static liquid in a real MuJoCo scene: a 50 mL tube on a carriage is tilted to 60° and
//! shaken sideways; an accelerometer on the tube drives the surface pendulum each physics step, the
//! surface offset is re-solved from the volume, and a mocap disk shows the surface in the scene and
//! in an MCAP recording. The geometric volume under the solved surface, measured by an independent
//! slicing integral, stays within 0.5% of the target, and the surface relaxes at the rate its
//! damping sets.

use mujoco_rs::prelude::*;
use physics::liquid::{Container, Liquid, Nanolitres, V3};
use results::recording::{LiquidFrame, RecordError, Recorder, read_recording};

const R: f64 = physics::scenes::TUBE.0;
const H: f64 = physics::scenes::TUBE.1;
const TIP: f64 = physics::scenes::TUBE.2;
const SEGMENTS: usize = physics::scenes::TUBE.3;
const DT: f64 = 0.002;

fn scene() -> String {
    physics::scenes::shaken_tube()
}

/// Volume of the 64-sided tube mesh below `n·x = d`, by slicing along z (Simpson, 4,000 slices)
/// and clipping each polygonal cross-section by the plane's trace: independent of the solver's
/// divergence-theorem volume.
fn sliced_volume(n: V3, d: f64) -> f64 {
    let section = |z: f64| -> f64 {
        let r = if z < TIP { R * z / TIP } else { R };
        let poly: Vec<(f64, f64)> = (0..SEGMENTS)
            .map(|i| {
                let a = std::f64::consts::TAU * i as f64 / SEGMENTS as f64;
                (r * a.cos(), r * a.sin())
            })
            .collect();
        // Keep n_x x + n_y y <= d - n_z z.
        let c = d - n[2] * z;
        let f = |p: (f64, f64)| n[0] * p.0 + n[1] * p.1 - c;
        let mut clipped = Vec::new();
        for i in 0..poly.len() {
            let (a, b) = (poly[i], poly[(i + 1) % poly.len()]);
            let (fa, fb) = (f(a), f(b));
            if fa <= 0.0 {
                clipped.push(a);
            }
            if (fa <= 0.0) != (fb <= 0.0) {
                let t = fa / (fa - fb);
                clipped.push((a.0 + (b.0 - a.0) * t, a.1 + (b.1 - a.1) * t));
            }
        }
        let mut area = 0.0;
        for i in 0..clipped.len() {
            let (a, b) = (clipped[i], clipped[(i + 1) % clipped.len()]);
            area += a.0 * b.1 - b.0 * a.1;
        }
        area.abs() / 2.0
    };
    let n_slices = 4000;
    let h = H / n_slices as f64;
    let mut sum = section(0.0) + section(H);
    for k in 1..n_slices {
        sum += section(k as f64 * h) * if k % 2 == 1 { 4.0 } else { 2.0 };
    }
    sum * h / 3.0
}

/// Rotation (w, x, y, z) taking +z to `n`.
fn quat_z_to(n: V3) -> [f64; 4] {
    let (x, y, z) = (n[0], n[1], n[2]);
    if z < -0.999_999 {
        return [0.0, 1.0, 0.0, 0.0];
    }
    let w = 1.0 + z;
    let q = [w, -y, x, 0.0];
    let l = (q.iter().map(|v| v * v).sum::<f64>()).sqrt();
    [q[0] / l, q[1] / l, q[2] / l, q[3] / l]
}

struct Sim {
    model: MjModel,
    site: usize,
    mocap: usize,
}

impl Sim {
    fn new() -> Sim {
        let model = MjModel::from_xml_string(&scene()).unwrap();
        let site = model.name_to_id(MjtObjBase::mjOBJ_SITE, "tube").unwrap();
        assert!(
            model
                .name_to_id(MjtObjBase::mjOBJ_BODY, "surface")
                .is_some()
        );
        let mocap = 0; // the scene's only mocap body

        Sim { model, site, mocap }
    }

    /// Steps once and updates the liquid and the surface disk; returns the frame to record.
    fn step(&self, data: &mut MjData<&MjModel>, liquid: &mut Liquid) -> LiquidFrame {
        data.step();
        let a = data.sensordata();
        liquid.step([a[0], a[1], a[2]], DT);
        let (c, radius) = liquid.surface_disk();
        let p = data.site_xpos()[self.site];
        let m = data.site_xmat()[self.site];
        let world = |v: V3| -> V3 {
            [
                m[0] * v[0] + m[1] * v[1] + m[2] * v[2],
                m[3] * v[0] + m[4] * v[1] + m[5] * v[2],
                m[6] * v[0] + m[7] * v[1] + m[8] * v[2],
            ]
        };
        let cw = world(c);
        let centre = [p[0] + cw[0], p[1] + cw[1], p[2] + cw[2]];
        let quat = quat_z_to(world(liquid.surface.normal()));
        data.mocap_pos_mut()[self.mocap] = centre;
        data.mocap_quat_mut()[self.mocap] = quat;
        LiquidFrame {
            volume_ul: liquid.volume.microlitres(),
            normal: liquid.surface.normal(),
            offset_m: liquid.offset(),
            centre,
            quat,
            radius_m: radius,
        }
    }
}

#[test]
fn volume_holds_while_the_tube_tilts_and_shakes() {
    let sim = Sim::new();
    let mut data = MjData::new(&sim.model);
    let container = Container::tube(R, H, TIP, SEGMENTS);
    let target_ul = 20_000.0;
    let mut liquid = Liquid::new(container, Nanolitres::from_microlitres(target_ul), 0.03);
    let dir = std::env::temp_dir().join(format!("autobio-liquid-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let path = dir.join("liquid.mcap");
    let mut rec = Recorder::create(&path).unwrap();
    let (mut worst, mut max_tilt) = (0.0f64, 0.0f64);
    // The shake itself: the carriage's acceleration along the slide, inside and outside the
    // shaking window (gravity never enters it: the slide is horizontal).
    let (mut shake_in, mut shake_before) = (0.0f64, 0.0f64);
    let (mut disk_checked, mut worst_centre, mut worst_radius) = (0, 0.0f64, 0.0f64);
    let steps = (4.0 / DT) as usize;
    let mut moved = 0.0f64;
    for k in 0..steps {
        let t = k as f64 * DT;
        // Tilt to 60° over 1.5 s, shake ±3 cm at 2 Hz from 1 s to 3 s.
        data.ctrl_mut()[1] = (t / 1.5).min(1.0) * 60f64.to_radians();
        data.ctrl_mut()[0] = if (1.0..3.0).contains(&t) {
            0.03 * (std::f64::consts::TAU * 2.0 * (t - 1.0)).sin()
        } else {
            0.0
        };
        let frame = sim.step(&mut data, &mut liquid);
        if k % 10 == 0 {
            rec.liquid(t, "tube", &frame).unwrap();
        }
        max_tilt = max_tilt.max(data.qpos()[1]);
        let slide_acc = data.qacc()[0].abs();
        if (1.2..2.8).contains(&t) {
            shake_in = shake_in.max(slide_acc);
        } else if (0.2..0.9).contains(&t) {
            shake_before = shake_before.max(slide_acc);
        }
        // The surface disk: where the plane cuts only the cylindrical wall (above the conical tip,
        // below the open top), the cut is an ellipse
        // centred on the axis with semi-major axis R / |n_z|.
        let n = frame.normal;
        let low = (frame.offset_m - R * n[0].hypot(n[1])) / n[2];
        let high = (frame.offset_m + R * n[0].hypot(n[1])) / n[2];
        if n[2] > 0.2 && low > TIP + 1e-3 && high < H - 1e-3 {
            let (c, radius) = liquid.surface_disk();
            worst_centre = worst_centre.max(c[0].hypot(c[1]));
            worst_radius = worst_radius.max((radius - R / n[2].abs()).abs() / (R / n[2].abs()));
            disk_checked += 1;
        }
        let first = data.mocap_pos()[sim.mocap];
        moved = moved.max((first[1]).abs());
    }
    rec.finish().unwrap();
    assert!(max_tilt > 59f64.to_radians(), "tilted to {max_tilt} rad");
    // ±3 cm at 2 Hz: a commanded peak of 0.03 (4π)² = 4.74 m/s²; the position servo overshoots
    // it (measured 5.77 m/s²). The bound excludes no shake and a shake of twice the amplitude.
    assert!((3.5..8.0).contains(&shake_in), "shaken at {shake_in} m/s²");
    assert!(
        shake_before < 0.5,
        "the carriage moved before the shake: {shake_before} m/s²"
    );
    assert!(moved > 0.01, "the surface disk follows the tube: {moved} m");
    assert!(
        disk_checked > 100,
        "{disk_checked} steps with the surface on the wall"
    );
    // docs/physics.md: the centre 0.11 mm off the axis, the radius R/n_z to 0.014%.
    assert!(
        worst_centre < 1.5e-4,
        "disk centre {worst_centre} m off the axis"
    );
    assert!(
        worst_radius < 2e-4,
        "disk radius off by {:.3}%",
        100.0 * worst_radius
    );
    // Every recorded frame holds the target volume under its own recorded surface, measured
    // independently from the frame's normal and offset (not from the solver's bookkeeping).
    let bytes = std::fs::read(&path).unwrap();
    let mut liquid_messages = 0;
    for m in mcap::MessageStream::new(&bytes).unwrap() {
        let m = m.unwrap();
        assert_ne!(m.channel.topic, "/labware/state", "not an episode");
        if m.channel.topic == "/liquid/tube" {
            let f: LiquidFrame = serde_json::from_slice(&m.data).unwrap();
            let v = sliced_volume(f.normal, f.offset_m) * 1e9;
            worst = worst.max((v - target_ul).abs() / target_ul);
            liquid_messages += 1;
        }
    }
    assert_eq!(liquid_messages, steps / 10);
    eprintln!(
        "liquid: tilt {:.1} deg, carriage shaken at up to {shake_in:.2} m/s² ({shake_before:.3} \
         before), worst volume error {:.4}%, disk centre off axis {:.2e} m, radius off {:.3}% \
         over {disk_checked} steps",
        max_tilt.to_degrees(),
        100.0 * worst,
        worst_centre,
        100.0 * worst_radius
    );
    // docs/physics.md's figure: under 0.03% (measured 0.024%).
    assert!(worst < 3e-4, "volume error up to {:.4}%", 100.0 * worst);
    assert!(
        matches!(
            read_recording(&path),
            Err(RecordError::Missing("/labware/state"))
        ),
        "no labware channel to re-score"
    );
    std::fs::remove_dir_all(&dir).unwrap();
}

/// Decay time of ln(peak) over time, by least squares.
fn decay_time(peaks: &[(f64, f64)]) -> f64 {
    let n = peaks.len() as f64;
    assert!(n >= 4.0, "{peaks:?}");
    let (sx, sy) = peaks
        .iter()
        .fold((0.0, 0.0), |(a, b), (t, p)| (a + t, b + p.ln()));
    let (mx, my) = (sx / n, sy / n);
    let (num, den) = peaks.iter().fold((0.0, 0.0), |(a, b), (t, p)| {
        (a + (t - mx) * (p.ln() - my), b + (t - mx) * (t - mx))
    });
    -1.0 / (num / den)
}

/// Envelope decay time of the surface's oscillation after the tube stops tilting.
fn relaxation(damping: f64) -> (f64, f64) {
    let sim = Sim::new();
    let mut data = MjData::new(&sim.model);
    let mut liquid = Liquid::new(
        Container::tube(R, H, TIP, SEGMENTS),
        Nanolitres::from_microlitres(20_000.0),
        damping,
    );
    // A quick 20° tilt, then hold: the surface swings toward the new vertical and settles.
    let mut peaks: Vec<(f64, f64)> = Vec::new();
    let mut prev = [0.0; 2];
    for k in 0..(6.0 / DT) as usize {
        let t = k as f64 * DT;
        data.ctrl_mut()[1] = 20f64.to_radians();
        sim.step(&mut data, &mut liquid);
        let a = data.sensordata();
        let g = [a[0], a[1], a[2]];
        let gn = (g[0] * g[0] + g[1] * g[1] + g[2] * g[2]).sqrt();
        let n = liquid.surface.normal();
        let cos = (n[0] * g[0] + n[1] * g[1] + n[2] * g[2]) / gn;
        let angle = cos.clamp(-1.0, 1.0).acos();
        // Local maxima of the deviation after the tube has settled (1 s).
        if t > 1.0 && prev[1] > prev[0] && prev[1] > angle {
            peaks.push((t, prev[1]));
        }
        prev = [prev[1], angle];
    }
    (
        decay_time(&peaks),
        liquid.surface.relaxation_time(9.81, liquid.length),
    )
}

#[test]
fn the_surface_relaxes_at_the_rate_its_damping_sets() {
    for damping in [0.03, 0.08] {
        let (measured, predicted) = relaxation(damping);
        eprintln!("liquid: damping {damping}: relaxation {measured:.3} s, 1/(ζω) {predicted:.3} s");
        // Measured to 0.1% (docs/physics.md); 2% leaves room for the peak picking's step size.
        assert!(
            (measured - predicted).abs() / predicted < 0.02,
            "damping {damping}: relaxation {measured:.3} s, predicted {predicted:.3} s"
        );
    }
}

/// Relaxation after a 20° step of the apparent gravity about `axis` (0: x, 1: y), fed to the
/// liquid directly in the container frame.
fn relaxation_about(axis: usize) -> f64 {
    let mut liquid = Liquid::new(
        Container::tube(R, H, TIP, SEGMENTS),
        Nanolitres::from_microlitres(20_000.0),
        0.03,
    );
    let (s, c) = 20f64.to_radians().sin_cos();
    let g = if axis == 0 {
        [0.0, 9.81 * s, 9.81 * c]
    } else {
        [9.81 * s, 0.0, 9.81 * c]
    };
    let mut peaks = Vec::new();
    let mut prev = [0.0; 2];
    for k in 0..(6.0 / DT) as usize {
        let t = k as f64 * DT;
        liquid.step(g, DT);
        let n = liquid.surface.normal();
        let cos = (n[0] * g[0] + n[1] * g[1] + n[2] * g[2]) / 9.81;
        let angle = cos.clamp(-1.0, 1.0).acos();
        if t > 0.5 && prev[1] > prev[0] && prev[1] > angle {
            peaks.push((t, prev[1]));
        }
        prev = [prev[1], angle];
    }
    decay_time(&peaks)
}

#[test]
fn damping_is_the_same_about_both_axes() {
    // The chart the pendulum is integrated in once made damping depend on the tilt's direction
    // (3.8 s against 2.2 s); a tilt about x and one about y must relax alike.
    let (x, y) = (relaxation_about(0), relaxation_about(1));
    eprintln!("liquid: relaxation after a 20° tilt about x {x:.3} s, about y {y:.3} s");
    assert!(
        (x - y).abs() / x < 0.03,
        "about x {x:.3} s, about y {y:.3} s"
    );
}
