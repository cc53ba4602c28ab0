//! `autobio describe` (a task sheet with each step's reach margin, or the catalogue) and
//! `autobio compile` (the task as JSON).

use crate::front::Front;
use anyhow::{Context, Result};
use std::path::PathBuf;
use std::process::ExitCode;

#[derive(Clone, Debug, clap::Args)]
pub(crate) struct DescribeArgs {
    #[arg(required_unless_present = "catalogue")]
    file: Option<PathBuf>,
    /// Print the catalogue of labware kinds and lab primitives instead
    #[arg(long)]
    catalogue: bool,
    /// Also show the parameters and instruction one episode with this seed draws
    #[arg(long)]
    seed: Option<u64>,
}

#[derive(Clone, Debug, clap::Args)]
pub(crate) struct CompileArgs {
    file: PathBuf,
}

pub(crate) fn describe(front: &Front, a: &DescribeArgs) -> Result<ExitCode> {
    if a.catalogue {
        out!("{}", compiler::describe::catalogue());
        return Ok(ExitCode::SUCCESS);
    }
    let file = a
        .file
        .as_ref()
        .context("a protocol or chain file is needed")?;
    let task = front.load(file)?;
    out!("{}", compiler::describe::describe(&task));
    out!("{}", environment_state(&task));
    out!("{}", reach_margins(&task));
    if let Some(seed) = a.seed {
        out!("{}", compiler::describe::example(&task, seed));
    }
    Ok(ExitCode::SUCCESS)
}

pub(crate) fn compile(front: &Front, a: &CompileArgs) -> Result<ExitCode> {
    let task = front.load(&a.file)?;
    outln!("{}", serde_json::to_string_pretty(&task)?);
    Ok(ExitCode::SUCCESS)
}

/// The task's environment-state layout (`--observation state`, a profile's
/// `environment_state_key`): every value's name, in order.
fn environment_state(task: &compiler::Task) -> String {
    let layout = results::environment_state::EnvironmentState::of(task);
    format!(
        "\nenvironment state ({} values, privileged): {}\n",
        layout.len(),
        layout.names().join(", ")
    )
}

/// Each step's reach margin in seed 0's layout (`expert::reach::margins`), as the sheet's last
/// section.
fn reach_margins(task: &compiler::Task) -> String {
    use std::fmt::Write;
    let mut w = String::new();
    if task.stages.len() != 1 {
        let _ = writeln!(
            w,
            "\nreach: measured per protocol; describe a stage's file for its margins"
        );
        return w;
    }
    let margins = expert::reach::margins(task);
    let _ = writeln!(
        w,
        "\nreach in seed 0's layout (how far each step's targets could move away from its robot and still be reached)"
    );
    for (i, (_, step)) in task.steps().enumerate() {
        let label = format!("{}. {} with {}", i + 1, step.primitive, step.robot);
        let margin = match margins.iter().find(|m| m.step == i) {
            None => "not checked (no target of its own, or one an earlier step moved)".to_string(),
            Some(m) => match m.margin {
                None => "out of reach (E0036: see `autobio check`)".to_string(),
                Some(d) if d >= expert::reach::MARGIN_MAX - 1e-9 => {
                    format!("at least {:.0} cm", d * 100.0)
                }
                Some(d) => format!("{:.0} cm", d * 100.0),
            },
        };
        let _ = writeln!(w, "  {label}: {margin}");
    }
    w
}
