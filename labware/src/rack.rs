//! Racks: a static block with a grid of square holes that hold tubes upright (the `tube_rack` for
//! 50 and 15 mL tubes, the `microtube_rack` for 1.5 mL tubes and cryovials). Collision is boxes
//! only: a base plate the tubes stand on and a top plate made of bars between the holes, so a
//! seated tube is held by cheap box contacts.
//!
//! Frame: origin at the centre of the rack's footprint at mid-height, +z up; columns run along +x
//! (column 1 at the +x end), rows along +y (row A at the -y side). Dimensions from
//! `upstream-autobio.md` §11.3 (the `centrifuge_10slot` rack's 50 mL grid).

use crate::frame::{Pose, Vec3, translation};
use crate::mjcf::{Fragment, pose_attrs, v3};
use crate::model::{Instrument, LabwareState};
use serde::{Deserialize, Serialize};

#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Params {
    /// Outer size: length (x), width (y), height (z), metres.
    pub size: Vec3,
    pub rows: u32,
    pub cols: u32,
    /// Distance between hole centres along a row (x) and a column (y).
    pub col_pitch: f64,
    pub row_pitch: f64,
    /// Side of a square hole.
    pub hole: f64,
    /// Thickness of the base plate and of the top plate.
    pub plate: f64,
    pub rgba: [f64; 4],
}

impl Params {
    /// The 2x5 rack for 50 mL tubes: 0.205 x 0.096 x 0.060 m, 30 mm holes at 36 mm.
    pub fn tube_rack() -> Params {
        Params {
            size: [0.205, 0.096, 0.060],
            rows: 2,
            cols: 5,
            col_pitch: 0.036,
            row_pitch: 0.036,
            hole: 0.030,
            plate: 0.006,
            rgba: [0.25, 0.45, 0.75, 1.0],
        }
    }

    /// The 6x10 rack for 1.5 mL tubes and cryovials: 11.2 mm holes.
    pub fn microtube_rack() -> Params {
        Params {
            size: [0.197, 0.085, 0.021],
            rows: 6,
            cols: 10,
            col_pitch: 0.017,
            row_pitch: 0.0125,
            hole: 0.0112,
            plate: 0.003,
            rgba: [0.85, 0.55, 0.2, 1.0],
        }
    }

    /// Centre of a slot's hole in the rack frame (x, y), from its name (`A1` .. `B5`).
    pub fn slot_xy(&self, slot: &str) -> Option<(f64, f64)> {
        let mut chars = slot.chars();
        let row = chars.next()?;
        let row = (row as u32).checked_sub('A' as u32)?;
        let col: u32 = chars.as_str().parse().ok()?;
        if row >= self.rows || col == 0 || col > self.cols {
            return None;
        }
        let x = (self.cols - 1) as f64 / 2.0 * self.col_pitch - (col - 1) as f64 * self.col_pitch;
        let y = -((self.rows - 1) as f64) / 2.0 * self.row_pitch + row as f64 * self.row_pitch;
        Some((x, y))
    }

    /// Height of the base plate's top (where tubes stand), rack frame.
    fn seat_z(&self) -> f64 {
        -self.size[2] / 2.0 + self.plate
    }

    /// Bars of the top plate: (centre, half size) in the rack frame.
    fn bars(&self) -> Vec<(Vec3, Vec3)> {
        let [l, w, h] = self.size;
        let z = h / 2.0 - self.plate / 2.0;
        let hp = self.plate / 2.0;
        let mut bars = Vec::new();
        // Lines between and beside the rows (full length) and between and beside the columns.
        let edges = |n: u32, pitch: f64, half: f64| -> Vec<(f64, f64)> {
            let mut cuts = vec![-half];
            for i in 0..n {
                let c = -((n - 1) as f64) / 2.0 * pitch + i as f64 * pitch;
                cuts.push(c - self.hole / 2.0);
                cuts.push(c + self.hole / 2.0);
            }
            cuts.push(half);
            cuts.chunks(2)
                .map(|p| (p[0], p[1]))
                .filter(|(a, b)| b - a > 1e-4)
                .collect()
        };
        for (a, b) in edges(self.rows, self.row_pitch, w / 2.0) {
            bars.push(([0.0, (a + b) / 2.0, z], [l / 2.0, (b - a) / 2.0, hp]));
        }
        for (a, b) in edges(self.cols, self.col_pitch, l / 2.0) {
            bars.push(([(a + b) / 2.0, 0.0, z], [(b - a) / 2.0, w / 2.0, hp]));
        }
        bars
    }

    /// The rack's geoms (base plate, top bars, end walls) with its centre at `centre` in the frame
    /// of the body they go in, named `{prefix}/...`: a rack on its own, or a block of wells built
    /// into an instrument (the thermal mixer's thermoblock).
    pub fn geoms(&self, prefix: &str, centre: Vec3) -> String {
        let [l, w, h] = self.size;
        let at = |p: Vec3| v3([p[0] + centre[0], p[1] + centre[1], p[2] + centre[2]]);
        let colour = crate::mjcf::rgba(self.rgba);
        let mut geoms = format!(
            r#"  <geom name="{prefix}/base_plate" type="box" size="{} {} {}" pos="{}" rgba="{colour}"/>
"#,
            l / 2.0,
            w / 2.0,
            self.plate / 2.0,
            at([0.0, 0.0, -h / 2.0 + self.plate / 2.0])
        );
        for (i, (c, s)) in self.bars().iter().enumerate() {
            geoms += &format!(
                r#"  <geom name="{prefix}/bar{i}" type="box" size="{}" pos="{}" rgba="{colour}"/>
"#,
                v3(*s),
                at(*c)
            );
        }
        // End walls carry the top plate (visual only: nothing reaches under the plate).
        for sx in [-1.0, 1.0] {
            geoms += &format!(
                r#"  <geom type="box" size="{} {} {}" pos="{}" rgba="{colour}" contype="0" conaffinity="0"/>
"#,
                self.plate / 2.0,
                w / 2.0,
                h / 2.0 - self.plate,
                at([sx * (l / 2.0 - self.plate / 2.0), 0.0, 0.0])
            );
        }
        geoms
    }

    /// Where a tube stands in `slot`, in the rack's own frame (centre of its footprint at
    /// mid-height).
    pub fn seat_in_rack(&self, slot: &str) -> Option<Vec3> {
        let (x, y) = self.slot_xy(slot)?;
        Some([x, y, self.seat_z()])
    }
}

impl Instrument for Params {
    fn fragment(&self, name: &str, placement: &Pose) -> Fragment {
        let geoms = self.geoms(name, [0.0; 3]);
        Fragment {
            worldbody: format!(
                "<body name=\"{name}/base\" {}>\n{geoms}</body>\n",
                pose_attrs(placement)
            ),
            ..Fragment::default()
        }
    }

    fn slot_seat(&self, slot: &str, s: &LabwareState) -> Option<Pose> {
        Some(s.pose * translation(self.seat_in_rack(slot)?))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn slots_follow_the_grid_and_bars_leave_the_holes_open() {
        let p = Params::tube_rack();
        assert_eq!(p.slot_xy("A1"), Some((0.072, -0.018)));
        let (x, y) = p.slot_xy("B5").unwrap();
        assert!((x + 0.072).abs() < 1e-12 && (y - 0.018).abs() < 1e-12);
        assert_eq!(p.slot_xy("C1"), None);
        assert_eq!(p.slot_xy("A6"), None);
        // No bar covers any hole centre.
        for slot in ["A1", "A3", "B2", "B5"] {
            let (x, y) = p.slot_xy(slot).unwrap();
            for (c, s) in p.bars() {
                let inside = (x - c[0]).abs() < s[0] && (y - c[1]).abs() < s[1];
                assert!(!inside, "{slot} is covered by a bar at {c:?}");
            }
        }
        // 3 lengthwise bars for 2 rows, 6 crosswise bars for 5 columns.
        assert_eq!(p.bars().len(), 9);
        assert!(Params::microtube_rack().slot_xy("F10").is_some());
        assert!(Params::microtube_rack().slot_xy("G1").is_none());
    }
}
