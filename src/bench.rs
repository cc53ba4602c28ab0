//! `autobio bench`: throughput figures, each measured in the same run as its baseline.
//! - physics, per task scene (by default the thermal cycler's, the tube transfer's, the two-arm
//!   task's and the two-Aloha unscrewing scene, the thread under load): harness
//!   steps/s (episode stepping with instrument logic) vs a bare `mj_step` loop on the same compiled
//!   model and initial state;
//! - rendering: frames/s of one 224x224 camera image (both task cameras, alternating), with the
//!   full meshes, the simplified ones, and the simplified ones under every visual perturbation
//!   at its strong preset (light, material, camera, noise: docs/robustness.md);
//! - expert: full scripted-expert episodes per minute (no recording);
//! - lab physics: each mechanism's scene with it and without it (ratio), one liquid solve, and
//!   the pipetting process's cost per step while a tip draws (as a share of the pipetting
//!   scene's step where one is measured; the pipetting scene is among the default scenes);
//! - front end: `autobio check` on the thermal cycler's and the tube transfer's protocols, its
//!   proof and its reach pass solved afresh and answered from the reach store (the authoring
//!   loop); checking a protocol whose parameter has 50,000 values and 50,000 exclusions,
//!   against the same domain with none (the proof must stay near-linear in the domain);
//!   `autobio import` of an Opentrons file of 680 commands (`crate::bench_import`);
//! - harness, on the first scene: expert episodes/s with two workers against one; and with a
//!   model in the loop (the reference openpi server on loopback answering the expert's recorded
//!   actions), the harness's time per control step beyond the same episodes run in-process:
//!   rendering, encoding and the round trip, for a query every 50 steps (pi0's chunks) and every
//!   step (as vla-eval servers are driven); recorded frames/s of dataset generation with one
//!   worker (AV1 and H.264; against upstream's expert plus `render.py`, a reference figure) and
//!   two, and of a state dataset (no camera);
//! - leaderboard (`crate::bench_leaderboard`): verification's episodes/s with one worker and two,
//!   and the site's build time from 50 submissions x 16 tasks x 100 episodes;
//! - photoreal (`crate::bench_photoreal`): Blender's frames/s per engine and sample count against
//!   the rasteriser's, and the two renderers' silhouette agreement.

use anyhow::{Context, Result};
use mujoco_rs::prelude::*;
use std::sync::Arc;
use std::time::Instant;

/// Upstream's transfer scene on this machine kind (mesh collisions and the thread SDF), steps/s:
/// the figure the transfer scene is compared with (not measured here; see docs/physics.md).
const UPSTREAM_TRANSFER_STEPS_S: f64 = 810.0;

/// Upstream's expert plus `render.py` writing a dataset on this machine kind, frames/s: the
/// expert at 0.140 s per simulated second of the thermal cycler's close (50 frames) and
/// `render.py` at 16.1 frames/s with two cameras at 224x224 (../shared/reference/
/// packages-and-interfaces.md), one after the other: 1 / (0.140 / 50 + 1 / 16.1). Not
/// measured here: upstream's code is not installed.
const UPSTREAM_DATASET_FRAMES_S: f64 = 1.0 / (0.140 / 50.0 + 1.0 / 16.1);

/// A group of figures (`autobio bench --only`).
#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum)]
pub(crate) enum Section {
    /// Checking a large parameter domain.
    FrontEnd,
    /// Workers, a model in the loop, dataset generation (on the first scene).
    Harness,
    /// Physics, rendering and the expert per task scene.
    Scenes,
    /// The lab mechanisms and the liquid.
    Physics,
    /// Verifying a bundle and building the leaderboard site.
    Leaderboard,
    /// The Python package against the Rust environment (on the first scene).
    Python,
    /// Hours of lab time: a 30-cycle PCR episode and a 10-minute spin, with the event-driven
    /// clock against stepping every control step.
    LabTime,
    /// Blender's photoreal frames/s per engine and sample count, against the rasteriser (on the
    /// first scene).
    Photoreal,
}

#[derive(Clone, Debug, clap::Args)]
pub(crate) struct BenchArgs {
    /// Task scenes to measure (repeatable)
    #[arg(
        long,
        default_values = [
            "protocols/thermal_cycler/close_lid.toml",
            "protocols/tube/transfer.toml",
            "protocols/two_arm/close_lid_and_transfer.toml",
            "protocols/tube/unscrew_cap.toml",
            "protocols/vortex_mixer/mix_tube.toml",
            "protocols/pipette/aspirate.toml"
        ]
    )]
    protocol: Vec<std::path::PathBuf>,
    /// Measure only these sections (repeatable; default: all)
    #[arg(long, value_enum)]
    only: Vec<Section>,
}

/// `autobio bench`.
pub(crate) fn run_cli(
    front: &crate::front::Front,
    a: &BenchArgs,
) -> Result<std::process::ExitCode> {
    let tasks = front.load_all(&a.protocol)?;
    run(&tasks, &a.only)?;
    Ok(std::process::ExitCode::SUCCESS)
}

/// Every figure for each task's scene, then the lab-physics figures once; `only` (when not empty)
/// picks sections.
pub(crate) fn run(tasks: &[compiler::Task], only: &[Section]) -> Result<()> {
    let wants = |s: Section| only.is_empty() || only.contains(&s);
    if wants(Section::FrontEnd) {
        front_end_figures()?;
    }
    if wants(Section::Harness)
        && let Some(first) = tasks.first()
    {
        harness_figures(first)?;
    }
    if wants(Section::Leaderboard)
        && let Some(first) = tasks.first()
    {
        crate::bench_leaderboard::figures(first)?;
    }
    if wants(Section::Python)
        && let Some(first) = tasks.first()
    {
        crate::bench_python::figures(first)?;
    }
    if wants(Section::Photoreal)
        && let Some(first) = tasks.first()
    {
        crate::bench_photoreal::figures(first)?;
    }
    // The liquid's share is of the first pipetting scene's step where one is measured (a scene
    // with a liquid tool), else of the first scene's.
    let mut first_step_s = None;
    let mut pipetting_step_s = None;
    if wants(Section::Scenes) {
        for task in tasks {
            outln!("scene    {}", task.id);
            let step_s = scene_figures(task)?;
            first_step_s.get_or_insert(step_s);
            let pipetting = task
                .labware
                .iter()
                .any(|l| labware::kind(&l.kind).is_some_and(|k| k.liquid_tool));
            if pipetting {
                pipetting_step_s.get_or_insert(step_s);
            }
        }
    }
    let first_step_s = pipetting_step_s.or(first_step_s);
    if wants(Section::Physics) {
        physics_figures(first_step_s)?;
    }
    if wants(Section::LabTime) {
        lab_time_figures()?;
    }
    Ok(())
}

/// The shipped protocols whose lab time the bench measures: a 30-cycle PCR and a 10-minute spin.
const LAB_TIME_PROTOCOLS: [&str; 2] = ["protocols/lab/pcr_run.toml", "protocols/lab/spin.toml"];

/// Wall time of one expert episode (seed 0) of each lab-time protocol, against the same lab time
/// stepped control step by control step: the baseline is the episode's own wall time per
/// control step times the control steps its simulated time holds, measured in the same run.
fn lab_time_figures() -> Result<()> {
    for path in LAB_TIME_PROTOCOLS {
        let text = std::fs::read_to_string(path).with_context(|| format!("reading {path}"))?;
        let (task, diags) = compiler::compile_source(&text, path);
        let task = task.with_context(|| format!("{path} does not compile: {diags:?}"))?;
        let opts = scoring::eval::EvalOptions {
            episodes: 1,
            workers: 1,
            ..Default::default()
        };
        let report = scoring::eval::evaluate(&task, &opts, |_| {})?;
        let e = report
            .episodes
            .first()
            .with_context(|| format!("{path}: no episode ran"))?;
        let period = task.physics.timestep_s * task.physics.substeps as f64;
        let stepped = e.sim_time_s / period;
        let per_step = e.wall_time_s / e.control_steps.max(1) as f64;
        let baseline = stepped * per_step;
        outln!(
            "labtime  {:<22} {:>8.2} s wall for {:.0} s of lab time ({}) in {} control steps; stepping all {stepped:.0} would take ~{baseline:.0} s: {:.0}x",
            task.id,
            e.wall_time_s,
            e.sim_time_s,
            if e.success { "success" } else { "failure" },
            e.control_steps,
            baseline / e.wall_time_s.max(1e-9),
        );
    }
    Ok(())
}

/// Physics (harness vs a bare `mj_step` loop on the same model), rendering and expert figures of
/// one task's scene; returns the bare loop's seconds per step.
fn scene_figures(task: &compiler::Task) -> Result<f64> {
    let instance = task.sample(0);
    let scene = Arc::new(runtime::Scene::build(task, &instance)?);
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
            ep.physics_step()?;
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
    outln!("physics  bare mj_step   {bare_rate:>10.0} steps/s");
    outln!(
        "physics  harness        {harness_rate:>10.0} steps/s   ratio {:.3}x{}",
        harness_rate / bare_rate,
        if task.id == "tube.transfer" {
            format!(
                "   ({:.1}x upstream's {UPSTREAM_TRANSFER_STEPS_S:.0} steps/s transfer scene)",
                harness_rate / UPSTREAM_TRANSFER_STEPS_S
            )
        } else {
            String::new()
        }
    );

    let names: Vec<String> = task.cameras.iter().map(|c| c.name.clone()).collect();
    let mut rates = Vec::new();
    for detail in [robots::Detail::Full, robots::Detail::Simplified] {
        rates.push(render_rate(&scene, &mut ep, &names, detail, None)?);
    }
    // Every visual perturbation at its strong preset, on the scene built for it (its spare
    // lights), drawn as the environment draws it (the look, then the sensor noise).
    let looks: Vec<compiler::perturb::Preset> = ["light:2", "material:2", "camera:2", "noise:2"]
        .iter()
        .map(|p| p.parse())
        .collect::<Result<_, _>>()?;
    let shaken = task
        .clone()
        .with_perturb(&compiler::perturb::Preset::combine(&looks));
    let shaken_instance = shaken.sample(0);
    let shaken_scene = Arc::new(runtime::Scene::build(&shaken, &shaken_instance)?);
    let mut shaken_ep = runtime::Episode::new(shaken_scene.clone(), &shaken, &shaken_instance);
    let perturbed = render_rate(
        &shaken_scene,
        &mut shaken_ep,
        &names,
        robots::Detail::Simplified,
        shaken_instance.perturbation.as_ref(),
    )?;
    outln!(
        "render   224x224 full   {:>10.1} frames/s ({} cameras, one control step between sets, not timed)",
        rates[0],
        names.len()
    );
    outln!(
        "render   224x224 simple {:>10.1} frames/s   ratio {:.2}x (simplified visual meshes, the default at this size)",
        rates[1],
        rates[1] / rates[0]
    );
    outln!(
        "render   224x224 perturbed {:>7.1} frames/s   ratio {:.2}x the clean simplified figure (light, material, camera and noise at strength 2)",
        perturbed,
        perturbed / rates[1]
    );

    let n = 3;
    let opts = scoring::eval::EvalOptions {
        policy: scoring::policies::PolicySpec::Expert,
        episodes: n,
        seed: 0,
        out: None,
        record: false,
        image_every: 0,
        resume: false,
        ..Default::default()
    };
    let report = scoring::eval::evaluate(task, &opts, |_| {})?;
    let sim: f64 = report.episodes.iter().map(|e| e.sim_time_s).sum();
    outln!(
        "expert   episodes       {:>10.1} episodes/min ({n} episodes, {:.1} s simulated, {:.0}x real time, {} successful)",
        n as f64 * 60.0 / report.summary.wall_time_s,
        sim,
        sim / report.summary.wall_time_s,
        report.summary.successes
    );
    Ok(1.0 / bare_rate)
}

/// Frames/s of every task camera at 224x224 with this level of detail (and an episode's drawn
/// perturbation: its look and its sensor noise): the best of three rounds of 40 frame sets, one
/// control step between sets (not timed: rendering only).
fn render_rate(
    scene: &runtime::Scene,
    ep: &mut runtime::Episode,
    names: &[String],
    detail: robots::Detail,
    drawn: Option<&compiler::perturb::Drawn>,
) -> Result<f64> {
    let mut cams = runtime::render::Cameras::with_detail(scene, 224, 224, detail)
        .map_err(anyhow::Error::msg)?;
    cams.set_look(scene, drawn);
    cams.render(&ep.data, ep.logic(), names)
        .map_err(anyhow::Error::msg)?;
    let rounds = 40;
    let mut best = f64::MAX;
    for _ in 0..3 {
        let mut spent = 0.0;
        for k in 0..rounds {
            ep.control_step()?;
            let t = Instant::now();
            let mut frames = cams
                .render(&ep.data, ep.logic(), names)
                .map_err(anyhow::Error::msg)?;
            runtime::perturb::degrade_frames(&mut frames, drawn, 0, k);
            spent += t.elapsed().as_secs_f64();
        }
        best = best.min(spent);
    }
    Ok((rounds as usize * names.len()) as f64 / best)
}

/// Steps/s of a model from its XML: the best of three timed runs of `steps` steps, `drive` called
/// before each step (actuator commands, liquid updates).
fn rate(xml: &str, steps: usize, mut drive: impl FnMut(&mut MjData<&MjModel>)) -> Result<f64> {
    physics::register()?;
    let model = MjModel::from_xml_string(xml).map_err(|e| anyhow::anyhow!("{e}"))?;
    let mut best = f64::MAX;
    for _ in 0..3 {
        let mut data = MjData::new(&model);
        let t = Instant::now();
        for _ in 0..steps {
            drive(&mut data);
            data.step();
        }
        best = best.min(t.elapsed().as_secs_f64());
    }
    Ok(steps as f64 / best)
}

fn row(name: &str, with: f64, without: f64, note: &str) {
    outln!(
        "plugin   {name:<14} {with:>10.0} steps/s   without {without:>10.0}   ratio {:.3}x  {note}",
        with / without
    );
}

/// The lab-physics figures: each mechanism's scene with it and without it, in the same run, and
/// the cost of one liquid surface solve.
/// `task_step_s` is one physics step of the task scene measured above: the liquid's per-step cost
/// is reported against it.
pub(crate) fn physics_figures(task_step_s: Option<f64>) -> Result<()> {
    use physics::detent::Detent;
    use physics::eccentric::{Eccentric, rpm_to_rad_s};
    use physics::liquid::{Container, Liquid, Nanolitres};
    use physics::scenes;
    use physics::thread::ScrewCap;

    let knob = Detent {
        lo: 0.0,
        hi: 4.6,
        n: 11,
        stiffness: 0.0401,
        damping: 0.004,
    };
    let kick = |d: &mut MjData<&MjModel>| {
        if d.time() == 0.0 {
            d.qpos_mut()[0] = 1.0;
        }
    };
    let with = rate(&scenes::knob(&knob, true), 200_000, kick)?;
    let without = rate(&scenes::knob(&knob, false), 200_000, kick)?;
    row("detent", with, without, "(knob, 11 positions)");

    // A 1.5 mL cap half a turn up its thread, settling under gravity with upstream's friction.
    let cap = ScrewCap::new(physics::thread::CONTAINERS[0].1);
    let with = rate(
        &scenes::screw_cap(&cap, 0.5, 1.0, true, true),
        5_000,
        |_| {},
    )?;
    let without = rate(
        &scenes::screw_cap(&cap, 0.5, 1.0, true, false),
        5_000,
        |_| {},
    )?;
    row(
        "thread",
        with,
        without,
        "(screwed 1.5 mL tube, 1 ms steps; target >= 2000 steps/s)",
    );

    let drive = Eccentric::default();
    let spin = |d: &mut MjData<&MjModel>| d.ctrl_mut()[0] = rpm_to_rad_s(2500.0);
    let with = rate(&scenes::vortex(&drive, true), 100_000, spin)?;
    let without = rate(&scenes::vortex(&drive, false), 100_000, spin)?;
    row("eccentric", with, without, "(vortex cup at 2,500 rpm)");

    let (r, h, tip, sides) = scenes::TUBE;
    let container = Container::tube(r, h, tip, sides);
    let mut liquid = Liquid::new(
        container.clone(),
        Nanolitres::from_microlitres(20_000.0),
        0.03,
    );
    let shake = |d: &mut MjData<&MjModel>| {
        let t = d.time();
        d.ctrl_mut()[0] = 0.03 * (std::f64::consts::TAU * 2.0 * t).sin();
        d.ctrl_mut()[1] = 0.6 * (std::f64::consts::TAU * 0.5 * t).sin();
    };
    // The normal every physics step, the surface solved for each 50 Hz frame that shows it. The
    // liquid's own time is clocked around its calls (differencing two tiny scenes is too noisy).
    let mut k = 0u64;
    let (mut spent, mut solves, mut iterations) = (0.0f64, 0u64, 0u64);
    let with = rate(&scenes::shaken_tube(), 20_000, |d| {
        shake(d);
        let a = d.sensordata();
        let g = [a[0], a[1], a[2]];
        let t = Instant::now();
        liquid.step(g, 0.002);
        k += 1;
        if k.is_multiple_of(10) {
            liquid.offset();
            solves += 1;
            iterations += u64::from(liquid.iterations);
        }
        spent += t.elapsed().as_secs_f64();
    })?;
    let without = rate(&scenes::shaken_tube(), 20_000, shake)?;
    let per_step = spent / k as f64;
    row(
        "liquid",
        with,
        without,
        &format!(
            "(50 mL tube shaken; {:.2} µs per step{}, {:.1} iterations per 50 Hz solve; target < 10%)",
            per_step * 1e6,
            match task_step_s {
                Some(step) => format!(" = {:.1}% of a task-scene step", 100.0 * per_step / step),
                None => String::new(),
            },
            iterations as f64 / solves.max(1) as f64
        ),
    );

    pipetting_figure(task_step_s)?;

    // One surface solve: warm-started from the last offset after a small change of normal (as in
    // a step), and cold from the middle of the range.
    let normals: Vec<[f64; 3]> = (0..1000)
        .map(|i| {
            let a = 1.0 * (i as f64 / 1000.0);
            [a.sin() * 0.6, 0.0, a.cos()]
        })
        .collect();
    let target = 20e-6;
    let tol = 1e-6 * container.capacity();
    let t = Instant::now();
    let mut d = 0.05;
    let mut iterations = 0;
    for n in &normals {
        let l = (n[0] * n[0] + n[2] * n[2]).sqrt();
        let (x, it) = container.solve_offset([n[0] / l, 0.0, n[2] / l], target, d, tol);
        d = x;
        iterations += it;
    }
    let warm = t.elapsed().as_secs_f64() / normals.len() as f64;
    let t = Instant::now();
    for n in &normals {
        let l = (n[0] * n[0] + n[2] * n[2]).sqrt();
        let (lo, hi) = container.range([n[0] / l, 0.0, n[2] / l]);
        container.solve_offset([n[0] / l, 0.0, n[2] / l], target, (lo + hi) / 2.0, tol);
    }
    let cold = t.elapsed().as_secs_f64() / normals.len() as f64;
    outln!(
        "liquid   height solve   {:>10.1} µs warm ({:.1} iterations)   {:.1} µs cold   ({} triangles)",
        warm * 1e6,
        iterations as f64 / normals.len() as f64,
        cold * 1e6,
        container.triangles.len()
    );
    Ok(())
}

/// The pipetting process's cost per physics step while a tip draws: the shipped pipette's tip
/// drawing without pause from under the surface of a shipped 50 mL tube's liquid, the volume
/// changing by a microlitre a step (a fast thumb's release: a solve of the surface every five or
/// six steps, as the level is solved again each 5 µL), as a share of a task-scene step.
fn pipetting_figure(task_step_s: Option<f64>) -> Result<()> {
    use labware::process::{PENDING_UL, VOLUME_UL, Vessel};
    let (Some(labware::Model::Tube(tube)), Some(labware::Model::Pipette(pipette))) = (
        labware::Model::for_kind("tube_50ml").map(|m| {
            m.for_start(
                &[("cap".to_string(), "off".to_string())]
                    .into_iter()
                    .collect(),
            )
        }),
        labware::Model::for_kind("pipette"),
    ) else {
        anyhow::bail!("the catalogue has no 50 mL tube or pipette model");
    };
    let interior =
        labware::Liquid::interior(&tube).ok_or_else(|| anyhow::anyhow!("the tube has no bore"))?;
    let vessels = [Vessel { item: 0, interior }];
    let mut process = labware::Liquid::processes(&pipette, "pipette", 1, &vessels).remove(0);
    // The tip's opening 20 mm above the tube's base, under 30 mL of liquid.
    let poses = [
        labware::Pose::identity(),
        labware::frame::translation([0.0, 0.0, 0.02]),
    ];
    let mut logic = vec![labware::Logic::new(), labware::Logic::new()];
    logic[0].insert(VOLUME_UL.into(), 30_000.0);
    let steps = 20_000;
    let t = Instant::now();
    for k in 0..steps {
        // Topped up each step, to a volume a little different each step (as a draw leaves it).
        logic[0].insert(VOLUME_UL.into(), 30_000.0 - (k % 100) as f64);
        logic[1].insert(PENDING_UL.into(), 1_000.0);
        logic[1].insert(VOLUME_UL.into(), 0.0);
        process.step(0.002, &poses, &mut logic);
    }
    let per_step = t.elapsed().as_secs_f64() / steps as f64;
    outln!(
        "liquid   pipetting      {:>10.2} µs per step drawing{} (target < 10%)",
        per_step * 1e6,
        match task_step_s {
            Some(step) => format!(" = {:.1}% of a task-scene step", 100.0 * per_step / step),
            None => String::new(),
        }
    );
    Ok(())
}

/// A shipped protocol with a `choice` of `values` values, the first `excluded` of them excluded
/// (and one value never in the domain, so that something is left to draw).
fn big_domain(values: usize, excluded: usize) -> String {
    let base = include_str!("../protocols/thermal_cycler/close_lid.toml");
    let quoted = |n: usize| (0..n).map(|i| format!("\"v{i}\"")).collect::<Vec<_>>();
    let mut exclude = quoted(excluded.min(values - 1));
    exclude.push("\"none\"".into());
    let param = format!(
        "[params.colour]\nchoice = [{}]\nexclude = [{}]\n\n[[steps]]",
        quoted(values).join(", "),
        exclude.join(", ")
    );
    base.replacen("[[steps]]", &param, 1)
}

/// Seconds to check (parse, resolve, prove, lower) a protocol, best of three.
fn check_seconds(source: &str) -> Result<f64> {
    let mut best = f64::MAX;
    for _ in 0..3 {
        let t = Instant::now();
        let (task, diags) = compiler::compile_source(source, "bench.toml");
        if task.is_none() {
            anyhow::bail!("the front-end bench protocol does not compile: {diags:?}");
        }
        best = best.min(t.elapsed().as_secs_f64());
    }
    Ok(best)
}

/// The tube transfer with its column drawn from `values` integers of which all but 1..5 are
/// excluded: a domain used in a slot name (`target.{row}{col}`), beside two others, so the proof
/// samples its combinations.
fn slot_domain(values: usize) -> String {
    let base = include_str!("../protocols/tube/transfer.toml");
    let all: Vec<String> = (1..=values).map(|v| v.to_string()).collect();
    base.replacen(
        "[params.col]\nint = [1, 5]",
        &format!(
            "[params.col]\nchoice = [{}]\nexclude = [{}]",
            all.join(", "),
            all[5..].join(", ")
        ),
        1,
    )
}

/// The authoring loop on shipped protocols: `autobio check`'s proof (parse, resolve, prove,
/// lower) and its reach pass solved afresh (an empty store: every sampled layout's scene built
/// and solved) and answered from the store the first run filled (what a re-check of an unchanged
/// file costs); best of three each.
fn authoring_figures() -> Result<()> {
    for path in [
        "protocols/thermal_cycler/close_lid.toml",
        "protocols/tube/transfer.toml",
    ] {
        let source = std::fs::read_to_string(path)?;
        let proof = check_seconds(&source)?;
        let store_dir = tempfile::tempdir()?;
        let mut cold = f64::MAX;
        let mut warm = f64::MAX;
        for _ in 0..3 {
            let fresh = tempfile::tempdir()?;
            cold = cold.min(reach_seconds(
                path,
                &expert::reach::Store::at(fresh.path()),
            )?);
            let store = expert::reach::Store::at(store_dir.path());
            reach_seconds(path, &store)?;
            warm = warm.min(reach_seconds(path, &store)?);
        }
        outln!(
            "check    {path:<44} proof {:>7.1} ms   reach afresh {:>7.1} ms   reach kept {:>6.1} ms",
            proof * 1e3,
            cold * 1e3,
            warm * 1e3
        );
    }
    Ok(())
}

/// Seconds of the reach pass on the protocol at `path` (compiled first, not timed).
fn reach_seconds(path: &str, store: &expert::reach::Store) -> Result<f64> {
    let mut checked = compiler::check_file(std::path::Path::new(path), None)?;
    let t = Instant::now();
    expert::reach::check(&mut checked, store);
    Ok(t.elapsed().as_secs_f64())
}

fn front_end_figures() -> Result<()> {
    authoring_figures()?;
    crate::bench_import::figures()?;
    let n = 50_000;
    let in_slot = check_seconds(&slot_domain(n))?;
    let small = check_seconds(include_str!("../protocols/tube/transfer.toml"))?;
    outln!(
        "check    {n}-value column in a slot name, {} exclusions {:>8.1} ms   ({:.1} ms with `int = [1, 5]`)",
        n - 5,
        in_slot * 1e3,
        small * 1e3
    );
    let baseline = check_seconds(&big_domain(n, 0))?;
    let excluded = check_seconds(&big_domain(n, n))?;
    outln!(
        "check    {n}-value choice, no exclusions      {:>8.1} ms",
        baseline * 1e3
    );
    outln!(
        "check    {n}-value choice, {n} exclusions {:>8.1} ms   ratio {:.2}x",
        excluded * 1e3,
        excluded / baseline
    );
    Ok(())
}

/// Expert episodes/s with one worker and with two; then a model in the loop.
fn harness_figures(task: &compiler::Task) -> Result<()> {
    let n = 24;
    let rate = |workers: usize| -> Result<(f64, results::run::EvalReport)> {
        let opts = scoring::eval::EvalOptions {
            episodes: n,
            workers,
            ..Default::default()
        };
        let t = Instant::now();
        let report = scoring::eval::evaluate(task, &opts, |_| {})?;
        Ok((n as f64 / t.elapsed().as_secs_f64(), report))
    };
    // A first, untimed run warms the caches and the scene's first build for both.
    rate(1)?;
    let (one, _) = rate(1)?;
    let (two, _) = rate(2)?;
    outln!(
        "harness  workers        {two:>10.2} episodes/s with 2 workers, {one:.2} with 1: {:.2}x ({n} expert episodes of {}; target 1.8x on two cores)",
        two / one,
        task.id
    );
    model_in_the_loop(task)?;
    dataset_figures(task)
}

/// Recorded frames/s of dataset generation (two cameras at 224x224, 50 Hz, AV1), with one
/// worker and with two.
fn dataset_figures(task: &compiler::Task) -> Result<()> {
    let dir = std::env::temp_dir().join(format!("autobio-bench-ds-{}", std::process::id()));
    let rate = |codec, workers, observations| -> Result<f64> {
        let _ = std::fs::remove_dir_all(&dir);
        let opts = demos::GenerateOptions {
            episodes: 2,
            seed: 0,
            out: dir.clone(),
            version: dataset::Version::V30,
            codec,
            renderer: Default::default(),
            resume: false,
            image_size: [224, 224],
            workers,
            shard: None,
            file_sizes: Default::default(),
            observations,
        };
        let t = Instant::now();
        let done = demos::generate(std::slice::from_ref(task), &opts, |_| {})?;
        Ok(done.frames as f64 / t.elapsed().as_secs_f64())
    };
    use dataset::{Codec, Observations};
    let av1 = rate(Codec::Av1, 1, Observations::Vision)?;
    let av1_2 = rate(Codec::Av1, 2, Observations::Vision)?;
    let h264 = rate(Codec::H264, 1, Observations::Vision)?;
    let state = rate(Codec::Av1, 1, Observations::State)?;
    let _ = std::fs::remove_dir_all(&dir);
    let up = UPSTREAM_DATASET_FRAMES_S;
    outln!(
        "dataset  lerobot-v30    {av1:>10.1} frames/s with 1 worker (AV1, LeRobot's default codec; 2 cameras at 224x224, 2 episodes): {:.1}x upstream's expert + render.py ({up:.1} frames/s)",
        av1 / up
    );
    outln!(
        "dataset  lerobot-v30    {h264:>10.1} frames/s with 1 worker (H.264): {:.1}x upstream's",
        h264 / up
    );
    outln!(
        "dataset  lerobot-v30    {av1_2:>10.1} frames/s with 2 workers (AV1), {av1:.1} with 1: {:.2}x",
        av1_2 / av1
    );
    outln!(
        "dataset  lerobot-v30    {state:>10.1} frames/s with 1 worker, --observation state (no camera): {:.1}x upstream's",
        state / up
    );
    Ok(())
}

/// The harness's cost per control step with a model server in the loop, against the same
/// episodes with the expert in-process (identical trajectories: the server sends the expert's
/// float64 actions), so physics cancels and what is left is rendering, encoding, the socket and
/// the server's lookup.
fn model_in_the_loop(task: &compiler::Task) -> Result<()> {
    let root = std::path::Path::new(env!("CARGO_MANIFEST_DIR"));
    let python = root.join(".deps/servers/bin/python");
    if !python.exists() {
        outln!(
            "harness  model          skipped: no {} (run `make setup`)",
            python.display()
        );
        return Ok(());
    }
    let n = 3;
    let dir = std::env::temp_dir().join(format!("autobio-bench-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    let expert = scoring::eval::EvalOptions {
        episodes: n,
        out: Some(dir.join("expert")),
        record: true,
        ..Default::default()
    };
    let baseline = scoring::eval::evaluate(task, &expert, |_| {})?;
    let pi0 = results::profile::BUILT_IN[0].1;
    for execute in [50usize, 1] {
        let mut server = std::process::Command::new(&python)
            .arg(root.join("tests/servers/openpi_server.py"))
            .args(["--recordings", &dir.join("expert").display().to_string()])
            .args(["--execute", &execute.to_string()])
            .stdout(std::process::Stdio::piped())
            .spawn()?;
        let mut line = String::new();
        std::io::BufRead::read_line(
            &mut std::io::BufReader::new(server.stdout.take().expect("piped")),
            &mut line,
        )?;
        let url = line
            .trim()
            .strip_prefix("listening on ")
            .unwrap_or_default()
            .to_string();
        let text = pi0
            .replace("reset_frame = false", "reset_frame = true")
            .replace("execute = 50", &format!("execute = {execute}"));
        let profile = results::profile::LoadedProfile::from_text(text, "bench".into())?;
        let opts = scoring::eval::EvalOptions {
            episodes: n,
            model: Some(scoring::eval::ModelSpec {
                url,
                wire: results::run::record::Wire::Openpi,
                profile,
                attempts: 4,
                backoff_s: 0.25,
            }),
            ..Default::default()
        };
        let report = scoring::eval::evaluate(task, &opts, |_| {});
        let _ = server.kill();
        let _ = server.wait();
        let report = report?;
        let steps: u64 = report.episodes.iter().map(|e| e.control_steps).sum();
        let same = report
            .episodes
            .iter()
            .zip(&baseline.episodes)
            .all(|(a, b)| a.trajectory_hash == b.trajectory_hash);
        let wall: f64 = report.episodes.iter().map(|e| e.wall_time_s).sum();
        let base: f64 = baseline.episodes.iter().map(|e| e.wall_time_s).sum();
        let waiting: f64 = report.episodes.iter().map(|e| e.policy_time_s).sum();
        outln!(
            "harness  model          {:>10.2} ms/control step overhead, a query every {execute:>2} steps (2 cameras at 224x224 rendered per query; {:.2} ms of it waiting on the socket and server; {steps} steps{})",
            1e3 * (wall - base) / steps as f64,
            1e3 * waiting / steps as f64,
            if same {
                ", trajectories identical to the in-process expert"
            } else {
                ", TRAJECTORIES DIFFER"
            }
        );
    }
    let _ = std::fs::remove_dir_all(&dir);
    Ok(())
}
