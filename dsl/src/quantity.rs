//! Physical quantities with units: "30 s", "5 deg", "10 mm", "200 µL", "37 °C", "1200 rpm".
//! Values are converted to each dimension's canonical unit at parse time (m, rad, s, µL, °C, rpm:
//! SI where lab practice agrees, the lab's own unit where it does not); the caller checks the
//! dimension.

use serde::Serialize;

#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
#[serde(rename_all = "lowercase")]
pub enum Dimension {
    Length,
    Angle,
    Time,
    Volume,
    Temperature,
    Speed,
    /// A centrifuge's relative centrifugal force, in multiples of g (`× g`).
    Acceleration,
}

impl Dimension {
    pub fn name(self) -> &'static str {
        match self {
            Dimension::Length => "length",
            // "plane angle" reads right after "a", as every other name does.
            Dimension::Angle => "plane angle",
            Dimension::Time => "time",
            Dimension::Volume => "volume",
            Dimension::Temperature => "temperature",
            Dimension::Speed => "rotational speed",
            Dimension::Acceleration => "relative centrifugal force",
        }
    }

    pub fn example_units(self) -> &'static str {
        match self {
            Dimension::Length => "m, mm, cm",
            Dimension::Angle => "rad, deg",
            Dimension::Time => "s, ms, min, h",
            Dimension::Volume => "µL, uL, mL, L",
            Dimension::Temperature => "°C, degC",
            Dimension::Speed => "rpm",
            Dimension::Acceleration => "x g, × g",
        }
    }

    /// The canonical unit values of this dimension are stored in.
    pub fn canonical_unit(self) -> &'static str {
        match self {
            Dimension::Length => "m",
            Dimension::Angle => "rad",
            Dimension::Time => "s",
            Dimension::Volume => "µL",
            Dimension::Temperature => "°C",
            Dimension::Speed => "rpm",
            Dimension::Acceleration => "× g",
        }
    }
}

/// A value in its dimension's canonical unit.
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
    ("h", Dimension::Time, 3600.0),
    ("µL", Dimension::Volume, 1.0),
    // The Greek mu, which looks the same; the parser warns about it (W0006).
    ("\u{3bc}L", Dimension::Volume, 1.0),
    ("uL", Dimension::Volume, 1.0),
    ("ul", Dimension::Volume, 1.0),
    ("mL", Dimension::Volume, 1000.0),
    ("ml", Dimension::Volume, 1000.0),
    ("L", Dimension::Volume, 1e6),
    ("°C", Dimension::Temperature, 1.0),
    ("degC", Dimension::Temperature, 1.0),
    ("degc", Dimension::Temperature, 1.0),
    ("rpm", Dimension::Speed, 1.0),
    ("× g", Dimension::Acceleration, 1.0),
    ("×g", Dimension::Acceleration, 1.0),
    ("x g", Dimension::Acceleration, 1.0),
    ("xg", Dimension::Acceleration, 1.0),
];

/// Looks up a unit symbol (also used for unit-suffixed keys such as `yaw_deg`).
pub(crate) fn unit(symbol: &str) -> Option<(Dimension, f64)> {
    UNITS
        .iter()
        .find(|(s, _, _)| *s == symbol)
        .map(|(_, d, f)| (*d, *f))
}

/// The unit a symbol that is not one most likely means: lab spellings (`C`, `deg C`, `RPM`,
/// `sec`, `secs`, `mins`, `seconds`), other case (`ML`), else the closest symbol by spelling.
pub(crate) fn suggest_unit(symbol: &str) -> Option<&'static str> {
    let folded: String = symbol
        .chars()
        .filter(|c| !c.is_whitespace() && *c != '.')
        .collect::<String>()
        .to_lowercase();
    let spelled = match folded.as_str() {
        "c" | "degc" | "degreesc" | "degreec" | "celsius" | "ºc" | "°c" => Some("°C"),
        "rpm" | "rpms" | "r/min" => Some("rpm"),
        "g" | "*g" | "rcf" | "xgravity" => Some("x g"),
        "sec" | "secs" | "second" | "seconds" => Some("s"),
        "mins" | "minute" | "minutes" => Some("min"),
        "hr" | "hrs" | "hour" | "hours" => Some("h"),
        "msec" | "msecs" | "millisecond" | "milliseconds" => Some("ms"),
        "degree" | "degrees" => Some("deg"),
        "microliter" | "microliters" | "microlitre" | "microlitres" => Some("µL"),
        "milliliter" | "milliliters" | "millilitre" | "millilitres" => Some("mL"),
        _ => None,
    };
    spelled
        .or_else(|| {
            UNITS
                .iter()
                .map(|(s, _, _)| *s)
                .find(|s| s.to_lowercase() == folded)
        })
        // By spelling, but never to a force: `kg` is one letter from `xg` and means nothing like it.
        .or_else(|| {
            let spelled = UNITS
                .iter()
                .filter(|(_, d, _)| *d != Dimension::Acceleration)
                .map(|(s, _, _)| *s);
            crate::did_you_mean(symbol, spelled)
        })
}

/// Why a text is not a quantity. Its messages are lowercase and quote the text.
#[derive(Clone, Debug, PartialEq, Eq, thiserror::Error)]
pub enum ParseQuantityError {
    #[error("`{text}` does not start with a number")]
    NoNumber { text: String },
    #[error("`{text}` is not a finite number")]
    NotFinite { text: String },
    #[error("`{text}` has no unit")]
    NoUnit { text: String },
    /// A unit symbol no dimension knows; the message names the known one it most likely means.
    #[error("unknown unit `{unit}` in `{text}`{}", suggestion_note(.unit))]
    UnknownUnit { unit: String, text: String },
}

fn suggestion_note(unit: &str) -> String {
    suggest_unit(unit)
        .map(|u| format!("; did you mean `{u}`?"))
        .unwrap_or_default()
}

/// Parses "<number> <unit>" (the space is optional).
pub fn parse_quantity(text: &str) -> Result<Quantity, ParseQuantityError> {
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
    let text = || text.to_string();
    let value: f64 = num
        .parse()
        .map_err(|_| ParseQuantityError::NoNumber { text: text() })?;
    if !value.is_finite() {
        return Err(ParseQuantityError::NotFinite { text: text() });
    }
    if sym.is_empty() {
        return Err(ParseQuantityError::NoUnit { text: text() });
    }
    let (dimension, factor) = unit(sym).ok_or_else(|| ParseQuantityError::UnknownUnit {
        unit: sym.to_string(),
        text: text(),
    })?;
    Ok(Quantity {
        si: value * factor,
        dimension,
    })
}

#[cfg(test)]
mod tests {
    #[test]
    fn a_misspelt_unit_gets_the_one_it_means() {
        for (typed, meant) in [
            ("C", "°C"),
            ("deg C", "°C"),
            ("RPM", "rpm"),
            ("sec", "s"),
            ("secs", "s"),
            ("mins", "min"),
            ("ML", "mL"),
            ("Mm", "mm"),
            ("g", "x g"),
            ("rcf", "x g"),
        ] {
            assert_eq!(super::suggest_unit(typed), Some(meant), "{typed}");
            let e = super::parse_quantity(&format!("37 {typed}"))
                .unwrap_err()
                .to_string();
            assert!(e.ends_with(&format!("did you mean `{meant}`?")), "{e}");
        }
        assert_eq!(super::suggest_unit("parsecs"), None);
    }

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
        assert_eq!(parse_quantity("1.5 mL").unwrap().si, 1500.0);
        assert_eq!(parse_quantity("200 µL").unwrap().si, 200.0);
        assert_eq!(
            parse_quantity("37 °C").unwrap().dimension,
            Dimension::Temperature
        );
        assert_eq!(parse_quantity("1200 rpm").unwrap().si, 1200.0);
    }

    #[test]
    fn rejects_bad_quantities() {
        let e = |text: &str| parse_quantity(text).unwrap_err().to_string();
        assert_eq!(e("30"), "`30` has no unit");
        assert_eq!(e("30 kg"), "unknown unit `kg` in `30 kg`");
        assert_eq!(e("fast"), "`fast` does not start with a number");
        assert_eq!(e("1e999 s"), "`1e999 s` is not a finite number");
        assert_eq!(
            e(" 37 C"),
            "unknown unit `C` in ` 37 C`; did you mean `°C`?"
        );
    }
}
