//! `autobio describe` (a task sheet, or the catalogue) and `autobio compile` (the task as JSON).

use crate::front::Front;
use anyhow::{Context, Result};
use std::path::PathBuf;
use std::process::ExitCode;

#[derive(Clone, Debug, clap::Args)]
pub struct DescribeArgs {
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
pub struct CompileArgs {
    file: PathBuf,
}

pub fn describe(front: &Front, a: &DescribeArgs) -> Result<ExitCode> {
    if a.catalogue {
        out!("{}", compiler::describe::catalogue());
        return Ok(ExitCode::SUCCESS);
    }
    let file = a
        .file
        .as_ref()
        .context("a protocol or chain file is needed")?;
    let task = front.load(file)?;
    out!("{}", compiler::describe(&task));
    if let Some(seed) = a.seed {
        out!("{}", compiler::describe::example(&task, seed));
    }
    Ok(ExitCode::SUCCESS)
}

pub fn compile(front: &Front, a: &CompileArgs) -> Result<ExitCode> {
    let task = front.load(&a.file)?;
    outln!("{}", serde_json::to_string_pretty(&task)?);
    Ok(ExitCode::SUCCESS)
}
