//! A dataset's task table read back, whichever format wrote it (v2.1's `meta/tasks.jsonl`, v3.0's
//! `meta/tasks.parquet`): what the Python package's `autobio.dataset_tasks` returns, so a user
//! maps `task_index` to its instruction without pandas or pyarrow. Reading only.

use crate::DatasetError;
use std::path::Path;

/// Every task of the dataset at `root`: (task_index, task), in index order.
pub fn task_table(root: &Path) -> Result<Vec<(i64, String)>, DatasetError> {
    let meta = root.join("meta");
    let parquet = meta.join("tasks.parquet");
    let mut rows = if parquet.exists() {
        crate::parquet::read_tasks(&parquet)?
    } else {
        let path = meta.join("tasks.jsonl");
        let text =
            std::fs::read_to_string(&path).map_err(|e| DatasetError::io("read", &path, e))?;
        text.lines()
            .filter(|l| !l.trim().is_empty())
            .enumerate()
            .map(|(n, line)| {
                let bad = |why: &str| DatasetError::Existing {
                    path: path.clone(),
                    why: format!("line {}: {why}", n + 1),
                };
                let v: serde_json::Value =
                    serde_json::from_str(line).map_err(|e| bad(&e.to_string()))?;
                let index = v["task_index"]
                    .as_i64()
                    .ok_or_else(|| bad("no task_index"))?;
                let task = v["task"].as_str().ok_or_else(|| bad("no task"))?;
                Ok((index, task.to_string()))
            })
            .collect::<Result<Vec<_>, DatasetError>>()?
    };
    rows.sort();
    Ok(rows)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn both_formats_read_back_the_tasks_they_were_written_with() {
        let tasks = vec!["close the lid".to_string(), "open the lid".to_string()];
        let v30 = std::env::temp_dir().join(format!("autobio-meta-v30-{}", std::process::id()));
        std::fs::create_dir_all(v30.join("meta")).unwrap();
        crate::parquet::write_tasks(&v30.join("meta/tasks.parquet"), &tasks).unwrap();
        let v21 = std::env::temp_dir().join(format!("autobio-meta-v21-{}", std::process::id()));
        std::fs::create_dir_all(v21.join("meta")).unwrap();
        std::fs::write(
            v21.join("meta/tasks.jsonl"),
            "{\"task_index\": 1, \"task\": \"open the lid\"}\n{\"task_index\": 0, \"task\": \"close the lid\"}\n",
        )
        .unwrap();
        let want = vec![(0, tasks[0].clone()), (1, tasks[1].clone())];
        assert_eq!(task_table(&v30).unwrap(), want);
        assert_eq!(task_table(&v21).unwrap(), want);
        std::fs::write(v21.join("meta/tasks.jsonl"), "{\"task\": \"x\"}\n").unwrap();
        let err = task_table(&v21).unwrap_err().to_string();
        assert!(err.contains("line 1: no task_index"), "{err}");
        std::fs::remove_dir_all(v30).ok();
        std::fs::remove_dir_all(v21).ok();
    }
}
