//! How the liquid an item holds is drawn: its surface as a flat disc at the level its volume
//! stands at (the quasi-static surface, level in the world), and the body of liquid under it as a
//! stack of short cylinders up the bore, each as wide as the bore where it stands, on mocap bodies
//! the item's fragment declares and the renderer places each frame from the item's logic. A
//! disc's radius is fixed in the model, so each item has a few, of shrinking radii: the largest
//! that fits the bore at the level is shown (in a cone, the surface narrows); a cylinder shows
//! while the liquid covers it. What is not shown is parked out of sight. The stack follows the
//! item's axis (a tilted tube's liquid is drawn as if upright below its level surface). Pure:
//! the renderer in `runtime` moves the bodies.

use crate::frame::Pose;
use crate::mjcf::Fragment;
use physics::liquid::{Container, Liquid, Nanolitres};

/// The discs' radii as shares of the bore's largest radius.
pub const SHARES: [f64; 4] = [0.95, 0.7, 0.45, 0.2];

/// Where an unused disc waits: under the floor.
const PARKED: [f64; 3] = [0.0, 0.0, -5.0];

/// How many cylinders stack up a bore.
pub const LAYERS: usize = 12;

/// The liquid's colour.
const RGBA: &str = "0.05 0.3 0.95 1";

/// The mocap bodies of `name`'s discs (in [`SHARES`] order), then its layers (from the bottom).
pub fn bodies(name: &str) -> Vec<String> {
    (0..SHARES.len())
        .map(|i| format!("{name}/liquid{i}"))
        .chain((0..LAYERS).map(|i| format!("{name}/layer{i}")))
        .collect()
}

/// A bore's layers: each one's centre height in the item's frame, half height and radius (m).
fn layers(bore: &Container) -> Vec<(f64, f64, f64)> {
    let (lo, hi) = bore.range([0.0, 0.0, 1.0]);
    let h = (hi - lo) / LAYERS as f64;
    (0..LAYERS)
        .map(|i| {
            let z = lo + (i as f64 + 0.5) * h;
            // As wide as the bore at the layer's bottom (a cone narrows downward).
            let (_, area) = bore.volume_below([0.0, 0.0, 1.0], z - 0.5 * h + 1e-6);
            (z, 0.5 * h, 0.97 * (area / std::f64::consts::PI).sqrt())
        })
        .collect()
}

/// The discs and layers for an item with this bore: mocap bodies parked out of sight, thin blue
/// cylinders that only cameras see.
pub fn fragment(name: &str, bore: &Container) -> Fragment {
    let radius = radius(bore);
    let body = |n: String, r: f64, hz: f64| {
        format!(
            r#"<body name="{n}" mocap="true" pos="{} {} {}">
  <geom name="{n}" type="cylinder" size="{r} {hz}" rgba="{RGBA}" contype="0" conaffinity="0" group="1"/>
</body>
"#,
            PARKED[0], PARKED[1], PARKED[2]
        )
    };
    let mut worldbody: String = SHARES
        .iter()
        .enumerate()
        .map(|(i, share)| body(format!("{name}/liquid{i}"), share * radius, 0.0004))
        .collect();
    for (i, (_, hz, r)) in layers(bore).into_iter().enumerate() {
        worldbody += &body(format!("{name}/layer{i}"), r, hz);
    }
    Fragment {
        worldbody,
        ..Default::default()
    }
}

/// The largest radius of the bore (m).
pub fn radius(bore: &Container) -> f64 {
    bore.vertices
        .iter()
        .map(|v| v[0].hypot(v[1]))
        .fold(0.0, f64::max)
}

/// Where each of [`bodies`] goes (world poses) for `ul` µL in `bore` with the item at `at`: the
/// disc that fits at the surface's centre, level in the world, and each layer the liquid covers
/// along the item's axis; everything else parked, everything when the item holds nothing.
pub fn discs(bore: &Container, at: &Pose, ul: f64) -> Vec<Pose> {
    let parked = crate::frame::translation(PARKED);
    let mut out = vec![parked; SHARES.len() + LAYERS];
    if ul <= 0.0 {
        return out;
    }
    let up = at.rotation.inverse() * nalgebra::Vector3::z();
    let mut liquid = Liquid::new(bore.clone(), Nanolitres::from_microlitres(ul), 0.0);
    liquid.surface = physics::liquid::Surface::new([up.x, up.y, up.z], 0.0);
    let (centre, r) = liquid.surface_disk();
    let full = radius(bore);
    if let Some(k) = SHARES.iter().position(|s| s * full <= r + 1e-9) {
        let c = at * nalgebra::Point3::from(centre);
        out[k] = crate::frame::translation([c.x, c.y, c.z]);
    }
    // The level on the axis: where the surface plane crosses it.
    let level = if up.z.abs() > 1e-6 {
        liquid.offset() / up.z
    } else {
        f64::NEG_INFINITY
    };
    for (i, (z, hz, _)) in layers(bore).into_iter().enumerate() {
        if z + hz <= level + 1e-9 {
            out[SHARES.len() + i] = at * crate::frame::translation([0.0, 0.0, z]);
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_disc_sits_at_the_level_and_narrows_in_the_cone() {
        let bore = Container::tube(0.013, 0.11, 0.02, 32).shifted([0.0, 0.0, 0.002]);
        let at = crate::frame::translation([0.1, 0.2, 0.8]);
        // 30 mL: in the cylinder, the widest disc, at the level the volume stands at.
        let d = discs(&bore, &at, 30_000.0);
        let level = Liquid::new(bore.clone(), Nanolitres::from_microlitres(30_000.0), 0.0).offset();
        assert!(
            (d[0].translation.vector.z - 0.8 - level).abs() < 1e-3,
            "{d:?}"
        );
        assert!(
            d[1..SHARES.len()]
                .iter()
                .all(|p| p.translation.vector.z < -1.0)
        );
        // 1 mL: down in the cone, a narrower disc, lower.
        let small = discs(&bore, &at, 1000.0);
        let k = small[..SHARES.len()]
            .iter()
            .position(|p| p.translation.vector.z > 0.0)
            .unwrap();
        assert!(k > 0 && small[k].translation.vector.z < d[0].translation.vector.z);
        // The layers under the level show, up to it, and none above.
        let shown: Vec<f64> = d[SHARES.len()..]
            .iter()
            .map(|p| p.translation.vector.z)
            .filter(|z| *z > 0.0)
            .collect();
        assert!(
            !shown.is_empty() && shown.iter().all(|z| *z < 0.8 + level),
            "{shown:?}"
        );
        assert!(
            shown.len()
                > small[SHARES.len()..]
                    .iter()
                    .filter(|p| p.translation.vector.z > 0.0)
                    .count()
        );
        // Empty: nothing shows.
        assert!(
            discs(&bore, &at, 0.0)
                .iter()
                .all(|p| p.translation.vector.z < -1.0)
        );
    }
}
