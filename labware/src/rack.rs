//! Racks: a static block with a grid of square holes that hold tubes upright (the `tube_rack` for
//! 50 and 15 mL tubes, the `microtube_rack` for 1.5 mL tubes and cryovials). Collision is boxes
//! only: a base plate the tubes stand on and a top plate made of bars between the holes, so a
//! seated tube is held by cheap box contacts.
//!
//! A rack may also be made from a published definition ([`Params::from_definition`]): its
//! footprint, where its places stand and how high a tube's bottom rests come from the definition;
//! the body holding the tubes (plates, bars, holes sized to our tubes) is ours.
//!
//! Frame: origin at the centre of the rack's footprint at mid-height, +z up; columns run along +x
//! (column 1 at the +x end), rows along +y (row A at the -y side): a definition's frame turned
//! half a turn about z (its column 1 is at its left, row A at its back). Dimensions from
//! `upstream-autobio.md` §11.3 (the `centrifuge_10slot` rack's 50 mL grid).

use crate::definition::{Definition, DefinitionError};
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
    /// The grid's centre from the footprint's centre (x, y); zero for our own racks.
    #[serde(default, skip_serializing_if = "is_zero")]
    pub grid_offset: [f64; 2],
    /// Thickness of the base plate, where it differs from the top plate's: how high a tube's
    /// bottom stands (a definition's well bottom).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub base: Option<f64>,
    /// The published definition the geometry came from (`namespace/loadName/version`).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub definition: Option<String>,
}

fn is_zero(v: &[f64; 2]) -> bool {
    *v == [0.0, 0.0]
}

/// Room around a tube in a definition rack's hole (m): the 50 mL rack's 1 mm on the diameter.
const HOLE_CLEARANCE: f64 = 0.001;
/// The top plate of a definition rack (m).
const DEFINED_PLATE: f64 = 0.003;
/// A rack with more places than this is crowded: its small tubes' walls touch its bars at many
/// points at once (a 96-place block's three PCR tubes, with a pipette's tip in one, made 433
/// contacts and 1,308 constraint rows, past MuJoCo's default 15 MB arena), so its scene asks for
/// [`CROWDED_ARENA_MB`]. The `microtube_rack`'s 60 places are not crowded (its scenes stay as
/// they were); the 96-place block is.
const CROWDED_PLACES: u32 = 60;
const CROWDED_ARENA_MB: usize = 64;
/// A definition rack's colour: Opentrons' grey polymer.
const DEFINED_RGBA: [f64; 4] = [0.78, 0.8, 0.82, 1.0];

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
            grid_offset: [0.0, 0.0],
            base: None,
            definition: None,
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
            grid_offset: [0.0, 0.0],
            base: None,
            definition: None,
        }
    }

    /// A rack from a published definition, for tubes of outer radius `tube_radius`: the
    /// definition's footprint, its wells' grid as places (a tube rack's wells are the insides of
    /// the tubes it holds), the base plate as high as a tube's bottom rests, holes a millimetre
    /// wider than the tube, and a top plate holding the tube at half its depth.
    pub fn from_definition(def: &Definition, tube_radius: f64) -> Result<Params, DefinitionError> {
        let grid = def.grid()?;
        let hole = 2.0 * tube_radius + HOLE_CLEARANCE;
        // The pitch between neighbours, along whichever of rows and columns has more than one.
        let pitch = [(grid.cols, grid.col_pitch), (grid.rows, grid.row_pitch)]
            .iter()
            .filter(|(n, _)| *n > 1)
            .map(|(_, p)| *p)
            .fold(f64::INFINITY, f64::min);
        if hole >= pitch {
            return Err(DefinitionError::TooClose {
                uri: def.uri(),
                pitch_mm: pitch * 1e3,
                tube_mm: 2e3 * tube_radius,
            });
        }
        let mm = 1e-3;
        Ok(Params {
            size: [
                def.dimensions.x_dimension * mm,
                def.dimensions.y_dimension * mm,
                grid.bottom + grid.depth / 2.0,
            ],
            rows: grid.rows,
            cols: grid.cols,
            col_pitch: grid.col_pitch,
            row_pitch: grid.row_pitch,
            hole,
            plate: DEFINED_PLATE,
            rgba: DEFINED_RGBA,
            // Half a turn about z: the definition's +x and +y are our -x and -y.
            grid_offset: [-grid.centre_offset[0], -grid.centre_offset[1]],
            base: Some(grid.bottom),
            definition: Some(def.uri()),
        })
    }

    /// The rack of a catalogue kind with a `definition`, for the widest tube the kind accepts
    /// (the definition is embedded and checked at build time, and a test makes every such kind).
    pub fn defined(kind: &str) -> Params {
        let k = crate::kind(kind).expect("a registry kind is catalogued");
        let uri = k.definition.expect("a defined rack's kind names its definition");
        let def = crate::published::definition(uri).expect("every catalogue definition is embedded");
        let radius = k
            .slots
            .iter()
            .flat_map(|s| s.accepts)
            .filter_map(|accepted| match crate::Model::for_kind(accepted) {
                Some(crate::Model::Tube(t)) => Some(t.radius),
                _ => None,
            })
            .fold(0.0, f64::max);
        Params::from_definition(&def, radius).expect("a catalogued definition fits its tubes")
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
        Some((x + self.grid_offset[0], y + self.grid_offset[1]))
    }

    /// Height of the base plate's top (where tubes stand) over the rack's bottom.
    pub fn seat_z_from_bottom(&self) -> f64 {
        self.base_plate()
    }

    /// The arena a scene with this rack asks MuJoCo for (MB; 0: the default).
    pub fn arena_mb(&self) -> usize {
        if self.rows * self.cols > CROWDED_PLACES {
            CROWDED_ARENA_MB
        } else {
            0
        }
    }

    /// Height of the base plate's top (where tubes stand), rack frame.
    fn seat_z(&self) -> f64 {
        -self.size[2] / 2.0 + self.base_plate()
    }

    fn base_plate(&self) -> f64 {
        self.base.unwrap_or(self.plate)
    }

    /// Bars of the top plate: (centre, half size) in the rack frame.
    fn bars(&self) -> Vec<(Vec3, Vec3)> {
        let [l, w, h] = self.size;
        let z = h / 2.0 - self.plate / 2.0;
        let hp = self.plate / 2.0;
        let mut bars = Vec::new();
        // Lines between and beside the rows (full length) and between and beside the columns.
        let edges = |n: u32, pitch: f64, half: f64, offset: f64| -> Vec<(f64, f64)> {
            let mut cuts = vec![-half];
            for i in 0..n {
                let c = -((n - 1) as f64) / 2.0 * pitch + i as f64 * pitch + offset;
                cuts.push(c - self.hole / 2.0);
                cuts.push(c + self.hole / 2.0);
            }
            cuts.push(half);
            cuts.chunks(2)
                .map(|p| (p[0], p[1]))
                .filter(|(a, b)| b - a > 1e-4)
                .collect()
        };
        for (a, b) in edges(self.rows, self.row_pitch, w / 2.0, self.grid_offset[1]) {
            bars.push(([0.0, (a + b) / 2.0, z], [l / 2.0, (b - a) / 2.0, hp]));
        }
        for (a, b) in edges(self.cols, self.col_pitch, l / 2.0, self.grid_offset[0]) {
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
            self.base_plate() / 2.0,
            at([0.0, 0.0, -h / 2.0 + self.base_plate() / 2.0])
        );
        for (i, (c, s)) in self.bars().iter().enumerate() {
            geoms += &format!(
                r#"  <geom name="{prefix}/bar{i}" type="box" size="{}" pos="{}" rgba="{colour}"/>
"#,
                v3(*s),
                at(*c)
            );
        }
        // End walls carry the top plate (visual only: nothing reaches under the plate), from the
        // base plate up.
        let (wall_z, wall_half) = match self.base {
            None => (0.0, h / 2.0 - self.plate),
            Some(base) => ((base - self.plate) / 2.0, (h - self.plate - base) / 2.0),
        };
        for sx in [-1.0, 1.0] {
            geoms += &format!(
                r#"  <geom type="box" size="{} {} {}" pos="{}" rgba="{colour}" contype="0" conaffinity="0"/>
"#,
                self.plate / 2.0,
                w / 2.0,
                wall_half,
                at([sx * (l / 2.0 - self.plate / 2.0), 0.0, wall_z])
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
    fn footprint_radius(&self) -> f64 {
        0.5 * self.size[0].hypot(self.size[1])
    }

    fn fragment(&self, name: &str, placement: &Pose) -> Fragment {
        let geoms = self.geoms(name, [0.0; 3]);
        Fragment {
            worldbody: format!(
                "<body name=\"{name}/base\" {}>\n{geoms}</body>\n",
                pose_attrs(placement)
            ),
            arena_mb: self.arena_mb(),
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

    /// Every kind made from a published definition: its catalogue layout is the definition's
    /// grid, and each place stands where its well is (turned half a turn, about the footprint's
    /// centre), a tube's bottom resting at the well's bottom.
    #[test]
    fn defined_racks_put_every_place_where_the_definition_puts_its_well() {
        let defined: Vec<_> = crate::KINDS.iter().filter(|k| k.definition.is_some()).collect();
        assert!(defined.len() >= 2);
        for k in defined {
            let def = crate::published::definition(k.definition.unwrap()).unwrap();
            let p = Params::defined(k.name);
            let slots = k.slots.unwrap();
            assert_eq!(
                slots.layout,
                crate::SlotLayout::Grid { rows: p.rows, cols: p.cols },
                "{}",
                k.name
            );
            let [xd, yd] = [def.dimensions.x_dimension, def.dimensions.y_dimension];
            for name in slots.layout.names() {
                let well = def.wells[&name];
                let seat = p.seat_in_rack(&name).unwrap();
                let (x, y) = (-(well.x - xd / 2.0) * 1e-3, -(well.y - yd / 2.0) * 1e-3);
                assert!(
                    (seat[0] - x).abs() < 6e-5 && (seat[1] - y).abs() < 6e-5,
                    "{} {name}: {seat:?} against ({x}, {y})",
                    k.name
                );
                assert!((seat[2] + p.size[2] / 2.0 - well.z * 1e-3).abs() < 1e-9);
            }
            // No bar covers a hole: each place has its hole's width clear around it.
            for name in slots.layout.names() {
                let (x, y) = p.slot_xy(&name).unwrap();
                for (c, s) in p.bars() {
                    let inside = (x - c[0]).abs() < s[0] + p.hole / 2.0 - 1e-9
                        && (y - c[1]).abs() < s[1] + p.hole / 2.0 - 1e-9;
                    assert!(!inside, "{} {name}: a bar at {c:?} narrows the hole", k.name);
                }
            }
        }
    }

    /// A definition with one row of three wells `pitch_mm` apart, for tubes to be sized against.
    fn one_row(pitch_mm: f64) -> Definition {
        let well = |x: f64| {
            format!(
                r#"{{"depth": 40, "totalLiquidVolume": 1500, "shape": "circular", "diameter": 10, "x": {x}, "y": 40, "z": 10}}"#
            )
        };
        let text = format!(
            r#"{{"schemaVersion": 2, "namespace": "test", "version": 1,
               "metadata": {{"displayName": "t", "displayCategory": "tubeRack"}},
               "parameters": {{"loadName": "row", "format": "irregular", "isTiprack": false}},
               "dimensions": {{"xDimension": 100, "yDimension": 80, "zDimension": 50}},
               "ordering": [["A1"], ["A2"], ["A3"]],
               "wells": {{"A1": {}, "A2": {}, "A3": {}}}}}"#,
            well(50.0 - pitch_mm),
            well(50.0),
            well(50.0 + pitch_mm)
        );
        Definition::parse(&text, "row").unwrap()
    }

    /// A single row is sized by its column pitch alone (its row pitch is none), and places too
    /// close for the tubes are refused with the pitch and the tube's width.
    #[test]
    fn a_row_of_places_is_sized_by_its_one_pitch() {
        let p = Params::from_definition(&one_row(20.0), 0.00535).unwrap();
        assert_eq!((p.rows, p.cols), (1, 3));
        let (x1, _) = p.slot_xy("A1").unwrap();
        let (x3, _) = p.slot_xy("A3").unwrap();
        assert!((x1 - x3 - 0.040).abs() < 1e-9, "A1 at +x, 40 mm from A3");
        let err = Params::from_definition(&one_row(11.0), 0.00535).unwrap_err();
        assert!(
            matches!(err, DefinitionError::TooClose { .. }),
            "{err}"
        );
        assert!(err.to_string().contains("11.0 mm apart"), "{err}");
    }
}
