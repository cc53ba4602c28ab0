//! `autobio leaderboard submit` (finished suite runs packed into a bundle) and `autobio
//! leaderboard verify` (a bundle checked offline, every episode re-enacted from its seed and
//! actions). The work is `leaderboard::bundle` and `leaderboard::verify`; the re-enactment is
//! `scoring::replay::reenact`, handed to the verifier.

use anyhow::Result;
use std::path::PathBuf;
use std::process::ExitCode;

#[derive(Clone, Debug, clap::Subcommand)]
pub enum LeaderboardCommand {
    /// Pack finished suite runs (`eval --suite ... --out RUN`, or its shards) into a bundle: a tar
    /// archive (zstd-compressed when BUNDLE ends in .zst) with an index of every file's SHA-256
    Submit {
        /// The runs' --out folders
        #[arg(required = true)]
        runs: Vec<PathBuf>,
        /// The model's name on the leaderboard
        #[arg(long)]
        model_name: String,
        /// How the model was trained, as free text ("100 demos")
        #[arg(long)]
        training: Option<String>,
        #[arg(long, value_name = "BUNDLE")]
        out: PathBuf,
    },
    /// Verify a bundle offline: file hashes, the shipped suite and protocols, a complete seed set,
    /// and every episode re-enacted from its seed and recorded actions alone. Exit 0: accepted;
    /// 1: refused (each reason listed)
    Verify {
        bundle: PathBuf,
        /// Where the shipped suites are
        #[arg(long, default_value = "suites")]
        suites: PathBuf,
        /// Episodes re-enacted at once
        #[arg(long, default_value_t = 2, value_parser = clap::value_parser!(u32).range(1..=256))]
        workers: u32,
        /// The folder to unpack into (default: a fresh one under the system's temporary folder,
        /// removed afterwards)
        #[arg(long)]
        work: Option<PathBuf>,
    },
}

pub fn run(c: &LeaderboardCommand) -> Result<ExitCode> {
    match c {
        LeaderboardCommand::Submit {
            runs,
            model_name,
            training,
            out,
        } => {
            let opts = leaderboard::bundle::SubmitOptions {
                model_name: model_name.clone(),
                training: training.clone(),
                out: out.clone(),
            };
            let index = leaderboard::bundle::submit(runs, &opts)?;
            outln!(
                "wrote {}: {} for suite {} ({} files)",
                out.display(),
                index.model.name,
                index.suite.name,
                index.files.len()
            );
            Ok(ExitCode::SUCCESS)
        }
        LeaderboardCommand::Verify {
            bundle,
            suites,
            workers,
            work,
        } => verify(bundle, suites, *workers as usize, work.as_deref()),
    }
}

fn verify(
    bundle: &std::path::Path,
    suites: &std::path::Path,
    workers: usize,
    work: Option<&std::path::Path>,
) -> Result<ExitCode> {
    let temp = std::env::temp_dir().join(format!("autobio-verify-{}", std::process::id()));
    let dir = work.unwrap_or(&temp);
    let unpacked = leaderboard::bundle::unpack(bundle, dir, &Default::default());
    let unpacked = match unpacked {
        Ok(u) => u,
        Err(e) => {
            if work.is_none() {
                let _ = std::fs::remove_dir_all(&temp);
            }
            outln!("refused: {}: {e}", bundle.display());
            return Ok(ExitCode::from(1));
        }
    };
    let opts = leaderboard::verify::VerifyOptions {
        suites: suites.to_path_buf(),
        workers,
    };
    let reenact = |task: &compiler::Task, seed: u64, actions: &[Vec<f64>]| {
        scoring::replay::reenact(task, seed, actions)
            .map(|r| leaderboard::verify::Reenacted {
                hash: r.hash,
                success: r.verdict.success,
                score: r.verdict.score,
                control_steps: r.control_steps,
                finished: r.finished,
                unused_actions: r.unused_actions,
                refused: r.refused,
            })
            .map_err(|e| e.to_string())
    };
    let v = leaderboard::verify::verify(&unpacked, &opts, &reenact);
    if work.is_none() {
        let _ = std::fs::remove_dir_all(&temp);
    }
    let i = &unpacked.index;
    outln!(
        "{}: {} on suite {} ({} tasks, {} episodes); {} episodes re-enacted in {:.1} s ({:.1}/s, {} workers)",
        bundle.display(),
        i.model.name,
        i.suite.name,
        v.tasks,
        v.episodes,
        v.reenacted,
        v.reenact_wall_s,
        v.reenacted as f64 / v.reenact_wall_s.max(1e-9),
        workers
    );
    if v.accepted() {
        outln!("accepted");
        return Ok(ExitCode::SUCCESS);
    }
    for f in &v.failures {
        outln!("refused: {f}");
    }
    outln!("{} reason(s) to refuse the bundle", v.failures.len());
    Ok(ExitCode::from(1))
}
