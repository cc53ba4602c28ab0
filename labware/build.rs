//! Embeds the published labware definitions the catalogue builds kinds from
//! (`embedded-definitions.txt`), read from the package `make setup` installs under `.deps`, and
//! checks each parses and forms a grid: a definition missing or malformed stops the build with
//! what to do, never a task that fails later.
// A build script speaks to Cargo through `cargo:` lines on stdout.
#![allow(clippy::print_stdout)]

// The library's module, whose `pub` items the library exports and this script does not.
#[allow(unreachable_pub)]
#[path = "src/definition.rs"]
#[allow(dead_code)]
mod definition;

use std::fmt::Write as _;
use std::path::PathBuf;

fn main() {
    println!("cargo:rerun-if-changed=embedded-definitions.txt");
    println!("cargo:rerun-if-changed=src/definition.rs");
    println!("cargo:rerun-if-env-changed=AUTOBIO_DEPS");
    // `include_str!` resolves a relative path against the generated file: make it absolute.
    let deps = PathBuf::from(std::env::var("AUTOBIO_DEPS").unwrap_or_else(|_| "../.deps".into()));
    let deps = std::fs::canonicalize(&deps).unwrap_or(deps);
    let installed = definition::Installed::under(&deps);
    let list = std::fs::read_to_string("embedded-definitions.txt")
        .expect("labware/embedded-definitions.txt is part of the crate");
    let mut out = String::from(
        "/// The embedded definitions: (URI, JSON text).\npub const EMBEDDED: &[(&str, &str)] = &[\n",
    );
    for uri in list
        .lines()
        .map(str::trim)
        .filter(|l| !l.is_empty() && !l.starts_with('#'))
    {
        let checked = installed.load(uri).and_then(|def| def.grid().map(|_| def));
        let def = match checked {
            Ok(def) => def,
            Err(e) => panic!("{e}"),
        };
        assert_eq!(
            def.uri(),
            uri,
            "the file for {uri} names itself {}",
            def.uri()
        );
        let path = installed.path(uri).expect("loaded above");
        println!("cargo:rerun-if-changed={}", path.display());
        writeln!(
            out,
            "    ({uri:?}, include_str!({:?})),",
            path.display().to_string()
        )
        .unwrap();
    }
    out.push_str("];\n");
    let dest = PathBuf::from(std::env::var("OUT_DIR").unwrap()).join("embedded_definitions.rs");
    std::fs::write(dest, out).unwrap();
}
