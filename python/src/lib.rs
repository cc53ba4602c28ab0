//! The native core of the `autobio` Python package (`autobio._core`), built with maturin: shipped
//! tasks and protocol files compiled (`tasks`), one task's episodes stepped by hand (`env::Env`),
//! N episodes stepped on N threads (`vector::VecEnv`), and recordings read back (`recording`).
//!
//! It adds no simulation of its own: every step is `runtime::Env`'s, so an episode here is the
//! episode `autobio eval` runs for the same seed and actions (the same trajectory hash). The
//! Python layer (`python/autobio/`) shapes these values into gymnasium's spaces, vla-eval's
//! benchmark and numpy arrays.
//!
//! Its tests are python/tests (pytest, run by `make test` against the installed wheel).

mod env;
mod recording;
mod tasks;
mod vector;

use pyo3::prelude::*;
use pyo3::types::PyDict;

pyo3::create_exception!(
    _core,
    ProtocolError,
    pyo3::exceptions::PyValueError,
    "A protocol that cannot be loaded: unknown, unreadable, or with errors (each with its file:line:col, code and hint)."
);

pub(crate) fn load_err(e: tasks::LoadError) -> PyErr {
    ProtocolError::new_err(e.to_string())
}

/// Every shipped task: a dict per task with `id`, `file`, `level`, `instruction`, `stages`
/// (their instructions), `robots`, `cameras`, `state_names`, `action_names`,
/// `environment_state_names` (the privileged state layout, `results::environment_state`), `time_limit_s`,
/// `control_dt`, `max_steps`, `params` (names) and `simulated` (the runtime can build its scene).
#[pyfunction]
#[pyo3(name = "tasks")]
fn shipped_tasks(py: Python<'_>) -> PyResult<Vec<Bound<'_, PyDict>>> {
    tasks::shipped()
        .iter()
        .map(|s| sheet(py, &s.task, &format!("protocols/{}", s.file), s.simulated))
        .collect()
}

/// The same dict as `tasks()` gives, for a shipped task id or a protocol file.
#[pyfunction]
fn task_info<'py>(py: Python<'py>, task: &str) -> PyResult<Bound<'py, PyDict>> {
    let t = tasks::load(task).map_err(load_err)?;
    let simulated = tasks::simulated(&t);
    let file = t.source.clone();
    sheet(py, &t, &file, simulated)
}

fn sheet<'py>(
    py: Python<'py>,
    t: &compiler::Task,
    file: &str,
    simulated: bool,
) -> PyResult<Bound<'py, PyDict>> {
    let d = PyDict::new(py);
    d.set_item("id", &t.id)?;
    d.set_item("file", file)?;
    d.set_item("level", &t.level)?;
    d.set_item("instruction", &t.instruction)?;
    let stages: Vec<&str> = t.stages.iter().map(|s| s.instruction.as_str()).collect();
    d.set_item("stages", stages)?;
    let robots: Vec<(&str, &str)> = t
        .robots
        .iter()
        .map(|r| (r.name.as_str(), r.model.as_str()))
        .collect();
    d.set_item("robots", robots)?;
    let cameras: Vec<&str> = t.cameras.iter().map(|c| c.name.as_str()).collect();
    d.set_item("cameras", cameras)?;
    d.set_item("state_names", env::layout(t, |m| m.state_names()))?;
    d.set_item("action_names", env::layout(t, |m| m.action_names()))?;
    d.set_item(
        "environment_state_names",
        results::environment_state::EnvironmentState::of(t).names(),
    )?;
    d.set_item("time_limit_s", t.time_limit_s)?;
    d.set_item("control_dt", env::control_dt(t))?;
    d.set_item("max_steps", env::max_steps(t))?;
    let params: Vec<&str> = t.params.iter().map(|p| p.name.as_str()).collect();
    d.set_item("params", params)?;
    d.set_item("simulated", simulated)?;
    Ok(d)
}

/// The compiled task of a shipped task id or a protocol file, as JSON (`autobio compile`'s form).
#[pyfunction]
fn compile(task: &str) -> PyResult<String> {
    let task = tasks::load(task).map_err(load_err)?;
    serde_json::to_string(&task).map_err(env::runtime_err)
}

#[pymodule]
fn _core(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add("__version__", env!("CARGO_PKG_VERSION"))?;
    m.add("ProtocolError", m.py().get_type::<ProtocolError>())?;
    m.add_class::<env::Env>()?;
    m.add_class::<vector::VecEnv>()?;
    m.add_function(wrap_pyfunction!(shipped_tasks, m)?)?;
    m.add_function(wrap_pyfunction!(compile, m)?)?;
    m.add_function(wrap_pyfunction!(task_info, m)?)?;
    m.add_function(wrap_pyfunction!(recording::read_recording, m)?)?;
    m.add_function(wrap_pyfunction!(recording::decode_png, m)?)?;
    m.add_function(wrap_pyfunction!(recording::dataset_tasks, m)?)?;
    Ok(())
}
