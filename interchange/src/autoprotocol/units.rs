//! Autoprotocol's quantities: `"<magnitude>:<unit>"` (`"25:microliter"`, `"-10.5:microliters"`,
//! `"1000:g"`), read into our units (µL, s, °C, g, rpm) and written back. Unit names are the
//! specification's (`Definitions/units.md`) in singular or plural, with the short forms
//! autoprotocol-python also accepts (`ul`, `µL`, `s`, `min`, `h`); anything else is an error that
//! says which units the field takes.

use std::fmt;

/// What a quantity measures.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Dimension {
    Volume,
    Time,
    Temperature,
    Acceleration,
    Speed,
}

impl Dimension {
    fn units(self) -> &'static [(&'static str, f64)] {
        match self {
            Dimension::Volume => &[
                ("nanoliter", 1e-3),
                ("microliter", 1.0),
                ("milliliter", 1e3),
                ("liter", 1e6),
                ("nl", 1e-3),
                ("ul", 1.0),
                ("µl", 1.0),
                ("μl", 1.0),
                ("ml", 1e3),
                ("l", 1e6),
            ],
            Dimension::Time => &[
                ("millisecond", 1e-3),
                ("second", 1.0),
                ("minute", 60.0),
                ("hour", 3600.0),
                ("day", 86_400.0),
                ("ms", 1e-3),
                ("s", 1.0),
                ("sec", 1.0),
                ("min", 60.0),
                ("h", 3600.0),
                ("hr", 3600.0),
            ],
            Dimension::Temperature => &[("celsius", 1.0), ("degc", 1.0), ("°c", 1.0)],
            Dimension::Acceleration => &[("g", 1.0), ("meter/second^2", 1.0 / 9.806_65)],
            Dimension::Speed => &[("rpm", 1.0), ("hertz", 60.0), ("hz", 60.0)],
        }
    }

    /// The unit written on export.
    pub fn canonical(self) -> &'static str {
        match self {
            Dimension::Volume => "microliter",
            Dimension::Time => "second",
            Dimension::Temperature => "celsius",
            Dimension::Acceleration => "g",
            Dimension::Speed => "rpm",
        }
    }

    /// The unit names the specification gives, for messages.
    fn names(self) -> &'static str {
        match self {
            Dimension::Volume => "nanoliter, microliter, milliliter, liter",
            Dimension::Time => "millisecond, second, minute, hour, day",
            Dimension::Temperature => "celsius",
            Dimension::Acceleration => "g, meter/second^2",
            Dimension::Speed => "rpm, hertz",
        }
    }

    fn noun(self) -> &'static str {
        match self {
            Dimension::Volume => "a volume",
            Dimension::Time => "a time",
            Dimension::Temperature => "a temperature",
            Dimension::Acceleration => "an acceleration",
            Dimension::Speed => "a speed",
        }
    }
}

/// Why a quantity does not read.
#[derive(Clone, Debug, PartialEq)]
pub enum UnitError {
    /// No `magnitude:unit` shape, or a magnitude that is not a finite number.
    Shape(String),
    /// A unit this field does not take.
    Unit {
        text: String,
        unit: String,
        wanted: Dimension,
    },
}

impl fmt::Display for UnitError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            UnitError::Shape(text) => write!(
                f,
                "`{text}` is no quantity: Autoprotocol writes one as `<number>:<unit>`"
            ),
            UnitError::Unit { text, unit, wanted } => {
                write!(
                    f,
                    "`{text}`: `{unit}` is not {} unit (it takes {})",
                    wanted.noun(),
                    wanted.names()
                )
            }
        }
    }
}

/// Reads `text` as a quantity of `dim`, in our unit of it (µL, s, °C, g, rpm).
pub fn read(text: &str, dim: Dimension) -> Result<f64, UnitError> {
    let Some((magnitude, unit)) = text.split_once(':') else {
        return Err(UnitError::Shape(text.to_string()));
    };
    let value: f64 = magnitude
        .trim()
        .parse()
        .ok()
        .filter(|v: &f64| v.is_finite())
        .ok_or_else(|| UnitError::Shape(text.to_string()))?;
    let unit_lower = unit.trim().to_lowercase();
    let singular = unit_lower
        .strip_suffix('s')
        .filter(|u| u.len() > 2)
        .unwrap_or(&unit_lower);
    dim.units()
        .iter()
        .find(|(name, _)| *name == unit_lower || *name == singular)
        .map(|(_, factor)| value * factor)
        .ok_or_else(|| UnitError::Unit {
            text: text.to_string(),
            unit: unit.trim().to_string(),
            wanted: dim,
        })
}

/// Writes a quantity in our unit of `dim` as Autoprotocol text.
pub fn write(value: f64, dim: Dimension) -> String {
    format!("{}:{}", crate::draft::number(value), dim.canonical())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn quantities_read_in_our_units_and_refuse_the_wrong_dimension() {
        assert_eq!(read("25:microliter", Dimension::Volume), Ok(25.0));
        assert_eq!(read("-10.5:microliters", Dimension::Volume), Ok(-10.5));
        assert_eq!(read("1:milliliter", Dimension::Volume), Ok(1000.0));
        assert_eq!(read("2:minute", Dimension::Time), Ok(120.0));
        assert_eq!(read("1.5:hours", Dimension::Time), Ok(5400.0));
        assert_eq!(read("95:celsius", Dimension::Temperature), Ok(95.0));
        assert_eq!(read("1000:g", Dimension::Acceleration), Ok(1000.0));
        assert_eq!(read("600:rpm", Dimension::Speed), Ok(600.0));
        assert!(matches!(
            read("25:second", Dimension::Volume),
            Err(UnitError::Unit { .. })
        ));
        assert!(matches!(
            read("25 microliter", Dimension::Volume),
            Err(UnitError::Shape(_))
        ));
        assert!(matches!(
            read("nan:s", Dimension::Time),
            Err(UnitError::Shape(_))
        ));
        let e = read("5:parsec", Dimension::Time).unwrap_err().to_string();
        assert!(
            e.contains("`parsec` is not a time unit") && e.contains("minute"),
            "{e}"
        );
        assert_eq!(write(25.0, Dimension::Volume), "25:microliter");
        assert_eq!(read(&write(0.5, Dimension::Time), Dimension::Time), Ok(0.5));
    }
}
