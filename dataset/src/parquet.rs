//! Parquet files in the Arrow types LeRobot's loaders expect: frames (`observation.state` and
//! `action` as `FixedSizeList<float32>`, `timestamp` float32, the int64 indices) with the
//! `huggingface` schema metadata `datasets` reads its features from; v3.0's episodes table; and
//! v3.0's `tasks.parquet`, a pandas frame indexed by the task string (with pandas' metadata, so
//! pandas rebuilds the index).
//!
//! It writes tables only; layouts and statistics live elsewhere.

use crate::DatasetError;
use arrow_array::builder::{ListBuilder, StringBuilder};
use arrow_array::{
    ArrayRef, FixedSizeListArray, Float32Array, Float64Array, Int64Array, RecordBatch, StringArray,
};
use arrow_schema::{ArrowError, DataType, Field, Schema};
use parquet::arrow::ArrowWriter;
use parquet::basic::Compression;
use parquet::file::properties::WriterProperties;
use serde_json::json;
use std::collections::HashMap;
use std::path::Path;
use std::sync::Arc;

/// One frame's row.
#[derive(Clone, Debug, PartialEq)]
pub(crate) struct Row {
    pub state: Vec<f32>,
    /// `observation.environment_state`; empty when the dataset has none.
    pub environment_state: Vec<f32>,
    pub action: Vec<f32>,
    pub timestamp: f32,
    pub frame_index: i64,
    pub episode_index: i64,
    pub index: i64,
    pub task_index: i64,
}

fn write(path: &Path, batch: RecordBatch) -> Result<(), DatasetError> {
    let bad = |e: String| DatasetError::Parquet {
        path: path.to_path_buf(),
        why: e,
    };
    let file = std::fs::File::create(path).map_err(|e| DatasetError::io("create", path, e))?;
    let props = WriterProperties::builder()
        .set_compression(Compression::SNAPPY)
        .set_created_by("autobio".into())
        .build();
    let mut w =
        ArrowWriter::try_new(file, batch.schema(), Some(props)).map_err(|e| bad(e.to_string()))?;
    w.write(&batch).map_err(|e| bad(e.to_string()))?;
    let file = w.into_inner().map_err(|e| bad(e.to_string()))?;
    file.sync_all()
        .map_err(|e| DatasetError::io("sync", path, e))
}

fn list(values: Vec<f32>, width: usize) -> Result<ArrayRef, ArrowError> {
    let item = Arc::new(Field::new("item", DataType::Float32, true));
    FixedSizeListArray::try_new(
        item,
        width as i32,
        Arc::new(Float32Array::from(values)),
        None,
    )
    .map(|a| Arc::new(a) as ArrayRef)
}

/// The frames table: one row per frame.
pub(crate) fn write_frames(path: &Path, rows: &[Row]) -> Result<(), DatasetError> {
    let bad = |e: String| DatasetError::Parquet {
        path: path.to_path_buf(),
        why: e,
    };
    let sw = rows.first().map_or(0, |r| r.state.len());
    let ew = rows.first().map_or(0, |r| r.environment_state.len());
    let aw = rows.first().map_or(0, |r| r.action.len());
    let item = Arc::new(Field::new("item", DataType::Float32, true));
    let seq = |n: usize| DataType::FixedSizeList(item.clone(), n as i32);
    let value = |dtype: &str| json!({"dtype": dtype, "_type": "Value"});
    let sequence =
        |n: usize| json!({"feature": value("float32"), "length": n, "_type": "Sequence"});
    let mut features = json!({
        "observation.state": sequence(sw),
        "action": sequence(aw),
        "timestamp": value("float32"),
        "frame_index": value("int64"),
        "episode_index": value("int64"),
        "index": value("int64"),
        "task_index": value("int64"),
    });
    let mut fields = vec![Field::new("observation.state", seq(sw), true)];
    if ew > 0 {
        features["observation.environment_state"] = sequence(ew);
        fields.push(Field::new("observation.environment_state", seq(ew), true));
    }
    fields.extend([
        Field::new("action", seq(aw), true),
        Field::new("timestamp", DataType::Float32, true),
        Field::new("frame_index", DataType::Int64, true),
        Field::new("episode_index", DataType::Int64, true),
        Field::new("index", DataType::Int64, true),
        Field::new("task_index", DataType::Int64, true),
    ]);
    let hf = json!({"info": {"features": features}});
    let schema = Schema::new_with_metadata(
        fields,
        HashMap::from([("huggingface".to_string(), hf.to_string())]),
    );
    let ints = |f: fn(&Row) -> i64| {
        Arc::new(Int64Array::from(rows.iter().map(f).collect::<Vec<_>>())) as ArrayRef
    };
    let mut columns: Vec<ArrayRef> = vec![
        list(
            rows.iter().flat_map(|r| r.state.iter().copied()).collect(),
            sw,
        )
        .map_err(|e| bad(e.to_string()))?,
    ];
    if ew > 0 {
        columns.push(
            list(
                rows.iter()
                    .flat_map(|r| r.environment_state.iter().copied())
                    .collect(),
                ew,
            )
            .map_err(|e| bad(e.to_string()))?,
        );
    }
    columns.extend([
        list(
            rows.iter().flat_map(|r| r.action.iter().copied()).collect(),
            aw,
        )
        .map_err(|e| bad(e.to_string()))?,
        Arc::new(Float32Array::from(
            rows.iter().map(|r| r.timestamp).collect::<Vec<_>>(),
        )),
        ints(|r| r.frame_index),
        ints(|r| r.episode_index),
        ints(|r| r.index),
        ints(|r| r.task_index),
    ]);
    let batch = RecordBatch::try_new(Arc::new(schema), columns).map_err(|e| bad(e.to_string()))?;
    write(path, batch)
}

/// v3.0's `meta/tasks.parquet`: `task_index`, indexed by the task string.
pub(crate) fn write_tasks(path: &Path, tasks: &[String]) -> Result<(), DatasetError> {
    let bad = |e: String| DatasetError::Parquet {
        path: path.to_path_buf(),
        why: e,
    };
    let pandas = json!({
        "index_columns": ["__index_level_0__"],
        "column_indexes": [{"name": null, "field_name": null, "pandas_type": "unicode", "numpy_type": "object", "metadata": {"encoding": "UTF-8"}}],
        "columns": [
            {"name": "task_index", "field_name": "task_index", "pandas_type": "int64", "numpy_type": "int64", "metadata": null},
            {"name": null, "field_name": "__index_level_0__", "pandas_type": "unicode", "numpy_type": "object", "metadata": null}
        ],
        "creator": {"library": "autobio", "version": env!("CARGO_PKG_VERSION")},
        "pandas_version": "2.2.3"
    });
    let schema = Schema::new_with_metadata(
        vec![
            Field::new("task_index", DataType::Int64, true),
            Field::new("__index_level_0__", DataType::Utf8, true),
        ],
        HashMap::from([("pandas".to_string(), pandas.to_string())]),
    );
    let batch = RecordBatch::try_new(
        Arc::new(schema),
        vec![
            Arc::new(Int64Array::from(
                (0..tasks.len() as i64).collect::<Vec<_>>(),
            )),
            Arc::new(StringArray::from(tasks.to_vec())),
        ],
    )
    .map_err(|e| bad(e.to_string()))?;
    write(path, batch)
}

/// One episode's row in v3.0's `meta/episodes` table.
#[derive(Clone, Debug)]
pub(crate) struct EpisodeRow {
    pub episode_index: i64,
    pub tasks: Vec<String>,
    pub length: i64,
    pub from_index: i64,
    pub to_index: i64,
    /// The data file holding its rows: (chunk, file).
    pub data_file: (i64, i64),
    /// Per camera key: its video file (chunk, file) and (from_timestamp, to_timestamp) inside it.
    pub videos: Vec<EpisodeVideo>,
}

/// Where one camera's frames of an episode are in v3.0's shared videos.
#[derive(Clone, Debug)]
pub(crate) struct EpisodeVideo {
    pub key: String,
    pub file: (i64, i64),
    pub from_s: f64,
    pub to_s: f64,
}

/// v3.0's `meta/episodes/chunk-000/file-000.parquet` (one metadata file).
pub(crate) fn write_episodes(path: &Path, eps: &[EpisodeRow]) -> Result<(), DatasetError> {
    let bad = |e: String| DatasetError::Parquet {
        path: path.to_path_buf(),
        why: e,
    };
    let ints = |f: &dyn Fn(&EpisodeRow) -> i64| {
        Arc::new(Int64Array::from(eps.iter().map(f).collect::<Vec<_>>())) as ArrayRef
    };
    let mut tasks = ListBuilder::new(StringBuilder::new());
    for e in eps {
        for t in &e.tasks {
            tasks.values().append_value(t);
        }
        tasks.append(true);
    }
    let mut fields = vec![
        Field::new("episode_index", DataType::Int64, true),
        Field::new(
            "tasks",
            DataType::List(Arc::new(Field::new("item", DataType::Utf8, true))),
            true,
        ),
        Field::new("length", DataType::Int64, true),
        Field::new("data/chunk_index", DataType::Int64, true),
        Field::new("data/file_index", DataType::Int64, true),
        Field::new("dataset_from_index", DataType::Int64, true),
        Field::new("dataset_to_index", DataType::Int64, true),
    ];
    let mut columns: Vec<ArrayRef> = vec![
        ints(&|e| e.episode_index),
        Arc::new(tasks.finish()),
        ints(&|e| e.length),
        ints(&|e| e.data_file.0),
        ints(&|e| e.data_file.1),
        ints(&|e| e.from_index),
        ints(&|e| e.to_index),
    ];
    // Columns in key order, as info.json lists the features (not in camera order: a dataset
    // read back, e.g. to merge shards, knows its cameras only by key).
    let mut keys: Vec<(usize, String)> = eps
        .first()
        .map(|e| e.videos.iter().map(|v| v.key.clone()).enumerate().collect())
        .unwrap_or_default();
    keys.sort_by(|a, b| a.1.cmp(&b.1));
    for (k, key) in &keys {
        let k = *k;
        for (name, part) in [("chunk_index", 0), ("file_index", 1)] {
            fields.push(Field::new(
                format!("videos/{key}/{name}"),
                DataType::Int64,
                true,
            ));
            columns.push(ints(&|e| {
                let f = e.videos[k].file;
                if part == 0 { f.0 } else { f.1 }
            }));
        }
        fields.push(Field::new(
            format!("videos/{key}/from_timestamp"),
            DataType::Float64,
            true,
        ));
        columns.push(Arc::new(Float64Array::from(
            eps.iter().map(|e| e.videos[k].from_s).collect::<Vec<_>>(),
        )));
        fields.push(Field::new(
            format!("videos/{key}/to_timestamp"),
            DataType::Float64,
            true,
        ));
        columns.push(Arc::new(Float64Array::from(
            eps.iter().map(|e| e.videos[k].to_s).collect::<Vec<_>>(),
        )));
    }
    for name in ["meta/episodes/chunk_index", "meta/episodes/file_index"] {
        fields.push(Field::new(name, DataType::Int64, true));
        columns.push(ints(&|_| 0));
    }
    let batch = RecordBatch::try_new(Arc::new(Schema::new(fields)), columns)
        .map_err(|e| bad(e.to_string()))?;
    write(path, batch)
}

/// Joins episodes' frame tables, in order, into one file (v3.0's shared data file).
pub(crate) fn concat_frames(parts: &[std::path::PathBuf], out: &Path) -> Result<(), DatasetError> {
    use parquet::arrow::arrow_reader::ParquetRecordBatchReaderBuilder;
    let bad = |e: String| DatasetError::Parquet {
        path: out.to_path_buf(),
        why: e,
    };
    let mut writer: Option<ArrowWriter<std::fs::File>> = None;
    for p in parts {
        let file = std::fs::File::open(p).map_err(|e| DatasetError::io("open", p, e))?;
        let builder =
            ParquetRecordBatchReaderBuilder::try_new(file).map_err(|e| bad(e.to_string()))?;
        // The file's schema, with its metadata (the batches' schemas carry none).
        let schema = builder.schema().clone();
        let reader = builder.build().map_err(|e| bad(e.to_string()))?;
        for batch in reader {
            let batch = batch.map_err(|e| bad(e.to_string()))?;
            if writer.is_none() {
                let file =
                    std::fs::File::create(out).map_err(|e| DatasetError::io("create", out, e))?;
                let props = WriterProperties::builder()
                    .set_compression(Compression::SNAPPY)
                    .set_created_by("autobio".into())
                    .build();
                writer = Some(
                    ArrowWriter::try_new(file, schema.clone(), Some(props))
                        .map_err(|e| bad(e.to_string()))?,
                );
            }
            let batch = batch
                .with_schema(schema.clone())
                .map_err(|e| bad(e.to_string()))?;
            writer
                .as_mut()
                .expect("made above")
                .write(&batch)
                .map_err(|e| bad(e.to_string()))?;
        }
    }
    if let Some(w) = writer {
        let file = w.into_inner().map_err(|e| bad(e.to_string()))?;
        file.sync_all()
            .map_err(|e| DatasetError::io("sync", out, e))?;
    }
    Ok(())
}

/// A table file's record batches, to read in order.
fn batches(
    path: &Path,
) -> Result<parquet::arrow::arrow_reader::ParquetRecordBatchReader, DatasetError> {
    use parquet::arrow::arrow_reader::ParquetRecordBatchReaderBuilder;
    let file = std::fs::File::open(path).map_err(|e| DatasetError::io("open", path, e))?;
    ParquetRecordBatchReaderBuilder::try_new(file)
        .and_then(|b| b.build())
        .map_err(|e| DatasetError::Parquet {
            path: path.to_path_buf(),
            why: e.to_string(),
        })
}

/// One frame's vectors: `observation.state`, `observation.environment_state` (empty when the
/// table has none) and `action`.
#[derive(Clone, Debug, Default, PartialEq)]
pub(crate) struct Frame {
    pub state: Vec<f32>,
    pub environment_state: Vec<f32>,
    pub action: Vec<f32>,
}

/// Every frame's vectors of an episode's frames table, in order.
pub(crate) fn read_frames(path: &Path) -> Result<Vec<Frame>, DatasetError> {
    use arrow_array::Array;
    let bad = |e: String| DatasetError::Parquet {
        path: path.to_path_buf(),
        why: e,
    };
    let reader = batches(path)?;
    let mut rows = Vec::new();
    for batch in reader {
        let batch = batch.map_err(|e| bad(e.to_string()))?;
        let column = |name: &str| -> Result<Vec<Vec<f32>>, DatasetError> {
            let list = batch
                .column_by_name(name)
                .and_then(|c| c.as_any().downcast_ref::<FixedSizeListArray>())
                .ok_or_else(|| bad(format!("no fixed-size list column `{name}`")))?;
            let width = list.value_length() as usize;
            let values = list
                .values()
                .as_any()
                .downcast_ref::<Float32Array>()
                .ok_or_else(|| bad(format!("`{name}` is not float32")))?;
            Ok((0..list.len())
                .map(|i| values.values()[i * width..(i + 1) * width].to_vec())
                .collect())
        };
        let environment = match batch.column_by_name("observation.environment_state") {
            Some(_) => column("observation.environment_state")?,
            None => vec![Vec::new(); batch.num_rows()],
        };
        rows.extend(
            column("observation.state")?
                .into_iter()
                .zip(environment)
                .zip(column("action")?)
                .map(|((state, environment_state), action)| Frame {
                    state,
                    environment_state,
                    action,
                }),
        );
    }
    Ok(rows)
}

/// v3.0's `meta/tasks.parquet` read back: (task_index, task) in file order.
pub(crate) fn read_tasks(path: &Path) -> Result<Vec<(i64, String)>, DatasetError> {
    let bad = |e: String| DatasetError::Parquet {
        path: path.to_path_buf(),
        why: e,
    };
    let reader = batches(path)?;
    let mut rows = Vec::new();
    for batch in reader {
        let batch = batch.map_err(|e| bad(e.to_string()))?;
        let index = batch
            .column_by_name("task_index")
            .and_then(|c| c.as_any().downcast_ref::<Int64Array>())
            .ok_or_else(|| bad("no int64 column `task_index`".into()))?;
        let task = batch
            .column_by_name("__index_level_0__")
            .or_else(|| batch.column_by_name("task"))
            .and_then(|c| c.as_any().downcast_ref::<StringArray>())
            .ok_or_else(|| bad("no task string column (the pandas index or `task`)".into()))?;
        rows.extend(
            index
                .values()
                .iter()
                .zip(task.iter())
                .map(|(&i, t)| (i, t.unwrap_or_default().to_string())),
        );
    }
    Ok(rows)
}
