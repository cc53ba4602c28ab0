//! Thermal profiles as a protocol writes them in one string: holds and cycles interleaved, as an
//! extended profile (Opentrons' `runExtendedProfile`, Autoprotocol's `thermocycle` groups) has
//! them:
//!
//! ```text
//! "95 °C 3 min, 30 x [95 °C 15 s, 55 °C 15 s, 72 °C 30 s], 72 °C 5 min"
//! ```
//!
//! A hold is a temperature and a time (`for` between them is allowed); a cycle is a count, `x`
//! and a bracketed profile (cycles nest). Parsed into the holds in the order they run
//! ([`labware::run::Hold`]), cycles unrolled. It checks ranges against the cycler's block (4 to
//! 99 °C) and nothing about what runs the profile.

use dsl::{Dimension, parse_quantity};
use labware::run::Hold;

/// The block's range (°C) and the most holds an unrolled profile may have.
pub const BLOCK_MIN_C: f64 = 4.0;
pub const BLOCK_MAX_C: f64 = 99.0;
const MAX_HOLDS: usize = 10_000;

/// Why a profile text is not a profile; messages lowercase, quoting the text.
#[derive(Clone, Debug, PartialEq, Eq, thiserror::Error)]
pub enum ProfileError {
    #[error("the profile is empty")]
    Empty,
    #[error("`{text}` is not a hold (a temperature and a time, e.g. `95 °C 30 s`)")]
    NotAHold { text: String },
    #[error("`{text}`: {reason}")]
    Quantity { text: String, reason: String },
    #[error("`{text}` holds at {celsius} °C, outside the block's {BLOCK_MIN_C}..{BLOCK_MAX_C} °C")]
    OutOfRange { text: String, celsius: String },
    #[error("`{text}` is not a cycle count (a whole number of at least 1 before `x`)")]
    BadCount { text: String },
    #[error("unbalanced brackets in `{text}`")]
    Brackets { text: String },
    #[error("the profile unrolls to more than {MAX_HOLDS} holds")]
    TooLong,
}

/// The holds of `text`, in the order they run.
pub fn parse_profile(text: &str) -> Result<Vec<Hold>, ProfileError> {
    let holds = parse_items(text)?;
    if holds.is_empty() {
        return Err(ProfileError::Empty);
    }
    Ok(holds)
}

/// The profile as written at its top level: each hold as a group run once, each cycle as its
/// holds (inner cycles unrolled) and its count; what Autoprotocol's `thermocycle` groups are.
pub fn parse_groups(text: &str) -> Result<Vec<(usize, Vec<Hold>)>, ProfileError> {
    parse_profile(text)?;
    let mut out = Vec::new();
    for item in split_top(text)? {
        let item = item.trim();
        if item.is_empty() {
            continue;
        }
        match (item.find(['[', '(']), item.rfind([']', ')'])) {
            (Some(open), Some(close)) => {
                let holds = parse_items(&item[open + 1..close])?;
                let all = parse_items(item)?;
                out.push((all.len() / holds.len().max(1), holds));
            }
            _ => out.push((1, vec![parse_hold(item)?])),
        }
    }
    Ok(out)
}

fn parse_items(text: &str) -> Result<Vec<Hold>, ProfileError> {
    let mut out = Vec::new();
    for item in split_top(text)? {
        let item = item.trim();
        if item.is_empty() {
            continue;
        }
        if let Some(open) = item.find(['[', '(']) {
            let close = item
                .rfind([']', ')'])
                .filter(|c| *c > open && item[c + 1..].trim().is_empty())
                .ok_or_else(|| ProfileError::Brackets { text: item.into() })?;
            let head = item[..open].trim();
            let count = head
                .strip_suffix('x')
                .or_else(|| head.strip_suffix('×'))
                .or_else(|| head.strip_suffix('X'))
                .and_then(|n| n.trim().parse::<usize>().ok())
                .filter(|n| *n >= 1)
                .ok_or_else(|| ProfileError::BadCount { text: head.into() })?;
            let body = parse_items(&item[open + 1..close])?;
            if body.is_empty() {
                return Err(ProfileError::Empty);
            }
            if count.saturating_mul(body.len()).saturating_add(out.len()) > MAX_HOLDS {
                return Err(ProfileError::TooLong);
            }
            for _ in 0..count {
                out.extend_from_slice(&body);
            }
        } else {
            out.push(parse_hold(item)?);
        }
        if out.len() > MAX_HOLDS {
            return Err(ProfileError::TooLong);
        }
    }
    Ok(out)
}

/// Splits at the commas outside brackets.
fn split_top(text: &str) -> Result<Vec<&str>, ProfileError> {
    let mut depth = 0i32;
    let mut start = 0;
    let mut out = Vec::new();
    for (i, c) in text.char_indices() {
        match c {
            '[' | '(' => depth += 1,
            ']' | ')' => {
                depth -= 1;
                if depth < 0 {
                    return Err(ProfileError::Brackets { text: text.into() });
                }
            }
            ',' | ';' if depth == 0 => {
                out.push(&text[start..i]);
                start = i + c.len_utf8();
            }
            _ => {}
        }
    }
    if depth != 0 {
        return Err(ProfileError::Brackets { text: text.into() });
    }
    out.push(&text[start..]);
    Ok(out)
}

/// `95 °C 30 s` or `95 °C for 30 s`: the split between the two quantities is the first one at
/// which the left part reads as a temperature and the right as a time.
fn parse_hold(text: &str) -> Result<Hold, ProfileError> {
    let words: Vec<&str> = text
        .split_whitespace()
        .filter(|w| !w.eq_ignore_ascii_case("for"))
        .collect();
    let mut last_reason = None;
    for cut in 1..words.len() {
        let (t, d) = (words[..cut].join(" "), words[cut..].join(" "));
        match (parse_quantity(&t), parse_quantity(&d)) {
            (Ok(t), Ok(d))
                if t.dimension == Dimension::Temperature && d.dimension == Dimension::Time =>
            {
                if !(BLOCK_MIN_C..=BLOCK_MAX_C).contains(&t.si) {
                    return Err(ProfileError::OutOfRange {
                        text: text.into(),
                        celsius: t.si.to_string(),
                    });
                }
                if d.si <= 0.0 {
                    return Err(ProfileError::Quantity {
                        text: text.into(),
                        reason: "a hold lasts more than 0 s".into(),
                    });
                }
                return Ok(Hold {
                    celsius: t.si,
                    seconds: d.si,
                });
            }
            // The reason kept is from a cut where the other half reads: the half that is wrong.
            (Err(e), Ok(_)) | (Ok(_), Err(e)) => {
                last_reason.get_or_insert(e.to_string());
            }
            _ => {}
        }
    }
    Err(match last_reason {
        Some(reason) if words.len() >= 3 => ProfileError::Quantity {
            text: text.into(),
            reason,
        },
        _ => ProfileError::NotAHold { text: text.into() },
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn holds_and_cycles_interleave_and_unroll() {
        let h = parse_profile(
            "95 °C 3 min, 30 x [95 °C 15 s, 55 °C for 15 s, 72 °C 30 s], 72 °C 5 min",
        )
        .unwrap();
        assert_eq!(h.len(), 1 + 90 + 1);
        assert_eq!(h[0].seconds, 180.0);
        assert_eq!(h[2].celsius, 55.0);
        assert_eq!(h[91].seconds, 300.0);
        let nested = parse_profile("2 x [95 °C 1 s, 3 x (60 °C 1 s)]").unwrap();
        assert_eq!(nested.len(), 8);
        let groups = parse_groups(
            "95 °C 3 min, 30 x [95 °C 15 s, 55 °C 15 s], 2 x [95 °C 1 s, 3 x (60 °C 1 s)]",
        )
        .unwrap();
        let shape: Vec<(usize, usize)> = groups.iter().map(|(n, h)| (*n, h.len())).collect();
        assert_eq!(shape, vec![(1, 1), (30, 2), (2, 4)]);
    }

    #[test]
    fn mistakes_are_named() {
        assert!(matches!(parse_profile(""), Err(ProfileError::Empty)));
        assert!(matches!(
            parse_profile("95 °C"),
            Err(ProfileError::NotAHold { .. })
        ));
        assert!(matches!(
            parse_profile("120 °C 30 s"),
            Err(ProfileError::OutOfRange { .. })
        ));
        assert!(matches!(
            parse_profile("0 x [95 °C 1 s]"),
            Err(ProfileError::BadCount { .. })
        ));
        assert!(matches!(
            parse_profile("3 x [95 °C 1 s"),
            Err(ProfileError::Brackets { .. })
        ));
        let e = parse_profile("95 C 30 s").unwrap_err().to_string();
        assert!(e.contains("did you mean `°C`"), "{e}");
        assert!(matches!(
            parse_profile("100000 x [95 °C 1 s]"),
            Err(ProfileError::TooLong)
        ));
    }
}
