//! `autobio`: the command-line front end. Thin by design: `main` parses arguments, `run` calls one
//! library function per subcommand and renders its result; no logic lives here beyond formatting.

mod bench;
mod diagnostics;

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
    /// Record scripted-expert demonstrations (MCAP with camera images) into a folder
    Demo {
        #[arg(long)]
        protocol: PathBuf,
        #[arg(long, default_value_t = 1)]
        episodes: usize,
        #[arg(long, default_value_t = 0)]
        seed: u64,
        #[arg(long, default_value = "out/demo")]
        out: PathBuf,
    },
    /// Evaluate a policy on protocols: seeded episodes, a results table and results JSON
    Eval {
        #[arg(long, required = true)]
        protocol: Vec<PathBuf>,
        /// The policy: `expert` (the scripted expert) or `hold` (no motion: the control every task
        /// must fail)
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
    },
    /// Re-score a recording offline from its recorded state (no simulation)
    Replay { recording: PathBuf },
    /// Measure throughput: physics steps/s (harness vs bare mj_step), rendered frames/s, expert episodes/min
    Bench {
        /// Task scenes to measure (repeatable)
        #[arg(
            long,
            default_values = ["protocols/thermal_cycler/close_lid.toml", "protocols/tube/transfer.toml"]
        )]
        protocol: Vec<PathBuf>,
    },
}

fn main() -> ExitCode {
    match run(Cli::parse()) {
        Ok(code) => code,
        Err(e) => {
            eprintln!("error: {e:#}");
            ExitCode::from(2)
        }
    }
}

fn load(path: &Path) -> Result<compiler::Task> {
    let source =
        std::fs::read_to_string(path).with_context(|| format!("cannot read {}", path.display()))?;
    let name = path.display().to_string();
    let (task, diags) = compiler::compile_source(&source, &name);
    match task {
        Some(t) => Ok(t),
        None => {
            eprint!("{}", diagnostics::render_all(&name, &source, &diags));
            bail!("{name} has errors; run `autobio check {name}`")
        }
    }
}

fn run(cli: Cli) -> Result<ExitCode> {
    match cli.command {
        Command::Check { files, json } => {
            let mut failed = false;
            for f in &files {
                let source = std::fs::read_to_string(f)
                    .with_context(|| format!("cannot read {}", f.display()))?;
                let name = f.display().to_string();
                let (_, diags) = compiler::compile_source(&source, &name);
                failed |= diags.iter().any(|d| d.is_error());
                if json {
                    for d in &diags {
                        println!("{}", diagnostics::to_json(&name, &source, d));
                    }
                } else if diags.is_empty() {
                    println!("ok: {name}");
                } else {
                    eprint!("{}", diagnostics::render_all(&name, &source, &diags));
                }
            }
            Ok(if failed {
                ExitCode::FAILURE
            } else {
                ExitCode::SUCCESS
            })
        }
        Command::Explain { code, all } => {
            if all {
                for c in dsl::Code::ALL {
                    println!("{c}  {}", c.summary());
                }
                return Ok(ExitCode::SUCCESS);
            }
            let code = code.unwrap_or_default();
            match dsl::Code::from_name(&code) {
                Some(c) => {
                    println!("{c}: {}\n\n{}", c.summary(), c.explanation());
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
                print!("{}", compiler::describe::catalogue());
                return Ok(ExitCode::SUCCESS);
            }
            let file = file.context("a protocol or chain file is needed")?;
            let task = load(&file)?;
            print!("{}", compiler::describe(&task));
            if let Some(seed) = seed {
                print!("{}", compiler::describe::example(&task, seed));
            }
            Ok(ExitCode::SUCCESS)
        }
        Command::Compile { file } => {
            let task = load(&file)?;
            println!("{}", serde_json::to_string_pretty(&task)?);
            Ok(ExitCode::SUCCESS)
        }
        Command::Demo {
            protocol,
            episodes,
            seed,
            out,
        } => {
            let task = load(&protocol)?;
            let opts = scoring::eval::EvalOptions {
                policy: "expert".into(),
                episodes,
                seed,
                out: Some(out.clone()),
                record: true,
                image_every: 5,
            };
            let report = scoring::evaluate(&task, &opts, |e| {
                println!(
                    "seed {:>4}  {}  {:.1} s  {}",
                    e.seed,
                    if e.success { "success" } else { "FAIL   " },
                    e.sim_time_s,
                    e.recording.as_deref().unwrap_or("")
                );
            })
            .map_err(anyhow::Error::msg)?;
            println!(
                "{} demonstrations of {} in {} ({} successful)",
                report.summary.episodes,
                task.id,
                out.display(),
                report.summary.successes
            );
            Ok(ExitCode::SUCCESS)
        }
        Command::Eval {
            protocol,
            policy,
            episodes,
            seed,
            out,
            record,
        } => {
            if !scoring::POLICIES.contains(&policy.as_str()) {
                bail!(
                    "unknown policy `{policy}`: this build evaluates {} (model servers over websocket come with `--model`)",
                    scoring::POLICIES.join(", ")
                );
            }
            let mut rows = Vec::new();
            for p in &protocol {
                let task = load(p)?;
                let opts = scoring::eval::EvalOptions {
                    policy: policy.clone(),
                    episodes,
                    seed,
                    out: out.clone(),
                    record,
                    image_every: if record { 5 } else { 0 },
                };
                eprintln!(
                    "evaluating {} ({} episodes from seed {seed})",
                    task.id, episodes
                );
                let report = scoring::evaluate(&task, &opts, |e| {
                    if let Some(err) = &e.error {
                        eprintln!("  seed {}: failed: {err}", e.seed);
                    }
                })
                .map_err(anyhow::Error::msg)?;
                rows.push(report);
            }
            println!(
                "{:<32} {:>7} {:>16} {:>6} {:>9} {:>10}",
                "task", "policy", "success (±SEM)", "score", "episodes", "wall time"
            );
            for r in &rows {
                let s = &r.summary;
                println!(
                    "{:<32} {:>7} {:>8.1}% ± {:>4.1} {:>6.3} {:>9} {:>9.1}s",
                    r.task_id,
                    r.policy,
                    100.0 * s.success_rate,
                    100.0 * s.sem,
                    s.mean_score,
                    s.episodes,
                    s.wall_time_s
                );
            }
            if let Some(o) = &out {
                println!("results: {}/<task>.results.json", o.display());
            }
            Ok(ExitCode::SUCCESS)
        }
        Command::Replay { recording } => {
            let rec = runtime::record::read_recording(&recording)
                .with_context(|| format!("cannot read {}", recording.display()))?;
            let task: compiler::Task = serde_json::from_value(rec.task.clone())
                .context("the recording's task does not match this autobio's task schema")?;
            let params: compiler::params::Bindings =
                serde_json::from_value(rec.instance["params"].clone())
                    .context("the recording's scene instance has no drawn parameters")?;
            let verdict = scoring::Judge::replay(&task, &params, &rec.labware_series);
            println!(
                "{}: {} messages over {:.2} s",
                recording.display(),
                rec.messages,
                rec.duration_s
            );
            for (topic, n) in &rec.topics {
                println!("  {topic:<28} {n}");
            }
            println!(
                "re-scored: {} (score {:.3})",
                if verdict.success {
                    "success"
                } else {
                    "failure"
                },
                verdict.score
            );
            for (i, st) in verdict.stages.iter().enumerate() {
                let done = st
                    .completed_at_s
                    .map(|t| format!("done at {t:.2} s"))
                    .unwrap_or_else(|| "not done".into());
                println!("  stage {} `{}`: {done}", i + 1, st.id);
                for p in &st.predicates {
                    println!(
                        "    [{}] {:<28} value {:+.4} target {:+.4} tol {}",
                        if p.holds { "x" } else { " " },
                        p.text,
                        p.value,
                        p.target,
                        p.tolerance
                    );
                }
            }
            if let Some(v) = &rec.verdict {
                let recorded = v["verdict"]["success"].as_bool();
                if recorded != Some(verdict.success) {
                    println!("note: the recorded verdict was {recorded:?}");
                }
            }
            Ok(if verdict.success {
                ExitCode::SUCCESS
            } else {
                ExitCode::FAILURE
            })
        }
        Command::Bench { protocol } => {
            let tasks = protocol
                .iter()
                .map(|p| load(p))
                .collect::<Result<Vec<_>>>()?;
            bench::run(&tasks)?;
            Ok(ExitCode::SUCCESS)
        }
    }
}
