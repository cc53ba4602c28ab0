//! Compiles the one-function C++ shim over OMPL 1.5 (`cpp/shim.cpp`) and links `libompl`
//! (Debian's `libompl-dev`, installed by `make setup`). Its headers sit outside the default
//! include path and need Eigen's; `ompl.pc` is unusable, so no pkg-config.
fn main() {
    println!("cargo:rerun-if-changed=cpp/shim.cpp");
    let ompl = std::path::Path::new("/usr/include/ompl-1.5");
    if !ompl.exists() {
        panic!(
            "OMPL 1.5 headers not found at {}: run `make setup` (it installs libompl-dev)",
            ompl.display()
        );
    }
    cc::Build::new()
        .cpp(true)
        .std("c++17")
        .include(ompl)
        .include("/usr/include/eigen3")
        .flag_if_supported("-Wno-unused-parameter")
        .flag_if_supported("-Wno-deprecated-copy")
        .opt_level(2)
        .file("cpp/shim.cpp")
        .compile("autobio_ompl_shim");
    println!("cargo:rustc-link-lib=dylib=ompl");
}
