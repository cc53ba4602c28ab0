//! The tasks the package knows: every shipped protocol (compiled into the extension by its build
//! script, so an installed wheel needs no checkout) by id, and any protocol or chain file by path.
//! A protocol with errors is a [`LoadError::Protocol`] whose text is the diagnostics, each with
//! its file:line:col, code and hint, as `autobio check` reports them.
//!
//! It compiles; it does not simulate (a task's scene is built by `runtime::Env`).

use compiler::stage_files::{StageError, joined};
use compiler::{Task, check_file, compile_source_with};
use dsl::Diagnostic;
use std::path::Path;
use std::sync::OnceLock;

include!(concat!(env!("OUT_DIR"), "/protocols.rs"));

/// Why a task could not be loaded.
#[derive(Debug, thiserror::Error)]
pub(crate) enum LoadError {
    #[error("{0}")]
    File(#[from] compiler::FileError),
    /// The protocol's diagnostics, rendered.
    #[error("{file} has errors:\n{diagnostics}")]
    Protocol { file: String, diagnostics: String },
    #[error(
        "`{0}` is neither a shipped task id nor a protocol file (autobio.tasks() lists the ids)"
    )]
    Unknown(String),
}

/// One shipped task: its id, file, level, instruction, stage count and whether it simulates.
#[derive(Clone, Debug)]
pub(crate) struct Shipped {
    pub file: &'static str,
    pub task: Task,
    /// Every item has an instrument model, so the runtime can build its scene.
    pub simulated: bool,
}

/// Every shipped protocol that compiles, in file order (compiled once per process).
pub(crate) fn shipped() -> &'static [Shipped] {
    static TASKS: OnceLock<Vec<Shipped>> = OnceLock::new();
    TASKS.get_or_init(|| {
        SHIPPED
            .iter()
            // A workflow's stage files are compiled in as its chain reads them, but the task is
            // the chain (as `autobio tasks` counts them).
            .filter(|(file, _)| {
                !Path::new(file)
                    .components()
                    .any(|c| c.as_os_str() == "stages")
            })
            .filter_map(|(file, _)| {
                let task = compile_shipped(file).ok()?;
                let simulated = task.labware.iter().all(|l| l.params.instrument().is_some());
                Some(Shipped {
                    file,
                    task,
                    simulated,
                })
            })
            .collect()
    })
}

/// Every item has an instrument model: the runtime can build the task's scene.
pub(crate) fn simulated(task: &Task) -> bool {
    task.labware.iter().all(|l| l.params.instrument().is_some())
}

/// A shipped task by id, or a protocol or chain file by path (a chain's stages confined to its
/// folder, as `autobio check` reads them).
pub(crate) fn load(spec: &str) -> Result<Task, LoadError> {
    if let Some(s) = shipped().iter().find(|s| s.task.id == spec) {
        return Ok(s.task.clone());
    }
    let path = Path::new(spec);
    if !path.exists() {
        return Err(LoadError::Unknown(spec.to_string()));
    }
    let checked = check_file(path, None)?;
    match checked.task {
        Some(ref t) if !checked.diagnostics.iter().any(Diagnostic::is_error) => Ok(t.clone()),
        _ => Err(LoadError::Protocol {
            file: checked.file.clone(),
            diagnostics: checked
                .diagnostics
                .iter()
                .map(|d| render(d, checked.text_of(d)))
                .collect::<Vec<_>>()
                .join("\n"),
        }),
    }
}

/// A shipped protocol compiled from its embedded text, chain stages from the embedded set.
fn compile_shipped(file: &str) -> Result<Task, LoadError> {
    let text = embedded(file).ok_or_else(|| LoadError::Unknown(file.to_string()))?;
    let stages = |path: &str| {
        embedded(path)
            .map(str::to_string)
            .ok_or(StageError::NotAFile {
                path: path.to_string(),
            })
    };
    let (task, diagnostics) = compile_source_with(text, file, &stages);
    task.ok_or_else(|| LoadError::Protocol {
        file: file.to_string(),
        diagnostics: diagnostics
            .iter()
            .map(|d| render(d, Some((file.to_string(), text.to_string()))))
            .collect::<Vec<_>>()
            .join("\n"),
    })
}

fn embedded(path: &str) -> Option<&'static str> {
    let path = joined("", path);
    SHIPPED.iter().find(|(f, _)| *f == path).map(|(_, t)| *t)
}

/// `file:line:col: error[E0012]: message`, then its notes and hint.
fn render(d: &Diagnostic, text: Option<(String, String)>) -> String {
    let severity = if d.is_error() { "error" } else { "warning" };
    let place = match text {
        Some((file, text)) => {
            let (line, col) = dsl::render::line_col(&text, d.span.start);
            format!("{file}:{line}:{col}")
        }
        None => d.file.clone().unwrap_or_default(),
    };
    let mut s = format!("{place}: {severity}[{:?}]: {}", d.code, d.message);
    for n in &d.notes {
        s += &format!("\n  note: {n}");
    }
    if let Some(h) = &d.hint {
        s += &format!("\n  hint: {h}");
    }
    s
}
