//! Diagnostics as data: code, severity, span, message, hint. No formatting for terminals here.

use serde::Serialize;

/// A half-open byte range into the protocol source.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Default)]
pub struct Span {
    pub start: usize,
    pub end: usize,
}

impl Span {
    pub fn new(start: usize, end: usize) -> Self {
        Span { start, end }
    }
}

impl From<std::ops::Range<usize>> for Span {
    fn from(r: std::ops::Range<usize>) -> Self {
        Span::new(r.start, r.end)
    }
}

#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
#[serde(rename_all = "lowercase")]
pub enum Severity {
    Error,
    Warning,
}

/// Stable diagnostic codes. The number never changes meaning once released; `autobio explain`
/// prints [`Code::explanation`].
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
pub enum Code {
    /// The file is not valid TOML.
    E0001,
    /// A required table or key is missing.
    E0002,
    /// A key that the language does not define.
    E0003,
    /// A value of the wrong type.
    E0004,
    /// Unsupported `format` version.
    E0005,
    /// Unknown labware kind.
    E0010,
    /// Unknown robot model.
    E0011,
    /// Unknown lab primitive.
    E0012,
    /// A name that refers to no declared labware or robot.
    E0013,
    /// A primitive applied to labware that does not support it.
    E0014,
    /// A quantity with a missing, unknown or wrong-dimension unit.
    E0020,
    /// A value outside its allowed range.
    E0021,
    /// A success predicate that cannot be read.
    E0030,
    /// A step whose labware state precondition does not hold where it runs.
    E0031,
}

impl Code {
    pub fn as_str(self) -> &'static str {
        match self {
            Code::E0001 => "E0001",
            Code::E0002 => "E0002",
            Code::E0003 => "E0003",
            Code::E0004 => "E0004",
            Code::E0005 => "E0005",
            Code::E0010 => "E0010",
            Code::E0011 => "E0011",
            Code::E0012 => "E0012",
            Code::E0013 => "E0013",
            Code::E0014 => "E0014",
            Code::E0020 => "E0020",
            Code::E0021 => "E0021",
            Code::E0030 => "E0030",
            Code::E0031 => "E0031",
        }
    }

    pub const ALL: [Code; 14] = [
        Code::E0001,
        Code::E0002,
        Code::E0003,
        Code::E0004,
        Code::E0005,
        Code::E0010,
        Code::E0011,
        Code::E0012,
        Code::E0013,
        Code::E0014,
        Code::E0020,
        Code::E0021,
        Code::E0030,
        Code::E0031,
    ];

    pub fn from_name(name: &str) -> Option<Code> {
        Code::ALL
            .into_iter()
            .find(|c| c.as_str().eq_ignore_ascii_case(name))
    }

    /// Long-form documentation, printed by `autobio explain CODE`.
    pub fn explanation(self) -> &'static str {
        match self {
            Code::E0001 => {
                "The protocol file is not valid TOML (an unclosed string or table header, a duplicate key...).\nFix the syntax at the marked place; nothing else in the file is checked until it parses."
            }
            Code::E0002 => {
                "A table or key that every protocol needs is missing, e.g. `[protocol]`, `protocol.id`,\n`protocol.instruction`, `protocol.time_limit`, or at least one `[[steps]]` entry."
            }
            Code::E0003 => {
                "The key is not part of the protocol language (format 1). Usually a typo: the hint names the\nclosest known key. See docs/protocol-language.md for every table and key."
            }
            Code::E0004 => {
                "The value has the wrong TOML type, e.g. a number where a string is expected."
            }
            Code::E0005 => {
                "The file declares a `format` this autobio does not read. Format 1 is the current one."
            }
            Code::E0010 => "`kind` names no labware in the catalogue. Known kinds: thermal_cycler.",
            Code::E0011 => "`model` names no robot in the catalogue. Known models: ur5e_2f85.",
            Code::E0012 => {
                "`do` names no lab primitive in the catalogue. Known primitives: open_lid, close_lid."
            }
            Code::E0013 => {
                "A step, randomisation or predicate refers to a name that is not declared under\n`[labware]` or `[robots]`."
            }
            Code::E0014 => {
                "The primitive exists but this labware kind has no affordance for it (e.g. `open_lid` on\nsomething without a lid)."
            }
            Code::E0020 => {
                "A physical quantity has no unit, an unknown unit, or a unit of the wrong dimension.\nWrite quantities as strings with units (\"30 s\", \"5 deg\", \"10 mm\") or use a unit-suffixed key\n(`pos_m`, `yaw_deg`, `xy_mm`)."
            }
            Code::E0021 => {
                "The value is outside the range the language allows (e.g. a negative time limit, a\nrandomisation range whose low end exceeds its high end)."
            }
            Code::E0030 => {
                "A success predicate must read `<labware>.<part> is <state>`, e.g. \"cycler.lid is closed\";\nthe part and state must exist for that labware kind."
            }
            Code::E0031 => {
                "Each primitive declares the labware state it needs; tracing the steps from the declared\ninitial state, this step would start where its precondition does not hold (closing a lid\nthat is already closed)."
            }
        }
    }
}

impl std::fmt::Display for Code {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.as_str())
    }
}

/// One problem found in a protocol file.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Diagnostic {
    pub code: Code,
    pub severity: Severity,
    pub span: Span,
    /// Lowercase, quotes the offending input with backticks.
    pub message: String,
    pub hint: Option<String>,
}

impl Diagnostic {
    pub fn error(code: Code, span: Span, message: impl Into<String>) -> Self {
        Diagnostic {
            code,
            severity: Severity::Error,
            span,
            message: message.into(),
            hint: None,
        }
    }

    pub fn with_hint(mut self, hint: impl Into<String>) -> Self {
        self.hint = Some(hint.into());
        self
    }

    pub fn is_error(&self) -> bool {
        self.severity == Severity::Error
    }
}

/// The closest candidate by edit distance, if it is close enough to be a plausible typo.
pub fn did_you_mean<'a>(
    input: &str,
    candidates: impl IntoIterator<Item = &'a str>,
) -> Option<&'a str> {
    candidates
        .into_iter()
        .map(|c| (levenshtein(input, c), c))
        .filter(|(d, c)| *d <= (c.len().max(input.len()) / 3).max(1) + usize::from(c.len() > 8))
        .min_by_key(|(d, _)| *d)
        .map(|(_, c)| c)
}

fn levenshtein(a: &str, b: &str) -> usize {
    let b: Vec<char> = b.chars().collect();
    let mut prev: Vec<usize> = (0..=b.len()).collect();
    for (i, ca) in a.chars().enumerate() {
        let mut cur = vec![i + 1; b.len() + 1];
        for (j, cb) in b.iter().enumerate() {
            let sub = prev[j] + usize::from(ca != *cb);
            cur[j + 1] = sub.min(prev[j + 1] + 1).min(cur[j] + 1);
        }
        prev = cur;
    }
    prev[b.len()]
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn suggests_close_names_only() {
        assert_eq!(
            did_you_mean("thermal_cycle", ["thermal_cycler", "centrifuge"]),
            Some("thermal_cycler")
        );
        assert_eq!(
            did_you_mean("close_lidd", ["open_lid", "close_lid"]),
            Some("close_lid")
        );
        assert_eq!(did_you_mean("zzz", ["thermal_cycler"]), None);
    }

    #[test]
    fn codes_round_trip() {
        for c in Code::ALL {
            assert_eq!(Code::from_name(c.as_str()), Some(c));
            assert!(!c.explanation().is_empty());
        }
    }
}
