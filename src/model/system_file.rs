//! System files: a camera described once, in TOML, with the same factor specs
//! as the command-line flags.
//!
//! ```toml
//! name = "APS-C sensor, f/4 lens"
//! description = "optional free text"
//!
//! [[factor]]
//! kind = "optics"
//! spec = "diffraction:lambda=550nm,fnum=4"
//!
//! [[factor]]
//! kind = "aperture"
//! spec = "rect:A=4.3um,B=4.3um"
//! ```
//!
//! Unknown keys are rejected; `kind` is one of [`super::spec::KINDS`].

use super::spec::parse_factor;
use super::{ModelError, System};
use serde::Deserialize;
use std::path::Path;

/// One `[[factor]]` table.
#[derive(Debug, Clone, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct FactorEntry {
    /// Factor kind (`optics`, `aperture`, …).
    pub kind: String,
    /// Factor spec, as for the CLI flag of that kind.
    pub spec: String,
}

/// A parsed system file.
#[derive(Debug, Clone, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct SystemFile {
    /// Display name (plot titles).
    pub name: Option<String>,
    /// Free text.
    pub description: Option<String>,
    /// The factors, in order.
    #[serde(default)]
    pub factor: Vec<FactorEntry>,
}

impl SystemFile {
    /// Parses TOML text; `origin` names the file in errors.
    pub fn parse(text: &str, origin: &str) -> Result<SystemFile, ModelError> {
        toml::from_str(text).map_err(|e| ModelError::File {
            path: origin.to_string(),
            cause: e.message().to_string(),
        })
    }

    /// Reads and parses a system file.
    pub fn read(path: &Path) -> Result<SystemFile, ModelError> {
        let text = std::fs::read_to_string(path).map_err(|e| ModelError::File {
            path: path.display().to_string(),
            cause: e.to_string(),
        })?;
        Self::parse(&text, &path.display().to_string())
    }

    /// Builds the factors; errors name the file and the factor's position.
    pub fn build(&self, origin: &str) -> Result<System, ModelError> {
        let mut factors = Vec::with_capacity(self.factor.len());
        for (i, f) in self.factor.iter().enumerate() {
            let factor = parse_factor(&f.kind, &f.spec).map_err(|e| ModelError::File {
                path: origin.to_string(),
                cause: format!("factor {} ({}): {e}", i + 1, f.kind),
            })?;
            factors.push(factor);
        }
        Ok(System { factors })
    }
}

impl System {
    /// Reads a TOML system file (see [`SystemFile`]) and builds its factors.
    pub fn from_file(path: impl AsRef<Path>) -> Result<System, ModelError> {
        let path = path.as_ref();
        SystemFile::read(path)?.build(&path.display().to_string())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn parses_and_builds() {
        let text = r#"
name = "test"
[[factor]]
kind = "optics"
spec = "diffraction:lambda=550nm,fnum=4"
[[factor]]
kind = "gaussian"
spec = "sigma=1um"
"#;
        let f = SystemFile::parse(text, "t.toml").unwrap();
        assert_eq!(f.name.as_deref(), Some("test"));
        let s = f.build("t.toml").unwrap();
        assert_eq!(s.factors.len(), 2);
    }

    #[test]
    fn rejects_unknown_keys_and_kinds() {
        let e = SystemFile::parse("nmae = \"x\"", "t.toml")
            .unwrap_err()
            .to_string();
        assert!(e.contains("t.toml") && e.contains("nmae"), "{e}");
        let e = SystemFile::parse("[[factor]]\nkind=\"optics\"\nspec=\"x\"\ncolor=1", "t.toml")
            .unwrap_err()
            .to_string();
        assert!(e.contains("color"), "{e}");
        let f = SystemFile::parse("[[factor]]\nkind=\"lens\"\nspec=\"x\"", "t.toml").unwrap();
        let e = f.build("t.toml").unwrap_err().to_string();
        assert!(e.contains("factor 1") && e.contains("lens"), "{e}");
    }
}
