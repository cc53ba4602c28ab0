//! Build script of the `leaderboard` package: the shipped suites (`suites/*.toml`) and protocols
//! (`protocols/**/*.toml`) compiled in, so that `leaderboard verify` and `audit` know what was
//! shipped wherever the binary runs, with no checkout beside it.
// A build script speaks to Cargo through `cargo:` lines on stdout.
#![allow(clippy::print_stdout)]
#[path = "../build/toml_files.rs"]
mod toml_files;

use std::path::{Path, PathBuf};

fn main() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("..")
        .canonicalize()
        .expect("the checkout's root");
    let mut files = Vec::new();
    for top in ["suites", "protocols"] {
        toml_files::walk(&root.join(top), &mut files);
    }
    files.sort();
    let mut table = String::from("pub static SHIPPED: &[(&str, &[u8])] = &[\n");
    for f in &files {
        let rel = f.strip_prefix(&root).expect("under the root");
        table += &format!(
            "    ({:?}, include_bytes!({:?})),\n",
            rel.to_string_lossy().replace('\\', "/"),
            f.display().to_string()
        );
    }
    table += "];\n";
    let out = PathBuf::from(std::env::var("OUT_DIR").expect("cargo sets OUT_DIR"));
    std::fs::write(out.join("shipped.rs"), table).expect("OUT_DIR is writable");
}
