//! `autobio export PROTOCOL --to autoprotocol`: a protocol compiled and checked as `autobio
//! check` does, then its lab steps written as Autoprotocol JSON for one episode's draw
//! (`interchange::autoprotocol::export`); what the document leaves out is said on stderr.

use crate::diagnostics;
use crate::front::Front;
use anyhow::{Context, Result};
use std::path::Path;
use std::process::ExitCode;

pub(crate) fn run(front: &Front, protocol: &Path, out: &Path, seed: u64) -> Result<ExitCode> {
    let checked = compiler::check_file(protocol, front.root.as_deref())?;
    let Some(task) = checked
        .task
        .as_ref()
        .filter(|_| !checked.diagnostics.iter().any(|d| d.is_error()))
    else {
        err!("{}", diagnostics::render_all(&checked, front.color));
        errln!(
            "{}: not exported (the protocol does not check)",
            protocol.display()
        );
        return Ok(ExitCode::FAILURE);
    };
    let exported = match interchange::autoprotocol::export::export(task, seed) {
        Ok(e) => e,
        Err(e) => {
            errln!("{}: not exported: {e}", protocol.display());
            return Ok(ExitCode::FAILURE);
        }
    };
    if let Some(dir) = out.parent().filter(|d| !d.as_os_str().is_empty()) {
        std::fs::create_dir_all(dir).with_context(|| format!("creating {}", dir.display()))?;
    }
    std::fs::write(out, &exported.json).with_context(|| format!("writing {}", out.display()))?;
    for note in &exported.notes {
        errln!("note: {note}");
    }
    outln!(
        "exported: {} -> {} (Autoprotocol, seed {seed})",
        protocol.display(),
        out.display()
    );
    Ok(ExitCode::SUCCESS)
}
