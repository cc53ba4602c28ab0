//! What links what. The results layer and the leaderboard link no simulator: `cargo tree` of
//! `results` and `leaderboard` names neither MuJoCo nor EGL/GL, so a leaderboard build, a
//! verifier's bookkeeping and CI for submissions need neither (the runtime's tree is the control:
//! it must name MuJoCo, or this check could not fail). The dataset format and the Python wheel
//! link no planner (the expert's tree is that check's control).

use std::process::Command;

/// The packages in `package`'s normal (non-dev, non-build) dependency tree, one per line.
fn tree(package: &str) -> Vec<String> {
    let cargo = std::env::var("CARGO").unwrap_or_else(|_| "cargo".into());
    let out = Command::new(cargo)
        .args([
            "tree",
            "--offline",
            "-e",
            "normal",
            "--prefix",
            "none",
            "-p",
            package,
        ])
        .current_dir(env!("CARGO_MANIFEST_DIR"))
        .output()
        .expect("cargo runs");
    assert!(
        out.status.success(),
        "cargo tree -p {package}: {}",
        String::from_utf8_lossy(&out.stderr)
    );
    String::from_utf8_lossy(&out.stdout)
        .lines()
        .map(str::to_string)
        .collect()
}

fn simulator_crates(lines: &[String]) -> Vec<&String> {
    const SIMULATOR: [&str; 5] = ["mujoco", "glutin", "khronos-egl", "glow", "gl_generator"];
    lines
        .iter()
        .filter(|l| SIMULATOR.iter().any(|s| l.starts_with(s)))
        .collect()
}

#[test]
fn results_and_leaderboard_build_without_mujoco_or_egl() {
    for package in ["results", "leaderboard"] {
        let lines = tree(package);
        assert!(
            lines.iter().any(|l| l.starts_with("compiler v")),
            "{package}: the tree was not read: {lines:?}"
        );
        assert_eq!(simulator_crates(&lines), Vec::<&String>::new(), "{package}");
    }
    let runtime = tree("runtime");
    assert!(
        runtime.iter().any(|l| l.starts_with("mujoco-rs v")),
        "the control: the runtime links MuJoCo"
    );
}

/// The LeRobot dataset format and the Python wheel link no motion planner: `cargo tree` of
/// `dataset` (what a dataset reader links) and of `autobio-python` names neither `planner` (our
/// OMPL binding) nor the expert or the harness above it. The expert's tree is the control: it must
/// name the planner, or this check could not fail.
#[test]
fn the_dataset_format_and_the_python_wheel_link_no_planner() {
    const PLANNING: [&str; 4] = ["planner v", "expert v", "scoring v", "demos v"];
    for package in ["dataset", "autobio-python"] {
        let lines = tree(package);
        assert!(
            lines.iter().any(|l| l.starts_with("runtime v")),
            "{package}: the tree was not read: {lines:?}"
        );
        let planning: Vec<&String> = lines
            .iter()
            .filter(|l| PLANNING.iter().any(|p| l.starts_with(p)))
            .collect();
        assert_eq!(planning, Vec::<&String>::new(), "{package}");
    }
    assert!(
        tree("expert").iter().any(|l| l.starts_with("planner v")),
        "the control: the expert links the planner"
    );
}
