//! `autobio tasks`: the benchmark's task table (`docs/tasks.md`), measured, not written by hand.
//! Every protocol and chain under the given folders is compiled; each one the runtime can build
//! is run with the scripted expert and with `hold` (no motion) on the same seeds, and its row
//! says what a reader needs to pick it: instruction, level, robots, horizon (lab steps and the
//! expert's mean episode time), time limit, expert success with its Wilson interval and mean
//! score, and hold's mean score. Files that compile but cannot run yet are listed with the
//! runtime's reason. The same arguments give the same table.
//!
//! `--verify-hold TABLE` re-measures only the hold column of a written table, on the seeds the
//! table says it ran (or the first `--first N` of them), and fails unless every task scores 0
//! with no motion (each episode run to its time limit, with no error, some measured check
//! failing) and the table lists exactly the tasks that run (CI runs it on the first 30 on every
//! commit: `make hold-column`; it is the suite's every-task hold spread). With `--expert-first M`
//! it also re-runs the scripted expert on the table's first M seeds and fails where a task wins a
//! smaller share of them than its row's Wilson lower bound: the expert column, guarded like the
//! hold column (the whole table is `make tasks-doc`, about 40 minutes on 2 cores).

use anyhow::{Context, Result};
use results::run::EvalReport;
use scoring::eval::{EvalOptions, evaluate};
use scoring::policies::PolicySpec;
use std::fmt::Write as _;
use std::path::{Path, PathBuf};
use std::process::ExitCode;

#[derive(Clone, Debug, clap::Args)]
pub(crate) struct TasksArgs {
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
    #[arg(long, conflicts_with = "verify_hold")]
    out: Option<PathBuf>,
    /// Re-measure only the hold column of this written table (on the seeds its header names)
    /// and fail unless every task scores 0 with no motion and the table lists exactly the tasks
    /// that run
    #[arg(long, value_name = "TABLE", conflicts_with_all = ["episodes", "seed"])]
    verify_hold: Option<PathBuf>,
    /// With --verify-hold: only the first N of the table's seeds (CI's time budget); the
    /// table's own count when it has fewer
    #[arg(long, value_name = "N", requires = "verify_hold", value_parser = clap::value_parser!(u32).range(1..))]
    first: Option<u32>,
    /// With --verify-hold: also run the scripted expert on the table's first M seeds, and fail
    /// where a task wins a smaller share of them than its row's Wilson lower bound
    #[arg(long, value_name = "M", requires = "verify_hold", value_parser = clap::value_parser!(u32).range(1..))]
    expert_first: Option<u32>,
}

/// `autobio tasks`: measures the table and writes it.
pub(crate) fn run_cli(a: &TasksArgs) -> Result<ExitCode> {
    if let Some(table) = &a.verify_hold {
        return verify_hold_cli(table, a);
    }
    let opts = Options {
        dirs: a.dirs.clone(),
        episodes: a.episodes as usize,
        seed: a.seed,
        workers: a.workers as usize,
    };
    let table = table(&opts, |line| eprintln!("{line}"))?;
    match &a.out {
        Some(path) => {
            std::fs::write(path, table).with_context(|| format!("writing {}", path.display()))?;
            outln!("wrote {}", path.display());
        }
        None => outln!("{table}"),
    }
    Ok(ExitCode::SUCCESS)
}

/// What the table is measured over.
pub(crate) struct Options {
    pub dirs: Vec<PathBuf>,
    pub episodes: usize,
    pub seed: u64,
    pub workers: usize,
}

/// One simulated task's row.
struct Row {
    file: String,
    task: compiler::Task,
    expert: EvalReport,
    hold: EvalReport,
}

/// Where a workflow's stage protocols live, next to the chains that use them.
const STAGES_FOLDER: &str = "stages";

/// Every protocol file under `dirs` and their subfolders (as `protocols/` is laid out); scene
/// files, which are no tasks, left out, and so is a folder named `stages`: the protocols a
/// workflow chain is made of (`protocols/workflows/stages/`) each run alone, but the task is the
/// chain, and measuring each stage too would only repeat its figures.
fn protocol_files(dirs: &[PathBuf]) -> Result<Vec<PathBuf>> {
    let mut out = Vec::new();
    for dir in dirs {
        let mut walk = vec![dir.clone()];
        while let Some(d) = walk.pop() {
            for entry in
                std::fs::read_dir(&d).with_context(|| format!("reading {}", d.display()))?
            {
                let path = entry?.path();
                if path.is_dir() {
                    if path.file_name().is_some_and(|n| n == STAGES_FOLDER) {
                        continue;
                    }
                    walk.push(path);
                } else if path.extension().is_some_and(|e| e == "toml")
                    && !std::fs::read_to_string(&path).is_ok_and(|t| compiler::is_scene_file(&t))
                {
                    out.push(path);
                }
            }
        }
    }
    out.sort();
    Ok(out)
}

fn run(task: &compiler::Task, policy: PolicySpec, opts: &Options) -> Result<EvalReport> {
    let eval = EvalOptions {
        policy: policy.clone(),
        episodes: opts.episodes,
        seed: opts.seed,
        workers: opts.workers,
        ..Default::default()
    };
    evaluate(task, &eval, |_| {}).with_context(|| format!("{} under {policy}", task.id))
}

/// What a written table claims: the seeds it ran and each task's hold cell.
#[derive(Debug, PartialEq)]
struct Written {
    episodes: usize,
    seed: u64,
    /// Task id and its hold score cell, as written.
    hold: Vec<(String, String)>,
    /// Task id and the lower end of its expert success's Wilson interval (a fraction), where
    /// its row gives one (`100/100 (100%, [96, 100])`).
    expert_low: Vec<(String, f64)>,
}

/// The lower end of the Wilson interval in an expert success cell, as a fraction.
fn wilson_low(cell: &str) -> Option<f64> {
    let rest = &cell[cell.find("%, [")? + 4..];
    let low: f64 = rest[..rest.find(',')?].trim().parse().ok()?;
    Some(low / 100.0)
}

/// Reads the header's `--episodes N --seed S` and every task row's last cell.
fn read_written(text: &str) -> Option<Written> {
    let header = text
        .lines()
        .find(|l| l.starts_with("Generated by `autobio tasks"))?;
    let flag = |name: &str| -> Option<&str> {
        let rest = &header[header.find(name)? + name.len()..];
        rest.split([' ', '`']).find(|w| !w.is_empty())
    };
    let episodes = flag("--episodes ")?.parse().ok()?;
    let seed = flag("--seed ")?.parse().ok()?;
    // Each task row's cells: its id, its last cell (hold), and an expert success cell's interval.
    let rows: Vec<Vec<&str>> = text
        .lines()
        .filter(|l| l.starts_with("| `"))
        .map(|l| {
            l.trim()
                .trim_matches('|')
                .split('|')
                .map(str::trim)
                .collect()
        })
        .collect();
    let id = |cells: &[&str]| Some(cells.first()?.trim_matches('`').to_string());
    let hold = rows
        .iter()
        .filter_map(|cells| Some((id(cells)?, cells.last()?.to_string())))
        .collect();
    let expert_low = rows
        .iter()
        .filter_map(|cells| Some((id(cells)?, cells.iter().find_map(|c| wilson_low(c))?)))
        .collect();
    Some(Written {
        episodes,
        seed,
        hold,
        expert_low,
    })
}

fn verify_hold_cli(path: &Path, a: &TasksArgs) -> Result<ExitCode> {
    let text =
        std::fs::read_to_string(path).with_context(|| format!("reading {}", path.display()))?;
    let written = read_written(&text).with_context(|| {
        format!(
            "{} is not a task table: no `Generated by autobio tasks ... --episodes N --seed S` line",
            path.display()
        )
    })?;
    let opts = Options {
        dirs: a.dirs.clone(),
        episodes: a
            .first
            .map_or(written.episodes, |n| written.episodes.min(n as usize)),
        seed: written.seed,
        workers: a.workers as usize,
    };
    let expert = a.expert_first.map(|m| written.episodes.min(m as usize));
    let problems = verify_hold(&opts, &written, expert, |line| eprintln!("{line}"))?;
    if problems.is_empty() {
        outln!(
            "hold column of {} holds: every task scored 0 on seeds {}..{}",
            path.display(),
            opts.seed,
            opts.seed + opts.episodes as u64 - 1
        );
        if let Some(m) = expert {
            outln!(
                "expert column holds: every task won at least its row's Wilson lower bound on seeds {}..{}",
                opts.seed,
                opts.seed + m as u64 - 1
            );
        }
        return Ok(ExitCode::SUCCESS);
    }
    for p in &problems {
        outln!("error: {p}");
    }
    outln!(
        "{} problem(s) with the hold column of {}; a task a motionless robot passes is broken, \
         and a table that lists other tasks than run is stale (`make tasks-doc`)",
        problems.len(),
        path.display()
    );
    Ok(ExitCode::from(1))
}

/// Runs every task under hold on the written seeds (and, with `expert`, the expert on the first
/// that many); each returned line is one problem.
fn verify_hold(
    opts: &Options,
    written: &Written,
    expert: Option<usize>,
    mut log: impl FnMut(&str),
) -> Result<Vec<String>> {
    let mut problems = Vec::new();
    let mut ran = Vec::new();
    for path in protocol_files(&opts.dirs)? {
        let file = path.display().to_string();
        let checked =
            compiler::check_file(&path, None).with_context(|| format!("reading {file}"))?;
        let Some(task) = checked.task else { continue };
        if runtime::Scene::build(&task, &task.sample(opts.seed)).is_err() {
            continue;
        }
        let hold = run(&task, PolicySpec::Hold, opts)?;
        let s = &hold.summary;
        log(&format!(
            "{}: hold {}/{} ({:.3})",
            task.id, s.successes, s.episodes, s.mean_score
        ));
        if s.successes > 0 || s.mean_score != 0.0 {
            let first = hold
                .episodes
                .iter()
                .find(|e| e.success || e.verdict.score != 0.0)
                .map(|e| format!("seed {}: score {:.3}", e.seed, e.verdict.score))
                .unwrap_or_default();
            problems.push(format!(
                "{} ({file}): with no motion it won {} of {} episodes, mean score {:.3} (first: {first})",
                task.id, s.successes, s.episodes, s.mean_score
            ));
        }
        problems.extend(hold_episode_problems(&task, &hold, &file));
        if let Some(m) = expert {
            let first = Options {
                dirs: Vec::new(),
                episodes: m,
                seed: opts.seed,
                workers: opts.workers,
            };
            let won = run(&task, PolicySpec::Expert, &first)?.summary.successes;
            log(&format!("{}: expert {won}/{m}", task.id));
            match written.expert_low.iter().find(|(id, _)| *id == task.id) {
                None => problems.push(format!(
                    "{}: the table's row gives no expert interval to hold it to",
                    task.id
                )),
                Some((_, low)) if (won as f64) < low * m as f64 - 1e-9 => problems.push(format!(
                    "{} ({file}): the expert won {won} of the table's first {m} seeds, below its \
                     row's Wilson lower bound of {:.0}%",
                    task.id,
                    low * 100.0
                )),
                Some(_) => {}
            }
        }
        match written.hold.iter().find(|(id, _)| *id == task.id) {
            None => problems.push(format!(
                "{} ({file}) runs, but the table has no row for it",
                task.id
            )),
            Some((_, cell)) if cell != "0.000" => problems.push(format!(
                "{}: the table's hold cell reads {cell}, not 0.000",
                task.id
            )),
            Some(_) => {}
        }
        ran.push(task.id.clone());
    }
    for (id, _) in &written.hold {
        if !ran.contains(id) {
            problems.push(format!(
                "{id} is in the table, but no protocol file runs it"
            ));
        }
    }
    Ok(problems)
}

/// What each hold episode must show besides its score of 0: no error ended it, it ran to its
/// first stage's time limit (nothing ended it early), and some check that could be measured
/// failed (not only checks that cannot be measured).
fn hold_episode_problems(task: &compiler::Task, hold: &EvalReport, file: &str) -> Vec<String> {
    let limit = task.stages.first().map_or(0.0, |s| s.time_limit_s);
    let mut problems = Vec::new();
    for e in &hold.episodes {
        let seed = e.seed;
        if let Some(error) = &e.error {
            problems.push(format!(
                "{} ({file}) seed {seed}: hold ended in an error: {error}",
                task.id
            ));
        }
        if (e.sim_time_s - limit).abs() >= 0.05 {
            problems.push(format!(
                "{} ({file}) seed {seed}: hold ended at {:.2} s, not at its {limit} s limit",
                task.id, e.sim_time_s
            ));
        }
        let failing = e
            .verdict
            .predicates()
            .iter()
            .any(|p| !p.value.is_nan() && !p.holds);
        if !failing {
            problems.push(format!(
                "{} ({file}) seed {seed}: every measured check holds without motion",
                task.id
            ));
        }
    }
    problems
}

/// Builds the table; `log` hears one line per task as it is measured.
pub(crate) fn table(opts: &Options, mut log: impl FnMut(&str)) -> Result<String> {
    let mut rows = Vec::new();
    let mut not_run = Vec::new();
    for path in protocol_files(&opts.dirs)? {
        let file = path.display().to_string();
        let checked =
            compiler::check_file(&path, None).with_context(|| format!("reading {file}"))?;
        let Some(task) = checked.task else {
            not_run.push((file, "does not compile (see `autobio check`)".to_string()));
            continue;
        };
        if let Err(e) = runtime::Scene::build(&task, &task.sample(opts.seed)) {
            not_run.push((file, e.to_string()));
            continue;
        }
        let expert = run(&task, PolicySpec::Expert, opts)?;
        let hold = run(&task, PolicySpec::Hold, opts)?;
        log(&format!(
            "{}: expert {}/{} ({:.3}), hold {:.3}",
            task.id,
            expert.summary.successes,
            expert.summary.episodes,
            expert.summary.mean_score,
            hold.summary.mean_score
        ));
        rows.push(Row {
            file,
            task,
            expert,
            hold,
        });
    }
    Ok(render(opts, &rows, &not_run))
}

fn render(opts: &Options, rows: &[Row], not_run: &[(String, String)]) -> String {
    let mut s = String::new();
    let dirs: Vec<String> = opts.dirs.iter().map(|d| d.display().to_string()).collect();
    let _ = writeln!(s, "# Tasks\n");
    let _ = writeln!(
        s,
        "Generated by `autobio tasks {} --episodes {} --seed {}` (`make tasks-doc`); do not edit by hand. \
         Each simulated task ran {} seeded episodes (seeds {}..{}) with the scripted expert and the \
         same seeds with `hold` (no motion). A task whose hold score is not 0 would be broken.\n",
        dirs.join(" "),
        opts.episodes,
        opts.seed,
        opts.episodes,
        opts.seed,
        opts.seed + opts.episodes as u64 - 1,
    );
    let _ = writeln!(
        s,
        "Horizon: lab steps in the plan, and the expert's mean episode time. Expert success: \
         episodes won, with the Wilson 95% interval; score: mean episode score (progress-scored \
         tasks score partial credit).\n"
    );
    let _ = writeln!(
        s,
        "| task | level | robots | horizon | time limit | expert success | expert score | hold score |"
    );
    let _ = writeln!(s, "|---|---|---|---|---|---|---|---|");
    for r in rows {
        let e = &r.expert.summary;
        let robots: Vec<String> = r
            .task
            .robots
            .iter()
            .map(|x| format!("{} ({})", x.name, x.model))
            .collect();
        let steps = r.task.steps().count();
        let mean_t = r.expert.episodes.iter().map(|x| x.sim_time_s).sum::<f64>()
            / r.expert.episodes.len().max(1) as f64;
        let _ = writeln!(
            s,
            "| `{}` | {} | {} | {} {}, {:.1} s | {:.1} s | {}/{} ({:.0}%, [{:.0}, {:.0}]) | {:.3} | {:.3} |",
            r.task.id,
            r.task.level,
            robots.join(", "),
            steps,
            if steps == 1 { "step" } else { "steps" },
            mean_t,
            r.task.time_limit_s,
            e.successes,
            e.episodes,
            100.0 * e.success_rate,
            100.0 * e.wilson_95[0],
            100.0 * e.wilson_95[1],
            e.mean_score,
            r.hold.summary.mean_score,
        );
    }
    let _ = writeln!(s, "\n## Instructions\n");
    for r in rows {
        let _ = writeln!(
            s,
            "- `{}` ([{}](../{})): {}",
            r.task.id,
            Path::new(&r.file)
                .file_name()
                .map(|f| f.to_string_lossy().to_string())
                .unwrap_or_default(),
            r.file,
            r.task.instruction
        );
    }
    let failing: Vec<&Row> = rows
        .iter()
        .filter(|r| r.expert.summary.successes < r.expert.summary.episodes)
        .collect();
    if !failing.is_empty() {
        let _ = writeln!(s, "\n## Where the expert fails\n");
        for r in failing {
            let outcomes: Vec<String> = r
                .expert
                .summary
                .outcomes
                .iter()
                .filter(|(o, _)| **o != results::episode::Outcome::Success)
                .map(|(o, n)| {
                    let name = serde_json::to_value(o).unwrap_or_default();
                    format!("{} {n}", name.as_str().unwrap_or("?"))
                })
                .collect();
            let first = r
                .expert
                .episodes
                .iter()
                .find(|e| !e.success)
                .map(|e| match &e.error {
                    Some(why) => format!("seed {}: {why}", e.seed),
                    None => format!("seed {}: score {:.3}", e.seed, e.verdict.score),
                })
                .unwrap_or_default();
            let _ = writeln!(
                s,
                "- `{}`: {} (first: {first})",
                r.task.id,
                outcomes.join(", ")
            );
        }
    }
    if !not_run.is_empty() {
        let _ = writeln!(s, "\n## Compiled, not simulated yet\n");
        for (file, why) in not_run {
            let _ = writeln!(s, "- `{file}`: {why}");
        }
    }
    s
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_written_table_gives_its_seeds_and_hold_cells() {
        let text = "# Tasks\n\nGenerated by `autobio tasks protocols --episodes 7 --seed 40` (`make tasks-doc`); ...\n\n\
                    | task | level | hold score |\n|---|---|---|\n| `a.b` | easy | 0.000 |\n| `c.d` | hard | 0.250 |\n";
        assert_eq!(
            read_written(text),
            Some(Written {
                episodes: 7,
                seed: 40,
                hold: vec![
                    ("a.b".into(), "0.000".into()),
                    ("c.d".into(), "0.250".into())
                ],
                expert_low: vec![],
            })
        );
        let row = "Generated by `autobio tasks protocols --episodes 100 --seed 0`\n\
                   | `a.b` | easy | 95/100 (95%, [89, 98]) | 0.950 | 0.000 |\n";
        assert_eq!(
            read_written(row).unwrap().expert_low,
            [("a.b".into(), 0.89)]
        );
        assert_eq!(wilson_low("100/100 (100%, [96, 100])"), Some(0.96));
        assert_eq!(wilson_low("0.950"), None);
        assert_eq!(read_written("| `a.b` | 0.000 |\n"), None);
    }
}
