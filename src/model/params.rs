//! The `key=value,key=value` parameter lists of factor specs (`rect:A=5um,B=5um`),
//! shared by every factor parser: unit-aware getters, and an error for any key
//! that was given but never asked for.

use super::ModelError;
use crate::units::{parse_absorption_per_mm, parse_length_mm};
use std::cell::RefCell;

/// Parsed `key=value` pairs of one factor spec, with the factor's name for errors.
#[derive(Debug)]
pub struct Params {
    factor: String,
    pairs: Vec<(String, String)>,
    used: RefCell<Vec<bool>>,
}

impl Params {
    /// Splits `A=5um,B=5um` (comma separated, `=` between key and value) for factor `factor`.
    pub fn parse(factor: &str, text: &str) -> Result<Params, ModelError> {
        let mut pairs = Vec::new();
        for item in text.split(',').map(str::trim).filter(|s| !s.is_empty()) {
            let (k, v) = item.split_once('=').ok_or_else(|| ModelError::Parameter {
                factor: factor.to_string(),
                message: format!("'{item}' is not key=value"),
            })?;
            let k = k.trim().to_string();
            if pairs.iter().any(|(p, _): &(String, String)| *p == k) {
                return Err(ModelError::Parameter {
                    factor: factor.to_string(),
                    message: format!("'{k}' is given twice"),
                });
            }
            pairs.push((k, v.trim().to_string()));
        }
        let used = RefCell::new(vec![false; pairs.len()]);
        Ok(Params {
            factor: factor.to_string(),
            pairs,
            used,
        })
    }

    /// An error about this factor.
    pub fn error(&self, message: impl Into<String>) -> ModelError {
        ModelError::Parameter {
            factor: self.factor.clone(),
            message: message.into(),
        }
    }

    /// The raw text of `key`, if given (marks it used).
    pub fn raw(&self, key: &str) -> Option<&str> {
        let i = self.pairs.iter().position(|(k, _)| k == key)?;
        self.used.borrow_mut()[i] = true;
        Some(&self.pairs[i].1)
    }

    /// Whether `key` was given (does not mark it used).
    pub fn has(&self, key: &str) -> bool {
        self.pairs.iter().any(|(k, _)| k == key)
    }

    /// An optional length (mm), written with a unit.
    pub fn length_opt(&self, key: &str) -> Result<Option<f64>, ModelError> {
        self.raw(key)
            .map(|v| parse_length_mm(v).map_err(|e| self.error(format!("{key}: {e}"))))
            .transpose()
    }

    /// A required length (mm) that must be > 0.
    pub fn positive_length(&self, key: &str) -> Result<f64, ModelError> {
        let v = self
            .length_opt(key)?
            .ok_or_else(|| self.error(format!("missing {key}=<length> (e.g. {key}=5um)")))?;
        if v > 0.0 {
            Ok(v)
        } else {
            Err(self.error(format!("{key} must be a positive length, got {v} mm")))
        }
    }

    /// An optional absorption coefficient (1/mm), written as `0.05/um` or `500/cm`.
    pub fn absorption_opt(&self, key: &str) -> Result<Option<f64>, ModelError> {
        self.raw(key)
            .map(|v| parse_absorption_per_mm(v).map_err(|e| self.error(format!("{key}: {e}"))))
            .transpose()
    }

    /// An optional plain number.
    pub fn number_opt(&self, key: &str) -> Result<Option<f64>, ModelError> {
        self.raw(key)
            .map(|v| match v.parse::<f64>() {
                Ok(x) if x.is_finite() => Ok(x),
                _ => Err(self.error(format!("{key}: '{v}' is not a finite number"))),
            })
            .transpose()
    }

    /// A required plain number.
    pub fn number(&self, key: &str) -> Result<f64, ModelError> {
        self.number_opt(key)?
            .ok_or_else(|| self.error(format!("missing {key}=<number>")))
    }

    /// An optional word from a fixed list.
    pub fn choice_opt(&self, key: &str, allowed: &[&str]) -> Result<Option<String>, ModelError> {
        match self.raw(key) {
            None => Ok(None),
            Some(v) if allowed.contains(&v) => Ok(Some(v.to_string())),
            Some(v) => {
                Err(self.error(format!("{key}: '{v}' is not one of {}", allowed.join(", "))))
            }
        }
    }

    /// Fails if any given key was never asked for, naming the keys allowed.
    pub fn finish(&self, allowed: &[&str]) -> Result<(), ModelError> {
        let used = self.used.borrow();
        if let Some((k, _)) = self
            .pairs
            .iter()
            .zip(used.iter())
            .find(|(_, u)| !**u)
            .map(|(p, _)| p)
        {
            return Err(self.error(format!(
                "unknown key '{k}'; allowed: {}",
                allowed.join(", ")
            )));
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn reads_lengths_numbers_and_rejects_unknown_keys() {
        let p = Params::parse("aperture rect", "A=5um, B=0.004mm,n=3").unwrap();
        assert_eq!(p.positive_length("A").unwrap(), 0.005);
        assert_eq!(p.positive_length("B").unwrap(), 0.004);
        let e = p.finish(&["A", "B"]).unwrap_err().to_string();
        assert!(e.contains("unknown key 'n'"), "{e}");
        assert_eq!(p.number("n").unwrap(), 3.0);
        p.finish(&["A", "B", "n"]).unwrap();
    }

    #[test]
    fn errors_name_the_parameter() {
        let p = Params::parse("aperture rect", "A=5,B=-1um").unwrap();
        assert!(
            p.positive_length("A")
                .unwrap_err()
                .to_string()
                .contains("A:")
        );
        assert!(
            p.positive_length("B")
                .unwrap_err()
                .to_string()
                .contains("positive")
        );
        assert!(
            p.positive_length("C")
                .unwrap_err()
                .to_string()
                .contains("missing C")
        );
        assert!(Params::parse("x", "A=1um,A=2um").is_err());
        assert!(Params::parse("x", "A").is_err());
    }
}
