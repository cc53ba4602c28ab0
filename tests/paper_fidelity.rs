//! docs/paper-fidelity.md's table of what the paper suite runs, checked against the suite: every
//! task of suites/paper.toml has one row, and its level, time limit, fixed camera and success
//! rule are the compiled task's. A change to a paper task that the table does not follow fails
//! here, with the row the task now needs.

use crate::common;

use common::compile;
use std::collections::BTreeMap;

/// One row of the table: level, time limit, camera, success, as written.
#[derive(Debug, PartialEq)]
struct Row {
    level: String,
    limit: String,
    camera: String,
    success: String,
}

/// The rows of the table under `## Ours, as checked`, by task id.
fn table(doc: &str) -> BTreeMap<String, Row> {
    let start = doc
        .find("## Ours, as checked")
        .expect("docs/paper-fidelity.md has its checked table");
    let mut rows = BTreeMap::new();
    for line in doc[start..].lines().skip(1) {
        if line.starts_with("## ") {
            break;
        }
        let cells: Vec<&str> = line
            .trim()
            .trim_matches('|')
            .split('|')
            .map(str::trim)
            .collect();
        let [task, level, limit, camera, success] = cells[..] else {
            continue;
        };
        let Some(task) = task.strip_prefix('`').and_then(|t| t.strip_suffix('`')) else {
            continue;
        };
        let row = Row {
            level: level.into(),
            limit: limit.into(),
            camera: camera.into(),
            success: success.into(),
        };
        assert!(rows.insert(task.to_string(), row).is_none(), "{task} twice");
    }
    rows
}

/// A number as the table writes it: no trailing zeros, `0` for zero.
fn num(x: f64) -> String {
    let s = format!("{:.3}", x);
    let s = s.trim_end_matches('0').trim_end_matches('.');
    if s == "-0" { "0".into() } else { s.into() }
}

/// The row `task` needs: its fixed camera as `(x, y, z) m, P° down, fovy F°`, its success rule
/// as its predicates joined by `; `, each in backquotes.
fn row_of(task: &compiler::Task) -> Row {
    let fixed = task
        .cameras
        .iter()
        .find_map(|c| match &c.mount {
            compiler::CameraMount::Fixed {
                pos,
                xyaxes,
                fovy_deg,
            } => Some((pos, xyaxes, fovy_deg)),
            _ => None,
        })
        .expect("a fixed camera");
    let (pos, xy, fovy) = fixed;
    // The camera looks down its -z; z = x × y. Its pitch below the horizon is asin(z · up).
    let z_up = xy[0] * xy[4] - xy[1] * xy[3];
    let pitch = z_up.asin().to_degrees();
    let camera = format!(
        "({}, {}, {}) m, {}° down, fovy {}°",
        num(pos[0]),
        num(pos[1]),
        num(pos[2]),
        pitch.round(),
        num(*fovy)
    );
    let success: Vec<String> = task
        .stages
        .iter()
        .flat_map(|s| &s.success)
        .map(|p| format!("`{}`", p.text))
        .collect();
    Row {
        level: task.level.clone(),
        limit: format!("{} s", num(task.time_limit_s)),
        camera,
        success: success.join("; "),
    }
}

#[test]
fn the_fidelity_table_says_what_the_paper_suite_runs() {
    let doc = std::fs::read_to_string("docs/paper-fidelity.md").unwrap();
    let rows = table(&doc);
    let suite =
        results::suite::LoadedSuite::read(std::path::Path::new("suites/paper.toml")).unwrap();
    let protocols = suite.protocols();
    assert_eq!(protocols.len(), 9, "the paper's Table 2 has nine tasks");
    let mut ids = Vec::new();
    for protocol in protocols {
        let task = compile(protocol.to_str().unwrap());
        let want = row_of(&task);
        let Some(row) = rows.get(&task.id) else {
            panic!(
                "{} has no row; it needs:\n| `{}` | {} | {} | {} | {} |",
                task.id, task.id, want.level, want.limit, want.camera, want.success
            )
        };
        assert_eq!(
            row, &want,
            "{}'s row differs from the task; it needs:\n| `{}` | {} | {} | {} | {} |",
            task.id, task.id, want.level, want.limit, want.camera, want.success
        );
        ids.push(task.id);
    }
    ids.sort();
    let listed: Vec<String> = rows.keys().cloned().collect();
    assert_eq!(listed, ids, "a row for a task the paper suite does not run");
}

/// The table's levels are the paper's: three tasks per level, as its Table 2 groups them.
#[test]
fn the_paper_suite_has_the_papers_levels() {
    let doc = std::fs::read_to_string("docs/paper-fidelity.md").unwrap();
    let mut per_level: BTreeMap<String, Vec<String>> = BTreeMap::new();
    for (id, row) in table(&doc) {
        per_level.entry(row.level).or_default().push(id);
    }
    let paper = [
        (
            "easy",
            [
                "thermal_cycler.close_lid",
                "thermal_cycler.open_lid",
                "tube.pick_up",
            ],
        ),
        (
            "hard",
            [
                "centrifuge.insert_symmetric",
                "thermal_mixer.set_parameters",
                "tube.screw_cap",
            ],
        ),
        (
            "medium",
            ["pipette.aspirate", "tube.transfer", "tube.unscrew_cap"],
        ),
    ];
    for (level, tasks) in paper {
        assert_eq!(per_level[level], tasks, "{level}");
    }
}
