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
