//! Quasi-static liquid in a real MuJoCo scene: a 50 mL tube on a carriage is tilted to 60° and
//! shaken sideways; an accelerometer on the tube drives the surface pendulum each physics step, the
//! surface offset is re-solved from the volume, and a mocap disk shows the surface in the scene and
//! in an MCAP recording. The geometric volume under the solved surface, measured by an independent
//! slicing integral, stays within 0.5% of the target, and the surface relaxes at the rate its
//! damping sets.

use mujoco_rs::prelude::*;
use physics::liquid::{Container, Liquid, Nanolitres, V3};
use runtime::record::{LiquidFrame, Recorder, read_recording};

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
    let (mut worst, mut max_tilt, mut max_lateral) = (0.0f64, 0.0f64, 0.0f64);
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
        max_lateral = max_lateral.max(data.sensordata()[1].abs());
        let first = data.mocap_pos()[sim.mocap];
        moved = moved.max((first[1]).abs());
        if k % 50 == 0 {
            let v = sliced_volume(liquid.surface.normal(), liquid.offset()) * 1e9;
            worst = worst.max((v - target_ul).abs() / target_ul);
        }
    }
    rec.finish().unwrap();
    eprintln!(
        "liquid: tilt {:.1} deg, lateral {max_lateral:.1} m/s², worst volume error {:.4}%",
        max_tilt.to_degrees(),
        100.0 * worst
    );
    assert!(max_tilt > 59f64.to_radians(), "tilted to {max_tilt} rad");
    assert!(max_lateral > 3.0, "shaken at {max_lateral} m/s² sideways");
    assert!(worst < 0.005, "volume error up to {:.3}%", 100.0 * worst);
    assert!(moved > 0.01, "the surface disk follows the tube: {moved} m");
    let summary = read_recording(&path);
    // The recording has the liquid channel (no labware channel: this is not an episode).
    assert!(summary.is_err() || summary.unwrap().topics.contains_key("/liquid/tube"));
    let bytes = std::fs::read(&path).unwrap();
    let mut liquid_messages = 0;
    for m in mcap::MessageStream::new(&bytes).unwrap() {
        let m = m.unwrap();
        if m.channel.topic == "/liquid/tube" {
            let f: LiquidFrame = serde_json::from_slice(&m.data).unwrap();
            assert_eq!(f.volume_ul, target_ul);
            liquid_messages += 1;
        }
    }
    assert_eq!(liquid_messages, steps / 10);
    std::fs::remove_dir_all(&dir).unwrap();
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
    // Fit ln(peak) = a - t / tau by least squares.
    let n = peaks.len() as f64;
    assert!(n >= 4.0, "{peaks:?}");
    let (sx, sy) = peaks
        .iter()
        .fold((0.0, 0.0), |(a, b), (t, p)| (a + t, b + p.ln()));
    let (mx, my) = (sx / n, sy / n);
    let (num, den) = peaks.iter().fold((0.0, 0.0), |(a, b), (t, p)| {
        (a + (t - mx) * (p.ln() - my), b + (t - mx) * (t - mx))
    });
    let tau = -1.0 / (num / den);
    (tau, liquid.surface.relaxation_time(9.81, liquid.length))
}

#[test]
fn the_surface_relaxes_at_the_rate_its_damping_sets() {
    for damping in [0.03, 0.08] {
        let (measured, predicted) = relaxation(damping);
        eprintln!("liquid: damping {damping}: relaxation {measured:.3} s, 1/(ζω) {predicted:.3} s");
        assert!(
            (measured - predicted).abs() / predicted < 0.15,
            "damping {damping}: relaxation {measured:.3} s, predicted {predicted:.3} s"
        );
    }
}
