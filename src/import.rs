//! `autobio import`: an Opentrons analysis, a Protocol Designer file or an Autoprotocol document
//! written as a protocol file
//! (`interchange::import`), then checked as `autobio check` checks one. Findings about the source
//! are shown against the source file (its line and column, and the JSON path); the written
//! file's diagnostics against it, each inside a step with the source command the step realises.

use crate::diagnostics;
use crate::front::Front;
use anyhow::{Context, Result, bail};
use compiler::Checked;
use std::path::PathBuf;
use std::process::ExitCode;

#[derive(Clone, Debug, clap::Args)]
pub(crate) struct ImportArgs {
    /// The file to import: an Opentrons analysis (`opentrons analyze --json-output`), a
    /// Protocol Designer file (schema 8) or an Autoprotocol document (`refs`, `instructions`)
    file: PathBuf,
    /// Where to write the protocol file (nothing is written when the import is refused)
    #[arg(long)]
    out: PathBuf,
    /// The robots as `name=model`, comma-separated: the first holds the pipette, the second
    /// works the thermocycler's lid [default: left=ur5e_inspire,arm=ur5e_2f85]
    #[arg(long, value_delimiter = ',')]
    robots: Vec<String>,
    /// The protocol's id [default: imported.<the file's stem>]
    #[arg(long)]
    id: Option<String>,
    /// The protocol's instruction [default: from the file's protocol name]
    #[arg(long)]
    instruction: Option<String>,
    /// Keep a command of an instrument we have no model of (a magnet, a plate reader, a
    /// temperature module; Autoprotocol's spin and incubate) as an instrument-only step
    /// (`external`: the robots stand by for its duration) instead of refusing it
    #[arg(long)]
    keep_instrument_steps: bool,
}

pub(crate) fn run(front: &Front, a: &ImportArgs) -> Result<ExitCode> {
    let text = std::fs::read_to_string(&a.file)
        .with_context(|| format!("reading {}", a.file.display()))?;
    let mut robots = Vec::new();
    for r in &a.robots {
        let Some((name, model)) = r.split_once('=') else {
            bail!("--robots {r}: write each robot as name=model (left=ur5e_inspire)");
        };
        if !interchange::draft::bare_key(name.trim()) || model.trim().is_empty() {
            bail!(
                "--robots {r}: a robot's name is letters, digits, `_` and `-`, and it needs a model"
            );
        }
        robots.push((name.trim().to_string(), model.trim().to_string()));
    }
    let options = interchange::Options {
        id: a.id.clone(),
        instruction: a.instruction.clone(),
        robots,
        deps: runtime::deps::deps_dir(),
        file_name: a.file.file_name().map_or_else(
            || a.file.display().to_string(),
            |n| n.to_string_lossy().into(),
        ),
        keep_instrument_steps: a.keep_instrument_steps,
    };
    let imported = interchange::import(&text, &options);
    let source = Checked {
        file: a.file.display().to_string(),
        task: None,
        diagnostics: imported.diagnostics.clone(),
        source: text,
        stages: Default::default(),
    };
    if !source.diagnostics.is_empty() {
        err!("{}", diagnostics::render_all(&source, front.color));
    }
    let Some(protocol) = &imported.protocol else {
        errln!("{}: not imported", a.file.display());
        return Ok(ExitCode::FAILURE);
    };
    if let Some(dir) = a.out.parent().filter(|d| !d.as_os_str().is_empty()) {
        std::fs::create_dir_all(dir).with_context(|| format!("creating {}", dir.display()))?;
    }
    std::fs::write(&a.out, protocol).with_context(|| format!("writing {}", a.out.display()))?;
    let mut checked = compiler::check_file(&a.out, front.root.as_deref())?;
    expert::reach::check(&mut checked, &expert::reach::Store::from_env());
    // Each step's block, from its header line to the next step's (or `[success]`): quoted values
    // hold no line break, so a header at a line's start is a table header.
    let starts: Vec<usize> = protocol
        .match_indices("\n[[steps]]\n")
        .map(|(i, _)| i + 1)
        .collect();
    let end = protocol.find("\n[success]").unwrap_or(protocol.len());
    for d in &mut checked.diagnostics {
        if d.file.is_some() || d.span.start >= end {
            continue;
        }
        let step = starts.iter().rposition(|s| *s <= d.span.start);
        if let Some(Some(from)) = step.and_then(|k| imported.step_sources.get(k)) {
            d.notes
                .push(format!("this step realises {from} of {}", a.file.display()));
        }
    }
    let failed = checked.diagnostics.iter().any(|d| d.is_error());
    if checked.diagnostics.is_empty() {
        outln!(
            "imported: {} -> {} ({}, {} steps); ok",
            a.file.display(),
            a.out.display(),
            imported.format.as_deref().unwrap_or("?"),
            imported.step_sources.len()
        );
    } else {
        err!("{}", diagnostics::render_all(&checked, front.color));
        outln!(
            "imported: {} -> {} ({} steps){}",
            a.file.display(),
            a.out.display(),
            imported.step_sources.len(),
            if failed {
                "; the protocol does not check"
            } else {
                ""
            }
        );
    }
    Ok(if failed {
        ExitCode::FAILURE
    } else {
        ExitCode::SUCCESS
    })
}
