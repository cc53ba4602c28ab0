//! `autobio check` (every diagnostic of every file, as text or JSON lines) and `autobio explain`
//! (a diagnostic code's documentation).

use crate::diagnostics;
use crate::front::Front;
use anyhow::{Result, bail};
use std::path::PathBuf;
use std::process::ExitCode;

#[derive(Clone, Debug, clap::Args)]
pub(crate) struct CheckArgs {
    files: Vec<PathBuf>,
    /// Print the diagnostics as JSON lines (one object per diagnostic) instead of text
    #[arg(long)]
    json: bool,
}

#[derive(Clone, Debug, clap::Args)]
pub(crate) struct ExplainArgs {
    #[arg(required_unless_present = "all")]
    code: Option<String>,
    #[arg(long)]
    all: bool,
}

pub(crate) fn check(front: &Front, a: &CheckArgs) -> Result<ExitCode> {
    if a.files.is_empty() {
        bail!(
            "no files to check: name protocol or chain files, e.g. `autobio check protocols/*/*.toml`"
        );
    }
    let (mut failed, mut unreadable) = (false, false);
    for f in &a.files {
        // A file that cannot be read is reported, and the others are still checked.
        let mut checked = match compiler::check_file(f, front.root.as_deref()) {
            Ok(c) => c,
            Err(e) => {
                errln!("error: {e}");
                unreadable = true;
                continue;
            }
        };
        // What the language cannot see: whether each step's robot reaches its target.
        expert::reach::check(&mut checked, &expert::reach::Store::from_env());
        failed |= checked.diagnostics.iter().any(|d| d.is_error());
        if a.json {
            for d in &checked.diagnostics {
                outln!("{}", diagnostics::to_json(&checked, d));
            }
        } else if checked.diagnostics.is_empty() {
            match expert::reach::not_checked(&checked) {
                Some(why) => outln!("ok: {} (reach: {why})", checked.file),
                None => outln!("ok: {}", checked.file),
            }
        } else {
            err!("{}", diagnostics::render_all(&checked, front.color));
        }
    }
    Ok(if unreadable {
        ExitCode::from(2)
    } else if failed {
        ExitCode::FAILURE
    } else {
        ExitCode::SUCCESS
    })
}

pub(crate) fn explain(a: &ExplainArgs) -> Result<ExitCode> {
    if a.all {
        for c in dsl::Code::ALL {
            outln!("{c}  {}", c.summary());
        }
        return Ok(ExitCode::SUCCESS);
    }
    let code = a.code.clone().unwrap_or_default();
    match dsl::Code::from_name(&code) {
        Some(c) => {
            outln!("{c}: {}\n\n{}", c.summary(), c.explanation());
            Ok(ExitCode::SUCCESS)
        }
        None => bail!(
            "no diagnostic code `{code}` (codes look like E0010; `autobio explain --all` lists them)"
        ),
    }
}
