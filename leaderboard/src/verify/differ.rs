//! The first difference between two JSON values, named by its key path
//! (`verdict.stages[1].completed_at_s: 2 (derived 3.1)`): how a verifier says which claimed
//! figure its own derivation does not reproduce.
//!
//! It compares values; it neither reads files nor decides what must be equal.

use serde::Serialize;
use serde::de::DeserializeOwned;
use serde_json::Value;

/// A record as JSON, through its text and the parser (what a claimed record went through): two
/// figures are equal when their JSON is.
pub(super) fn as_json(record: &impl Serialize) -> Value {
    serde_json::to_string(record)
        .ok()
        .and_then(|t| serde_json::from_str::<Value>(&t).ok())
        .unwrap_or_default()
}

/// Parses a record strictly: JSON (no NaN or infinity, nesting at most 128 deep) into `T`, and
/// nothing in the text that `T` does not hold (an unknown field is a claim nobody checks).
pub(super) fn strict<T: DeserializeOwned + Serialize>(text: &[u8]) -> Result<T, String> {
    let typed: T = serde_json::from_slice(text).map_err(|e| e.to_string())?;
    let raw: Value = serde_json::from_slice(text).map_err(|e| e.to_string())?;
    match first_difference(&raw, &as_json(&typed)) {
        None => Ok(typed),
        Some(d) => Err(d),
    }
}

/// The first place where `claimed` is not `derived` (objects by key in order, arrays by index),
/// as `path: claimed (derived ...)`; `None` where they are equal.
pub(super) fn first_difference(claimed: &Value, derived: &Value) -> Option<String> {
    walk(claimed, derived, String::new())
}

fn walk(claimed: &Value, derived: &Value, at: String) -> Option<String> {
    let here = |what: String| {
        Some(if at.is_empty() {
            what
        } else {
            format!("{at}: {what}")
        })
    };
    match (claimed, derived) {
        (Value::Object(a), Value::Object(b)) => {
            for (k, w) in b {
                let path = join(&at, k);
                match a.get(k) {
                    Some(c) => {
                        if let Some(d) = walk(c, w, path) {
                            return Some(d);
                        }
                    }
                    None => return Some(format!("{path}: missing (derived {})", show(w))),
                }
            }
            a.keys()
                .find(|k| !b.contains_key(*k))
                .map(|k| format!("{}: not a field of it", join(&at, k)))
        }
        (Value::Array(a), Value::Array(b)) => {
            for (k, (c, w)) in a.iter().zip(b).enumerate() {
                if let Some(d) = walk(c, w, format!("{at}[{k}]")) {
                    return Some(d);
                }
            }
            (a.len() != b.len())
                .then(|| format!("{} entries (derived {})", a.len(), b.len()))
                .and_then(here)
        }
        (c, w) if c == w => None,
        (c, w) => here(format!("{} (derived {})", show(c), show(w))),
    }
}

fn join(at: &str, key: &str) -> String {
    if at.is_empty() {
        key.to_string()
    } else {
        format!("{at}.{key}")
    }
}

/// A value as it reads in a sentence, cut to 80 characters.
fn show(v: &Value) -> String {
    let s = v.to_string();
    match s.char_indices().nth(80) {
        Some((i, _)) => format!("{}...", &s[..i]),
        None => s,
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use serde_json::json;

    #[test]
    fn names_the_first_differing_path() {
        let derived =
            json!({"a": 1, "v": {"stages": [{"id": "x", "t": 1.5}, {"id": "y", "t": 3.0}]}});
        assert_eq!(first_difference(&derived, &derived), None);
        let claimed =
            json!({"a": 1, "v": {"stages": [{"id": "x", "t": 1.5}, {"id": "y", "t": 2.0}]}});
        assert_eq!(
            first_difference(&claimed, &derived).as_deref(),
            Some("v.stages[1].t: 2.0 (derived 3.0)")
        );
        let claimed = json!({"a": 1, "v": {"stages": [{"id": "x", "t": 1.5}]}, "extra": true});
        assert_eq!(
            first_difference(&claimed, &derived).as_deref(),
            Some("v.stages: 1 entries (derived 2)")
        );
        let claimed = json!({"a": 1, "v": {"stages": [{"id": "x", "t": 1.5}, {"id": "y", "t": 3.0}]}, "extra": true});
        assert_eq!(
            first_difference(&claimed, &derived).as_deref(),
            Some("extra: not a field of it")
        );
        assert_eq!(
            first_difference(&json!({"v": {}}), &json!({"v": {"k": 1}})).as_deref(),
            Some("v.k: missing (derived 1)")
        );
    }
}
