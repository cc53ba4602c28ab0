//! Build script of the Python extension: the MuJoCo rpath every package that links MuJoCo embeds
//! (`build/rpath.rs`), and the shipped protocols (`protocols/**/*.toml`) compiled into the
//! extension, so that an installed wheel names every shipped task without a checkout.
// A build script speaks to Cargo through `cargo:` lines on stdout.
#![allow(clippy::print_stdout)]
#[path = "../build/rpath.rs"]
mod rpath;
#[path = "../build/toml_files.rs"]
mod toml_files;

use std::path::{Path, PathBuf};

fn main() {
    rpath::main();
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("../protocols");
    let root = root
        .canonicalize()
        .expect("the checkout's protocols/ folder");
    let mut files = Vec::new();
    toml_files::walk(&root, &mut files);
    files.sort();
    let mut table = String::from("pub(crate) static SHIPPED: &[(&str, &str)] = &[\n");
    for f in &files {
        let rel = f.strip_prefix(&root).expect("under the root");
        table += &format!(
            "    ({:?}, include_str!({:?})),\n",
            rel.to_string_lossy(),
            f.display().to_string()
        );
    }
    table += "];\n";
    let out = PathBuf::from(std::env::var("OUT_DIR").expect("cargo sets OUT_DIR"));
    std::fs::write(out.join("protocols.rs"), table).expect("OUT_DIR is writable");
}
