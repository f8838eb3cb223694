//! Parsing of unit-suffixed values shared by every subcommand (`5um`, `550nm`,
//! `0.005mm`, `0.05/um`, `500/cm`).
//!
//! Lengths come back in millimetres and absorption coefficients in 1/mm, the
//! model's internal units (see DESIGN.md, "Units").

use thiserror::Error;

/// A value that could not be read as a quantity with a unit.
#[derive(Debug, Clone, PartialEq, Error)]
pub enum UnitError {
    /// The text is not a number followed by one of the allowed units.
    #[error("'{text}' is not a {what}; write a number with a unit, one of: {allowed}")]
    Malformed {
        /// The text as given.
        text: String,
        /// What was expected ("length", "absorption coefficient").
        what: &'static str,
        /// The units accepted.
        allowed: &'static str,
    },
    /// The number is not finite.
    #[error("'{0}' is not a finite number")]
    NotFinite(String),
}

const LENGTH_UNITS: &[(&str, f64)] = &[
    ("nm", 1e-6),
    ("um", 1e-3),
    ("µm", 1e-3),
    ("μm", 1e-3),
    ("mm", 1.0),
    ("cm", 10.0),
    ("m", 1000.0),
    ("in", 25.4),
];
const LENGTH_ALLOWED: &str = "nm, um (µm), mm, cm, m, in (e.g. 5um, 550nm, 0.005mm)";
const ABSORPTION_ALLOWED: &str = "/nm, /um, /mm, /cm, /m (e.g. 0.05/um, 500/cm)";

fn split_number(text: &str) -> Option<(f64, &str)> {
    let t = text.trim();
    let end = t
        .char_indices()
        .find(|&(i, c)| {
            !(c.is_ascii_digit()
                || c == '.'
                || c == '+'
                || c == '-'
                || ((c == 'e' || c == 'E')
                    && t[i + 1..]
                        .chars()
                        .next()
                        .is_some_and(|n| n.is_ascii_digit() || n == '-' || n == '+')))
        })
        .map(|(i, _)| i)
        .unwrap_or(t.len());
    let value: f64 = t[..end].parse().ok()?;
    Some((value, t[end..].trim()))
}

fn lookup(unit: &str) -> Option<f64> {
    LENGTH_UNITS
        .iter()
        .find(|(name, _)| *name == unit)
        .map(|&(_, f)| f)
}

/// Parses a length with a mandatory unit suffix; returns millimetres.
pub fn parse_length_mm(text: &str) -> Result<f64, UnitError> {
    let malformed = || UnitError::Malformed {
        text: text.to_string(),
        what: "length",
        allowed: LENGTH_ALLOWED,
    };
    let (value, unit) = split_number(text).ok_or_else(malformed)?;
    let factor = lookup(unit).ok_or_else(malformed)?;
    finite(value * factor, text)
}

/// Parses an absorption coefficient written as `number/length-unit`; returns 1/mm.
pub fn parse_absorption_per_mm(text: &str) -> Result<f64, UnitError> {
    let malformed = || UnitError::Malformed {
        text: text.to_string(),
        what: "absorption coefficient",
        allowed: ABSORPTION_ALLOWED,
    };
    let (value, rest) = split_number(text).ok_or_else(malformed)?;
    let unit = rest.strip_prefix('/').ok_or_else(malformed)?.trim();
    let factor = lookup(unit).ok_or_else(malformed)?;
    finite(value / factor, text)
}

fn finite(v: f64, text: &str) -> Result<f64, UnitError> {
    if v.is_finite() {
        Ok(v)
    } else {
        Err(UnitError::NotFinite(text.to_string()))
    }
}

/// Formats a length given in millimetres as micrometres with full precision (`5um`).
pub fn format_um(mm: f64) -> String {
    format!("{}um", mm * 1e3)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn lengths() {
        assert_eq!(parse_length_mm("5um").unwrap(), 5e-3);
        assert!((parse_length_mm("550nm").unwrap() - 550e-6).abs() < 1e-18);
        assert_eq!(parse_length_mm("0.005mm").unwrap(), 0.005);
        assert_eq!(parse_length_mm(" 2.5 µm").unwrap(), 2.5e-3);
        assert_eq!(parse_length_mm("1e-3m").unwrap(), 1.0);
        assert_eq!(parse_length_mm("-3um").unwrap(), -3e-3);
    }

    #[test]
    fn absorption() {
        assert!((parse_absorption_per_mm("0.05/um").unwrap() - 50.0).abs() < 1e-12);
        assert!((parse_absorption_per_mm("500/cm").unwrap() - 50.0).abs() < 1e-12);
        assert!((parse_absorption_per_mm("1e4 / cm").unwrap() - 1000.0).abs() < 1e-9);
    }

    #[test]
    fn rejects_bare_numbers_and_unknown_units() {
        for bad in ["5", "5 furlongs", "um", "", "5/um", "1e400um", "abc"] {
            assert!(parse_length_mm(bad).is_err(), "{bad}");
        }
        for bad in ["0.05", "0.05um", "/um", "5/parsec"] {
            assert!(parse_absorption_per_mm(bad).is_err(), "{bad}");
        }
        let msg = parse_length_mm("5").unwrap_err().to_string();
        assert!(msg.contains("nm, um"), "{msg}");
    }
}
