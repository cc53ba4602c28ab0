//! How close the scripted expert comes to each stage's own time limit in a run: a stage it ran out
//! of time in, or needed more than nine tenths of its limit for. A chain's later stage starts where
//! the stage before left the robot, not at its home pose, so the time limit its protocol file was
//! written with can be tight there. Only the figures; `eval` words the warning. Runs of other
//! policies say nothing about the task's time limits and are not read here.

use compiler::Task;
use results::episode::{EpisodeResult, Outcome};

/// One stage whose time limit the expert's run found tight.
#[derive(Clone, Debug, PartialEq)]
pub struct TightStage {
    /// 1-based, as `describe` numbers stages.
    pub stage: usize,
    pub id: String,
    pub limit_s: f64,
    /// The longest the expert took over the stage (to completion, or to the episode's end when it
    /// ran out of time in it), and on which seed.
    pub longest_s: f64,
    pub longest_seed: u64,
    /// Episodes that ended at the time limit with this stage the first one unfinished.
    pub ran_out: usize,
}

/// Past this share of its limit the stage counts as tight.
pub const TIGHT_SHARE: f64 = 0.9;

/// The stages of `task` that `episodes` (the expert's) found tight, in stage order.
pub fn tight_stages(task: &Task, episodes: &[EpisodeResult]) -> Vec<TightStage> {
    let mut out: Vec<TightStage> = task
        .stages
        .iter()
        .enumerate()
        .map(|(i, s)| TightStage {
            stage: i + 1,
            id: s.id.clone(),
            limit_s: s.time_limit_s,
            longest_s: 0.0,
            longest_seed: 0,
            ran_out: 0,
        })
        .collect();
    for e in episodes {
        let mut start = 0.0;
        for (i, s) in e.verdict.stages.iter().enumerate().take(out.len()) {
            let (took, done) = match s.completed_at_s {
                Some(t) => (t - start, true),
                None if e.outcome == Outcome::TimeLimit => (e.sim_time_s - start, false),
                None => break,
            };
            let t = &mut out[i];
            if took > t.longest_s {
                t.longest_s = took;
                t.longest_seed = e.seed;
            }
            if !done {
                t.ran_out += 1;
                break;
            }
            start = s.completed_at_s.unwrap_or(start);
        }
    }
    out.retain(|t| t.ran_out > 0 || t.longest_s > TIGHT_SHARE * t.limit_s);
    out
}
