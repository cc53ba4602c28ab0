//! `autobio demo`: scripted-expert demonstrations, as one MCAP recording per episode or as a
//! LeRobot dataset (`demos::generate`, printed by `crate::datasets`).

use crate::datasets::{CodecArg, FileSizeArgs, ObservationArg};
use crate::front::Front;
use anyhow::{Result, bail};
use std::path::{Path, PathBuf};
use std::process::ExitCode;

#[derive(Clone, Copy, Debug, clap::ValueEnum)]
pub(crate) enum DemoFormat {
    Mcap,
    #[value(name = "lerobot-v21")]
    LerobotV21,
    #[value(name = "lerobot-v30")]
    LerobotV30,
}

#[derive(Clone, Debug, clap::Args)]
pub(crate) struct DemoArgs {
    #[arg(long, required = true)]
    protocol: Vec<PathBuf>,
    #[arg(long, default_value_t = 1)]
    episodes: usize,
    #[arg(long, default_value_t = 0)]
    seed: u64,
    #[arg(long, default_value = "out/demo")]
    out: PathBuf,
    /// `mcap` (one recording per episode), `lerobot-v21` or `lerobot-v30`
    #[arg(long, value_enum, default_value = "mcap")]
    format: DemoFormat,
    /// Dataset videos: `av1` (libsvtav1, LeRobot's default) or `h264`
    #[arg(long, value_enum, default_value = "av1")]
    codec: CodecArg,
    /// Camera image size WxH (default: the task's own camera size)
    #[arg(long, value_parser = crate::replay::parse_size)]
    size: Option<[usize; 2]>,
    /// Datasets: what the frames observe: `vision` (cameras), `state` (the task's environment
    /// state, privileged; no camera is drawn) or `all`
    #[arg(long, value_enum, default_value = "vision")]
    observation: ObservationArg,
    /// Continue the recordings or dataset in --out (episodes already finished there are not
    /// recorded again; one cut short by a killed run is recorded again)
    #[arg(long)]
    resume: bool,
    /// Episodes recorded at once, each thread with its own scene and renderer
    #[arg(long, default_value_t = 1, value_parser = clap::value_parser!(u32).range(1..=256))]
    workers: u32,
    /// Record only shard I of N (datasets): every N-th episode of the plan from position I,
    /// into its own --out; join the shards with `autobio dataset merge`
    #[arg(long, value_name = "I/N")]
    shard: Option<results::run::Shard>,
    #[command(flatten)]
    files: FileSizeArgs,
    /// Record a protocol whose success already holds at the start (W0001; refused otherwise)
    #[arg(long)]
    allow_trivial: bool,
    #[command(flatten)]
    perturb: crate::front::PerturbArgs,
    #[command(flatten)]
    renderer: crate::front::RendererArgs,
}

pub(crate) fn run(front: &Front, a: &DemoArgs) -> Result<ExitCode> {
    let tasks: Vec<compiler::Task> = front
        .load_all_to_run(&a.protocol, a.allow_trivial)?
        .into_iter()
        .map(|t| a.perturb.apply(t))
        .collect::<Result<_>>()?;
    let version = match a.format {
        DemoFormat::Mcap if a.shard.is_some() => {
            bail!("--shard splits datasets; for recordings use eval --record --shard")
        }
        DemoFormat::Mcap => return mcap(&tasks, a),
        DemoFormat::LerobotV21 => dataset::Version::V21,
        DemoFormat::LerobotV30 => dataset::Version::V30,
    };
    // A dataset's frames: --size, else the first task's camera spec.
    let image_size = a.size.unwrap_or_else(|| {
        tasks
            .first()
            .and_then(|t| t.cameras.first())
            .map_or([224, 224], |c| [c.width as usize, c.height as usize])
    });
    let opts = demos::GenerateOptions {
        episodes: a.episodes,
        seed: a.seed,
        out: a.out.clone(),
        version,
        codec: a.codec.codec(),
        resume: a.resume,
        image_size,
        workers: a.workers as usize,
        shard: a.shard,
        file_sizes: a.files.sizes(),
        observations: a.observation.observations(),
        renderer: a.renderer.renderer(a.workers as usize),
    };
    crate::datasets::generate(&tasks, &opts)
}

/// `demo --format mcap`: one MCAP recording (with camera images) per expert episode.
fn mcap(tasks: &[compiler::Task], a: &DemoArgs) -> Result<ExitCode> {
    let out: &Path = &a.out;
    for task in tasks {
        let opts = scoring::eval::EvalOptions {
            episodes: a.episodes,
            seed: a.seed,
            out: Some(out.to_path_buf()),
            record: true,
            image_every: 5,
            image_size: a.size,
            renderer: a.renderer.renderer(a.workers as usize),
            workers: a.workers as usize,
            resume: a.resume,
            ..Default::default()
        };
        let report = scoring::eval::evaluate(task, &opts, |p| {
            let e = p.result;
            outln!(
                "seed {:>4}  {}  {:.1} s  {}",
                e.seed,
                if e.success { "success" } else { "FAIL   " },
                e.sim_time_s,
                e.recording.as_deref().unwrap_or("")
            );
        })?;
        outln!(
            "{} demonstrations of {} in {} ({} successful)",
            report.summary.episodes,
            task.id,
            out.display(),
            report.summary.successes
        );
    }
    Ok(ExitCode::SUCCESS)
}
