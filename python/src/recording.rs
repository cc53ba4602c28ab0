//! Recorded episodes (the MCAP files `autobio eval --record` and `autobio demo` write) and
//! LeRobot datasets' task tables read for
//! Python: `read_recording` returns plain values that `autobio/data.py` turns into numpy arrays,
//! `decode_png` a recorded frame's pixels. Reading only; recordings are written by the runtime.

use crate::env::runtime_err;
use pyo3::prelude::*;
use pyo3::types::{PyBytes, PyDict};
use std::path::PathBuf;

/// A recording's contents: `task`, `instance`, `verdict` (JSON text), `robots` (names in task
/// order), `actions` and `states` (per control step, every robot's block concatenated in task
/// order), `physics` (times and MuJoCo states), `labware` (times and JSON states), `images`
/// (camera to times and PNG bytes), `duration_s`.
#[pyfunction]
pub(crate) fn read_recording<'py>(py: Python<'py>, path: PathBuf) -> PyResult<Bound<'py, PyDict>> {
    let r = results::recording::read_recording(&path)
        .map_err(|e| pyo3::exceptions::PyValueError::new_err(format!("{}: {e}", path.display())))?;
    let robots: Vec<String> = r.task["robots"]
        .as_array()
        .map(|a| {
            a.iter()
                .filter_map(|r| r["name"].as_str().map(str::to_string))
                .collect()
        })
        .unwrap_or_default();
    let joined = |per: &std::collections::BTreeMap<String, Vec<Vec<f64>>>| -> Vec<Vec<f64>> {
        let steps = robots
            .iter()
            .map(|n| per.get(n).map_or(0, Vec::len))
            .min()
            .unwrap_or(0);
        (0..steps)
            .map(|k| robots.iter().flat_map(|n| per[n][k].clone()).collect())
            .collect()
    };
    let d = PyDict::new(py);
    d.set_item("task", r.task.to_string())?;
    d.set_item("instance", r.instance.to_string())?;
    d.set_item("verdict", r.verdict.as_ref().map(|v| v.to_string()))?;
    d.set_item("actions", joined(&r.actions))?;
    d.set_item("states", joined(&r.robot_states))?;
    d.set_item("robots", robots.clone())?;
    let (times, states): (Vec<f64>, Vec<Vec<f64>>) = r.physics.into_iter().unzip();
    d.set_item("physics", (times, states))?;
    let labware = r
        .labware_series
        .iter()
        .map(|(t, s)| Ok((*t, serde_json::to_string(s).map_err(runtime_err)?)))
        .collect::<PyResult<Vec<_>>>()?;
    d.set_item("labware", labware)?;
    let images = PyDict::new(py);
    for (camera, frames) in &r.images {
        let times: Vec<f64> = frames.iter().map(|f| f.0).collect();
        let pngs: Vec<Bound<'py, PyBytes>> =
            frames.iter().map(|f| PyBytes::new(py, &f.1)).collect();
        images.set_item(camera, (times, pngs))?;
    }
    d.set_item("images", images)?;
    d.set_item("duration_s", r.duration_s)?;
    Ok(d)
}

/// A PNG's pixels as (width, height, RGB bytes), for recorded frames (8-bit RGB).
#[pyfunction]
pub(crate) fn decode_png<'py>(
    py: Python<'py>,
    png: &[u8],
) -> PyResult<(u32, u32, Bound<'py, PyBytes>)> {
    let bad = |e: png::DecodingError| pyo3::exceptions::PyValueError::new_err(e.to_string());
    let mut decoder = png::Decoder::new(std::io::Cursor::new(png));
    decoder.set_transformations(png::Transformations::EXPAND | png::Transformations::STRIP_16);
    let mut reader = decoder.read_info().map_err(bad)?;
    let mut buf = vec![0; reader.output_buffer_size().unwrap_or(0)];
    let info = reader.next_frame(&mut buf).map_err(bad)?;
    buf.truncate(info.buffer_size());
    let rgb = match info.color_type {
        png::ColorType::Rgb => buf,
        png::ColorType::Rgba => buf.chunks(4).flat_map(|p| [p[0], p[1], p[2]]).collect(),
        png::ColorType::Grayscale => buf.iter().flat_map(|&g| [g, g, g]).collect(),
        png::ColorType::GrayscaleAlpha => buf.chunks(2).flat_map(|p| [p[0], p[0], p[0]]).collect(),
        png::ColorType::Indexed => {
            return Err(pyo3::exceptions::PyValueError::new_err(
                "an indexed PNG after expansion",
            ));
        }
    };
    Ok((info.width, info.height, PyBytes::new(py, &rgb)))
}

/// A LeRobot dataset's task table (either format autobio writes): [(task_index, task)].
#[pyfunction]
pub(crate) fn dataset_tasks(root: PathBuf) -> PyResult<Vec<(i64, String)>> {
    dataset::meta::task_table(&root)
        .map_err(|e| pyo3::exceptions::PyValueError::new_err(e.to_string()))
}
