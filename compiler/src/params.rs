//! Episode parameters: their compiled domains, `{name}` templates, per-episode draws from a seed,
//! and the enumeration of value combinations the compiler's state proof runs over.
//!
//! Values are text (a slot name, an integer, a quantity in canonical units), substituted verbatim
//! into templates. This module does no name resolution beyond the parameters themselves.

use rand_chacha::ChaCha8Rng;
use rand_core::{RngCore, SeedableRng};
use serde::{Deserialize, Serialize};
use std::collections::{BTreeMap, HashSet};

/// Drawn values by parameter name.
pub type Bindings = BTreeMap<String, String>;

#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct ParamSpec {
    pub name: String,
    pub domain: Domain,
    /// Values never drawn (templates over earlier parameters, rendered before the draw).
    pub exclude: Vec<String>,
}

#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Domain {
    Choice {
        values: Vec<String>,
    },
    Int {
        low: i64,
        high: i64,
        step: i64,
    },
    /// Uniform real in canonical `unit`.
    Real {
        low: f64,
        high: f64,
        unit: String,
    },
    /// Slots of `holder` (already without the ones occupied at the start when `free`).
    Slot {
        holder: String,
        slots: Vec<String>,
    },
    /// The slot across the ring from `of`'s slot: not drawn.
    Opposite {
        holder: String,
        of: String,
        ring: u32,
        /// The load's tubes, evenly spaced round the ring: the slot is `ring / tubes` on from
        /// `of`'s (2: the slot across).
        #[serde(default = "two", skip_serializing_if = "is_two")]
        tubes: u32,
    },
}

/// Largest integer domain enumerated value by value; larger ones are drawn by rejection.
const ENUMERABLE: i128 = 10_000;

impl ParamSpec {
    /// How many values the proof considers for this parameter, before exclusions.
    pub(crate) fn size(&self) -> u128 {
        match &self.domain {
            Domain::Choice { values } => values.len() as u128,
            Domain::Int { low, high, step } => {
                ((*high as i128 - *low as i128) / (*step).max(1) as i128 + 1).max(0) as u128
            }
            Domain::Real { .. } => 3,
            Domain::Slot { slots, .. } => slots.len() as u128,
            Domain::Opposite { .. } => 1,
        }
    }

    /// The values the proof considers: all of a finite domain, or low, middle and high of a real one.
    fn proof_values(&self, bound: &Bindings, excluded: &Exclusions) -> Vec<String> {
        let values = match &self.domain {
            Domain::Choice { values } => values.clone(),
            Domain::Int { low, high, step } => {
                let (low, high, step) = (*low as i128, *high as i128, (*step).max(1) as i128);
                (0..ENUMERABLE)
                    .map(|k| low + k * step)
                    .take_while(|v| *v <= high)
                    .map(|v| v.to_string())
                    .collect()
            }
            Domain::Real { low, high, .. } => [*low, (low + high) / 2.0, *high]
                .iter()
                .map(|v| format_number(*v))
                .collect(),
            Domain::Slot { slots, .. } => slots.clone(),
            Domain::Opposite {
                of, ring, tubes, ..
            } => bound
                .get(of)
                .and_then(|s| spaced(s, *ring, *tubes))
                .into_iter()
                .collect(),
        };
        let rendered = excluded.rendered(bound);
        values
            .into_iter()
            .filter(|v| !excluded.fixed.contains(v) && !rendered.contains(v))
            .collect()
    }

    /// Draws this parameter's value given the earlier ones. `excluded` is [`Exclusions::of`]
    /// this parameter and `fixed`, when its exclusions name no earlier parameter, the values it
    /// can take (the same for every draw): both made once per batch of draws ([`Drawer`]).
    fn draw(
        &self,
        rng: &mut ChaCha8Rng,
        bound: &Bindings,
        excluded: &Exclusions,
        fixed: Option<&[String]>,
    ) -> Option<String> {
        if let Domain::Real { low, high, .. } = &self.domain {
            return Some(format_number(uniform(rng, *low, *high)));
        }
        if let Domain::Int { low, step, .. } = &self.domain
            && self.size() > ENUMERABLE as u128
        {
            // Too many values to list: draw, rejecting exclusions, a bounded number of times.
            let rendered = excluded.rendered(bound);
            for _ in 0..64 {
                let k = (rng.next_u64() as u128 % self.size()) as i128;
                let v = (*low as i128 + k * (*step).max(1) as i128).to_string();
                if !excluded.fixed.contains(&v) && !rendered.contains(&v) {
                    return Some(v);
                }
            }
            return None;
        }
        let owned;
        let candidates: &[String] = match fixed {
            Some(c) => c,
            None => {
                owned = self.proof_values(bound, excluded);
                &owned
            }
        };
        if let Domain::Opposite { .. } = self.domain {
            return candidates.first().cloned();
        }
        if candidates.is_empty() {
            return None;
        }
        let i = (rng.next_u64() % candidates.len() as u64) as usize;
        candidates.get(i).cloned()
    }
}

/// Slot `i` of a ring of `n` and the one across from it (`1..=n`).
pub fn opposite(slot: &str, n: u32) -> Option<String> {
    spaced(slot, n, 2)
}

/// The slot after `slot` in a load of `tubes` evenly spaced round a ring of `n` (`n / tubes` on).
pub fn spaced(slot: &str, n: u32, tubes: u32) -> Option<String> {
    let i: u32 = slot.parse().ok().filter(|i| (1..=n).contains(i))?;
    Some(((i - 1 + n / tubes.max(1)) % n + 1).to_string())
}

fn two() -> u32 {
    2
}

fn is_two(n: &u32) -> bool {
    *n == 2
}

/// Shortest text that reads back as the same f64 (integers without a fraction).
pub fn format_number(v: f64) -> String {
    if v.fract() == 0.0 && v.abs() < 1e15 {
        format!("{}", v as i64)
    } else {
        format!("{v}")
    }
}

/// Uniform draw in [lo, hi) from 53 random bits.
pub(crate) fn uniform(rng: &mut ChaCha8Rng, lo: f64, hi: f64) -> f64 {
    let u = (rng.next_u64() >> 11) as f64 * (1.0 / (1u64 << 53) as f64);
    lo + (hi - lo) * u
}

/// Draws every parameter in order. `None` when exclusions leave a parameter nothing to draw.
pub fn draw_all(params: &[ParamSpec], rng: &mut ChaCha8Rng) -> Option<Bindings> {
    Drawer::new(params).draw(rng)
}

/// Draws parameter combinations, with each parameter's exclusions split once and, where they
/// name no earlier parameter, its candidate values listed once: a batch of draws (the proof's
/// sample) costs one pass over each domain, not one per draw. Draws exactly as
/// [`ParamSpec::draw`] would one by one.
struct Drawer<'a> {
    params: &'a [ParamSpec],
    exclusions: Vec<Exclusions<'a>>,
    fixed: Vec<std::cell::OnceCell<Vec<String>>>,
}

impl<'a> Drawer<'a> {
    fn new(params: &'a [ParamSpec]) -> Self {
        Drawer {
            params,
            exclusions: params.iter().map(Exclusions::of).collect(),
            fixed: params.iter().map(|_| std::cell::OnceCell::new()).collect(),
        }
    }

    fn draw(&self, rng: &mut ChaCha8Rng) -> Option<Bindings> {
        let mut bound = Bindings::new();
        for (k, p) in self.params.iter().enumerate() {
            let excluded = &self.exclusions[k];
            // A domain whose values do not depend on earlier parameters: listed once.
            let listable = match p.domain {
                Domain::Opposite { .. } | Domain::Real { .. } => false,
                Domain::Int { .. } => p.size() <= ENUMERABLE as u128,
                _ => true,
            };
            let fixed = (excluded.templated.is_empty() && listable).then(|| {
                self.fixed[k]
                    .get_or_init(|| p.proof_values(&Bindings::new(), excluded))
                    .as_slice()
            });
            let v = p.draw(rng, &bound, excluded, fixed)?;
            bound.insert(p.name.clone(), v);
        }
        Some(bound)
    }
}

/// Most combinations the proof traces one by one; beyond this it samples [`PROOF_SAMPLE`].
pub const PROOF_LIMIT: usize = 65_536;
pub const PROOF_SAMPLE: usize = 256;

/// The parameter combinations the state proof runs over, and whether that is all of them.
/// The empty parameter list gives one empty combination.
pub fn proof_assignments(params: &[ParamSpec]) -> (Vec<Bindings>, bool) {
    let size = params
        .iter()
        .fold(1u128, |acc, p| acc.saturating_mul(p.size().max(1)));
    if size <= PROOF_LIMIT as u128 {
        let mut out = Vec::new();
        let mut complete = true;
        let exclusions: Vec<Exclusions> = params.iter().map(Exclusions::of).collect();
        enumerate(
            params,
            &exclusions,
            &mut Bindings::new(),
            &mut out,
            &mut complete,
        );
        return (out, complete);
    }
    let mut rng = ChaCha8Rng::seed_from_u64(0);
    let drawer = Drawer::new(params);
    let sample = (0..PROOF_SAMPLE)
        .filter_map(|_| drawer.draw(&mut rng))
        .collect();
    (sample, false)
}

/// A parameter's exclusions, split once into values (a set) and templates over earlier
/// parameters (rendered per combination): filtering stays linear in a domain and its exclusions
/// however many combinations of earlier values the proof walks.
struct Exclusions<'a> {
    fixed: HashSet<String>,
    templated: Vec<&'a str>,
}

impl<'a> Exclusions<'a> {
    fn of(p: &'a ParamSpec) -> Self {
        let (templated, fixed): (Vec<&String>, Vec<&String>) =
            p.exclude.iter().partition(|e| !placeholders(e).is_empty());
        Exclusions {
            fixed: fixed
                .into_iter()
                .filter_map(|e| render(e, &Bindings::new()).ok())
                .collect(),
            templated: templated.into_iter().map(String::as_str).collect(),
        }
    }

    fn rendered(&self, bound: &Bindings) -> HashSet<String> {
        self.templated
            .iter()
            .filter_map(|e| render(e, bound).ok())
            .collect()
    }
}

fn enumerate(
    params: &[ParamSpec],
    exclusions: &[Exclusions],
    bound: &mut Bindings,
    out: &mut Vec<Bindings>,
    ok: &mut bool,
) {
    if !*ok {
        return;
    }
    let Some((first, rest)) = params.split_first() else {
        out.push(bound.clone());
        if out.len() > PROOF_LIMIT {
            *ok = false;
        }
        return;
    };
    for v in first.proof_values(bound, &exclusions[0]) {
        bound.insert(first.name.clone(), v);
        enumerate(rest, &exclusions[1..], bound, out, ok);
        bound.remove(&first.name);
    }
}

/// A `{name}` in a template that names no bound parameter.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
#[error("unknown placeholder `{{{0}}}`")]
pub struct UnknownPlaceholder(pub String);

/// Substitutes `{name}` placeholders. `{{` and `}}` are literal braces.
pub fn render(template: &str, bound: &Bindings) -> Result<String, UnknownPlaceholder> {
    let mut out = String::with_capacity(template.len());
    let mut rest = template;
    while let Some(i) = rest.find(['{', '}']) {
        out.push_str(&rest[..i]);
        let tail = &rest[i..];
        if tail.starts_with("{{") || tail.starts_with("}}") {
            out.push_str(&tail[..1]);
            rest = &tail[2..];
            continue;
        }
        if let Some(after) = tail.strip_prefix('}') {
            out.push('}');
            rest = after;
            continue;
        }
        match tail[1..].find('}') {
            Some(j) => {
                let name = tail[1..1 + j].trim();
                let v = bound
                    .get(name)
                    .ok_or_else(|| UnknownPlaceholder(name.to_string()))?;
                out.push_str(v);
                rest = &tail[j + 2..];
            }
            None => {
                out.push_str(tail);
                rest = "";
            }
        }
    }
    out.push_str(rest);
    Ok(out)
}

/// Every placeholder name a template uses, with its byte offset in the template.
pub fn placeholders(template: &str) -> Vec<(usize, String)> {
    let mut out = Vec::new();
    let b = template.as_bytes();
    let mut i = 0;
    while i < b.len() {
        if b[i] == b'{' {
            if b.get(i + 1) == Some(&b'{') {
                i += 2;
                continue;
            }
            if let Some(j) = template[i + 1..].find('}') {
                out.push((i, template[i + 1..i + 1 + j].trim().to_string()));
                i += j + 2;
                continue;
            }
        }
        i += 1;
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    fn spec(name: &str, domain: Domain, exclude: &[&str]) -> ParamSpec {
        ParamSpec {
            name: name.into(),
            domain,
            exclude: exclude.iter().map(|s| s.to_string()).collect(),
        }
    }

    /// A batch of draws lists each domain once, and draws exactly what drawing one parameter at
    /// a time from scratch draws: the same values from the same seed (episodes depend on it).
    #[test]
    fn batched_draws_are_the_one_by_one_draws() {
        let ps = vec![
            spec(
                "row",
                Domain::Choice {
                    values: vec!["A".into(), "B".into(), "C".into()],
                },
                &["B"],
            ),
            spec(
                "col",
                Domain::Choice {
                    // The row letters too, so the `{row}` exclusion has something to exclude.
                    values: (0..500)
                        .map(|i| i.to_string())
                        .chain(["A", "B", "C"].map(String::from))
                        .collect(),
                },
                &["3", "7", "{row}"],
            ),
            spec(
                "n",
                Domain::Int {
                    low: 0,
                    high: 40,
                    step: 2,
                },
                &["4"],
            ),
            spec(
                "far",
                Domain::Real {
                    low: 0.0,
                    high: 1.0,
                    unit: "m".into(),
                },
                &[],
            ),
        ];
        let one_by_one = |rng: &mut ChaCha8Rng| {
            let mut bound = Bindings::new();
            for p in &ps {
                let v = p.draw(rng, &bound, &Exclusions::of(p), None)?;
                bound.insert(p.name.clone(), v);
            }
            Some(bound)
        };
        let (mut a, mut b) = (ChaCha8Rng::seed_from_u64(7), ChaCha8Rng::seed_from_u64(7));
        let drawer = Drawer::new(&ps);
        let mut first = Vec::new();
        let mut letters = 0;
        for _ in 0..2000 {
            let (x, y) = (drawer.draw(&mut a), one_by_one(&mut b));
            assert_eq!(x, y);
            let x = x.unwrap();
            assert_ne!(x["row"], "B");
            assert!(!["3", "7"].contains(&x["col"].as_str()));
            assert_ne!(x["col"], x["row"], "the {{row}} exclusion");
            letters += usize::from(x["col"].parse::<u32>().is_err());
            assert_ne!(x["n"], "4");
            let far: f64 = x["far"].parse().unwrap();
            assert!((0.0..1.0).contains(&far), "far {far}");
            if first.len() < 3 {
                first.push([x["row"].clone(), x["col"].clone(), x["n"].clone()]);
            }
        }
        // A letter column was drawn (the exclusion had work), and the first draws are pinned:
        // a change to the generator or the draw order fails here, not only in the goldens.
        assert!(letters > 0);
        let pinned = [["C", "496", "12"], ["A", "240", "24"], ["C", "277", "34"]];
        assert_eq!(first, pinned.map(|d| d.map(String::from)));
    }

    #[test]
    fn renders_templates() {
        let b: Bindings = [("row".to_string(), "B".to_string())].into();
        assert_eq!(render("rack.{row}3", &b).unwrap(), "rack.B3");
        assert_eq!(render("{{literal}}", &b).unwrap(), "{literal}");
        assert_eq!(
            render("{col}", &b),
            Err(UnknownPlaceholder("col".to_string()))
        );
        assert_eq!(placeholders("a {x} b {{y}} {z}").len(), 2);
    }

    #[test]
    fn exclusions_and_opposites() {
        let ps = vec![
            spec(
                "first",
                Domain::Choice {
                    values: vec!["1".into(), "2".into()],
                },
                &[],
            ),
            spec(
                "second",
                Domain::Opposite {
                    holder: "rotor".into(),
                    of: "first".into(),
                    ring: 30,
                    tubes: 2,
                },
                &[],
            ),
            spec(
                "temp",
                Domain::Int {
                    low: 24,
                    high: 26,
                    step: 1,
                },
                &["25"],
            ),
        ];
        let (all, complete) = proof_assignments(&ps);
        assert!(complete);
        assert_eq!(all.len(), 4);
        assert!(all.iter().all(|b| b["temp"] != "25"));
        // Written out, not recomputed: slot k's opposite on a 30-slot ring is k + 15.
        let got: std::collections::BTreeSet<[&str; 3]> = all
            .iter()
            .map(|b| [&*b["first"], &*b["second"], &*b["temp"]])
            .collect();
        let want: std::collections::BTreeSet<[&str; 3]> = [
            ["1", "16", "24"],
            ["1", "16", "26"],
            ["2", "17", "24"],
            ["2", "17", "26"],
        ]
        .into();
        assert_eq!(got, want);
        assert_eq!(opposite("15", 30).as_deref(), Some("30"));
        assert_eq!(opposite("30", 30).as_deref(), Some("15"));
        assert_eq!(opposite("3", 6).as_deref(), Some("6"));
        assert_eq!(opposite("0", 30), None);
        assert_eq!(opposite("31", 30), None);
        assert_eq!(opposite("x", 30), None);
        let mut rng = ChaCha8Rng::seed_from_u64(3);
        for _ in 0..50 {
            let b = draw_all(&ps, &mut rng).unwrap();
            assert_ne!(b["temp"], "25");
            let pair = (b["first"].as_str(), b["second"].as_str());
            assert!(pair == ("1", "16") || pair == ("2", "17"), "{pair:?}");
        }
    }

    #[test]
    fn large_spaces_are_sampled() {
        let ps: Vec<ParamSpec> = (0..5)
            .map(|i| {
                spec(
                    &format!("p{i}"),
                    Domain::Int {
                        low: 0,
                        high: 20,
                        step: 1,
                    },
                    &[],
                )
            })
            .collect();
        let (sample, complete) = proof_assignments(&ps);
        assert!(!complete);
        assert_eq!(sample.len(), PROOF_SAMPLE);
    }
}

#[cfg(test)]
mod huge {
    use super::*;

    #[test]
    fn huge_integer_domains_are_drawn_not_listed() {
        let p = ParamSpec {
            name: "n".into(),
            domain: Domain::Int {
                low: i64::MIN,
                high: i64::MAX,
                step: 1,
            },
            exclude: vec!["0".into()],
        };
        let (sample, complete) = proof_assignments(std::slice::from_ref(&p));
        assert!(!complete);
        assert_eq!(sample.len(), PROOF_SAMPLE);
    }
}
