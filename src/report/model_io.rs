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

/// Encodes an RGB8 buffer of `w`×`h` pixels as PNG bytes.
pub fn encode_png(rgb: &[u8], w: u32, h: u32) -> Result<Vec<u8>, String> {
    use image::ImageEncoder;
    let mut out = Vec::new();
    image::codecs::png::PngEncoder::new(&mut out)
        .write_image(rgb, w, h, image::ExtendedColorType::Rgb8)
        .map_err(|e| e.to_string())?;
    Ok(out)
}

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
