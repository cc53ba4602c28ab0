//! Labware definitions in Opentrons' published format (labware schema 2, the JSON files of the
//! `opentrons-shared-data` package, which `make setup` installs under
//! `.deps/opentrons-shared-data`): the typed definition, the regular grid its wells form, and
//! where installed definitions are found by URI (`namespace/loadName/version`).
//!
//! A definition gives a footprint, well positions, depths and inner diameters, in millimetres
//! from the footprint's front-left-bottom corner. What a well is depends on the labware: a
//! plate's well is its cavity, a tube rack's "well" is the inside of the tube standing in it (its
//! bottom is where the tube stands). Read here: dimensions, wells, ordering and parameters; not
//! read: stacking offsets, gripper heights, inner-geometry sections, liquid classes. This module
//! generates no MJCF (the racks built from a definition are `rack.rs`'s) and depends on serde alone,
//! so the crate's build script can check the definitions it embeds with it.

use serde::Deserialize;
use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

/// Where `make setup` unpacks the package's definitions, under the dependencies folder.
pub const INSTALLED_DIR: &str =
    "opentrons-shared-data/opentrons_shared_data/data/labware/definitions/2";

/// Two wells of one column (or row) are on one grid line when their centres differ by less than
/// this (mm): published definitions place wells to 0.01 mm.
const GRID_SLACK_MM: f64 = 0.05;

/// A labware definition (schema 2). Unknown fields are ignored: the schema grows by addition.
#[derive(Clone, Debug, PartialEq, Deserialize)]
#[serde(rename_all = "camelCase")]
pub struct Definition {
    pub schema_version: u32,
    pub namespace: String,
    pub version: u32,
    pub metadata: Metadata,
    pub parameters: Parameters,
    pub dimensions: Dimensions,
    /// Wells by column, each column from row A (at the back) forward, as the definition lists
    /// it (A1, B1, ...).
    pub ordering: Vec<Vec<String>>,
    pub wells: BTreeMap<String, Well>,
}

#[derive(Clone, Debug, PartialEq, Deserialize)]
#[serde(rename_all = "camelCase")]
pub struct Metadata {
    pub display_name: String,
    pub display_category: String,
}

#[derive(Clone, Debug, PartialEq, Deserialize)]
#[serde(rename_all = "camelCase")]
pub struct Parameters {
    pub load_name: String,
    pub format: String,
    pub is_tiprack: bool,
    #[serde(default)]
    pub tip_length: Option<f64>,
}

/// The footprint and height (mm).
#[derive(Clone, Copy, Debug, PartialEq, Deserialize)]
#[serde(rename_all = "camelCase")]
pub struct Dimensions {
    pub x_dimension: f64,
    pub y_dimension: f64,
    pub z_dimension: f64,
}

/// One well: its centre (x, y) and bottom (z) from the labware's front-left-bottom corner, its
/// depth, capacity and cross-section (mm, µL).
#[derive(Clone, Copy, Debug, PartialEq, Deserialize)]
#[serde(rename_all = "camelCase")]
pub struct Well {
    pub x: f64,
    pub y: f64,
    pub z: f64,
    pub depth: f64,
    pub total_liquid_volume: f64,
    #[serde(flatten)]
    pub shape: WellShape,
}

#[derive(Clone, Copy, Debug, PartialEq, Deserialize)]
#[serde(tag = "shape", rename_all = "camelCase")]
pub enum WellShape {
    #[serde(rename_all = "camelCase")]
    Circular { diameter: f64 },
    #[serde(rename_all = "camelCase")]
    Rectangular { x_dimension: f64, y_dimension: f64 },
}

impl WellShape {
    /// The widest the well is across (mm): a circle's diameter, a rectangle's diagonal.
    pub fn span_mm(&self) -> f64 {
        match *self {
            WellShape::Circular { diameter } => diameter,
            WellShape::Rectangular {
                x_dimension,
                y_dimension,
            } => x_dimension.hypot(y_dimension),
        }
    }
}

/// Wells on a regular grid: rows `A..` from the back forward, columns `1..` left to right, all
/// wells alike and standing at one height (metres from here on).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Grid {
    pub rows: u32,
    pub cols: u32,
    /// Distance between neighbouring columns' centres (along the definition's x) and rows'
    /// (along its y).
    pub col_pitch: f64,
    pub row_pitch: f64,
    /// The grid's centre, from the footprint's centre, in the definition's x (right) and y (back).
    pub centre_offset: [f64; 2],
    /// The wells' bottom above the labware's base, their depth and widest span across.
    pub bottom: f64,
    pub depth: f64,
    pub span: f64,
    pub capacity_ul: f64,
}

/// Why a definition cannot be read or used.
#[derive(Debug, thiserror::Error)]
pub enum DefinitionError {
    #[error("labware definition {uri} is not installed (looked for {path}; run `make setup`)")]
    NotInstalled { uri: String, path: PathBuf },
    #[error("labware definition URI `{0}` is not `namespace/loadName/version`")]
    BadUri(String),
    #[error("cannot read labware definition {path}: {source}")]
    Io {
        path: PathBuf,
        source: std::io::Error,
    },
    #[error("labware definition {what} is not valid schema-2 JSON: {source}")]
    Json {
        what: String,
        source: serde_json::Error,
    },
    #[error("labware definition {uri} has schema version {found}; only 2 is read")]
    SchemaVersion { uri: String, found: u32 },
    #[error("labware definition {uri} lists well `{well}` in its ordering but does not define it")]
    UndefinedWell { uri: String, well: String },
    #[error("labware definition {uri} is not a regular grid: {reason}")]
    NotAGrid { uri: String, reason: String },
    #[error(
        "labware definition {uri} places its wells {pitch_mm:.1} mm apart, too close for tubes {tube_mm:.1} mm across"
    )]
    TooClose {
        uri: String,
        pitch_mm: f64,
        tube_mm: f64,
    },
}

impl Definition {
    /// Parses a definition's JSON; `what` names it in errors (a path or a URI).
    pub fn parse(text: &str, what: &str) -> Result<Definition, DefinitionError> {
        let def: Definition =
            serde_json::from_str(text).map_err(|source| DefinitionError::Json {
                what: what.to_string(),
                source,
            })?;
        if def.schema_version != 2 {
            return Err(DefinitionError::SchemaVersion {
                uri: def.uri(),
                found: def.schema_version,
            });
        }
        if let Some(well) = def
            .ordering
            .iter()
            .flatten()
            .find(|w| !def.wells.contains_key(*w))
        {
            return Err(DefinitionError::UndefinedWell {
                uri: def.uri(),
                well: well.clone(),
            });
        }
        Ok(def)
    }

    /// `namespace/loadName/version`, as Opentrons protocols name it (`definitionUri`).
    pub fn uri(&self) -> String {
        format!(
            "{}/{}/{}",
            self.namespace, self.parameters.load_name, self.version
        )
    }

    /// The wells as a regular grid, or why they are not one (columns of unequal length, a well
    /// off its column's or row's line, uneven pitches, wells of different sizes or heights, or
    /// names that are not `<row letter><column number>` in place).
    pub fn grid(&self) -> Result<Grid, DefinitionError> {
        let uri = self.uri();
        let not = |reason: String| DefinitionError::NotAGrid {
            uri: uri.clone(),
            reason,
        };
        let cols = self.ordering.len();
        let rows = self.ordering.first().map_or(0, Vec::len);
        if cols == 0 || rows == 0 || rows > 26 {
            return Err(not(format!("{rows} rows by {cols} columns")));
        }
        if let Some((c, col)) = self
            .ordering
            .iter()
            .enumerate()
            .find(|(_, col)| col.len() != rows)
        {
            return Err(not(format!(
                "column {} has {} wells, column 1 has {rows}",
                c + 1,
                col.len()
            )));
        }
        let well = |r: usize, c: usize| &self.wells[&self.ordering[c][r]];
        let first = well(0, 0);
        let pitch = |n: usize, at: &dyn Fn(usize) -> f64| -> f64 {
            if n < 2 {
                0.0
            } else {
                (at(n - 1) - at(0)) / (n - 1) as f64
            }
        };
        let col_pitch = pitch(cols, &|c| well(0, c).x);
        // Rows are listed back to front in y (A at the back): the pitch is positive going A->B.
        let row_pitch = pitch(rows, &|r| first.y - well(r, 0).y);
        for (n, p, what) in [
            (cols, col_pitch, "columns 1, 2, .. left to right"),
            (rows, row_pitch, "rows A, B, .. back to front"),
        ] {
            if n > 1 && p <= GRID_SLACK_MM {
                return Err(not(format!(
                    "its {what} are not in order ({p:.2} mm apart)"
                )));
            }
        }
        for (c, column) in self.ordering.iter().enumerate() {
            for (r, name) in column.iter().enumerate() {
                let w = &self.wells[name];
                let expected = format!("{}{}", (b'A' + r as u8) as char, c + 1);
                if *name != expected {
                    return Err(not(format!(
                        "well `{name}` stands where `{expected}` would"
                    )));
                }
                let (x, y) = (
                    first.x + c as f64 * col_pitch,
                    first.y - r as f64 * row_pitch,
                );
                if (w.x - x).abs() > GRID_SLACK_MM || (w.y - y).abs() > GRID_SLACK_MM {
                    return Err(not(format!(
                        "well `{name}` is at ({}, {}) mm, off the grid's ({x:.2}, {y:.2})",
                        w.x, w.y
                    )));
                }
                if (w.z - first.z).abs() > GRID_SLACK_MM
                    || (w.depth - first.depth).abs() > GRID_SLACK_MM
                    || (w.shape.span_mm() - first.shape.span_mm()).abs() > GRID_SLACK_MM
                {
                    return Err(not(format!(
                        "well `{name}` differs in size or height from A1"
                    )));
                }
            }
        }
        let last = well(rows - 1, cols - 1);
        let mm = 1e-3;
        Ok(Grid {
            rows: rows as u32,
            cols: cols as u32,
            col_pitch: col_pitch * mm,
            row_pitch: row_pitch * mm,
            centre_offset: [
                ((first.x + last.x) / 2.0 - self.dimensions.x_dimension / 2.0) * mm,
                ((first.y + last.y) / 2.0 - self.dimensions.y_dimension / 2.0) * mm,
            ],
            bottom: first.z * mm,
            depth: first.depth * mm,
            span: first.shape.span_mm() * mm,
            capacity_ul: first.total_liquid_volume,
        })
    }
}

/// The definitions installed under a dependencies folder (`.deps`), by URI.
#[derive(Clone, Debug)]
pub struct Installed {
    dir: PathBuf,
}

impl Installed {
    /// The definitions under `deps` (the folder `make setup` fills).
    pub fn under(deps: &Path) -> Installed {
        Installed {
            dir: deps.join(INSTALLED_DIR),
        }
    }

    /// The file a URI names: `<dir>/<loadName>/<version>.json`, for the `opentrons` namespace
    /// (the one the package publishes).
    pub fn path(&self, uri: &str) -> Result<PathBuf, DefinitionError> {
        let bad = || DefinitionError::BadUri(uri.to_string());
        let mut parts = uri.split('/');
        let (Some(namespace), Some(load_name), Some(version), None) =
            (parts.next(), parts.next(), parts.next(), parts.next())
        else {
            return Err(bad());
        };
        let plain = |s: &str| {
            !s.is_empty()
                && s.chars()
                    .all(|c| c.is_ascii_alphanumeric() || matches!(c, '_' | '.' | '-'))
                && s != "."
                && s != ".."
        };
        if !plain(namespace) || !plain(load_name) || version.parse::<u32>().is_err() {
            return Err(bad());
        }
        let path = self.dir.join(load_name).join(format!("{version}.json"));
        if namespace != "opentrons" || !path.is_file() {
            return Err(DefinitionError::NotInstalled {
                uri: uri.to_string(),
                path,
            });
        }
        Ok(path)
    }

    /// Reads and parses the definition a URI names.
    pub fn load(&self, uri: &str) -> Result<Definition, DefinitionError> {
        let path = self.path(uri)?;
        let text = std::fs::read_to_string(&path).map_err(|source| DefinitionError::Io {
            path: path.clone(),
            source,
        })?;
        Definition::parse(&text, &path.display().to_string())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A 2x3 rack written for the test: wells 20 mm apart, A at the back.
    fn rack_json(b2_x: f64) -> String {
        let well = |x: f64, y: f64| {
            format!(
                r#"{{"depth": 30, "totalLiquidVolume": 1500, "shape": "circular", "diameter": 10, "x": {x}, "y": {y}, "z": 5}}"#
            )
        };
        format!(
            r#"{{"schemaVersion": 2, "namespace": "test", "version": 1,
               "metadata": {{"displayName": "t", "displayCategory": "tubeRack"}},
               "parameters": {{"loadName": "t_6", "format": "irregular", "isTiprack": false}},
               "dimensions": {{"xDimension": 100, "yDimension": 60, "zDimension": 40}},
               "ordering": [["A1", "B1"], ["A2", "B2"], ["A3", "B3"]],
               "wells": {{"A1": {}, "B1": {}, "A2": {}, "B2": {}, "A3": {}, "B3": {}}}}}"#,
            well(30.0, 40.0),
            well(30.0, 20.0),
            well(50.0, 40.0),
            well(b2_x, 20.0),
            well(70.0, 40.0),
            well(70.0, 20.0),
        )
    }

    #[test]
    fn a_regular_rack_is_a_grid_in_metres_about_its_footprint() {
        let def = Definition::parse(&rack_json(50.0), "test").unwrap();
        assert_eq!(def.uri(), "test/t_6/1");
        let g = def.grid().unwrap();
        assert_eq!((g.rows, g.cols), (2, 3));
        assert!((g.col_pitch - 0.020).abs() < 1e-12 && (g.row_pitch - 0.020).abs() < 1e-12);
        // Grid centre (50, 30) mm against the footprint's (50, 30): no offset.
        assert!(g.centre_offset.iter().all(|v| v.abs() < 1e-12));
        assert!((g.bottom - 0.005).abs() < 1e-12 && (g.span - 0.010).abs() < 1e-12);
    }

    #[test]
    fn a_well_off_its_line_is_refused_with_its_name() {
        let def = Definition::parse(&rack_json(53.0), "test").unwrap();
        let err = def.grid().unwrap_err().to_string();
        assert!(
            err.contains("`B2`") && err.contains("off the grid"),
            "{err}"
        );
    }

    /// Columns listed right to left (a pitch that is not positive) are no grid we can place.
    #[test]
    fn columns_out_of_order_are_refused() {
        let text = rack_json(50.0).replace(
            r#"[["A1", "B1"], ["A2", "B2"], ["A3", "B3"]]"#,
            r#"[["A3", "B3"], ["A2", "B2"], ["A1", "B1"]]"#,
        );
        let def = Definition::parse(&text, "test").unwrap();
        let err = def.grid().unwrap_err().to_string();
        assert!(err.contains("not in order"), "{err}");
    }

    #[test]
    fn broken_json_and_missing_wells_are_errors() {
        let err = Definition::parse("{\"schemaVersion\": 2", "x.json").unwrap_err();
        assert!(matches!(err, DefinitionError::Json { .. }), "{err}");
        let text = rack_json(50.0).replace(r#""A3", "B3""#, r#""A3", "C9""#);
        let err = Definition::parse(&text, "x.json").unwrap_err();
        assert!(err.to_string().contains("`C9`"), "{err}");
        let text = rack_json(50.0).replace(r#""schemaVersion": 2"#, r#""schemaVersion": 3"#);
        let err = Definition::parse(&text, "x.json").unwrap_err();
        assert!(matches!(
            err,
            DefinitionError::SchemaVersion { found: 3, .. }
        ));
    }

    #[test]
    fn uris_are_checked_before_any_path_is_made() {
        let installed = Installed::under(Path::new("/nonexistent"));
        for bad in [
            "a/b",
            "opentrons/../x/1",
            "opentrons/x/v1",
            "a/b/1/2",
            "opentrons//1",
        ] {
            assert!(
                matches!(installed.path(bad), Err(DefinitionError::BadUri(_))),
                "{bad}"
            );
        }
        assert!(matches!(
            installed.path("opentrons/nest_96_wellplate_100ul_pcr_full_skirt/2"),
            Err(DefinitionError::NotInstalled { .. })
        ));
    }
}
