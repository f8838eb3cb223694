//! Atomic output for the model reports: every file is written to a temporary
//! file in the same folder and renamed into place, so a failure never leaves
//! a half-written file and never destroys an earlier result.

use std::path::{Path, PathBuf};
use thiserror::Error;

/// An output file could not be written.
#[derive(Debug, Error)]
#[error("{path}: {cause}")]
pub struct OutputError {
    /// The file.
    pub path: String,
    /// What went wrong.
    pub cause: String,
}

impl OutputError {
    /// An error about `path`.
    pub fn new(path: &Path, cause: impl std::fmt::Display) -> Self {
        OutputError {
            path: path.display().to_string(),
            cause: cause.to_string(),
        }
    }
}

/// Writes `bytes` to `path` atomically (temp file + rename), creating the folder.
pub fn write_atomic(path: &Path, bytes: &[u8]) -> Result<(), OutputError> {
    let dir = match path.parent() {
        Some(d) if !d.as_os_str().is_empty() => d.to_path_buf(),
        _ => PathBuf::from("."),
    };
    std::fs::create_dir_all(&dir).map_err(|e| OutputError::new(path, e))?;
    let name = path
        .file_name()
        .ok_or_else(|| OutputError::new(path, "not a file name"))?
        .to_string_lossy()
        .into_owned();
    let tmp = dir.join(format!(".{name}.tmp-{}", std::process::id()));
    let result = (|| {
        use std::io::Write;
        let mut f = std::fs::File::create(&tmp)?;
        f.write_all(bytes)?;
        f.sync_all()?;
        drop(f);
        std::fs::rename(&tmp, path)
    })();
    if let Err(e) = result {
        let _ = std::fs::remove_file(&tmp);
        return Err(OutputError::new(path, e));
    }
    Ok(())
}

/// Formats an f64 so that it reads back to the same value: Rust's shortest
/// round-trip digits, plain (`0.25`, `300`) for ordinary magnitudes and in
/// exponent form (`1e300`, `1.2e-19`) for very large or small ones.
pub fn fmt_f64(x: f64) -> String {
    let a = x.abs();
    if a != 0.0 && a.is_finite() && !(1e-5..1e16).contains(&a) {
        format!("{x:e}")
    } else {
        format!("{x}")
    }
}

pub use crate::plot::encode_png;

/// Unique column names `mtf_<name>` for the factors, numbering repeats (`mtf_gaussian_2`).
pub fn factor_columns(names: &[String]) -> Vec<String> {
    let mut out: Vec<String> = Vec::with_capacity(names.len());
    for n in names {
        let base = format!("mtf_{n}");
        let mut col = base.clone();
        let mut k = 2;
        while out.contains(&col) {
            col = format!("{base}_{k}");
            k += 1;
        }
        out.push(col);
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn numbers_round_trip_compactly() {
        for x in [
            0.0,
            1.0,
            0.25,
            300.0,
            1e300,
            5e-324,
            -1.0359718658155233e-19,
            0.1 + 0.2,
            123456.789,
        ] {
            let s = fmt_f64(x);
            assert_eq!(s.parse::<f64>().unwrap(), x, "{s}");
            assert!(s.len() <= 24, "{s}");
        }
        assert_eq!(fmt_f64(300.0), "300");
        assert_eq!(fmt_f64(1e300), "1e300");
    }

    #[test]
    fn repeated_factor_names_get_numbers() {
        let names = ["a", "b", "a", "a"].map(String::from);
        assert_eq!(
            factor_columns(&names),
            ["mtf_a", "mtf_b", "mtf_a_2", "mtf_a_3"]
        );
    }

    #[test]
    fn atomic_write_replaces_and_leaves_no_temp() {
        let dir = std::env::temp_dir().join(format!("sweepmtf-io-{}", std::process::id()));
        let p = dir.join("sub/x.txt");
        write_atomic(&p, b"one").unwrap();
        write_atomic(&p, b"two").unwrap();
        assert_eq!(std::fs::read(&p).unwrap(), b"two");
        let n = std::fs::read_dir(p.parent().unwrap()).unwrap().count();
        assert_eq!(n, 1);
        std::fs::remove_dir_all(&dir).unwrap();
    }
}
