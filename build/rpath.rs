//! Build script shared by every package that links MuJoCo: embeds the absolute path of the
//! unpacked MuJoCo library (from `.cargo/config.toml`'s `MUJOCO_DYNAMIC_LINK_DIR`) as an rpath,
//! so binaries and tests run without `LD_LIBRARY_PATH`. It does nothing else.
// A build script speaks to Cargo through `cargo:` lines on stdout.
#![allow(clippy::print_stdout)]
pub(crate) fn main() {
    println!("cargo:rerun-if-env-changed=MUJOCO_DYNAMIC_LINK_DIR");
    if let Ok(dir) = std::env::var("MUJOCO_DYNAMIC_LINK_DIR") {
        println!("cargo:rustc-link-arg=-Wl,-rpath,{dir}");
    }
}
