//! `autobio`: the command-line front end. Thin by design: `main` parses arguments, `run` calls one
//! library function per subcommand and renders its result; no logic lives here beyond formatting.

#[macro_use]
mod output;
mod bench;
mod datasets;
mod diagnostics;
mod progress;
mod replay;
mod tasks_doc;

use anyhow::{Context, Result, bail};
use clap::{Parser, Subcommand};
use std::path::{Path, PathBuf};
use std::process::ExitCode;

#[derive(Parser)]
#[command(
    name = "autobio",
    version,
    about = "Lab protocols as robot tasks: compile, demonstrate, evaluate, replay"
)]
struct Cli {
    #[command(subcommand)]
    command: Command,
    /// The folder a chain's stage files must stay inside (default: each chain's own folder)
    #[arg(long, global = true, value_name = "DIR")]
    root: Option<PathBuf>,
    /// Colour diagnostics: `auto` (on a terminal, unless NO_COLOR is set), `always` or `never`
    #[arg(long, global = true, value_enum, default_value = "auto")]
    color: diagnostics::ColorChoice,
}

/// What every subcommand that reads protocols needs.
struct Front {
    root: Option<PathBuf>,
    color: bool,
}

#[derive(Subcommand)]
enum Command {
    /// Check protocol or chain files and report every problem with file:line:col (exit 1 on errors)
    Check {
        files: Vec<PathBuf>,
        /// Print the diagnostics as JSON lines (one object per diagnostic) instead of text
        #[arg(long)]
        json: bool,
    },
    /// Print the documentation of a diagnostic code (e.g. E0010); `autobio explain --all` lists them
    Explain {
        #[arg(required_unless_present = "all")]
        code: Option<String>,
        #[arg(long)]
        all: bool,
    },
    /// Print a task sheet: instruction, parameters, randomisation, plan, checks, time limits
    Describe {
        #[arg(required_unless_present = "catalogue")]
        file: Option<PathBuf>,
        /// Print the catalogue of labware kinds and lab primitives instead
        #[arg(long)]
        catalogue: bool,
        /// Also show the parameters and instruction one episode with this seed draws
        #[arg(long)]
        seed: Option<u64>,
    },
    /// Compile a protocol and print the task as JSON
    Compile { file: PathBuf },
    /// Record scripted-expert demonstrations: MCAP recordings, or a LeRobot dataset (v2.1 for
    /// openpi, v3.0 for lerobot 0.4+) with every camera at 50 Hz; failed episodes are not written
    Demo {
        #[arg(long, required = true)]
        protocol: Vec<PathBuf>,
        #[arg(long, default_value_t = 1)]
        episodes: usize,
        #[arg(long, default_value_t = 0)]
        seed: u64,
        #[arg(long, default_value = "out/demo")]
        out: PathBuf,
        /// `mcap` (one recording per episode), `lerobot-v21` or `lerobot-v30`
        #[arg(long, default_value = "mcap")]
        format: DemoFormat,
        /// Dataset videos: `av1` (libsvtav1, LeRobot's default) or `h264`
        #[arg(long, default_value = "av1")]
        codec: String,
        /// Continue the dataset in --out (episodes already in it are not recorded again)
        #[arg(long)]
        resume: bool,
        /// Episodes recorded at once, each thread with its own scene and renderer
        #[arg(long, default_value_t = 1, value_parser = clap::value_parser!(u32).range(1..=256))]
        workers: u32,
        /// Record only shard I of N (datasets): every N-th episode of the plan from position I,
        /// into its own --out; join the shards with `autobio dataset merge`
        #[arg(long, value_name = "I/N")]
        shard: Option<scoring::eval::Shard>,
        #[command(flatten)]
        files: datasets::FileSizeArgs,
    },
    /// Turn MCAP recordings into a LeRobot dataset (cameras redrawn from the recorded states)
    Export {
        /// Recordings, or folders of them
        #[arg(required = true)]
        recordings: Vec<PathBuf>,
        /// `lerobot-v21` or `lerobot-v30`
        #[arg(long, default_value = "lerobot-v30")]
        format: datasets::DatasetFormat,
        #[arg(long)]
        out: PathBuf,
        /// Dataset videos: `av1` (libsvtav1, LeRobot's default) or `h264`
        #[arg(long, value_enum, default_value = "av1")]
        codec: datasets::CodecArg,
        /// Camera image size WxH
        #[arg(long, default_value = "224x224", value_parser = replay::parse_size)]
        size: [usize; 2],
        /// Continue the dataset in --out (recordings already in it are skipped)
        #[arg(long)]
        resume: bool,
        #[command(flatten)]
        files: datasets::FileSizeArgs,
    },
    /// Work with datasets
    Dataset {
        #[command(subcommand)]
        command: DatasetCommand,
    },
    /// Evaluate a policy on protocols: seeded episodes, a results table and results JSON
    Eval {
        #[arg(long, required = true)]
        protocol: Vec<PathBuf>,
        /// The policy: `expert` (the scripted expert), `hold` (no motion: the control every task
        /// must fail) or `replay:PATH` (the actions of a recording, or of `<task>_seed<seed>.mcap`
        /// in a folder, for the same seed)
        #[arg(long, default_value = "expert")]
        policy: String,
        #[arg(long, default_value_t = 20)]
        episodes: usize,
        #[arg(long, default_value_t = 0)]
        seed: u64,
        /// Folder for results JSON, the episode journal and (with --record) recordings
        #[arg(long)]
        out: Option<PathBuf>,
        /// Write one MCAP recording per episode (with camera images)
        #[arg(long)]
        record: bool,
        /// With --record: camera images every this many control steps (0: none)
        #[arg(long, default_value_t = 5, requires = "record")]
        image_every: u32,
        /// Continue the run in --out: only if its manifest matches (task, protocol, policy, seed,
        /// version), never rerunning a finished episode
        #[arg(long, requires = "out")]
        resume: bool,
        /// Evaluate the model server at this address (`ws://HOST:PORT`) instead of --policy
        #[arg(long, value_name = "URL", conflicts_with = "policy")]
        model: Option<String>,
        /// The protocol the model server speaks: `openpi` or `vla-eval`
        #[arg(long, default_value = "openpi", requires = "model")]
        wire: scoring::remote::Wire,
        /// How observations and actions map onto the model: `pi0`, `rdt` or a profile file
        #[arg(long, default_value = "pi0", requires = "model")]
        profile: String,
        /// Connection attempts per episode before it fails as a server fault (backoff from
        /// 0.25 s, doubling)
        #[arg(long, default_value_t = 4, requires = "model")]
        connect_attempts: u32,
        /// Repeat the evaluation K times on fresh seeds (run r starts at seed + r*2^20): per-run
        /// figures and their mean ± SEM
        #[arg(long, default_value_t = 1, value_name = "K", value_parser = clap::value_parser!(u32).range(1..))]
        runs: u32,
        /// Episodes run at once, each thread with its own scene, renderer and model connection
        #[arg(long, default_value_t = 1, value_parser = clap::value_parser!(u32).range(1..=256))]
        workers: u32,
        /// Run only share I of N of the episodes (0-based), into its own --out; join the shards
        /// with `autobio results merge`
        #[arg(long, value_name = "I/N", requires = "out")]
        shard: Option<scoring::eval::Shard>,
    },
    /// Work with finished run records
    Results {
        #[command(subcommand)]
        command: ResultsCommand,
    },
    /// Re-score a recording offline; re-simulate it from its recorded state (--simulate) or redraw
    /// its cameras at any size (--render)
    Replay(replay::ReplayArgs),
    /// Measure every task under the folders (expert and hold on the same seeds) and write the task
    /// table (docs/tasks.md)
    Tasks {
        /// Folders of protocol files
        #[arg(default_values = ["protocols"])]
        dirs: Vec<PathBuf>,
        /// Episodes per task and policy
        #[arg(long, default_value_t = 100, value_parser = clap::value_parser!(u32).range(1..))]
        episodes: u32,
        #[arg(long, default_value_t = 0)]
        seed: u64,
        /// Episodes run at once
        #[arg(long, default_value_t = 2, value_parser = clap::value_parser!(u32).range(1..=256))]
        workers: u32,
        /// Where to write the table (default: standard output)
        #[arg(long)]
        out: Option<PathBuf>,
    },
    /// Measure throughput: physics steps/s (harness vs bare mj_step), rendered frames/s, expert episodes/min
    Bench {
        /// Task scenes to measure (repeatable)
        #[arg(
            long,
            default_values = [
                "protocols/thermal_cycler/close_lid.toml",
                "protocols/tube/transfer.toml",
                "protocols/two_arm/close_lid_and_transfer.toml"
            ]
        )]
        protocol: Vec<PathBuf>,
        /// Measure only these sections (repeatable; default: all)
        #[arg(long, value_enum)]
        only: Vec<bench::Section>,
    },
}

#[derive(Clone, Copy, clap::ValueEnum)]
enum DemoFormat {
    Mcap,
    #[value(name = "lerobot-v21")]
    LerobotV21,
    #[value(name = "lerobot-v30")]
    LerobotV30,
}

#[derive(Subcommand)]
enum DatasetCommand {
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

#[derive(Subcommand)]
enum ResultsCommand {
    /// Join the run records of a run's shards (`eval --shard I/N`, one folder each) into one
    Merge {
        /// The shards' --out folders
        #[arg(required = true)]
        shards: Vec<PathBuf>,
        /// The folder for the merged record (its journal, manifest and results)
        #[arg(long)]
        out: PathBuf,
    },
}

fn main() -> ExitCode {
    match run(Cli::parse()) {
        Ok(code) => code,
        Err(e) => {
            errln!("error: {e:#}");
            ExitCode::from(2)
        }
    }
}

impl Front {
    /// Checks a protocol or chain file and returns its task, or shows its diagnostics and fails.
    fn load(&self, path: &Path) -> Result<compiler::Task> {
        let checked = compiler::check_file(path, self.root.as_deref())?;
        match checked.task {
            Some(ref t) if !checked.diagnostics.iter().any(|d| d.is_error()) => Ok(t.clone()),
            _ => {
                err!("{}", diagnostics::render_all(&checked, self.color));
                let name = &checked.file;
                bail!("{name} has errors; run `autobio check {name}`")
            }
        }
    }
}

fn run(cli: Cli) -> Result<ExitCode> {
    if let Some(r) = &cli.root
        && !r.is_dir()
    {
        bail!("--root {}: not a folder", r.display());
    }
    let front = Front {
        root: cli.root,
        color: cli.color.for_stderr(),
    };
    match cli.command {
        Command::Check { files, json } => {
            if files.is_empty() {
                bail!(
                    "no files to check: name protocol or chain files, e.g. `autobio check protocols/*/*.toml`"
                );
            }
            let (mut failed, mut unreadable) = (false, false);
            for f in &files {
                // A file that cannot be read is reported, and the others are still checked.
                let checked = match compiler::check_file(f, front.root.as_deref()) {
                    Ok(c) => c,
                    Err(e) => {
                        errln!("error: {e}");
                        unreadable = true;
                        continue;
                    }
                };
                failed |= checked.diagnostics.iter().any(|d| d.is_error());
                if json {
                    for d in &checked.diagnostics {
                        outln!("{}", diagnostics::to_json(&checked, d));
                    }
                } else if checked.diagnostics.is_empty() {
                    outln!("ok: {}", checked.file);
                } else {
                    err!("{}", diagnostics::render_all(&checked, front.color));
                }
            }
            Ok(if unreadable {
                ExitCode::from(2)
            } else if failed {
                ExitCode::FAILURE
            } else {
                ExitCode::SUCCESS
            })
        }
        Command::Explain { code, all } => {
            if all {
                for c in dsl::Code::ALL {
                    outln!("{c}  {}", c.summary());
                }
                return Ok(ExitCode::SUCCESS);
            }
            let code = code.unwrap_or_default();
            match dsl::Code::from_name(&code) {
                Some(c) => {
                    outln!("{c}: {}\n\n{}", c.summary(), c.explanation());
                    Ok(ExitCode::SUCCESS)
                }
                None => bail!(
                    "no diagnostic code `{code}` (codes look like E0010; `autobio explain --all` lists them)"
                ),
            }
        }
        Command::Describe {
            file,
            catalogue,
            seed,
        } => {
            if catalogue {
                out!("{}", compiler::describe::catalogue());
                return Ok(ExitCode::SUCCESS);
            }
            let file = file.context("a protocol or chain file is needed")?;
            let task = front.load(&file)?;
            out!("{}", compiler::describe(&task));
            if let Some(seed) = seed {
                out!("{}", compiler::describe::example(&task, seed));
            }
            Ok(ExitCode::SUCCESS)
        }
        Command::Compile { file } => {
            let task = front.load(&file)?;
            outln!("{}", serde_json::to_string_pretty(&task)?);
            Ok(ExitCode::SUCCESS)
        }
        Command::Demo {
            protocol,
            episodes,
            seed,
            out,
            format,
            codec,
            resume,
            workers,
            shard,
            files,
        } => {
            let tasks = protocol
                .iter()
                .map(|p| front.load(p))
                .collect::<Result<Vec<_>>>()?;
            let version = match format {
                DemoFormat::Mcap if shard.is_some() => {
                    bail!("--shard splits datasets; for recordings use eval --record --shard")
                }
                DemoFormat::Mcap => {
                    return demo_mcap(&tasks, episodes, seed, &out, workers as usize);
                }
                DemoFormat::LerobotV21 => dataset::Version::V21,
                DemoFormat::LerobotV30 => dataset::Version::V30,
            };
            let codec = match codec.as_str() {
                "av1" => dataset::Codec::Av1,
                "h264" => dataset::Codec::H264,
                other => bail!("unknown codec `{other}`: av1 or h264"),
            };
            let opts = dataset::GenerateOptions {
                episodes,
                seed,
                out,
                version,
                codec,
                resume,
                image_size: [224, 224],
                workers: workers as usize,
                shard,
                file_sizes: files.sizes(),
            };
            datasets::generate(&tasks, &opts)
        }
        Command::Export {
            recordings,
            format,
            out,
            codec,
            size,
            resume,
            files,
        } => {
            let opts = dataset::ExportOptions {
                out,
                version: format.version(),
                codec: codec.codec(),
                image_size: size,
                resume,
                file_sizes: files.sizes(),
            };
            datasets::export(&recordings, &opts)
        }
        Command::Dataset {
            command: DatasetCommand::Merge { shards, out },
        } => datasets::merge(&shards, &out),
        Command::Eval {
            protocol,
            policy,
            episodes,
            seed,
            out,
            record,
            image_every,
            resume,
            model,
            wire,
            profile,
            connect_attempts,
            runs,
            workers,
            shard,
        } => {
            if !scoring::policy::known(&policy) {
                bail!(
                    "unknown policy `{policy}`: this build evaluates {} (a model server with `--model ws://HOST:PORT`)",
                    scoring::POLICIES.join(", ")
                );
            }
            let model = match model {
                Some(url) => Some(scoring::eval::ModelSpec {
                    url,
                    wire,
                    profile: scoring::profile::LoadedProfile::load(&profile)?,
                    attempts: connect_attempts.max(1),
                    backoff_s: 0.25,
                }),
                None => None,
            };
            let mut rows = Vec::new();
            for p in &protocol {
                let task = front.load(p)?;
                let opts = scoring::eval::EvalOptions {
                    policy: policy.clone(),
                    episodes,
                    seed,
                    out: out.clone(),
                    record,
                    image_every: if record { image_every } else { 0 },
                    resume,
                    model: model.clone(),
                    runs,
                    workers: workers as usize,
                    shard,
                };
                errln!(
                    "evaluating {} ({episodes} episodes{}{} from seed {seed}{})",
                    task.id,
                    if runs > 1 {
                        format!(" x {runs} runs")
                    } else {
                        String::new()
                    },
                    shard.map(|s| format!(", shard {s}")).unwrap_or_default(),
                    if workers > 1 {
                        format!(", {workers} workers")
                    } else {
                        String::new()
                    },
                );
                if let Some(m) = &model {
                    errln!(
                        "  model {} over {} with profile {} ({})",
                        m.url,
                        m.wire,
                        m.profile.profile.name,
                        m.profile.origin
                    );
                }
                let mut view = progress::ProgressView::new(&task.id);
                let report = scoring::evaluate(&task, &opts, |p| view.update(p));
                view.finish();
                let report = report?;
                rows.push(report);
            }
            print_table(&rows);
            print_runs(&rows);
            if let Some(o) = &out {
                outln!("results: {}/<task>.results.json", o.display());
            }
            Ok(ExitCode::SUCCESS)
        }
        Command::Results {
            command: ResultsCommand::Merge { shards, out },
        } => {
            let rows = scoring::eval::merge(&shards, &out)?;
            print_table(&rows);
            print_runs(&rows);
            outln!("merged: {}/<task>.results.json", out.display());
            Ok(ExitCode::SUCCESS)
        }
        Command::Replay(args) => replay::run(&args),
        Command::Tasks {
            dirs,
            episodes,
            seed,
            workers,
            out,
        } => {
            let opts = tasks_doc::Options {
                dirs,
                episodes: episodes as usize,
                seed,
                workers: workers as usize,
            };
            let table = tasks_doc::table(&opts, |line| eprintln!("{line}"))?;
            match out {
                Some(path) => {
                    std::fs::write(&path, table)
                        .with_context(|| format!("writing {}", path.display()))?;
                    outln!("wrote {}", path.display());
                }
                None => outln!("{table}"),
            }
            Ok(ExitCode::SUCCESS)
        }
        Command::Bench { protocol, only } => {
            let tasks = protocol
                .iter()
                .map(|p| front.load(p))
                .collect::<Result<Vec<_>>>()?;
            bench::run(&tasks, &only)?;
            Ok(ExitCode::SUCCESS)
        }
    }
}

/// The results table: one row per task.
fn print_table(rows: &[scoring::EvalReport]) {
    outln!(
        "{:<32} {:>7} {:>16} {:>14} {:>6} {:>9} {:>10}",
        "task",
        "policy",
        "success (±SEM)",
        "Wilson 95%",
        "score",
        "episodes",
        "wall time"
    );
    for r in rows {
        let s = &r.summary;
        outln!(
            "{:<32} {:>7} {:>8.1}% ± {:>4.1} [{:>5.1}, {:>5.1}] {:>6.3} {:>9} {:>9.1}s",
            r.task_id,
            r.policy.split(' ').next().unwrap_or_default(),
            100.0 * s.success_rate,
            100.0 * s.sem,
            100.0 * s.wilson_95[0],
            100.0 * s.wilson_95[1],
            s.mean_score,
            s.episodes,
            s.wall_time_s
        );
    }
}

/// Over several runs: each task's per-run success rates and their mean ± SEM; over several
/// tasks: the mean per level and overall.
fn print_runs(rows: &[scoring::EvalReport]) {
    if rows.len() > 1 {
        for g in scoring::eval::aggregate(rows.iter().map(|r| (r.level.as_str(), &r.summary))) {
            outln!(
                "{:<32} {:>7} {:>8.1}% (mean over {} tasks, {} episodes), score {:.3}",
                g.group,
                "",
                100.0 * g.success_rate,
                g.tasks,
                g.episodes,
                g.mean_score
            );
        }
    }
    for r in rows {
        if let Some(a) = &r.summary.across_runs {
            let each: Vec<String> = r
                .summary
                .runs
                .iter()
                .map(|x| format!("{:.1}%", 100.0 * x.success_rate))
                .collect();
            outln!(
                "{}: {} runs ({}): success {:.1}% ± {:.1} (mean ± SEM over runs), score {:.3} ± {:.3}",
                r.task_id,
                a.runs,
                each.join(", "),
                100.0 * a.success_rate_mean,
                100.0 * a.success_rate_sem,
                a.mean_score_mean,
                a.mean_score_sem
            );
        }
    }
}

/// `demo --format mcap`: one MCAP recording (with camera images) per expert episode.
fn demo_mcap(
    tasks: &[compiler::Task],
    episodes: usize,
    seed: u64,
    out: &Path,
    workers: usize,
) -> Result<ExitCode> {
    for task in tasks {
        let opts = scoring::eval::EvalOptions {
            policy: "expert".into(),
            episodes,
            seed,
            out: Some(out.to_path_buf()),
            record: true,
            image_every: 5,
            workers,
            ..Default::default()
        };
        let report = scoring::evaluate(task, &opts, |p| {
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
