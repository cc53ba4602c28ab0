//! Where a value stands in a JSON text: the byte range of the value a path of keys and indices
//! names (`commands` / 12 / `params` / `volume`), so that a finding about an imported file points
//! at its line and column as a protocol diagnostic does. A scanner over the text's structure
//! only (strings, nesting); it trusts that the text parsed as JSON already and answers `None` for
//! a path the text does not have. No values are decoded here.

use dsl::Span;

/// One step of a path into a JSON document.
#[derive(Clone, Debug, PartialEq)]
pub enum Key {
    Field(String),
    Index(usize),
}

impl Key {
    pub fn field(name: &str) -> Key {
        Key::Field(name.to_string())
    }
}

/// The path as JSON Pointer text (`/commands/12/params/volume`).
pub fn pointer(path: &[Key]) -> String {
    path.iter()
        .map(|k| match k {
            Key::Field(f) => format!("/{}", f.replace('~', "~0").replace('/', "~1")),
            Key::Index(i) => format!("/{i}"),
        })
        .collect()
}

/// The span of the value at `path` in `text`; for the empty path, the whole document.
pub fn locate(text: &str, path: &[Key]) -> Option<Span> {
    let b = text.as_bytes();
    let mut at = skip_ws(b, 0);
    for key in path {
        at = match key {
            Key::Field(name) => field(b, at, name)?,
            Key::Index(i) => element(b, at, *i)?,
        };
    }
    Some(Span::new(at, value_end(b, at)?))
}

/// The deepest span along `path` that the text has: the value itself, else its nearest
/// enclosing value (a missing key is reported at the object that lacks it).
pub fn nearest(text: &str, path: &[Key]) -> Span {
    (0..=path.len())
        .rev()
        .find_map(|n| locate(text, &path[..n]))
        .unwrap_or_default()
}

fn skip_ws(b: &[u8], mut i: usize) -> usize {
    while i < b.len() && b[i].is_ascii_whitespace() {
        i += 1;
    }
    i
}

/// The end of the string starting at `i` (just past its closing quote).
fn string_end(b: &[u8], i: usize) -> Option<usize> {
    let mut j = i + 1;
    while j < b.len() {
        match b[j] {
            b'\\' => j += 2,
            b'"' => return Some(j + 1),
            _ => j += 1,
        }
    }
    None
}

/// The end of the value starting at `i`.
fn value_end(b: &[u8], i: usize) -> Option<usize> {
    match b.get(i)? {
        b'"' => string_end(b, i),
        b'{' | b'[' => {
            let mut depth = 0usize;
            let mut j = i;
            while j < b.len() {
                match b[j] {
                    b'"' => {
                        j = string_end(b, j)?;
                        continue;
                    }
                    b'{' | b'[' => depth += 1,
                    b'}' | b']' => {
                        depth -= 1;
                        if depth == 0 {
                            return Some(j + 1);
                        }
                    }
                    _ => {}
                }
                j += 1;
            }
            None
        }
        _ => {
            let mut j = i;
            while j < b.len() && !matches!(b[j], b',' | b'}' | b']') && !b[j].is_ascii_whitespace()
            {
                j += 1;
            }
            Some(j)
        }
    }
}

/// The start of member `name`'s value in the object at `i`.
fn field(b: &[u8], i: usize, name: &str) -> Option<usize> {
    if b.get(i) != Some(&b'{') {
        return None;
    }
    let mut j = skip_ws(b, i + 1);
    while b.get(j) == Some(&b'"') {
        let key_end = string_end(b, j)?;
        let key: String = serde_json::from_slice(&b[j..key_end]).ok()?;
        j = skip_ws(b, key_end);
        if b.get(j) != Some(&b':') {
            return None;
        }
        let value = skip_ws(b, j + 1);
        if key == name {
            return Some(value);
        }
        j = skip_ws(b, value_end(b, value)?);
        if b.get(j) == Some(&b',') {
            j = skip_ws(b, j + 1);
        }
    }
    None
}

/// The start of element `n` of the array at `i`.
fn element(b: &[u8], i: usize, n: usize) -> Option<usize> {
    if b.get(i) != Some(&b'[') {
        return None;
    }
    let mut j = skip_ws(b, i + 1);
    for _ in 0..n {
        if b.get(j) == Some(&b']') {
            return None;
        }
        j = skip_ws(b, value_end(b, j)?);
        if b.get(j) != Some(&b',') {
            return None;
        }
        j = skip_ws(b, j + 1);
    }
    (b.get(j) != Some(&b']')).then_some(j)
}

#[cfg(test)]
mod tests {
    use super::*;

    const TEXT: &str = r#"{"a": 1, "commands": [ {"commandType": "x", "params": {"v": 2.5}},
  {"commandType": "say \"}\"", "params": {"volume": [1, {"z": null}]}} ], "b/c": true}"#;

    fn at(path: &[Key]) -> &'static str {
        let s = locate(TEXT, path).unwrap();
        &TEXT[s.start..s.end]
    }

    #[test]
    fn paths_find_their_values_across_strings_with_brackets_and_quotes() {
        use Key::*;
        assert_eq!(at(&[Key::field("a")]), "1");
        assert_eq!(
            at(&[Key::field("commands"), Index(1), Key::field("commandType")]),
            r#""say \"}\"""#
        );
        assert_eq!(
            at(&[
                Key::field("commands"),
                Index(1),
                Key::field("params"),
                Key::field("volume"),
                Index(1)
            ]),
            r#"{"z": null}"#
        );
        assert_eq!(
            at(&[Key::field("commands"), Index(0), Key::field("params")]),
            r#"{"v": 2.5}"#
        );
        assert_eq!(at(&[Key::field("b/c")]), "true");
        assert_eq!(locate(TEXT, &[Key::field("commands"), Index(2)]), None);
        assert_eq!(locate(TEXT, &[Key::field("missing")]), None);
        // A missing key is reported at the object that lacks it.
        let s = nearest(
            TEXT,
            &[Key::field("commands"), Index(0), Key::field("nope")],
        );
        assert!(TEXT[s.start..s.end].starts_with(r#"{"commandType": "x""#));
        assert_eq!(
            pointer(&[Key::field("commands"), Index(3), Key::field("b/c")]),
            "/commands/3/b~1c"
        );
    }
}
