//! The paper's own results as shipped (`reference/paper.toml`): the reference entry the site
//! shows beside the submissions, "reported by the paper, not re-run".
//!
//! It reads the shipped table; it re-runs nothing and ranks nothing.

use serde::{Deserialize, Serialize};

/// The paper's reported results (`reference/paper.toml`).
#[derive(Clone, Debug, Deserialize, Serialize)]
pub struct Reference {
    pub source: String,
    /// What a reader must know to compare with the paper's rows (what its ± is taken over,
    /// where our robots differ from upstream's), shown under them.
    #[serde(default)]
    pub notes: Vec<String>,
    pub entry: Vec<ReferenceEntry>,
    pub chain: Vec<ReferenceChain>,
}

#[derive(Clone, Debug, Deserialize, Serialize)]
pub struct ReferenceEntry {
    pub model: String,
    pub training: String,
    pub scores: Vec<ReferenceScore>,
}

#[derive(Clone, Debug, Deserialize, Serialize)]
pub struct ReferenceScore {
    pub task: String,
    #[serde(default)]
    pub level: String,
    pub mean: f64,
    pub sem: f64,
}

#[derive(Clone, Debug, Deserialize, Serialize)]
pub struct ReferenceChain {
    pub model: String,
    pub stages: Vec<ReferenceScore>,
}

/// The paper's results as shipped.
pub fn paper() -> Reference {
    toml::from_str(include_str!("../../reference/paper.toml")).expect("the shipped reference reads")
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_paper_reference_reads_with_its_nine_tasks() {
        let p = paper();
        assert_eq!(p.entry.len(), 4);
        assert!(p.entry.iter().all(|e| e.scores.len() == 9));
        let pi0_100 = &p.entry[1];
        assert_eq!(
            (pi0_100.model.as_str(), pi0_100.training.as_str()),
            ("pi0", "100 demos")
        );
        assert_eq!(pi0_100.scores[0].mean, 99.7);
        assert_eq!(p.chain[1].stages[3].mean, 8.7);
    }
}
