//! The published labware definitions built into the crate (`embedded-definitions.txt`, embedded
//! by `build.rs` from the installed package): what the catalogue's definition-backed kinds are
//! made from, with no file read at compile or run time. Reading other installed definitions is
//! [`crate::definition::Installed`]'s.

use crate::definition::Definition;

include!(concat!(env!("OUT_DIR"), "/embedded_definitions.rs"));

/// The built-in definition a URI names; `None` if it is not embedded.
pub fn definition(uri: &str) -> Option<Definition> {
    let (_, text) = EMBEDDED.iter().find(|(u, _)| *u == uri)?;
    // The build script parsed and checked every embedded text: this cannot fail.
    Some(Definition::parse(text, uri).expect("embedded definitions are checked by build.rs"))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::definition::{DefinitionError, Installed};
    use std::path::Path;

    /// The package `make setup` installed, read at run time as an importer reads it: a 96-well
    /// PCR plate is an 8x12 grid at 9 mm, Opentrons' mixed 50/15 mL rack is refused as no grid,
    /// and each embedded definition is the installed file.
    #[test]
    fn installed_definitions_read_from_the_package() {
        let installed = Installed::under(Path::new(env!("AUTOBIO_DEPS")));
        let plate = installed
            .load("opentrons/nest_96_wellplate_100ul_pcr_full_skirt/2")
            .unwrap();
        let g = plate.grid().unwrap();
        assert_eq!((g.rows, g.cols), (8, 12));
        assert!((g.col_pitch - 0.009).abs() < 1e-9 && (g.row_pitch - 0.009).abs() < 1e-9);
        assert_eq!(g.capacity_ul, 100.0);
        let mixed = installed
            .load("opentrons/opentrons_10_tuberack_falcon_4x50ml_6x15ml_conical/2")
            .unwrap();
        assert!(
            matches!(mixed.grid(), Err(DefinitionError::NotAGrid { .. })),
            "{:?}",
            mixed.grid()
        );
        for (uri, _) in EMBEDDED {
            assert_eq!(installed.load(uri).unwrap(), definition(uri).unwrap());
        }
    }
}
