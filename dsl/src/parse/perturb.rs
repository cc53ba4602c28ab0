//! The `[perturb]` table's syntax: which dimensions there are, the fields each takes, and their
//! units (`shift_m`, `turn_deg`, `joints_rad`). A dimension is a preset strength (`light = 2`)
//! or a table of fields. Ranges, camera and parameter names are the compiler's to check.

use super::{Parser, Value, ordered, span_of, split_unit, type_name};
use crate::Code;
use crate::ast::{Perturb, PerturbDimension, PerturbField, PerturbSetting, PerturbValue, Spanned};
use crate::quantity::Dimension;
use toml::de::DeValue;

/// What a field's value is.
#[derive(Clone, Copy)]
enum Shape {
    /// A number; in a unit of this dimension when `Some` (from the key's suffix or a string).
    Number(Option<Dimension>),
    /// `[low, high]`, plain numbers.
    Range,
    /// An array of strings.
    Texts,
}

/// The dimensions and their fields, in the order docs/robustness.md lists them.
const DIMENSIONS: &[(&str, &[(&str, Shape)])] = &[
    (
        "light",
        &[
            ("intensity", Shape::Range),
            ("direction", Shape::Number(Some(Dimension::Angle))),
            ("colour", Shape::Number(None)),
            ("lights", Shape::Range),
        ],
    ),
    (
        "material",
        &[
            ("of", Shape::Texts),
            ("hue", Shape::Number(None)),
            ("saturation", Shape::Number(None)),
            ("value", Shape::Number(None)),
        ],
    ),
    (
        "camera",
        &[
            ("shift", Shape::Number(Some(Dimension::Length))),
            ("turn", Shape::Number(Some(Dimension::Angle))),
            ("fovy", Shape::Number(Some(Dimension::Angle))),
            ("cameras", Shape::Texts),
        ],
    ),
    (
        "noise",
        &[
            ("gaussian", Shape::Number(None)),
            ("blur_px", Shape::Number(None)),
            ("jpeg_quality", Shape::Range),
        ],
    ),
    ("language", &[("rewrite", Shape::Number(None))]),
    (
        "robot_start",
        &[("joints", Shape::Number(Some(Dimension::Angle)))],
    ),
    (
        "layout",
        &[
            ("shift", Shape::Number(Some(Dimension::Length))),
            ("turn", Shape::Number(Some(Dimension::Angle))),
        ],
    ),
    (
        "distractors",
        &[("count", Shape::Range), ("kinds", Shape::Texts)],
    ),
];

/// The `[perturb]` table's dimensions, in their documented order.
pub fn dimension_names() -> impl Iterator<Item = &'static str> {
    DIMENSIONS.iter().map(|(n, _)| *n)
}

impl Parser {
    pub(super) fn perturb(&mut self, v: &Value<'_>) -> Option<Perturb> {
        let t = self.table(v, "`[perturb]`")?;
        let names: Vec<&str> = DIMENSIONS.iter().map(|(n, _)| *n).collect();
        let mut dimensions = Vec::new();
        for (key, value) in ordered(t) {
            let name = key.get_ref().as_ref();
            let Some((_, fields)) = DIMENSIONS.iter().find(|(n, _)| *n == name) else {
                self.unknown_key(key, &names, "`[perturb]`");
                continue;
            };
            let setting = match value.get_ref() {
                DeValue::Integer(_) => self
                    .integer(value, &format!("perturb.{name}"))
                    .map(PerturbSetting::Strength),
                DeValue::Table(ft) => Some(PerturbSetting::Fields(
                    self.perturb_fields(name, fields, ft),
                )),
                other => {
                    self.err(
                        Code::E0004,
                        span_of(value),
                        format!(
                            "`perturb.{name}` must be a strength (1 or 2) or a table, found {}",
                            type_name(other)
                        ),
                        Some(format!("e.g. `{name} = 1`, the dimension's mild preset")),
                    );
                    None
                }
            };
            if let Some(setting) = setting {
                dimensions.push(PerturbDimension {
                    name: Spanned::new(name.to_string(), span_of(key)),
                    setting,
                });
            }
        }
        Some(Perturb {
            dimensions,
            span: span_of(v),
        })
    }

    fn perturb_fields(
        &mut self,
        dimension: &str,
        fields: &[(&str, Shape)],
        t: &toml::de::DeTable<'_>,
    ) -> Vec<PerturbField> {
        let allowed: Vec<&str> = fields.iter().map(|(n, _)| *n).collect();
        let mut out = Vec::new();
        for (key, value) in self.settings(t) {
            let k = key.get_ref().as_ref();
            // A plain key may itself contain `_` (`blur_px`): look it up whole first; a unit
            // suffix is read only on a field that takes a unit.
            let (base, shape) = match fields.iter().find(|(n, _)| *n == k) {
                Some((n, s)) => (*n, *s),
                None => match fields.iter().find(|(n, _)| *n == split_unit(k).0) {
                    Some((n, s @ Shape::Number(Some(_)))) => (*n, *s),
                    Some((n, _)) => {
                        self.err(
                            Code::E0020,
                            span_of(key),
                            format!("`{n}` in `perturb.{dimension}` takes no unit"),
                            Some(format!("write `{n} = ...`")),
                        );
                        continue;
                    }
                    None => {
                        self.unknown_key(key, &allowed, &format!("`perturb.{dimension}`"));
                        continue;
                    }
                },
            };
            let what = format!("perturb.{dimension}.{k}");
            let parsed = match shape {
                Shape::Number(Some(dim)) => self
                    .quantity(k, value, dim)
                    .map(|q| Spanned::new(PerturbValue::Number(q.value), q.span)),
                Shape::Number(None) => self
                    .number(value, &what)
                    .map(|x| Spanned::new(PerturbValue::Number(x), span_of(value))),
                Shape::Range => self.perturb_range(value, &what),
                Shape::Texts => self
                    .texts(value, &what)
                    .map(|t| Spanned::new(PerturbValue::Texts(t), span_of(value))),
            };
            if let Some(value) = parsed {
                out.push(PerturbField {
                    key: Spanned::new(base.to_string(), span_of(key)),
                    value,
                });
            }
        }
        out
    }

    fn perturb_range(&mut self, v: &Value<'_>, what: &str) -> Option<Spanned<PerturbValue>> {
        let DeValue::Array(items) = v.get_ref() else {
            self.err(
                Code::E0004,
                span_of(v),
                format!(
                    "`{what}` must be `[low, high]`, found {}",
                    type_name(v.get_ref())
                ),
                None,
            );
            return None;
        };
        let mut xs = Vec::new();
        for item in items.iter() {
            xs.push(self.number(item, what)?);
        }
        let [low, high] = xs[..] else {
            self.err(
                Code::E0004,
                span_of(v),
                format!("`{what}` must be `[low, high]`, found {} values", xs.len()),
                None,
            );
            return None;
        };
        if low > high {
            self.err(
                Code::E0021,
                span_of(v),
                format!("`{what}` runs from {low} down to {high}"),
                Some("write the range as `[low, high]`".into()),
            );
            return None;
        }
        Some(Spanned::new(PerturbValue::Range([low, high]), span_of(v)))
    }

    /// A non-empty array of non-blank strings.
    pub(super) fn texts(&mut self, v: &Value<'_>, what: &str) -> Option<Vec<Spanned<String>>> {
        let DeValue::Array(items) = v.get_ref() else {
            self.err(
                Code::E0004,
                span_of(v),
                format!(
                    "`{what}` must be an array of strings, found {}",
                    type_name(v.get_ref())
                ),
                None,
            );
            return None;
        };
        let mut texts = Vec::new();
        for item in items.iter() {
            let text = self.string(item, what)?;
            if text.value.trim().is_empty() {
                self.err(
                    Code::E0021,
                    text.span,
                    format!("`{what}` holds a blank string"),
                    None,
                );
                return None;
            }
            texts.push(text);
        }
        if texts.is_empty() {
            self.err(
                Code::E0021,
                span_of(v),
                format!("`{what}` is empty"),
                Some("leave it out, or list at least one".into()),
            );
            return None;
        }
        Some(texts)
    }
}
