//! Diagnostics as the compiler collects them: the sink every pass reports into ([`Cx`], which
//! tags each diagnostic with the file it points into and drops repeats) and the hint line for a
//! name that is not known ([`hint_for`]). It decides nothing about protocols.

use dsl::{Code, Diagnostic, Span, did_you_mean};

pub(crate) fn hint_for(input: &str, candidates: &[&str], what: &str) -> String {
    match did_you_mean(input, candidates.iter().copied()) {
        Some(s) => format!("did you mean `{s}`?"),
        None if candidates.is_empty() => format!("there are no {what}"),
        None => format!("known {what}: {}", candidates.join(", ")),
    }
}

/// Diagnostics sink that tags each diagnostic with the file it points into (for chain stages).
pub(crate) struct Cx {
    pub diags: Vec<Diagnostic>,
    pub file: Option<String>,
    /// Places already reported (code, span, file), for constant-time deduplication.
    reported: std::collections::HashSet<(Code, Span, Option<String>)>,
}

impl Cx {
    pub(crate) fn new(file: Option<String>) -> Self {
        Cx {
            diags: Vec::new(),
            file,
            reported: Default::default(),
        }
    }

    pub(crate) fn push(&mut self, mut d: Diagnostic) {
        d.file = self.file.clone();
        // One report per place: the proof may hit the same failure under many parameter values.
        if self.reported.insert((d.code, d.span, d.file.clone())) {
            self.diags.push(d);
        }
    }

    pub(crate) fn err(&mut self, code: Code, span: Span, msg: String, hint: Option<String>) {
        let mut d = Diagnostic::new(code, span, msg);
        d.hint = hint;
        self.push(d);
    }

    pub(crate) fn has_errors(&self) -> bool {
        self.diags.iter().any(|d| d.is_error())
    }
}
