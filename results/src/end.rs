//! How an episode ended, decided once: [`EpisodeEnd`] is made where the end happens (the
//! environment for the judge's ends, an unstable simulation and a refused action; the harness for
//! a policy's or model server's error), and [`EpisodeEnd::conclude`] is the one function that
//! turns an end and the judge's verdict into the finished episode's outcome, error and score.
//! The harness, the verifier's re-enactment ([`Reenacted`]) and the Python environment all read
//! it; none of them classes an end on its own.
//!
//! It runs nothing: the environment and the harness say when an episode ends.

use crate::episode::Outcome;
use crate::verdict::Verdict;
use std::path::PathBuf;

/// How an episode ended.
#[derive(Clone, Debug, PartialEq)]
pub enum EpisodeEnd {
    /// The judge found every stage's checks held.
    Success,
    /// A stage's or the task's time limit passed first.
    TimeLimit,
    /// The simulation became unstable (why, with the time).
    Unstable(String),
    /// The policy failed, sent no actions, or sent an action the environment refused.
    PolicyError(String),
    /// The model server failed (refused or lost the connection, silence past the timeout, an
    /// error frame, frames that do not decode).
    ServerFault(String),
}

/// A finished episode's outcome, error and verdict, as [`EpisodeEnd::conclude`] derives them.
#[derive(Clone, Debug, PartialEq)]
pub struct Concluded {
    pub outcome: Outcome,
    /// Why it ended early as a failure, if it did.
    pub error: Option<String>,
    /// The judge's verdict, scored 0 where the episode ended by an error.
    pub verdict: Verdict,
}

impl EpisodeEnd {
    /// The judge's end of an episode whose verdict is `verdict`: success or the time limit.
    pub fn judged(verdict: &Verdict) -> EpisodeEnd {
        if verdict.success {
            EpisodeEnd::Success
        } else {
            EpisodeEnd::TimeLimit
        }
    }

    /// The end a journal line claims for an error only the harness saw: a model server's fault
    /// where its outcome says so, else a policy's error.
    pub fn claimed(outcome: Outcome, error: String) -> EpisodeEnd {
        match outcome {
            Outcome::ServerFault => EpisodeEnd::ServerFault(error),
            _ => EpisodeEnd::PolicyError(error),
        }
    }

    pub fn outcome(&self) -> Outcome {
        match self {
            EpisodeEnd::Success => Outcome::Success,
            EpisodeEnd::TimeLimit => Outcome::TimeLimit,
            EpisodeEnd::Unstable(_) => Outcome::Unstable,
            EpisodeEnd::PolicyError(_) => Outcome::PolicyError,
            EpisodeEnd::ServerFault(_) => Outcome::ServerFault,
        }
    }

    /// Why the episode ended early as a failure; `None` for the judge's ends.
    pub fn error(&self) -> Option<&str> {
        match self {
            EpisodeEnd::Success | EpisodeEnd::TimeLimit => None,
            EpisodeEnd::Unstable(why)
            | EpisodeEnd::PolicyError(why)
            | EpisodeEnd::ServerFault(why) => Some(why),
        }
    }

    /// The finished episode: its outcome, its error, and the verdict, which scores 0 where the
    /// episode ended by an error (a run's mean score never credits a policy that crashed, and a
    /// task whose success held at the start would otherwise score 1).
    pub fn conclude(self, mut verdict: Verdict) -> Concluded {
        let error = self.error().map(str::to_string);
        if error.is_some() {
            verdict.ended_by_error();
        }
        Concluded {
            outcome: self.outcome(),
            error,
            verdict,
        }
    }
}

/// An episode re-enacted from its seed and actions (what `leaderboard verify` trusts): the one
/// type the harness's re-enactment returns and the verifier reads.
#[derive(Clone, Debug, PartialEq)]
pub struct Reenacted {
    /// The trajectory hash over the control steps the actions drove.
    pub hash: String,
    /// How it ended: the environment's end (a refused action or an unstable simulation first,
    /// then an error the claim names, then the judge's end); `None` where the actions ran out
    /// before the episode ended and no error is claimed.
    pub end: Option<EpisodeEnd>,
    /// The judge's verdict, scored 0 where the episode ended by an error.
    pub verdict: Verdict,
    /// Simulated time at the end (s).
    pub time_s: f64,
    pub control_steps: u64,
    /// Actions left over once the episode had ended (a claimed episode that ran on after its
    /// end).
    pub unused_actions: usize,
}

/// What a re-enactment writes besides its outcome.
#[derive(Clone, Debug, Default)]
pub struct ReenactOptions {
    /// Write the re-enacted episode's recording here, as `eval` writes one (with camera frames
    /// every `image_every` control steps at `image_size`; 0: none).
    pub record: Option<PathBuf>,
    pub image_every: u32,
    pub image_size: Option<[usize; 2]>,
    /// The error the episode is said to have ended with ([`EpisodeEnd::claimed`]), used where
    /// no action was refused: a policy's or a model server's, which only the harness saw. The
    /// verdict then scores 0 and the recording's verdict carries it, as the harness wrote them.
    pub claimed: Option<EpisodeEnd>,
}

#[cfg(test)]
mod tests {
    use super::*;

    fn verdict(success: bool) -> Verdict {
        Verdict {
            success,
            score: if success { 1.0 } else { 0.25 },
            stages: Vec::new(),
        }
    }

    #[test]
    fn the_judges_ends_keep_the_verdict_and_errors_score_zero() {
        let ok = EpisodeEnd::judged(&verdict(true)).conclude(verdict(true));
        assert_eq!(
            (ok.outcome, ok.error, ok.verdict.score),
            (Outcome::Success, None, 1.0)
        );
        let late = EpisodeEnd::judged(&verdict(false)).conclude(verdict(false));
        assert_eq!(
            (late.outcome, late.verdict.score),
            (Outcome::TimeLimit, 0.25)
        );
        // An error after the success held still fails the episode.
        let crashed = EpisodeEnd::Unstable("t=1 s".into()).conclude(verdict(true));
        assert_eq!(crashed.outcome, Outcome::Unstable);
        assert_eq!(crashed.error.as_deref(), Some("t=1 s"));
        assert!(!crashed.verdict.success);
        assert_eq!(crashed.verdict.score, 0.0);
    }

    #[test]
    fn a_claimed_error_is_a_server_fault_only_where_the_claim_says_so() {
        let fault = EpisodeEnd::claimed(Outcome::ServerFault, "silent".into());
        assert_eq!(fault.outcome(), Outcome::ServerFault);
        for other in [
            Outcome::Success,
            Outcome::TimeLimit,
            Outcome::PolicyError,
            Outcome::Unstable,
        ] {
            assert_eq!(
                EpisodeEnd::claimed(other, "x".into()).outcome(),
                Outcome::PolicyError
            );
        }
    }
}
