//! Renders diagnostics like rustc: `error[CODE]: message`, `--> file:line:col`, the source line
//! with a caret underline, notes and the hint; or as JSON lines for editors and CI. A diagnostic
//! that points into another file (a chain's stage) is rendered against that file's text.

use dsl::Diagnostic;
use dsl::render::{line_col, line_of};
use std::fmt::Write;

pub fn render_all(file: &str, source: &str, diags: &[Diagnostic]) -> String {
    let mut out = String::new();
    for d in diags {
        let (name, text) = source_of(file, source, d);
        render_one(&mut out, &name, &text, d);
    }
    let errors = diags.iter().filter(|d| d.is_error()).count();
    if errors > 0 {
        let _ = writeln!(
            out,
            "{file}: {errors} error{}",
            if errors == 1 { "" } else { "s" }
        );
    }
    out
}

/// The file a diagnostic points into and its text (read from disk for a chain's stage).
fn source_of(file: &str, source: &str, d: &Diagnostic) -> (String, String) {
    match &d.file {
        Some(f) => (f.clone(), std::fs::read_to_string(f).unwrap_or_default()),
        None => (file.to_string(), source.to_string()),
    }
}

fn render_one(out: &mut String, file: &str, source: &str, d: &Diagnostic) {
    let (line, col) = line_col(source, d.span.start);
    let (text, from, width) = line_of(source, d.span);
    let sev = if d.is_error() { "error" } else { "warning" };
    let gutter = " ".repeat(line.to_string().len());
    let _ = writeln!(out, "{sev}[{}]: {}", d.code, d.message);
    let _ = writeln!(out, "{gutter}--> {file}:{line}:{col}");
    let _ = writeln!(out, "{gutter} |");
    let _ = writeln!(out, "{line} | {text}");
    let _ = writeln!(out, "{gutter} | {}{}", " ".repeat(from), "^".repeat(width));
    for n in &d.notes {
        let _ = writeln!(out, "{gutter} = note: {n}");
    }
    if let Some(h) = &d.hint {
        let _ = writeln!(out, "{gutter} = hint: {h}");
    }
    let _ = writeln!(out);
}

/// One diagnostic as a JSON object with its resolved file, line and column.
pub fn to_json(file: &str, source: &str, d: &Diagnostic) -> String {
    let (name, text) = source_of(file, source, d);
    let (line, col) = line_col(&text, d.span.start);
    serde_json::json!({
        "file": name,
        "line": line,
        "column": col,
        "code": d.code,
        "severity": d.severity,
        "message": d.message,
        "hint": d.hint,
        "notes": d.notes,
        "span": d.span,
    })
    .to_string()
}
