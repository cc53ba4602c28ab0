//! The results tables, golden: the results JSON of a real two-task, two-run evaluation
//! (`tests/data/`, written by `autobio eval --policy hold --runs 2`) read back through `results`
//! and printed as `autobio eval` prints them. Regenerate with `UPDATE_GOLDEN=1`.

use results::run::EvalReport;
use std::path::Path;

fn reports() -> Vec<EvalReport> {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data");
    let mut files: Vec<_> = std::fs::read_dir(&dir)
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|p| p.to_string_lossy().ends_with(".results.json"))
        .collect();
    files.sort();
    files
        .iter()
        .map(|f| serde_json::from_str(&std::fs::read_to_string(f).unwrap()).unwrap())
        .collect()
}

#[test]
fn the_results_tables_are_what_eval_prints() {
    let rows = reports();
    assert_eq!(rows.len(), 2);
    let text = leaderboard::table::results_table(&rows) + &leaderboard::table::runs_table(&rows);
    let golden = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/golden/tables.txt");
    if std::env::var_os("UPDATE_GOLDEN").is_some() {
        std::fs::write(&golden, &text).unwrap();
        // A run that rewrote the golden compared nothing: it never passes.
        panic!(
            "UPDATE_GOLDEN: {} written; review its diff, then run again without it",
            golden.display()
        );
    }
    assert_eq!(text, std::fs::read_to_string(&golden).unwrap());
    // One task of one run has no aggregate lines.
    assert_eq!(
        leaderboard::table::runs_table(&rows[..1]).lines().count(),
        1
    );
}
