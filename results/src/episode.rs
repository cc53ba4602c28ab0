//! What one episode produces: how it ended ([`Outcome`]), its [`EpisodeResult`] (a journal line),
//! and [`TrajectoryHash`], the one rule that says two trajectories are the same, used by the
//! environment that steps an episode and by the replay that re-simulates one.

use crate::verdict::Verdict;
use serde::{Deserialize, Serialize};
use sha2::{Digest, Sha256};

/// How an episode ended. Every class counts in a run's denominator.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Outcome {
    /// Every stage's checks held.
    Success,
    /// The time limit passed first.
    TimeLimit,
    /// The policy failed, sent no actions, or sent actions of the wrong shape, not finite or
    /// outside their actuators' ranges.
    PolicyError,
    /// The model server failed: refused or lost the connection, stayed silent past the
    /// timeout, reported an error, or sent frames that do not decode.
    ServerFault,
    /// The simulation became unstable.
    Unstable,
}

#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct EpisodeResult {
    pub seed: u64,
    /// The run it belongs to (`--runs`; 0 otherwise).
    #[serde(default)]
    pub run: u32,
    pub success: bool,
    pub outcome: Outcome,
    pub verdict: Verdict,
    /// Why the episode ended early as a failure (policy error, unstable physics), if it did.
    pub error: Option<String>,
    pub sim_time_s: f64,
    pub control_steps: u64,
    pub wall_time_s: f64,
    /// Wall time spent inside the policy (a model's round trips included): the harness's own
    /// time is `wall_time_s` minus this.
    #[serde(default)]
    pub policy_time_s: f64,
    /// [`TrajectoryHash`] of the episode: equal hashes, equal trajectories.
    pub trajectory_hash: String,
    pub recording: Option<String>,
}

/// SHA-256 over every control step's generalized positions (MuJoCo's `qpos` after the step, as
/// little-endian f64), in step order. The initial state is not hashed: it follows from the task
/// and the seed. An episode with no control step hashes to SHA-256 of nothing.
#[derive(Clone, Debug, Default)]
pub struct TrajectoryHash {
    hasher: Sha256,
    steps: u64,
}

impl TrajectoryHash {
    pub fn new() -> TrajectoryHash {
        TrajectoryHash::default()
    }

    /// One control step's `qpos`.
    pub fn step(&mut self, qpos: &[f64]) {
        for v in qpos {
            self.hasher.update(v.to_le_bytes());
        }
        self.steps += 1;
    }

    /// Control steps hashed so far.
    pub fn steps(&self) -> u64 {
        self.steps
    }

    /// The hash so far, as lower-case hex (the hashing goes on).
    pub fn hex(&self) -> String {
        hex(&self.hasher.clone().finalize())
    }
}

fn hex(bytes: &[u8]) -> String {
    bytes.iter().map(|b| format!("{b:02x}")).collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_hash_is_sha256_of_the_little_endian_positions() {
        let mut h = TrajectoryHash::new();
        assert_eq!(
            h.hex(),
            "e3b0c44298fc1c149afbf4c8996fb92427ae41e4649b934ca495991b7852b855"
        );
        h.step(&[1.0, -0.5]);
        h.step(&[2.0]);
        let bytes: Vec<u8> = [1.0f64, -0.5, 2.0]
            .iter()
            .flat_map(|v| v.to_le_bytes())
            .collect();
        assert_eq!(h.hex(), hex(&Sha256::digest(&bytes)));
        assert_eq!(h.steps(), 2);
        // Steps are not interchangeable with their concatenation's order.
        let mut other = TrajectoryHash::new();
        other.step(&[2.0]);
        other.step(&[1.0, -0.5]);
        assert_ne!(other.hex(), h.hex());
    }
}
