//! `autobio demo --format lerobot-*`, `autobio export` and `autobio dataset merge`: one call
//! into `dataset` each, with a progress bar and a closing summary; the dataset arguments
//! (`--format`, `--codec`, file sizes) parsed into their types.

use crate::progress::ProgressView;
use anyhow::Result;
use std::path::{Path, PathBuf};
use std::process::ExitCode;

/// `--format` of `export`.
#[derive(Clone, Copy, Debug, clap::ValueEnum)]
pub(crate) enum DatasetFormat {
    #[value(name = "lerobot-v21")]
    LerobotV21,
    #[value(name = "lerobot-v30")]
    LerobotV30,
}

impl DatasetFormat {
    pub(crate) fn version(self) -> dataset::Version {
        match self {
            DatasetFormat::LerobotV21 => dataset::Version::V21,
            DatasetFormat::LerobotV30 => dataset::Version::V30,
        }
    }
}

/// `--codec` of `demo` and `export`.
#[derive(Clone, Copy, Debug, clap::ValueEnum)]
pub(crate) enum CodecArg {
    Av1,
    H264,
}

impl CodecArg {
    pub(crate) fn codec(self) -> dataset::Codec {
        match self {
            CodecArg::Av1 => dataset::Codec::Av1,
            CodecArg::H264 => dataset::Codec::H264,
        }
    }
}

/// What a dataset's frames observe (`--observation`).
#[derive(Clone, Copy, Debug, clap::ValueEnum)]
pub(crate) enum ObservationArg {
    /// Every task camera and the robots' state (LeRobot's `observation.images.*`,
    /// `observation.state`)
    Vision,
    /// The task's environment state (privileged: `observation.environment_state`) and the
    /// robots' state; no camera is drawn
    State,
    /// Cameras, environment state and robot state
    All,
}

impl ObservationArg {
    pub(crate) fn observations(self) -> dataset::Observations {
        match self {
            ObservationArg::Vision => dataset::Observations::Vision,
            ObservationArg::State => dataset::Observations::State,
            ObservationArg::All => dataset::Observations::All,
        }
    }
}

#[derive(Clone, Debug, clap::Args)]
pub(crate) struct ExportArgs {
    /// Recordings, or folders of them; with `--to autoprotocol`, one protocol file
    #[arg(required = true)]
    recordings: Vec<PathBuf>,
    /// Write a protocol's lab steps in another lab language instead: `autoprotocol` (the
    /// robot's motions dropped; docs/import.md)
    #[arg(long, value_enum)]
    to: Option<LabLanguage>,
    /// With `--to`: the episode whose drawn parameters are written
    #[arg(long, default_value_t = 0, requires = "to")]
    seed: u64,
    /// `lerobot-v21` or `lerobot-v30`
    #[arg(long, value_enum, default_value = "lerobot-v30")]
    format: DatasetFormat,
    /// Where to write: the dataset's folder, or with `--to`, the document
    #[arg(long)]
    out: PathBuf,
    /// Dataset videos: `av1` (libsvtav1, LeRobot's default) or `h264`
    #[arg(long, value_enum, default_value = "av1")]
    codec: CodecArg,
    /// Camera image size WxH
    #[arg(long, default_value = "224x224", value_parser = crate::replay::parse_size)]
    size: [usize; 2],
    /// What the frames observe: `vision` (cameras), `state` (the environment state, no camera)
    /// or `all`
    #[arg(long, value_enum, default_value = "vision")]
    observation: ObservationArg,
    /// Continue the dataset in --out (recordings already in it are skipped)
    #[arg(long)]
    resume: bool,
    #[command(flatten)]
    files: FileSizeArgs,
    #[command(flatten)]
    renderer: crate::front::RendererArgs,
}

#[derive(Clone, Debug, clap::Subcommand)]
pub(crate) enum DatasetCommand {
    /// Join the datasets of a generation's shards (`demo --shard I/N`, one folder each) into one
    Merge {
        /// The shards' --out folders
        #[arg(required = true)]
        shards: Vec<PathBuf>,
        /// The folder for the merged dataset
        #[arg(long)]
        out: PathBuf,
    },
}

/// The lab languages a protocol exports to.
#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum)]
pub(crate) enum LabLanguage {
    Autoprotocol,
}

/// `autobio export`.
pub(crate) fn export_cli(front: &crate::front::Front, a: &ExportArgs) -> Result<ExitCode> {
    if let Some(LabLanguage::Autoprotocol) = a.to {
        let [protocol] = a.recordings.as_slice() else {
            anyhow::bail!("--to autoprotocol exports one protocol file");
        };
        return crate::export_protocol::run(front, protocol, &a.out, a.seed);
    }
    let opts = demos::ExportOptions {
        out: a.out.clone(),
        version: a.format.version(),
        codec: a.codec.codec(),
        image_size: a.size,
        resume: a.resume,
        file_sizes: a.files.sizes(),
        observations: a.observation.observations(),
        renderer: a.renderer.renderer(1),
    };
    export(&a.recordings, &opts)
}

/// `autobio dataset ...`.
pub(crate) fn dataset_cli(c: &DatasetCommand) -> Result<ExitCode> {
    match c {
        DatasetCommand::Merge { shards, out } => merge(shards, out),
    }
}

/// Where a v3.0 dataset's shared files roll over.
#[derive(Clone, Copy, Debug, clap::Args)]
pub(crate) struct FileSizeArgs {
    /// v3.0: start a new data file once one reaches this size (MiB)
    #[arg(long, default_value_t = 100.0, value_name = "MIB", value_parser = positive)]
    data_file_mb: f64,
    /// v3.0: start a new video file once one reaches this size (MiB)
    #[arg(long, default_value_t = 500.0, value_name = "MIB", value_parser = positive)]
    video_file_mb: f64,
}

fn positive(s: &str) -> Result<f64, String> {
    match s.parse::<f64>() {
        Ok(v) if v > 0.0 && v.is_finite() => Ok(v),
        _ => Err(format!("`{s}` is not a positive size")),
    }
}

impl FileSizeArgs {
    pub(crate) fn sizes(self) -> dataset::FileSizes {
        dataset::FileSizes {
            data_mb: self.data_file_mb,
            video_mb: self.video_file_mb,
        }
    }
}

fn summary(out: &Path, done: &demos::Generated, verb: &str) {
    outln!(
        "{}: {} episodes in the dataset, {} {verb}, {} left out, {} frames",
        out.display(),
        done.written,
        done.written - done.resumed,
        done.failed.len(),
        done.frames
    );
}

/// Runs a dataset job with a progress bar labelled `label`, then prints its summary.
fn with_progress(
    label: &str,
    verb: &str,
    out: &Path,
    job: impl FnOnce(&mut dyn FnMut(demos::Step<'_>)) -> Result<demos::Generated, dataset::DatasetError>,
) -> Result<ExitCode> {
    let mut view = ProgressView::new(label);
    let done = job(&mut |s| view.step(&s));
    view.finish();
    summary(out, &done?, verb);
    Ok(ExitCode::SUCCESS)
}

pub(crate) fn generate(
    tasks: &[compiler::Task],
    opts: &demos::GenerateOptions,
) -> Result<ExitCode> {
    with_progress("demo", "written", &opts.out, |progress| {
        demos::generate(tasks, opts, progress)
    })
}

pub(crate) fn export(recordings: &[PathBuf], opts: &demos::ExportOptions) -> Result<ExitCode> {
    with_progress("export", "exported", &opts.out, |progress| {
        demos::export(recordings, opts, progress)
    })
}

pub(crate) fn merge(shards: &[PathBuf], out: &Path) -> Result<ExitCode> {
    let m = dataset::merge(shards, out)?;
    outln!(
        "{}: {} episodes, {} frames, merged from {} shards",
        out.display(),
        m.episodes,
        m.frames,
        m.shards
    );
    Ok(ExitCode::SUCCESS)
}
