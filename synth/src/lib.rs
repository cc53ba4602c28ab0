//! Protocol synthesis (`autobio synth`, the paper's "compose long-horizon tasks from modular
//! primitives"): random long-horizon protocols made from the steps shipped protocols show on
//! their benches, each written as a protocol file that `autobio check` passes with nothing to say.
//!
//! How one protocol is made, all from one seed: a bench is drawn (`vocabulary`: a scene file and
//! the step shapes its protocols show), then a random walk over the abstract world (`walk`: each
//! step's precondition is its primitive's own, as the state proof runs it), written out (`text`),
//! compiled and proven as any protocol file, and reach-checked in the layouts the check samples
//! (`expert::reach`). A candidate with any diagnostic, or with a step out of reach, is dropped
//! and the next one drawn; the reasons are counted in the [`Report`]. The scene file is copied
//! beside the protocols, so the folder checks and runs on its own.
//!
//! It does not run the expert: `autobio tasks <out>` (or `eval`) measures what it wrote. Its
//! tests are tests/synth.rs. Each step is worded by its primitive's own phrase (declared beside it in
//! `compiler::primitives`, checked there for every registered primitive).

mod text;
pub mod vocabulary;
mod walk;

use compiler::world::World;
use rand_chacha::ChaCha8Rng;
use rand_core::SeedableRng;
use std::collections::BTreeMap;
use std::ops::RangeInclusive;
use std::path::{Path, PathBuf};
use std::sync::Mutex;
use std::sync::atomic::{AtomicUsize, Ordering};
use vocabulary::{Bench, Source};

pub struct Options {
    /// Protocol files, or folders searched for them.
    pub from: Vec<PathBuf>,
    /// Steps per protocol (each draws its length from this range).
    pub steps: RangeInclusive<usize>,
    pub seed: u64,
    pub count: usize,
    pub out: PathBuf,
    /// Candidates checked at once.
    pub workers: usize,
}

/// What a run wrote and what it dropped on the way.
#[derive(Debug, Default)]
pub struct Report {
    pub written: Vec<Written>,
    /// Benches found, with how many source protocols and step shapes each has.
    pub benches: Vec<(String, usize, usize)>,
    /// Source files not used, with why.
    pub skipped: Vec<(String, String)>,
    /// Candidates dropped, by reason (a diagnostic's code, "reach", a walk that stuck).
    pub rejected: BTreeMap<String, usize>,
    /// Protocols that could not be made (index, why): the rest are written.
    pub unmade: Vec<(usize, String)>,
}

#[derive(Clone, Debug)]
pub struct Written {
    pub path: PathBuf,
    pub id: String,
    pub bench: String,
    pub steps: usize,
    /// Candidates drawn before this one was kept (1: the first).
    pub tries: usize,
}

#[derive(Debug, thiserror::Error)]
pub enum SynthError {
    #[error(
        "no protocol under {0} names a scene file (`scene = \"..\"`): synthesis recombines the steps of protocols that share a bench"
    )]
    NoSources(String),
    #[error("cannot read protocol {path}: {error}")]
    Read { path: String, error: std::io::Error },
    #[error("cannot write {path}: {error}")]
    Write { path: String, error: std::io::Error },
    #[error("{0} is another file: write the protocols to a folder where the scene's copy can go")]
    Occupied(String),
    #[error("protocol {index}: no candidate in {tries} checked clean (dropped: {reasons})")]
    Exhausted {
        index: usize,
        tries: usize,
        reasons: String,
    },
}

/// Candidates drawn for one protocol before synthesis gives up.
const MAX_TRIES: usize = 60;

/// Synthesises `opts.count` protocols into `opts.out`; `progress` hears of each one written.
pub fn synthesize(
    opts: &Options,
    progress: &(dyn Fn(&Written) + Sync),
) -> Result<Report, SynthError> {
    let mut report = Report::default();
    let sources = load_sources(&opts.from, &mut report.skipped)?;
    let benches: Vec<Bench> = vocabulary::benches(&sources)
        .into_iter()
        .filter(|b| !b.templates.is_empty())
        .collect();
    if benches.is_empty() {
        let from: Vec<String> = opts.from.iter().map(|p| p.display().to_string()).collect();
        return Err(SynthError::NoSources(from.join(", ")));
    }
    report.benches = benches
        .iter()
        .map(|b| (b.name.clone(), b.sources.len(), b.templates.len()))
        .collect();
    std::fs::create_dir_all(&opts.out).map_err(|error| SynthError::Write {
        path: opts.out.display().to_string(),
        error,
    })?;
    for b in &benches {
        let to = opts.out.join(format!("{}.toml", b.name));
        let scene = std::fs::read(&b.scene).map_err(|error| SynthError::Read {
            path: b.scene.display().to_string(),
            error,
        })?;
        // Never over another file: a folder of sources given as --out keeps its scene as it is.
        match std::fs::read(&to) {
            Ok(there) if there == scene => continue,
            Ok(_) => return Err(SynthError::Occupied(to.display().to_string())),
            Err(_) => {}
        }
        std::fs::write(&to, &scene).map_err(|error| SynthError::Write {
            path: to.display().to_string(),
            error,
        })?;
    }
    let next = AtomicUsize::new(0);
    let results: Mutex<Vec<Result<Written, SynthError>>> = Mutex::new(Vec::new());
    let rejected: Mutex<BTreeMap<String, usize>> = Mutex::new(BTreeMap::new());
    std::thread::scope(|s| {
        for _ in 0..opts.workers.max(1) {
            s.spawn(|| {
                loop {
                    let i = next.fetch_add(1, Ordering::Relaxed);
                    if i >= opts.count {
                        break;
                    }
                    let mut dropped = BTreeMap::new();
                    let r = one(opts, &benches, i, &mut dropped);
                    if let Ok(w) = &r {
                        progress(w);
                    }
                    let mut all = rejected.lock().expect("no panics hold it");
                    for (k, v) in dropped {
                        *all.entry(k).or_default() += v;
                    }
                    results.lock().expect("no panics hold it").push(r);
                }
            });
        }
    });
    report.rejected = rejected.into_inner().expect("threads joined");
    let mut written = Vec::new();
    for r in results.into_inner().expect("threads joined") {
        match r {
            Ok(w) => written.push(w),
            // The others are still written; the caller says which could not be made.
            Err(SynthError::Exhausted {
                index,
                tries,
                reasons,
            }) => report.unmade.push((
                index,
                format!("no candidate in {tries} checked clean (dropped: {reasons})"),
            )),
            Err(e) => return Err(e),
        }
    }
    written.sort_by(|a, b| a.path.cmp(&b.path));
    report.unmade.sort();
    report.written = written;
    Ok(report)
}

/// Protocol `index`: candidates from its own seed stream until one checks clean and is reached.
fn one(
    opts: &Options,
    benches: &[Bench],
    index: usize,
    dropped: &mut BTreeMap<String, usize>,
) -> Result<Written, SynthError> {
    let stream = planner::mix(opts.seed, index as u64);
    // The bench is the protocol's, not the candidate's: a bench whose walks fail more often is
    // not drawn less.
    let bench = &benches[walk::below(&mut ChaCha8Rng::seed_from_u64(stream), benches.len())];
    for attempt in 0..MAX_TRIES {
        let mut rng = ChaCha8Rng::seed_from_u64(planner::mix(stream, attempt as u64 + 1));
        let (lo, hi) = (*opts.steps.start(), *opts.steps.end());
        let n = lo + walk::below(&mut rng, hi - lo + 1);
        let walk = match walk::walk(bench, n, &mut rng) {
            Ok(w) => w,
            Err(stuck) => {
                *dropped.entry(format!("walk: {stuck:?}")).or_default() += 1;
                continue;
            }
        };
        let stem = format!("{}_s{}_{index:04}", bench.name, opts.seed);
        let id = format!("synth.{stem}");
        let comment = format!(
            "Synthesised by `autobio synth --seed {}` (protocol {index}, candidate {}): a random walk\n\
             over the steps these protocols show on this bench: {}.\n\
             Every step's needs are met (state proof) and every target is reached (reach check).",
            opts.seed,
            attempt + 1,
            bench.sources.join(", ")
        );
        let header = text::Header {
            id: &id,
            scene: &format!("{}.toml", bench.name),
            comment: &comment,
        };
        if text::success(&walk.first, &walk.last, &bench.kinds).is_empty() {
            *dropped.entry("nothing changed".into()).or_default() += 1;
            continue;
        }
        let body = text::protocol(&header, &walk, &bench.kinds);
        let path = opts.out.join(format!("{stem}.toml"));
        std::fs::write(&path, &body).map_err(|error| SynthError::Write {
            path: path.display().to_string(),
            error,
        })?;
        match verdict(&path, &walk.first) {
            None => {
                return Ok(Written {
                    path,
                    id,
                    bench: bench.name.clone(),
                    steps: n,
                    tries: attempt + 1,
                });
            }
            Some(reason) => {
                *dropped.entry(reason).or_default() += 1;
                std::fs::remove_file(&path).map_err(|error| SynthError::Write {
                    path: path.display().to_string(),
                    error,
                })?;
            }
        }
    }
    let reasons: Vec<String> = dropped.iter().map(|(k, v)| format!("{k} x{v}")).collect();
    Err(SynthError::Exhausted {
        index,
        tries: MAX_TRIES,
        reasons: reasons.join(", "),
    })
}

/// Why a written candidate is dropped: its first diagnostic's code, a success predicate that
/// already holds where the walk starts (a motionless robot would pass it), or "reach" for a step
/// out of reach in some sampled layout; `None`: it stays.
fn verdict(path: &Path, first: &World) -> Option<String> {
    let checked = match compiler::check_file(path, None) {
        Ok(c) => c,
        Err(e) => return Some(format!("unreadable: {e}")),
    };
    if let Some(d) = checked.diagnostics.first() {
        return Some(d.code.to_string());
    }
    let Some(task) = checked.task.as_ref() else {
        return Some("does not compile".into());
    };
    let bound = compiler::params::Bindings::new();
    let holds_at_start = task
        .stages
        .iter()
        .flat_map(|s| &s.success)
        .any(|p| p.check.eval_abstract(first, &bound) == Some(true));
    if holds_at_start {
        return Some("a success predicate holds at the start".into());
    }
    (!expert::reach::reached_everywhere(task)).then(|| "reach".to_string())
}

/// Every protocol file under `from` that names a scene file and compiles clean to one stage.
fn load_sources(
    from: &[PathBuf],
    skipped: &mut Vec<(String, String)>,
) -> Result<Vec<Source>, SynthError> {
    let mut files = Vec::new();
    for p in from {
        collect(p, &mut files)?;
    }
    files.sort();
    files.dedup();
    let mut out = Vec::new();
    for f in files {
        let file = f.display().to_string();
        let text = std::fs::read_to_string(&f).map_err(|error| SynthError::Read {
            path: file.clone(),
            error,
        })?;
        let Ok(doc) = text.parse::<toml::Table>() else {
            skipped.push((file, "not TOML".into()));
            continue;
        };
        if !doc.contains_key("protocol") {
            // A scene file or a chain: the chain's stage files are read as sources themselves.
            continue;
        }
        let Some(scene) = vocabulary::scene_of(&text, &f) else {
            skipped.push((
                file,
                "its scene is written inline, not in a scene file".into(),
            ));
            continue;
        };
        let Ok(scene) = std::fs::canonicalize(&scene) else {
            skipped.push((
                file,
                format!("its scene file {} cannot be read", scene.display()),
            ));
            continue;
        };
        let checked = match compiler::check_file(&f, None) {
            Ok(c) => c,
            Err(e) => {
                skipped.push((file, e.to_string()));
                continue;
            }
        };
        match checked.task {
            Some(task) if task.stages.len() == 1 => out.push(Source { file, scene, task }),
            Some(_) => skipped.push((file, "more than one stage".into())),
            None => skipped.push((file, "does not compile".into())),
        }
    }
    Ok(out)
}

fn collect(p: &Path, files: &mut Vec<PathBuf>) -> Result<(), SynthError> {
    let read = |error| SynthError::Read {
        path: p.display().to_string(),
        error,
    };
    if p.is_dir() {
        for e in std::fs::read_dir(p).map_err(read)? {
            collect(&e.map_err(read)?.path(), files)?;
        }
    } else if p.extension().is_some_and(|e| e == "toml") {
        files.push(p.to_path_buf());
    } else if !p.exists() {
        return Err(read(std::io::Error::from(std::io::ErrorKind::NotFound)));
    }
    Ok(())
}
