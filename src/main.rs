//! `autobio`: the command-line front end. Thin by design: `main` parses arguments and `run`
//! dispatches each subcommand to its module (one per subcommand or pair of them), which makes one
//! library call and prints its result. Arguments are parsed into their types here, once.

#[macro_use]
mod output;
mod bench;
mod bench_import;
mod bench_leaderboard;
mod bench_photoreal;
mod bench_python;
mod check;
mod datasets;
mod demo;
mod describe;
mod diagnostics;
mod eval;
mod export_protocol;
mod front;
mod import;
mod picture;
mod progress;
mod replay;
mod submissions;
mod synth;
mod tasks_doc;

use anyhow::{Result, bail};
use clap::{Parser, Subcommand};
use std::path::PathBuf;
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

#[derive(Subcommand)]
enum Command {
    /// Check protocol or chain files and report every problem with file:line:col (exit 1 on errors)
    Check(check::CheckArgs),
    /// Write an Opentrons analysis or Protocol Designer file (schema 8), or an Autoprotocol document, as a
    /// protocol file and check it (exit 1 when refused or when the protocol does not check)
    Import(import::ImportArgs),
    /// Print the documentation of a diagnostic code (e.g. E0010); `autobio explain --all` lists them
    Explain(check::ExplainArgs),
    /// Print a task sheet: instruction, parameters, randomisation, plan, checks, time limits
    Describe(describe::DescribeArgs),
    /// Compile a protocol and print the task as JSON
    Compile(describe::CompileArgs),
    /// Record scripted-expert demonstrations: MCAP recordings, or a LeRobot dataset (v2.1 for
    /// openpi, v3.0 for lerobot 0.4+) with every camera at 50 Hz; failed episodes are not written
    Demo(demo::DemoArgs),
    /// Turn MCAP recordings into a LeRobot dataset (cameras redrawn from the recorded states), or a
    /// protocol into Autoprotocol (`--to autoprotocol`)
    Export(datasets::ExportArgs),
    /// Work with datasets
    Dataset {
        #[command(subcommand)]
        command: datasets::DatasetCommand,
    },
    /// Evaluate a policy on protocols: seeded episodes, a results table and results JSON
    Eval(eval::EvalArgs),
    /// Work with finished run records
    Results {
        #[command(subcommand)]
        command: eval::ResultsCommand,
    },
    /// Leaderboard submissions: pack finished suite runs into a bundle, verify a bundle offline
    Leaderboard {
        #[command(subcommand)]
        command: submissions::LeaderboardCommand,
    },
    /// Re-score a recording offline; re-simulate it from its recorded state (--simulate) or redraw
    /// its cameras at any size (--render)
    Replay(replay::ReplayArgs),
    /// Draw a seed's initial scene (every task camera and a view from above) to a PNG, without
    /// running the expert
    Render(picture::RenderArgs),
    /// Measure every task under the folders (expert and hold on the same seeds) and write the task
    /// table (docs/tasks.md)
    Tasks(tasks_doc::TasksArgs),
    /// Measure throughput: physics steps/s (harness vs bare mj_step), rendered frames/s, expert episodes/min
    Bench(bench::BenchArgs),
    /// Write random long-horizon protocols made of the steps given protocols show on their
    /// benches, each proven (state proof) and reach-checked: a training suite whose every task
    /// is possible
    Synth(synth::SynthArgs),
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

fn run(cli: Cli) -> Result<ExitCode> {
    if let Some(r) = &cli.root
        && !r.is_dir()
    {
        bail!("--root {}: not a folder", r.display());
    }
    let front = front::Front {
        root: cli.root,
        color: cli.color.for_stderr(),
    };
    match &cli.command {
        Command::Check(a) => check::check(&front, a),
        Command::Explain(a) => check::explain(a),
        Command::Import(a) => import::run(&front, a),
        Command::Describe(a) => describe::describe(&front, a),
        Command::Compile(a) => describe::compile(&front, a),
        Command::Demo(a) => demo::run(&front, a),
        Command::Export(a) => datasets::export_cli(&front, a),
        Command::Dataset { command } => datasets::dataset_cli(command),
        Command::Eval(a) => eval::eval(&front, a),
        Command::Results { command } => eval::results(command),
        Command::Leaderboard { command } => submissions::run(command),
        Command::Replay(a) => replay::run(a),
        Command::Render(a) => picture::run(&front, a),
        Command::Tasks(a) => tasks_doc::run_cli(a),
        Command::Bench(a) => bench::run_cli(&front, a),
        Command::Synth(a) => synth::run(a),
    }
}
