//! Compiles the one-function C++ shim over OMPL 1.5 (`cpp/shim.cpp`) and links `libompl`
//! (Debian's `libompl-dev`, installed by `make setup`). Its headers sit outside the default
//! include path and need Eigen's; `ompl.pc` is unusable, so no pkg-config.
// A build script speaks to Cargo through `cargo:` lines on stdout.
#![allow(clippy::print_stdout)]
fn main() {
    println!("cargo:rerun-if-changed=cpp/shim.cpp");
    // Debian's libompl-dev: 1.5 (bookworm); a later 1.x keeps the same API.
    let ompl = std::fs::read_dir("/usr/include")
        .into_iter()
        .flatten()
        .flatten()
        .map(|e| e.path())
        .filter(|p| {
            p.file_name()
                .and_then(|n| n.to_str())
                .is_some_and(|n| n.starts_with("ompl-1."))
        })
        .max()
        .unwrap_or_else(|| {
            panic!("OMPL headers not found under /usr/include/ompl-1.*: run `make setup` (it installs libompl-dev)")
        });
    cc::Build::new()
        .cpp(true)
        .std("c++17")
        .include(&ompl)
        .include("/usr/include/eigen3")
        .flag_if_supported("-Wno-unused-parameter")
        .flag_if_supported("-Wno-deprecated-copy")
        .opt_level(2)
        .file("cpp/shim.cpp")
        .compile("autobio_ompl_shim");
    println!("cargo:rustc-link-lib=dylib=ompl");
}
