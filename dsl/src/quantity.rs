//! Physical quantities with units: "30 s", "5 deg", "10 mm", "-1.2 rad". Values are converted to
//! SI (m, rad, s) at parse time; the unit's dimension is checked by the caller.

use serde::Serialize;

#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
#[serde(rename_all = "lowercase")]
pub enum Dimension {
    Length,
    Angle,
    Time,
}

impl Dimension {
    pub fn name(self) -> &'static str {
        match self {
            Dimension::Length => "length",
            Dimension::Angle => "angle",
            Dimension::Time => "time",
        }
    }

    pub fn example_units(self) -> &'static str {
        match self {
            Dimension::Length => "m, mm, cm",
            Dimension::Angle => "rad, deg",
            Dimension::Time => "s, ms, min",
        }
    }
}

/// A value in SI units with its dimension.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct Quantity {
    pub si: f64,
    pub dimension: Dimension,
}

const UNITS: &[(&str, Dimension, f64)] = &[
    ("m", Dimension::Length, 1.0),
    ("cm", Dimension::Length, 0.01),
    ("mm", Dimension::Length, 0.001),
    ("rad", Dimension::Angle, 1.0),
    ("deg", Dimension::Angle, std::f64::consts::PI / 180.0),
    ("°", Dimension::Angle, std::f64::consts::PI / 180.0),
    ("s", Dimension::Time, 1.0),
    ("ms", Dimension::Time, 0.001),
    ("min", Dimension::Time, 60.0),
];

/// Looks up a unit symbol (also used for unit-suffixed keys such as `yaw_deg`).
pub fn unit(symbol: &str) -> Option<(Dimension, f64)> {
    UNITS
        .iter()
        .find(|(s, _, _)| *s == symbol)
        .map(|(_, d, f)| (*d, *f))
}

/// Parses "<number> <unit>" (the space is optional). Errors are lowercase messages.
pub fn parse_quantity(text: &str) -> Result<Quantity, String> {
    let t = text.trim();
    let split = t
        .char_indices()
        .find(|(_, c)| !(c.is_ascii_digit() || matches!(c, '.' | '-' | '+' | 'e' | 'E' | '_')))
        .map(|(i, _)| i)
        .unwrap_or(t.len());
    // An exponent 'e' followed by a letter is the start of a unit, not an exponent; keep it simple:
    let (num, sym) = t.split_at(split);
    let num = num.trim().replace('_', "");
    let sym = sym.trim();
    let value: f64 = num
        .parse()
        .map_err(|_| format!("`{text}` does not start with a number"))?;
    if !value.is_finite() {
        return Err(format!("`{text}` is not a finite number"));
    }
    if sym.is_empty() {
        return Err(format!("`{text}` has no unit"));
    }
    let (dimension, factor) =
        unit(sym).ok_or_else(|| format!("unknown unit `{sym}` in `{text}`"))?;
    Ok(Quantity {
        si: value * factor,
        dimension,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn parses_units_to_si() {
        assert_eq!(parse_quantity("30 s").unwrap().si, 30.0);
        assert!((parse_quantity("90deg").unwrap().si - std::f64::consts::FRAC_PI_2).abs() < 1e-12);
        assert_eq!(parse_quantity("-10 mm").unwrap().si, -0.01);
        assert_eq!(
            parse_quantity("1.5 min").unwrap().dimension,
            Dimension::Time
        );
    }

    #[test]
    fn rejects_bad_quantities() {
        assert!(parse_quantity("30").unwrap_err().contains("no unit"));
        assert!(
            parse_quantity("30 kg")
                .unwrap_err()
                .contains("unknown unit `kg`")
        );
        assert!(
            parse_quantity("fast")
                .unwrap_err()
                .contains("does not start with a number")
        );
    }
}
