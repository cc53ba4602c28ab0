//! Renders diagnostics for people with `annotate-snippets` (rustc's own renderer): the code, the
//! message, `--> file:line:col`, the source lines with the span underlined, notes and the hint;
//! coloured on a terminal, plain otherwise. Or as JSON lines for editors and CI. The text shown
//! is the text that was checked (a chain's stages as the compiler read them, never re-read), and a
//! diagnostic whose file was not shown to the compiler as a protocol gets no snippet.

use annotate_snippets::{
    AnnotationKind, Group, Level, Origin, Renderer, Snippet, normalize_untrusted_str as untrusted,
};
use compiler::Checked;
use dsl::Diagnostic;
use dsl::render::line_col;
use std::io::IsTerminal;

/// When to colour diagnostics (`--color`), as cargo and ripgrep do.
#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum)]
pub(crate) enum ColorChoice {
    /// On a terminal, unless `NO_COLOR` is set to something non-empty.
    Auto,
    Always,
    Never,
}

impl ColorChoice {
    /// Whether diagnostics written to stderr are coloured.
    pub(crate) fn for_stderr(self) -> bool {
        match self {
            ColorChoice::Always => true,
            ColorChoice::Never => false,
            ColorChoice::Auto => {
                std::env::var_os("NO_COLOR").is_none_or(|v| v.is_empty())
                    && std::io::stderr().is_terminal()
            }
        }
    }
}

/// Every diagnostic of a checked file, then a count of errors.
pub(crate) fn render_all(checked: &Checked, color: bool) -> String {
    let renderer = if color {
        Renderer::styled()
    } else {
        Renderer::plain()
    };
    let mut out = String::new();
    for d in &checked.diagnostics {
        out.push_str(&renderer.render(&report(checked, d)));
        out.push_str("\n\n");
    }
    let errors = checked.diagnostics.iter().filter(|d| d.is_error()).count();
    if errors > 0 {
        out.push_str(&format!(
            "{}: {errors} error{}\n",
            checked.file,
            if errors == 1 { "" } else { "s" }
        ));
    }
    out
}

fn report<'a>(checked: &Checked, d: &'a Diagnostic) -> Vec<Group<'a>> {
    let level = if d.is_error() {
        Level::ERROR
    } else {
        Level::WARNING
    };
    let title = level.primary_title(d.message.as_str()).id(d.code.as_str());
    let mut group = match checked.text_of(d) {
        Some((name, text)) => {
            let span = fit(&text, d.span);
            Group::with_title(title).element(
                Snippet::source(text)
                    .path(untrusted(&name))
                    .fold(true)
                    .annotation(AnnotationKind::Primary.span(span)),
            )
        }
        None => Group::with_title(title).element(Origin::path(untrusted(
            d.file.as_deref().unwrap_or(&checked.file),
        ))),
    };
    // Notes and hints quote the input (names, parameter values, paths): annotate-snippets trusts
    // them, so control characters are neutralised here.
    for n in &d.notes {
        group = group.element(Level::NOTE.message(untrusted(n)));
    }
    if let Some(h) = &d.hint {
        group = group.element(Level::HELP.with_name("hint").message(untrusted(h)));
    }
    vec![group]
}

/// The span clipped to the text and widened to character boundaries (an E0008 span covers a
/// raw byte that the shown text holds as U+FFFD).
fn fit(text: &str, span: dsl::Span) -> std::ops::Range<usize> {
    let mut start = span.start.min(text.len());
    while !text.is_char_boundary(start) {
        start -= 1;
    }
    let mut end = span.end.clamp(start, text.len());
    while !text.is_char_boundary(end) {
        end += 1;
    }
    start..end
}

/// One diagnostic as a JSON object with its resolved file, line and column.
pub(crate) fn to_json(checked: &Checked, d: &Diagnostic) -> String {
    let (name, line, col) = match checked.text_of(d) {
        Some((name, text)) => {
            let (l, c) = line_col(&text, d.span.start);
            (name, Some(l), Some(c))
        }
        None => (d.file.clone().unwrap_or_default(), None, None),
    };
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
