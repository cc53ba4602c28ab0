//! `autobio bench`: throughput figures, each measured in the same run as its baseline.
//! - physics: harness steps/s (episode stepping with instrument logic) vs a bare `mj_step` loop on
//!   the same compiled model and initial state;
//! - rendering: frames/s of one 224x224 camera image (both task cameras, alternating);
//! - expert: full scripted-expert episodes per minute (no recording).

use anyhow::Result;
use mujoco_rs::prelude::*;
use std::sync::Arc;
use std::time::Instant;

pub fn run(task: &compiler::Task) -> Result<()> {
    let instance = task.sample(0);
    let scene = Arc::new(runtime::Scene::build(task, &instance).map_err(anyhow::Error::msg)?);
    let steps = 20_000;

    // Same model, same initial state: the bare loop starts from the episode's reset data.
    let mut ep = runtime::Episode::new(scene.clone(), task, &instance);
    let mut bare = MjData::new(scene.model.clone());
    bare.copy_state_from_data(
        &ep.data,
        mujoco_rs::mujoco_c::mjtState::mjSTATE_INTEGRATION as u32,
    )
    .map_err(|e| anyhow::anyhow!("{e:?}"))?;
    let mut best_bare = f64::MAX;
    let mut best_harness = f64::MAX;
    for _ in 0..3 {
        let t = Instant::now();
        for _ in 0..steps {
            bare.step();
        }
        best_bare = best_bare.min(t.elapsed().as_secs_f64());
        let t = Instant::now();
        for _ in 0..steps {
            ep.physics_step().map_err(anyhow::Error::msg)?;
        }
        best_harness = best_harness.min(t.elapsed().as_secs_f64());
        ep.reset(&instance);
        bare.copy_state_from_data(
            &ep.data,
            mujoco_rs::mujoco_c::mjtState::mjSTATE_INTEGRATION as u32,
        )
        .map_err(|e| anyhow::anyhow!("{e:?}"))?;
    }
    let (bare_rate, harness_rate) = (steps as f64 / best_bare, steps as f64 / best_harness);
    println!("physics  bare mj_step   {bare_rate:>10.0} steps/s");
    println!(
        "physics  harness        {harness_rate:>10.0} steps/s   ratio {:.3}x",
        harness_rate / bare_rate
    );

    let mut cams = runtime::render::Cameras::new(&scene, 224, 224).map_err(anyhow::Error::msg)?;
    let names: Vec<String> = task.cameras.iter().map(|c| c.name.clone()).collect();
    cams.render(&mut ep.data, &names)
        .map_err(anyhow::Error::msg)?;
    let rounds = 50;
    let t = Instant::now();
    for _ in 0..rounds {
        ep.control_step().map_err(anyhow::Error::msg)?;
        cams.render(&mut ep.data, &names)
            .map_err(anyhow::Error::msg)?;
    }
    let frames = rounds * names.len();
    println!(
        "render   224x224        {:>10.1} frames/s ({} cameras, 10 physics steps between pairs)",
        frames as f64 / t.elapsed().as_secs_f64(),
        names.len()
    );

    let n = 3;
    let opts = scoring::eval::EvalOptions {
        episodes: n,
        seed: 0,
        out: None,
        record: false,
        image_every: 0,
    };
    let report = scoring::evaluate(task, &opts, |_| {}).map_err(anyhow::Error::msg)?;
    let sim: f64 = report.episodes.iter().map(|e| e.sim_time_s).sum();
    println!(
        "expert   episodes       {:>10.1} episodes/min ({n} episodes, {:.1} s simulated, {:.0}x real time, {} successful)",
        n as f64 * 60.0 / report.summary.wall_time_s,
        sim,
        sim / report.summary.wall_time_s,
        report.summary.successes
    );
    Ok(())
}
