//! Renders diagnostics like rustc: `error[CODE]: message`, `--> file:line:col`, the source line
//! with a caret underline, and the hint.

use dsl::Diagnostic;
use dsl::render::{line_col, line_of};
use std::fmt::Write;

pub fn render_all(file: &str, source: &str, diags: &[Diagnostic]) -> String {
    let mut out = String::new();
    for d in diags {
        let (line, col) = line_col(source, d.span.start);
        let (text, from, width) = line_of(source, d.span);
        let sev = if d.is_error() { "error" } else { "warning" };
        let gutter = " ".repeat(line.to_string().len());
        let _ = writeln!(out, "{sev}[{}]: {}", d.code, d.message);
        let _ = writeln!(out, "{gutter}--> {file}:{line}:{col}");
        let _ = writeln!(out, "{gutter} |");
        let _ = writeln!(out, "{line} | {text}");
        let _ = writeln!(out, "{gutter} | {}{}", " ".repeat(from), "^".repeat(width));
        if let Some(h) = &d.hint {
            let _ = writeln!(out, "{gutter} = hint: {h}");
        }
        let _ = writeln!(out);
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
