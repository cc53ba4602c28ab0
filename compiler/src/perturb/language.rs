//! Deterministic rewording of an instruction template (placeholders `{name}` untouched, filled
//! after): one of the task's paraphrases, a framing around the instruction, and, at strength 2,
//! verbs and nouns swapped for synonyms a lab would use. No language model; the same draw gives
//! the same words.

use crate::params::uniform;
use rand_chacha::ChaCha8Rng;

/// Framings: `{}` is the instruction with its first letter lowered and its final full stop
/// dropped.
const FRAMINGS: &[&str] = &[
    "Please {}.",
    "Your task: {}.",
    "Next step: {}.",
    "I need you to {}.",
    "Robot, {}.",
    "Go ahead and {}.",
];

/// Words and phrases with a synonym (lowercase; the first letter's case is kept).
const SYNONYMS: &[(&str, &str)] = &[
    ("pick up", "lift"),
    ("place", "set"),
    ("put", "set"),
    ("insert", "put"),
    ("transfer", "move"),
    ("close", "shut"),
    ("unscrew", "twist off"),
    ("screw", "twist"),
    ("press", "push"),
    ("aspirate", "draw up"),
    ("dispense", "expel"),
    ("tube", "vial"),
    ("rack", "stand"),
    ("lid", "cover"),
    ("cap", "top"),
    ("bench", "table"),
    ("mixer", "shaker"),
    ("thermal cycler", "PCR machine"),
    ("set", "adjust"),
    ("rotor", "rotor head"),
];

/// `template` reworded at `rewrite` (1: a paraphrase, or a framing where there are none; 2: a
/// paraphrase or the instruction, framed, with synonyms), and how.
pub(super) fn reword(
    template: &str,
    paraphrases: &[String],
    rewrite: u8,
    rng: &mut ChaCha8Rng,
) -> (String, String) {
    let pick = |rng: &mut ChaCha8Rng, n: usize| (uniform(rng, 0.0, n as f64) as usize).min(n - 1);
    let mut how = Vec::new();
    let mut text = template.to_string();
    if !paraphrases.is_empty() {
        // At 2 the instruction itself is one of the choices: the framing and synonyms change it.
        let n = paraphrases.len() + usize::from(rewrite >= 2);
        let k = pick(rng, n);
        if let Some(p) = paraphrases.get(k) {
            text = p.clone();
            how.push(format!("paraphrase {}", k + 1));
        }
    }
    if paraphrases.is_empty() || rewrite >= 2 {
        let k = pick(rng, FRAMINGS.len());
        text = frame(FRAMINGS[k], &text);
        how.push(format!("framing {}", k + 1));
    }
    if rewrite >= 2 {
        let (swapped, n) = synonyms(&text, rng);
        if n > 0 {
            text = swapped;
            how.push(format!("{n} synonyms"));
        }
    }
    (text, how.join(", "))
}

fn frame(framing: &str, text: &str) -> String {
    let core = text.trim().trim_end_matches('.');
    let mut c = core.chars();
    let lowered = match c.next() {
        // An acronym or a placeholder keeps its case.
        Some(f) if !c.clone().next().is_some_and(char::is_uppercase) => {
            f.to_lowercase().collect::<String>() + c.as_str()
        }
        _ => core.to_string(),
    };
    framing.replace("{}", &lowered)
}

/// Each word or phrase with a synonym, outside placeholders, swapped with even odds; how many.
fn synonyms(text: &str, rng: &mut ChaCha8Rng) -> (String, usize) {
    let mut out = String::with_capacity(text.len());
    let mut n = 0;
    let mut rest = text;
    let mut depth = 0usize;
    let mut prev_word = false;
    while let Some(c) = rest.chars().next() {
        match c {
            '{' => depth += 1,
            '}' => depth = depth.saturating_sub(1),
            _ => {}
        }
        let word_start = !prev_word && c.is_alphabetic() && depth == 0;
        if word_start
            && let Some((from, to)) = SYNONYMS.iter().find(|(from, _)| starts_word(rest, from))
        {
            if uniform(rng, 0.0, 1.0) < 0.5 {
                let upper = rest.starts_with(|x: char| x.is_uppercase());
                out.push_str(&if upper {
                    capitalised(to)
                } else {
                    to.to_string()
                });
                n += 1;
            } else {
                out.push_str(&rest[..from.len()]);
            }
            rest = &rest[from.len()..];
            prev_word = true;
            continue;
        }
        out.push(c);
        prev_word = c.is_alphanumeric() || c == '_';
        rest = &rest[c.len_utf8()..];
    }
    (out, n)
}

/// Whether `text` starts with the word or phrase `w` (any case), followed by no letter.
fn starts_word(text: &str, w: &str) -> bool {
    text.get(..w.len())
        .is_some_and(|h| h.eq_ignore_ascii_case(w))
        && !text[w.len()..].starts_with(|c: char| c.is_alphanumeric() || c == '_')
}

fn capitalised(s: &str) -> String {
    let mut c = s.chars();
    c.next()
        .map(|f| f.to_uppercase().collect::<String>() + c.as_str())
        .unwrap_or_default()
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand_core::SeedableRng;

    #[test]
    fn rewording_keeps_placeholders_and_is_deterministic() {
        let t = "Pick up the tube from slot {slot} and place it in the rack.";
        let mut seen = std::collections::BTreeSet::new();
        for seed in 0..40 {
            let a = reword(t, &[], 2, &mut ChaCha8Rng::seed_from_u64(seed));
            let b = reword(t, &[], 2, &mut ChaCha8Rng::seed_from_u64(seed));
            assert_eq!(a, b);
            assert!(a.0.contains("{slot}"), "{}", a.0);
            assert_ne!(a.0, t);
            seen.insert(a.0);
        }
        assert!(seen.len() > 10, "{seen:?}");
        // Strength 1 with paraphrases draws one of them, unframed.
        let ps = vec![
            "Move the tube at {slot}.".to_string(),
            "Take {slot}.".into(),
        ];
        for seed in 0..10 {
            let (text, how) = reword(t, &ps, 1, &mut ChaCha8Rng::seed_from_u64(seed));
            assert!(
                ps.contains(&text) && how.starts_with("paraphrase"),
                "{text}"
            );
        }
        // A word inside a longer word or a placeholder is not a synonym's.
        let (s, _) = synonyms("Tubes {tube} tube_a", &mut ChaCha8Rng::seed_from_u64(0));
        assert_eq!(s, "Tubes {tube} tube_a");
    }
}
