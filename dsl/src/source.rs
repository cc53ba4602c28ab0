//! The protocol text before TOML sees it: bytes to UTF-8 with a located error, and a small
//! scanner of TOML's string and comment rules that finds where an unclosed string opens (toml
//! reports an unclosed multi-line string where the file ends, far from the mistake). No IO.

use crate::{Code, Diagnostic, Span};

/// The bytes as UTF-8 text, or an E0008 diagnostic at the first byte that is not.
pub fn decode(bytes: &[u8]) -> Result<&str, Diagnostic> {
    std::str::from_utf8(bytes).map_err(|e| {
        let at = e.valid_up_to();
        let len = e.error_len().unwrap_or(bytes.len() - at).max(1);
        let shown: Vec<String> = bytes[at..(at + len).min(bytes.len())]
            .iter()
            .map(|b| format!("0x{b:02x}"))
            .collect();
        Diagnostic::error(
            Code::E0008,
            Span::new(at, at + len),
            format!("the file is not UTF-8 text: byte {} here", shown.join(" ")),
        )
        .with_hint("save the file as UTF-8; protocol files are UTF-8 text")
    })
}

/// The text to show for a file [`decode`] refused: the valid part verbatim, each bad byte as
/// U+FFFD. Offsets before the first bad byte are the same in both.
pub fn lossy(bytes: &[u8]) -> String {
    String::from_utf8_lossy(bytes).into_owned()
}

/// A string literal that never closes.
#[derive(Clone, Debug, PartialEq)]
pub struct Unclosed {
    /// The opening delimiter.
    pub span: Span,
    /// "basic string", "multi-line literal string", ...
    pub what: &'static str,
    pub delimiter: &'static str,
}

/// The first string literal in `source` that is not closed where TOML requires: by the end of
/// its line for `"` and `'`, by the end of the file for `"""` and `'''`. Comments are skipped.
pub fn unclosed_string(source: &str) -> Option<Unclosed> {
    let b = source.as_bytes();
    let mut i = 0;
    while i < b.len() {
        match b[i] {
            b'#' => i = line_end(b, i),
            b'"' | b'\'' => {
                let q = b[i];
                let multi = b[i..].starts_with(if q == b'"' { b"\"\"\"" } else { b"'''" });
                let open = i;
                let (what, delimiter) = match (q, multi) {
                    (b'"', true) => ("multi-line basic string", "\"\"\""),
                    (b'"', false) => ("basic string", "\""),
                    (_, true) => ("multi-line literal string", "'''"),
                    (_, false) => ("literal string", "'"),
                };
                let found = Unclosed {
                    span: Span::new(open, open + delimiter.len()),
                    what,
                    delimiter,
                };
                i += delimiter.len();
                loop {
                    match b.get(i) {
                        None => return Some(found),
                        Some(b'\n') if !multi => return Some(found),
                        // An escape; in a one-line string, a backslash cannot escape its end.
                        Some(b'\\') if q == b'"' => {
                            if !multi && b.get(i + 1) == Some(&b'\n') {
                                return Some(found);
                            }
                            i += 2;
                        }
                        Some(&c) if c == q => {
                            if !multi {
                                i += 1;
                                break;
                            }
                            if b[i..].starts_with(delimiter.as_bytes()) {
                                // Up to two more quotes may belong to the content: `""""` ends
                                // with the last three.
                                i += 3;
                                for _ in 0..2 {
                                    if b.get(i) == Some(&q) {
                                        i += 1;
                                    }
                                }
                                break;
                            }
                            i += 1;
                        }
                        Some(_) => i += 1,
                    }
                }
            }
            _ => i += 1,
        }
    }
    None
}

fn line_end(b: &[u8], from: usize) -> usize {
    b[from..]
        .iter()
        .position(|&c| c == b'\n')
        .map(|p| from + p)
        .unwrap_or(b.len())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn decode_points_at_the_first_bad_byte() {
        let bytes = b"a = \"ok\"\nb = \"\xff\"\n";
        let d = decode(bytes).unwrap_err();
        assert_eq!(d.code, Code::E0008);
        assert_eq!(d.span, Span::new(14, 15));
        assert!(d.message.contains("0xff"), "{}", d.message);
        assert_eq!(crate::render::line_col(&lossy(bytes), d.span.start), (2, 6));
        assert_eq!(decode(b"a = 1\n").unwrap(), "a = 1\n");
    }

    #[test]
    fn finds_where_an_unclosed_string_opens() {
        let src = "a = \"x\" # it's \"fine\"\nb = \"\"\"one\ntwo\n[t]\nc = 1\n";
        let u = unclosed_string(src).unwrap();
        assert_eq!(u.what, "multi-line basic string");
        assert_eq!(&src[u.span.start..u.span.end], "\"\"\"");
        assert_eq!(u.span.start, src.find("\"\"\"").unwrap());

        let src = "a = 'x'\nb = 'y\nc = 2\n";
        let u = unclosed_string(src).unwrap();
        assert_eq!((u.what, u.span.start), ("literal string", 12));

        let src = "a = \"\"\"\nclosed \\\"\"\" here\"\"\"\nb = '''x''''\nc = \"q\\\"\"\n";
        assert_eq!(unclosed_string(src), None);
    }
}
