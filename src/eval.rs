//! `autobio eval` (a policy or a model server on protocols: a progress line per task, then the
//! results tables) and `autobio results merge` (shards' run records joined). The work is
//! `scoring::eval::evaluate` and `results::run::merge`; the tables are `leaderboard::table`'s.

use crate::front::Front;
use crate::progress;
use anyhow::Result;
use results::run::record::results_path;
use scoring::policies::PolicySpec;
use std::path::PathBuf;
use std::process::ExitCode;

#[derive(Clone, Debug, clap::Args)]
pub(crate) struct EvalArgs {
    #[arg(long, required_unless_present = "suite")]
    protocol: Vec<PathBuf>,
    /// Run a whole suite (`suites/*.toml`: its tasks, episodes, seed and runs, which the flags
    /// may not change) into --out, recording what a leaderboard submission needs
    #[arg(long, value_name = "FILE", requires = "out", conflicts_with_all = ["protocol", "episodes", "seed", "runs", "shard"])]
    suite: Option<PathBuf>,
    /// The policy: `expert` (the scripted expert), `hold` (no motion: the control every task
    /// must fail) or `replay:PATH` (the actions of a recording, or of `<task>_seed<seed>.mcap`
    /// in a folder, for the same seed)
    #[arg(long, default_value = "expert")]
    policy: PolicySpec,
    #[arg(long, default_value_t = 20)]
    episodes: usize,
    #[arg(long, default_value_t = 0)]
    seed: u64,
    /// Folder for results JSON, the episode journal and (with --record) recordings
    #[arg(long)]
    out: Option<PathBuf>,
    /// Write one MCAP recording per episode, with camera images. A model's or a suite's run
    /// records every episode anyway, without images (its actions and states: what a
    /// leaderboard's verifier re-simulates)
    #[arg(long)]
    record: bool,
    /// With --record: camera images every this many control steps (0: none)
    #[arg(long, default_value_t = 5, requires = "record")]
    image_every: u32,
    /// Camera image size WxH (default: the task's own; a model gets its profile's size)
    #[arg(long, value_parser = crate::replay::parse_size, conflicts_with = "model")]
    size: Option<[usize; 2]>,
    /// Continue the run in --out: only if its manifest matches (task, protocol, policy, seed,
    /// version), never rerunning a finished episode
    #[arg(long, requires = "out")]
    resume: bool,
    /// Evaluate the model server at this address (`ws://HOST:PORT`) instead of --policy
    #[arg(long, value_name = "URL", conflicts_with = "policy")]
    model: Option<String>,
    /// The protocol the model server speaks: `openpi` or `vla-eval`
    #[arg(long, default_value = "openpi", requires = "model")]
    wire: results::run::record::Wire,
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
    shard: Option<results::run::Shard>,
    /// Run a protocol whose success already holds at the start (W0001; refused otherwise: a
    /// robot that does nothing would pass it)
    #[arg(long)]
    allow_trivial: bool,
    /// (A suite names its own perturbations: not with --suite.)
    #[command(flatten)]
    perturb: crate::front::PerturbArgs,
    /// The checkpoint the model serves, one of several trained alike on different training
    /// seeds (a path, a hub revision, a hash): recorded in the run, so that a leaderboard shows
    /// the SEM over training seeds, as the paper does. Needs --training-seed
    #[arg(long, value_name = "NAME", requires = "training_seed")]
    checkpoint: Option<String>,
    /// Which training seed the checkpoint is (0-based): only run K of the runs is evaluated, so
    /// one --out per training seed, packed together, covers every run once
    #[arg(long, value_name = "K", requires = "checkpoint")]
    training_seed: Option<u32>,
}

#[derive(Clone, Debug, clap::Subcommand)]
pub(crate) enum ResultsCommand {
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

pub(crate) fn eval(front: &Front, a: &EvalArgs) -> Result<ExitCode> {
    let model = match &a.model {
        Some(url) => Some(scoring::eval::ModelSpec {
            url: url.clone(),
            wire: a.wire,
            profile: results::profile::LoadedProfile::load(&a.profile)?,
            attempts: a.connect_attempts.max(1),
            backoff_s: 0.25,
        }),
        None => None,
    };
    if a.suite.is_some() && !a.perturb.presets.is_empty() {
        anyhow::bail!(
            "--perturb changes the tasks a suite names, so the run would not be the suite's; run the tasks with --protocol"
        );
    }
    let suite = match (&a.suite, &a.out) {
        (Some(file), Some(out)) => Some(suite_run(file, out)?),
        _ => None,
    };
    let (entries, episodes, seed, runs) = match &suite {
        Some(s) => (s.entries(), s.suite.episodes, s.suite.seed, s.suite.runs),
        None => {
            let clean = |p: &PathBuf| results::suite::Entry {
                protocol: p.clone(),
                listed: p.display().to_string(),
                variant: None,
            };
            let entries = a.protocol.iter().map(clean).collect();
            (entries, a.episodes, a.seed, a.runs)
        }
    };
    let mut rows = Vec::new();
    let mut written = Vec::new();
    for entry in &entries {
        let loaded = front.load_to_run(&entry.protocol, a.allow_trivial)?;
        let task = entry.task(a.perturb.apply(loaded)?);
        crate::front::refuse_problems(&task)?;
        let opts = scoring::eval::EvalOptions {
            policy: a.policy.clone(),
            episodes,
            seed,
            out: a.out.clone(),
            record: a.record || a.model.is_some() || suite.is_some(),
            image_every: if a.record { a.image_every } else { 0 },
            image_size: a.size,
            // Scores are the rasteriser's: a model is compared with others on the same frames
            // (docs/decisions.md, "Photoreal frames are a dataset pass").
            renderer: Default::default(),
            resume: a.resume,
            model: model.clone(),
            runs,
            workers: a.workers as usize,
            shard: a.shard,
            checkpoint: a
                .checkpoint
                .clone()
                .zip(a.training_seed)
                .map(|(name, run)| results::run::Checkpoint { run, name }),
        };
        errln!(
            "evaluating {} ({} episodes{}{} from seed {}{})",
            task.id,
            episodes,
            if runs > 1 {
                format!(" x {runs} runs")
            } else {
                String::new()
            },
            a.shard.map(|s| format!(", shard {s}")).unwrap_or_default(),
            seed,
            if a.workers > 1 {
                format!(", {} workers", a.workers)
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
        let mut view = progress::ProgressView::for_task(&task);
        let report = scoring::eval::evaluate(&task, &opts, |p| view.update(p));
        view.finish();
        let report = report?;
        if report.policy == "expert" {
            warn_tight_stages(&task, &report.episodes);
        }
        rows.push(report);
        if let Some(o) = &a.out {
            written.push(results_path(o, &task.id));
        }
    }
    out!("{}", leaderboard::table::results_table(&rows));
    out!("{}", leaderboard::table::runs_table(&rows));
    for path in written {
        outln!("results: {}", path.display());
    }
    Ok(ExitCode::SUCCESS)
}

/// Says which stages' time limits the expert's run found tight (`scoring::stage_time`): an author
/// validating a protocol or chain with the expert learns it before a model is held to them.
fn warn_tight_stages(task: &compiler::Task, episodes: &[results::episode::EpisodeResult]) {
    for t in scoring::stage_time::tight_stages(task, episodes) {
        let ran_out = match t.ran_out {
            0 => String::new(),
            n => format!(
                ", and ran out of time in it on {n} of {} episodes",
                episodes.len()
            ),
        };
        let hint = if t.stage > 1 {
            format!(
                "it starts where stage {} left the robot, not at its home pose: give it more time \
                 with `time_limit` in the chain's `[[stages]]`",
                t.stage - 1
            )
        } else {
            "raise the protocol's `time_limit`".to_string()
        };
        errln!(
            "warning: stage {} `{}` has a tight time limit: the expert took up to {:.1} s of its \
             {} s (seed {}){ran_out}\n  = hint: {hint}",
            t.stage,
            t.id,
            t.longest_s,
            t.limit_s,
            t.longest_seed
        );
    }
}

/// Reads the suite and leaves its copy in `out` (a run continued into `out` must be of the same
/// suite, byte for byte).
fn suite_run(file: &std::path::Path, out: &std::path::Path) -> Result<results::suite::LoadedSuite> {
    use anyhow::Context;
    let suite = results::suite::LoadedSuite::read(file)?;
    let bytes = std::fs::read(file).with_context(|| format!("reading {}", file.display()))?;
    let copy = out.join(results::suite::SUITE_FILE);
    match std::fs::read(&copy) {
        Ok(there) if there != bytes => anyhow::bail!(
            "{} holds a run of another suite ({}); use another --out",
            out.display(),
            copy.display()
        ),
        Ok(_) => {}
        Err(_) => {
            std::fs::create_dir_all(out).with_context(|| format!("creating {}", out.display()))?;
            std::fs::write(&copy, &bytes).with_context(|| format!("writing {}", copy.display()))?;
        }
    }
    let variants = if suite.suite.perturb.is_empty() {
        String::new()
    } else {
        format!(", each clean and under {}", suite.suite.perturb.join(", "))
    };
    errln!(
        "suite {} ({} tasks{variants}, {} episodes x {} runs from seed {})",
        suite.suite.name,
        suite.suite.tasks.len(),
        suite.suite.episodes,
        suite.suite.runs,
        suite.suite.seed
    );
    Ok(suite)
}

pub(crate) fn results(c: &ResultsCommand) -> Result<ExitCode> {
    match c {
        ResultsCommand::Merge { shards, out } => {
            let rows = results::run::merge(shards, out)?;
            out!("{}", leaderboard::table::results_table(&rows));
            out!("{}", leaderboard::table::runs_table(&rows));
            for r in &rows {
                outln!("merged: {}", results_path(out, &r.task_id).display());
            }
            Ok(ExitCode::SUCCESS)
        }
    }
}
