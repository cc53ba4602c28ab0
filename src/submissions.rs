//! `autobio leaderboard submit` (finished suite runs packed into a bundle) and `autobio
//! leaderboard verify` (a bundle checked offline, every episode re-enacted from its seed and
//! actions). The work is `leaderboard::bundle` and `leaderboard::verify`; the re-enactment is
//! `scoring::replay::reenact`, handed to the verifier.

use anyhow::Result;
use std::path::PathBuf;
use std::process::ExitCode;

#[derive(Clone, Debug, clap::Subcommand)]
pub(crate) enum LeaderboardCommand {
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
        /// A folder of suites to verify against (default: the suites and protocols this autobio
        /// shipped, compiled into it: verification needs no checkout)
        #[arg(long)]
        suites: Option<PathBuf>,
        /// Episodes re-enacted at once
        #[arg(long, default_value_t = 2, value_parser = clap::value_parser!(u32).range(1..=256))]
        workers: u32,
        /// The folder to unpack into (default: a fresh one under the system's temporary folder,
        /// removed afterwards)
        #[arg(long)]
        work: Option<PathBuf>,
        /// Lower unpacking limits than a bundle's (members, bytes of a member, bytes in all):
        /// for tests of the refusals at the limits, which real bundles are far from
        #[arg(long, hide = true, num_args = 3, value_names = ["MEMBERS", "MEMBER_BYTES", "TOTAL_BYTES"])]
        limits: Option<Vec<u64>>,
    },
    /// Audit a bundle against the submitter's live model server: its success rate on fresh seeds,
    /// per suite task, tested against the bundle's claim (one-sided Fisher exact test). Exit 0:
    /// consistent; 1: inconsistent
    Audit {
        bundle: PathBuf,
        /// The model server (`ws://HOST:PORT`)
        #[arg(long, value_name = "URL")]
        model: String,
        /// The protocol the model server speaks: `openpi` or `vla-eval`
        #[arg(long, default_value = "openpi")]
        wire: results::run::record::Wire,
        /// The model's profile (`pi0`, `rdt` or a file): use the one the bundle's runs used
        #[arg(long, default_value = "pi0")]
        profile: String,
        /// Fresh episodes per task
        #[arg(long, default_value_t = 20)]
        episodes: usize,
        /// The audit's first seed (default: drawn from the operating system's randomness and
        /// printed, above any seed a suite plans); give it to repeat an audit
        #[arg(long)]
        seed: Option<u64>,
        /// A folder of suites (default: the ones this autobio shipped, compiled into it)
        #[arg(long)]
        suites: Option<PathBuf>,
        /// Episodes run at once
        #[arg(long, default_value_t = 1, value_parser = clap::value_parser!(u32).range(1..=256))]
        workers: u32,
    },
    /// Build the static leaderboard site from every bundle in DIR (with the verification and
    /// audit records `verify` and `audit` left beside each), plus the paper's reference entry
    Build {
        dir: PathBuf,
        #[arg(long, value_name = "SITE")]
        out: PathBuf,
        /// Who draws the episode pages' frames from the recorded states
        #[command(flatten)]
        renderer: crate::front::RendererArgs,
    },
}

pub(crate) fn run(c: &LeaderboardCommand) -> Result<ExitCode> {
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
            limits,
        } => {
            let mut lim = leaderboard::bundle::Limits::default();
            if let Some([members, member, total]) = limits.as_deref() {
                lim.max_members = *members as usize;
                lim.max_member = *member;
                lim.max_total = *total;
            }
            verify(
                bundle,
                suites.as_deref(),
                *workers as usize,
                work.as_deref(),
                &lim,
            )
        }
        LeaderboardCommand::Audit { .. } => audit(c),
        LeaderboardCommand::Build { dir, out, renderer } => {
            let renderer = renderer.renderer(1);
            let draw = move |p: &std::path::Path| draw_frames(p, renderer);
            // A fresh private folder, removed when dropped.
            let work = tempfile::Builder::new().prefix("autobio-site-").tempdir()?;
            let subs = leaderboard::site::load(dir, work.path())?;
            let files = leaderboard::site::build(&subs, out, Some(&draw))?;
            outln!(
                "built {} ({} submissions, {} files); open {}",
                out.display(),
                subs.len(),
                files.len(),
                out.join("index.html").display()
            );
            Ok(ExitCode::SUCCESS)
        }
    }
}

/// The verifier's re-enactment: `scoring::replay::reenact`, its error in the verifier's terms.
pub(crate) fn reenact(
    task: &compiler::Task,
    seed: u64,
    actions: &[Vec<f64>],
    opts: &leaderboard::verify::ReenactOptions,
) -> Result<leaderboard::verify::Reenacted, leaderboard::verify::ReenactError> {
    scoring::replay::reenact(task, seed, actions, opts)
        .map_err(|e| leaderboard::verify::ReenactError::new(task, seed, e))
}

/// Three frames (start, middle, end) of a recording's first camera at 224x224, drawn from its
/// recorded states by `renderer`: the submission page's look at an episode.
fn draw_frames(
    path: &std::path::Path,
    renderer: runtime::cameras::Renderer,
) -> Result<Vec<Vec<u8>>, String> {
    let rec = scoring::replay::Recording::open(path).map_err(|e| e.to_string())?;
    // Steps 0, about half way and about the end: three frames drawn, not the whole episode.
    let every = (rec.steps().saturating_sub(1) / 2).max(1);
    let opts = scoring::replay::FrameOptions {
        size: Some([224, 224]),
        detail: None,
        every: Some(every),
        renderer,
    };
    let mut pngs = Vec::new();
    scoring::replay::frames(&rec, &opts, |_, _, images| {
        if let Some(first) = images.first()
            && pngs.len() < 3
        {
            let png = first
                .to_png()
                .map_err(|e| scoring::replay::ReplayError::Consumer(Box::new(e)))?;
            pngs.push(png);
        }
        Ok(())
    })
    .map_err(|e| e.to_string())?;
    Ok(pngs)
}

/// A first seed nobody could have known: 2^40 plus 40 random bits from the operating system
/// (through the standard library's randomly keyed hasher), far above the seeds suites plan.
fn fresh_seed() -> u64 {
    use std::hash::{BuildHasher, Hasher};
    let mut h = std::collections::hash_map::RandomState::new().build_hasher();
    h.write_u64(std::process::id() as u64);
    (1 << 40) + (h.finish() >> 24)
}

fn audit(c: &LeaderboardCommand) -> Result<ExitCode> {
    use anyhow::Context;
    let LeaderboardCommand::Audit {
        bundle,
        model,
        wire,
        profile,
        episodes,
        seed,
        suites,
        workers,
    } = c
    else {
        unreachable!("called for audit only")
    };
    let temp = tempfile::Builder::new()
        .prefix("autobio-audit-")
        .tempdir()?;
    let suites = &suites_folder(suites.as_deref(), temp.path())?;
    let unpacked =
        leaderboard::bundle::unpack(bundle, &temp.path().join("bundle"), &Default::default())
            .with_context(|| format!("reading {}", bundle.display()))?;
    let claimed = leaderboard::audit::claimed(&unpacked)?;
    // The shipped suite the bundle ran, found by its file's hash (its name is never a path).
    let suite = leaderboard::verify::shipped_suite(suites, &unpacked.index.suite_sha256)
        .with_context(|| {
            format!(
                "{}'s suite `{}` is not a shipped suite in {}",
                bundle.display(),
                unpacked.index.suite.name,
                suites.display()
            )
        })?;
    let seed = seed.unwrap_or_else(fresh_seed);
    errln!(
        "auditing {} against {model}: {episodes} episodes per task from seed {seed}",
        bundle.display()
    );
    let spec = scoring::eval::ModelSpec {
        url: model.clone(),
        wire: *wire,
        profile: results::profile::LoadedProfile::load(profile)?,
        attempts: 4,
        backoff_s: 0.25,
    };
    let mut rows = Vec::new();
    for entry in suite.entries() {
        let protocol = &entry.protocol;
        let checked = compiler::check_file(protocol, None)?;
        let task = entry.task(
            checked
                .task
                .with_context(|| format!("the shipped {} does not compile", protocol.display()))?,
        );
        let opts = scoring::eval::EvalOptions {
            episodes: *episodes,
            seed,
            model: Some(spec.clone()),
            workers: *workers as usize,
            ..Default::default()
        };
        let report = scoring::eval::evaluate(&task, &opts, |_| {})?;
        let audited = leaderboard::audit::Count {
            successes: report.summary.successes as u64,
            episodes: report.summary.episodes as u64,
        };
        let claim = claimed
            .get(&task.id)
            .copied()
            .unwrap_or(leaderboard::audit::Count {
                successes: 0,
                episodes: 0,
            });
        rows.push((task.id.clone(), claim, audited));
    }
    let a = leaderboard::audit::audit(rows);
    outln!(
        "{:<34} {:>14} {:>14} {:>10}",
        "task",
        "claimed",
        "audited",
        "p"
    );
    for t in &a.tasks {
        outln!(
            "{:<34} {:>5}/{:<4} {:>3.0}% {:>5}/{:<4} {:>3.0}% {:>10.3e}",
            t.task,
            t.claimed.successes,
            t.claimed.episodes,
            100.0 * t.claimed.rate(),
            t.audited.successes,
            t.audited.episodes,
            100.0 * t.audited.rate(),
            t.p_value
        );
    }
    outln!(
        "{:<34} {:>5}/{:<4} {:>3.0}% {:>5}/{:<4} {:>3.0}% {:>10.3e}",
        "pooled",
        a.pooled_claimed.successes,
        a.pooled_claimed.episodes,
        100.0 * a.pooled_claimed.rate(),
        a.pooled_audited.successes,
        a.pooled_audited.episodes,
        100.0 * a.pooled_audited.rate(),
        a.pooled_p_value
    );
    outln!("rule: {}", a.rule);
    let reasons: Vec<String> = a
        .tasks
        .iter()
        .filter(|t| t.p_value < leaderboard::audit::ALPHA)
        .map(|t| {
            format!(
                "audit (seed {seed}): {} scored {}/{} live against {}/{} claimed (p = {:.2e})",
                t.task,
                t.audited.successes,
                t.audited.episodes,
                t.claimed.successes,
                t.claimed.episodes,
                t.p_value
            )
        })
        .collect();
    leaderboard::site::write_record(bundle, "audit", a.consistent, &reasons)?;
    if a.consistent {
        outln!("audited: consistent with the bundle's claim (seed {seed})");
        Ok(ExitCode::SUCCESS)
    } else {
        outln!("audit failed: the live model scores below the bundle's claim (seed {seed})");
        Ok(ExitCode::from(1))
    }
}

/// The suites folder to check a bundle against: the one given, or the shipped suites and
/// protocols compiled into this autobio, written out under `scratch`.
fn suites_folder(
    given: Option<&std::path::Path>,
    scratch: &std::path::Path,
) -> Result<std::path::PathBuf> {
    use anyhow::Context;
    match given {
        Some(dir) => Ok(dir.to_path_buf()),
        None => leaderboard::shipped::write_out(&scratch.join("shipped"))
            .with_context(|| format!("writing the shipped suites under {}", scratch.display())),
    }
}

fn verify(
    bundle: &std::path::Path,
    suites: Option<&std::path::Path>,
    workers: usize,
    work: Option<&std::path::Path>,
    limits: &leaderboard::bundle::Limits,
) -> Result<ExitCode> {
    // Fresh private folders (removed when dropped): the shipped files, and the bundle unpacked
    // unless --work names a folder for it.
    let temp = tempfile::Builder::new()
        .prefix("autobio-verify-")
        .tempdir()?;
    let suites = suites_folder(suites, temp.path())?;
    let dir = work.map_or_else(|| temp.path().join("bundle"), |w| w.to_path_buf());
    let unpacked = leaderboard::bundle::unpack(bundle, &dir, limits);
    let unpacked = match unpacked {
        Ok(u) => u,
        Err(e) => {
            leaderboard::site::write_record(bundle, "verification", false, &[e.to_string()])?;
            outln!("refused: {}: {e}", bundle.display());
            return Ok(ExitCode::from(1));
        }
    };
    let opts = leaderboard::verify::VerifyOptions { suites, workers };
    let v = leaderboard::verify::verify(&unpacked, &opts, &reenact);
    drop(temp);
    // The record the site reads: this verification, of these exact bytes.
    leaderboard::site::write_record(bundle, "verification", v.accepted(), &v.failures)?;
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
