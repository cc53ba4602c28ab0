//! Offline verification of a submission bundle, trusting nothing the submitter wrote but the
//! actions. Everything the site publishes is re-derived here, and every member is either
//! re-derived or checked; a bundle is accepted only if:
//! - every member's SHA-256 is the index's, and every member is in the index;
//! - its suite is a shipped one, byte for byte (`suites/<name>.toml`);
//! - every task's compiled content is the shipped protocol's ([`task_content_sha256`]): a result
//!   for a modified task is refused;
//! - every manifest names what verification derives: this autobio's results schema, the index's
//!   autobio version, commit and model, the shipped protocol (its path ends with the suite's
//!   entry for it, and its SHA-256, the compiled task's and every protocol file's are the shipped
//!   files'), the suite's seed and sizes, the task's conditions ([`manifest`]);
//! - the journals hold every episode the suite plans, each once, and no other;
//! - runs of training seeds (`eval --checkpoint`) are all the bundle's runs or none, each folder
//!   holds only its training seed's run, and each training seed is one checkpoint;
//! - every episode, re-enacted from the scene its seed builds for the shipped task and the
//!   recorded actions alone, reproduces the journal's line field by field (trajectory hash,
//!   outcome, verdict with every stage's success, score and time and every predicate's value,
//!   length, simulated time), and its recording message by message: the re-enactment writes its
//!   own, and the two must be the same but for the policy's `/stage` labels ([`claim`]);
//! - every results file is the report of its verified journal ([`manifest::check_results`]).
//!
//! Only what no re-enactment can know is taken as claimed, and checked for form: wall times, an
//! error text a policy or server ended an episode with, and the policy's stage labels. JSON is
//! parsed into typed records (no NaN or infinity, nesting at most 128 deep). Each failure is
//! named; verification goes on past the first so one run lists them all. The re-enactment
//! itself is the caller's ([`Reenact`]): this crate links no simulator.

mod claim;
mod differ;
mod manifest;

use crate::bundle::{INDEX, Unpacked};
use compiler::Task;
use results::episode::EpisodeResult;
use results::run::record::{sha256_hex, task_content_sha256};
use results::suite::{LoadedSuite, SUITE_FILE};
use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

pub use results::end::{ReenactOptions, Reenacted};

/// Re-enacts an episode of the (shipped) task from its seed and actions, in a simulator.
pub type Reenact<'a> =
    dyn Fn(&Task, u64, &[Vec<f64>], &ReenactOptions) -> Result<Reenacted, ReenactError> + Sync + 'a;

/// Why the caller's simulator could not re-enact an episode ([`Reenact`]'s error): the task and
/// seed it was asked to re-enact, and what the simulator said. Verification names the episode
/// itself and reports `why` ("... cannot be re-enacted: {why}").
#[derive(Debug, thiserror::Error)]
// The simulator's error is part of the message and not a `source`: a chain of causes prints it
// once.
#[error("{task} seed {seed} cannot be re-enacted: {why}")]
pub struct ReenactError {
    /// The task's id.
    pub task: String,
    pub seed: u64,
    pub why: Box<dyn std::error::Error + Send + Sync>,
}

impl ReenactError {
    /// The simulator's error `why` in re-enacting `task` from `seed`.
    pub fn new(
        task: &Task,
        seed: u64,
        why: impl Into<Box<dyn std::error::Error + Send + Sync>>,
    ) -> ReenactError {
        ReenactError {
            task: task.id.clone(),
            seed,
            why: why.into(),
        }
    }
}

#[derive(Clone, Debug)]
pub struct VerifyOptions {
    /// Where the shipped suites are (`suites/`, with the protocols they name beside it).
    pub suites: PathBuf,
    /// Episodes re-enacted at once.
    pub workers: usize,
}

/// What verification found.
#[derive(Clone, Debug, Default)]
pub struct Verification {
    /// Each reason the bundle is refused; empty: accepted.
    pub failures: Vec<String>,
    pub tasks: usize,
    pub episodes: usize,
    /// Episodes re-enacted, and the wall time it took (s).
    pub reenacted: usize,
    pub reenact_wall_s: f64,
}

impl Verification {
    pub fn accepted(&self) -> bool {
        self.failures.is_empty()
    }
}

/// One claimed episode to re-enact: the task as its run compiled it (the shipped task under
/// the run's own paths) and the claim.
struct Claim {
    task: usize,
    run_dir: PathBuf,
    claimed: EpisodeResult,
}

/// Verifies an unpacked bundle (see the module doc).
pub fn verify(bundle: &Unpacked, opts: &VerifyOptions, reenact: &Reenact) -> Verification {
    let mut v = Verification {
        failures: check_members(bundle),
        ..Verification::default()
    };
    let root = &bundle.root;
    // The suite: a shipped one, byte for byte, found by its hash among the shipped files (the
    // bundle's name for it is never made into a path).
    let name = &bundle.index.suite.name;
    let Some(shipped) = shipped_suite(&opts.suites, &bundle.index.suite_sha256) else {
        v.failures.push(format!(
            "suite `{name}` is not a shipped suite: no file in {} has its SHA-256",
            opts.suites.display()
        ));
        return v;
    };
    if shipped.suite != bundle.index.suite {
        v.failures.push(format!(
            "the index's suite `{name}` is not the suite file it names"
        ));
    }
    let run_dirs: Vec<PathBuf> = run_dirs(bundle);
    for dir in &run_dirs {
        match std::fs::read(dir.join(SUITE_FILE)) {
            Ok(bytes) if sha256_hex(&bytes) == shipped.sha256 => {}
            _ => v.failures.push(format!(
                "{}: its {SUITE_FILE} is not the shipped suite `{name}`",
                rel(root, dir)
            )),
        }
    }
    let suite = &shipped.suite;
    let planned = results::run::plan(suite.seed, suite.episodes, suite.runs, None);
    let planned_set: std::collections::BTreeSet<(u32, u64)> = planned.iter().copied().collect();
    // Every task: the shipped protocol compiled, the manifests' task and the journals' seeds.
    let mut ids: Vec<String> = Vec::new();
    let mut as_run: Vec<Task> = Vec::new();
    let mut claims: Vec<Claim> = Vec::new();
    // Run folders' tasks whose episodes are not re-enacted, their records refused already (so
    // their recordings are not refused again).
    let mut skipped: Vec<(PathBuf, String)> = Vec::new();
    // Tasks whose journals miss or repeat a planned seed (refused as such).
    let mut wrong_seeds: std::collections::BTreeSet<String> = std::collections::BTreeSet::new();
    let mut manifests_seen: Vec<results::run::record::Manifest> = Vec::new();
    // Each run folder's training-seed checkpoint, by task, and the runs of its episodes.
    let mut checkpoints: Vec<Checkpointed> = Vec::new();
    // Each (folder, task)'s manifest and journal, for its results file.
    let mut reports: Vec<manifest::Reported> = Vec::new();
    for suite_entry in shipped.entries() {
        let (entry, protocol) = (suite_entry.listed.as_str(), suite_entry.protocol.clone());
        // This task's results files, checked once its seeds are the plan's.
        let mut task_reports: Vec<manifest::Reported> = Vec::new();
        let task = match compiler::check_file(&protocol, None) {
            Ok(c) if c.trivial_at().is_some() => {
                v.failures.push(format!(
                    "the shipped {} is trivial (warning[W0001] at {}): a robot that does \
                     nothing passes it, and a leaderboard ranks no such task",
                    protocol.display(),
                    c.trivial_at().unwrap_or_default()
                ));
                continue;
            }
            // A preset's run is the shipped task under it (its id and content name it).
            Ok(c) => match c.task {
                Some(t) => suite_entry.task(t),
                None => {
                    v.failures.push(format!(
                        "the shipped {} does not compile",
                        protocol.display()
                    ));
                    continue;
                }
            },
            Err(e) => {
                v.failures.push(e.to_string());
                continue;
            }
        };
        let content = task_content_sha256(&task);
        let want = manifest::Shipped {
            task: &task,
            content: &content,
            protocol: &protocol,
            entry,
            suite,
        };
        let mut seen: BTreeMap<(u32, u64), usize> = BTreeMap::new();
        let mut manifests = 0;
        // A manifest or journal that does not read is its own refusal: its seeds are not missing
        // as well.
        let mut unreadable = false;
        for dir in &run_dirs {
            let manifest_path = results::run::record::manifest_path(dir, &task.id);
            if !manifest_path.exists() {
                continue;
            }
            manifests += 1;
            let shown = rel(root, &manifest_path);
            let m = match read_strict::<results::run::record::Manifest>(&manifest_path) {
                Ok(m) => m,
                Err(e) => {
                    v.failures.push(format!("{shown}: not a manifest: {e}"));
                    unreadable = true;
                    skipped.push((dir.clone(), task.id.clone()));
                    continue;
                }
            };
            let (ran, found) = manifest::check(&m, &shown, &want, &bundle.index);
            let manifest_clean = found.is_empty();
            v.failures.extend(found);
            let journal = results::run::record::journal_path(dir, &task.id);
            let episodes = match read_journal(&journal) {
                Ok(e) => e,
                Err(e) => {
                    v.failures.push(format!("{}: {e}", rel(root, &journal)));
                    unreadable = true;
                    skipped.push((dir.clone(), task.id.clone()));
                    continue;
                }
            };
            checkpoints.push(Checkpointed {
                shown: rel(root, &journal),
                checkpoint: m.checkpoint.clone(),
                runs: episodes.iter().map(|e| e.run).collect(),
            });
            let slot = as_run.len();
            let reenactable = ran.is_some();
            if !reenactable {
                skipped.push((dir.clone(), task.id.clone()));
            }
            as_run.push(ran.unwrap_or_else(|| task.clone()));
            for e in &episodes {
                let n = seen.entry((e.run, e.seed)).or_default();
                *n += 1;
                // Only a planned episode's first claim is re-enacted; the rest are refused below
                // without costing a simulation. A run whose paths are not the shipped ones has
                // been refused for them: its episodes cannot be re-derived.
                if reenactable && *n == 1 && planned_set.contains(&(e.run, e.seed)) {
                    claims.push(Claim {
                        task: slot,
                        run_dir: dir.clone(),
                        claimed: e.clone(),
                    });
                }
            }
            if manifest_clean {
                task_reports.push(manifest::Reported {
                    dir: dir.clone(),
                    manifest: m.clone(),
                    episodes,
                });
            }
            manifests_seen.push(m);
        }
        if manifests == 0 {
            v.failures.push(format!(
                "{}: no run of this suite task in the bundle",
                task.id
            ));
        }
        if manifests > 0 && !unreadable {
            let wrong = check_seeds(&task.id, &planned, &planned_set, &seen);
            if wrong.is_empty() {
                reports.extend(task_reports);
            } else {
                wrong_seeds.insert(task.id.clone());
            }
            v.failures.extend(wrong);
        }
        v.tasks += 1;
        ids.push(task.id.clone());
    }
    v.failures.extend(manifest::check_index(
        &bundle.index,
        &root.join(INDEX),
        &manifests_seen,
    ));
    v.failures
        .extend(check_checkpoints(&checkpoints, suite.runs));
    // Nothing else may ride along: every member is the index, or a run folder's suite file, or
    // a suite task's manifest, journal, results or recording (what the site and an audit read
    // is exactly what was checked here).
    v.failures.extend(check_extras(bundle, &ids, &run_dirs));
    // Every recording is a claimed episode's (its folder, task and seed).
    let claimed: std::collections::BTreeSet<PathBuf> = claims
        .iter()
        .map(|c| {
            c.run_dir
                .join(format!("{}_seed{}.mcap", as_run[c.task].id, c.claimed.seed))
        })
        .collect();
    let mut unread: std::collections::BTreeSet<(PathBuf, String)> =
        skipped.iter().cloned().collect();
    // A task folder with no manifest is refused for that (`check_extras`).
    for dir in &run_dirs {
        for id in &ids {
            if !results::run::record::manifest_path(dir, id).exists() {
                unread.insert((dir.clone(), id.clone()));
            }
        }
    }
    let planned_seeds: std::collections::BTreeSet<u64> = planned.iter().map(|p| p.1).collect();
    for member in bundle.members.iter().filter(|m| m.ends_with(".mcap")) {
        let path = root.join(member);
        let dir = path.parent().map(Path::to_path_buf).unwrap_or_default();
        let name = path
            .file_name()
            .and_then(|n| n.to_str())
            .unwrap_or_default();
        // Refused already: a member the index does not list, a folder whose records were
        // refused, or a planned seed its journal misses or repeats.
        let excused = !bundle.index.files.contains_key(member)
            || unread
                .iter()
                .any(|(d, id)| *d == dir && name.starts_with(&format!("{id}_seed")))
            || ids.iter().any(|id| {
                wrong_seeds.contains(id)
                    && name
                        .strip_prefix(&format!("{id}_seed"))
                        .and_then(|r| r.strip_suffix(".mcap"))
                        .and_then(|n| n.parse::<u64>().ok().filter(|s| s.to_string() == n))
                        .is_some_and(|s| planned_seeds.contains(&s))
            });
        if !claimed.contains(&path) && !excused {
            v.failures.push(format!(
                "{member} is the recording of no episode verified here (a planned seed of a \
                 suite task in this run folder's journal)"
            ));
        }
    }
    v.episodes = claims.len();
    // Every claimed episode re-enacted from its seed and recorded actions.
    let start = std::time::Instant::now();
    let found = reenact_claims(&claims, &as_run, root, reenact, opts.workers);
    v.reenacted = found.len();
    v.reenact_wall_s = start.elapsed().as_secs_f64();
    let verified: std::collections::BTreeSet<(PathBuf, u32, u64)> = claims
        .iter()
        .zip(&found)
        .filter(|(_, f)| f.is_none())
        .map(|(c, _)| (c.run_dir.clone(), c.claimed.run, c.claimed.seed))
        .collect();
    v.failures.extend(found.into_iter().flatten());
    // Each results file: the report of its journal, once its manifest checked clean and every
    // line of the journal verified (so that a forged line or manifest field, an unplanned or a
    // repeated seed is refused once, as what it is).
    for r in &reports {
        let keys: std::collections::BTreeSet<(u32, u64)> =
            r.episodes.iter().map(|e| (e.run, e.seed)).collect();
        let clean = keys.len() == r.episodes.len()
            && r.episodes
                .iter()
                .all(|e| verified.contains(&(r.dir.clone(), e.run, e.seed)));
        if clean {
            v.failures.extend(manifest::check_results(r, root));
        }
    }
    v
}

/// A JSON record read by [`differ::strict`].
fn read_strict<T: serde::de::DeserializeOwned + serde::Serialize>(
    path: &Path,
) -> Result<T, String> {
    let text = std::fs::read(path).map_err(|e| e.to_string())?;
    differ::strict(&text)
}

/// A journal's episodes, each line read by [`differ::strict`]; a bundle's journal is whole (a
/// last line cut short is refused, not skipped as a crash's trace).
fn read_journal(path: &Path) -> Result<Vec<EpisodeResult>, String> {
    let text = match std::fs::read(path) {
        Ok(t) => t,
        Err(e) => return Err(e.to_string()),
    };
    let mut out = Vec::new();
    for (k, line) in text.split_inclusive(|b| *b == b'\n').enumerate() {
        let Some(line) = line.strip_suffix(b"\n") else {
            return Err(format!("line {} is cut short", k + 1));
        };
        out.push(
            differ::strict(line)
                .map_err(|e| format!("line {} is not an episode result: {e}", k + 1))?,
        );
    }
    Ok(out)
}

/// The archive's members against the index: each listed, with the index's SHA-256, and each
/// listed file present.
fn check_members(bundle: &Unpacked) -> Vec<String> {
    let mut failures = Vec::new();
    let members: std::collections::BTreeSet<&String> = bundle.members.iter().collect();
    for member in &bundle.members {
        if member == INDEX {
            continue;
        }
        match bundle.index.files.get(member) {
            None => failures.push(format!("{member} is not in the index")),
            Some(want) => match file_sha256(&bundle.root.join(member)) {
                Ok(got) if got == *want => {}
                Ok(_) => failures.push(format!("{member}: its SHA-256 is not the index's")),
                Err(e) => failures.push(format!("{member}: {e}")),
            },
        }
    }
    for listed in bundle.index.files.keys() {
        if !members.contains(listed) {
            failures.push(format!("{listed} is in the index but not in the archive"));
        }
    }
    failures
}

/// The journals' seeds of a task (`seen`: how many times each) against the suite's plan: each
/// planned seed once, and no other.
fn check_seeds(
    task: &str,
    planned: &[(u32, u64)],
    planned_set: &std::collections::BTreeSet<(u32, u64)>,
    seen: &BTreeMap<(u32, u64), usize>,
) -> Vec<String> {
    let mut failures = Vec::new();
    for key in planned {
        match seen.get(key) {
            None => failures.push(format!("{task}: seed {} (run {}) is missing", key.1, key.0)),
            Some(&n) if n > 1 => failures.push(format!(
                "{task}: seed {} (run {}) is in the journals {n} times",
                key.1, key.0
            )),
            Some(_) => {}
        }
    }
    for (run, seed) in seen.keys() {
        if !planned_set.contains(&(*run, *seed)) {
            failures.push(format!(
                "{task}: seed {seed} (run {run}) is not one the suite plans"
            ));
        }
    }
    failures
}

/// Members that are not a suite run's files, and journals without their manifest.
fn check_extras(bundle: &Unpacked, ids: &[String], run_dirs: &[PathBuf]) -> Vec<String> {
    let mut failures = Vec::new();
    let ids: Vec<&str> = ids.iter().map(String::as_str).collect();
    for member in &bundle.members {
        if member != INDEX && !is_run_file(member, &ids) {
            failures.push(format!(
                "{member} is not a file of a suite run (runs/<k>/ with {SUITE_FILE} and each suite \
                 task's manifest, journal, results and recordings)"
            ));
        }
    }
    for dir in run_dirs {
        for id in &ids {
            let journal = results::run::record::journal_path(dir, id);
            if journal.exists() && !results::run::record::manifest_path(dir, id).exists() {
                failures.push(format!(
                    "{}: a journal without its manifest",
                    rel(&bundle.root, &journal)
                ));
            }
            let results = results::run::record::results_path(dir, id);
            if results.exists()
                && !journal.exists()
                && !results::run::record::manifest_path(dir, id).exists()
            {
                failures.push(format!(
                    "{}: a results file without its manifest",
                    rel(&bundle.root, &results)
                ));
            }
        }
    }
    failures
}

/// One task's run in one run folder: the checkpoint its manifest names and the runs its
/// journal's episodes belong to.
struct Checkpointed {
    shown: String,
    checkpoint: Option<results::run::Checkpoint>,
    runs: std::collections::BTreeSet<u32>,
}

/// A submission of training-seed runs (`eval --checkpoint`) is one: every task's run names its
/// checkpoint or none does (an SEM over training seeds and one over evaluation runs are never
/// mixed), a folder holds only its training seed's run, and each training seed is one
/// checkpoint throughout the suite.
fn check_checkpoints(runs: &[Checkpointed], suite_runs: u32) -> Vec<String> {
    let mut failures = Vec::new();
    for r in runs {
        if let Some(c) = &r.checkpoint
            && (c.run >= suite_runs || r.runs.is_empty())
        {
            failures.push(format!(
                "{}: the checkpoint of training seed {} names no run the suite plans (0..{suite_runs}) \
                 with an episode here",
                r.shown, c.run
            ));
        }
    }
    let named = runs.iter().filter(|r| r.checkpoint.is_some()).count();
    if named == 0 {
        return failures;
    }
    if named < runs.len() {
        let bare: Vec<&str> = runs
            .iter()
            .filter(|r| r.checkpoint.is_none())
            .map(|r| r.shown.as_str())
            .collect();
        failures.push(format!(
            "some runs name their training-seed checkpoint and {} do not: a submission's runs \
             are all training seeds or all evaluation runs of one model",
            bare.join(", ")
        ));
    }
    let mut names: BTreeMap<u32, (&str, &str)> = BTreeMap::new();
    for r in runs {
        let Some(c) = &r.checkpoint else { continue };
        if let Some(other) = r.runs.iter().find(|&&run| run != c.run) {
            failures.push(format!(
                "{}: the checkpoint of training seed {} is evaluated on run {} only, but an \
                 episode of run {other} is here",
                r.shown, c.run, c.run
            ));
        }
        match names.get(&c.run) {
            Some((name, first)) if *name != c.name => failures.push(format!(
                "{}: training seed {} is checkpoint `{}`, but `{}` in {first}",
                r.shown, c.run, c.name, name
            )),
            Some(_) => {}
            None => {
                names.insert(c.run, (c.name.as_str(), r.shown.as_str()));
            }
        }
    }
    failures
}

/// Re-enacts every claim on `workers` threads, each into its own recording under a private
/// folder; what differs from each claim, in the claims' order.
fn reenact_claims(
    claims: &[Claim],
    tasks: &[Task],
    root: &Path,
    reenact: &Reenact,
    workers: usize,
) -> Vec<Option<String>> {
    let scratch = match tempfile::Builder::new()
        .prefix("autobio-reenact-")
        .tempdir()
    {
        Ok(d) => d,
        Err(e) => {
            return claims
                .iter()
                .map(|_| Some(format!("no folder to re-enact into: {e}")))
                .collect();
        }
    };
    let next = std::sync::atomic::AtomicUsize::new(0);
    let found = std::sync::Mutex::new(Vec::new());
    std::thread::scope(|s| {
        for _ in 0..workers.max(1) {
            s.spawn(|| {
                loop {
                    let k = next.fetch_add(1, std::sync::atomic::Ordering::Relaxed);
                    let Some(c) = claims.get(k) else { break };
                    let out = scratch.path().join(format!("{k}.mcap"));
                    // A panic on a stranger's input is that episode's refusal, not the end of
                    // the verification.
                    let problem = std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| {
                        claim::check(&tasks[c.task], c, root, &out, reenact)
                    }))
                    .unwrap_or_else(|_| {
                        Some(format!(
                            "{} seed {} (run {}): its re-enactment failed on the bundle's input",
                            tasks[c.task].id, c.claimed.seed, c.claimed.run
                        ))
                    });
                    let _ = std::fs::remove_file(&out);
                    found.lock().unwrap().push((k, problem));
                }
            });
        }
    });
    let mut found = found.into_inner().unwrap();
    found.sort_by_key(|(k, _)| *k);
    found.into_iter().map(|(_, problem)| problem).collect()
}

/// The shipped suite whose file has this SHA-256, if one has.
pub fn shipped_suite(dir: &Path, sha256: &str) -> Option<LoadedSuite> {
    let mut files: Vec<PathBuf> = std::fs::read_dir(dir)
        .ok()?
        .filter_map(|e| e.ok().map(|e| e.path()))
        .filter(|p| p.extension().is_some_and(|e| e == "toml"))
        .collect();
    files.sort();
    files
        .iter()
        .filter_map(|f| LoadedSuite::read(f).ok())
        .find(|s| s.sha256 == sha256)
}

/// Whether `member` is a file a suite run of these tasks leaves: `runs/<k>/<file>`.
fn is_run_file(member: &str, tasks: &[&str]) -> bool {
    let mut parts = member.split('/');
    let (Some("runs"), Some(k), Some(file), None) =
        (parts.next(), parts.next(), parts.next(), parts.next())
    else {
        return false;
    };
    if k.is_empty() || !k.bytes().all(|b| b.is_ascii_digit()) {
        return false;
    }
    file == SUITE_FILE
        || tasks.iter().any(|t| {
            [".manifest.json", ".journal.jsonl", ".results.json"]
                .iter()
                .any(|ext| file.strip_prefix(t) == Some(ext))
                || file
                    .strip_prefix(t)
                    .and_then(|r| r.strip_prefix("_seed"))
                    .and_then(|r| r.strip_suffix(".mcap"))
                    .is_some_and(|n| !n.is_empty() && n.bytes().all(|b| b.is_ascii_digit()))
        })
}

/// A file's SHA-256, read in blocks.
fn file_sha256(path: &Path) -> std::io::Result<String> {
    use sha2::{Digest, Sha256};
    use std::io::Read;
    let mut f = std::fs::File::open(path)?;
    let mut h = Sha256::new();
    let mut buf = vec![0u8; 1 << 16];
    loop {
        let n = f.read(&mut buf)?;
        if n == 0 {
            break;
        }
        h.update(&buf[..n]);
    }
    Ok(h.finalize().iter().map(|b| format!("{b:02x}")).collect())
}

/// The run folders in the bundle (`runs/<k>/`), in order.
fn run_dirs(bundle: &Unpacked) -> Vec<PathBuf> {
    let mut dirs: Vec<PathBuf> = bundle
        .members
        .iter()
        .filter_map(|m| {
            let mut parts = m.split('/');
            match (parts.next(), parts.next(), parts.next()) {
                (Some("runs"), Some(k), Some(_)) => Some(bundle.root.join("runs").join(k)),
                _ => None,
            }
        })
        .collect();
    dirs.sort();
    dirs.dedup();
    dirs
}

pub(crate) fn rel(root: &Path, path: &Path) -> String {
    path.strip_prefix(root)
        .unwrap_or(path)
        .display()
        .to_string()
}
