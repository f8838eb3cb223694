//! Atomic output: every file is first written in full to a temporary file in
//! the same folder and then renamed over its final name, so a reader never
//! sees a half-written file and a failed run never damages earlier results.

use std::io::Write;
use std::path::{Path, PathBuf};
use thiserror::Error;

/// Why an output could not be written.
#[derive(Debug, Error)]
pub enum ReportError {
    /// A file could not be written.
    #[error("{path}: cannot write: {source}")]
    Io {
        /// The file.
        path: String,
        /// The cause.
        source: std::io::Error,
    },
    /// A plot could not be drawn.
    #[error("cannot draw {what}: {cause}")]
    Plot {
        /// Which plot.
        what: String,
        /// The cause.
        cause: String,
    },
}

fn io(path: &Path, source: std::io::Error) -> ReportError {
    ReportError::Io {
        path: path.display().to_string(),
        source,
    }
}

fn temp_name(path: &Path) -> PathBuf {
    let name = path
        .file_name()
        .map(|n| n.to_string_lossy().into_owned())
        .unwrap_or_default();
    let unique = format!(
        ".{name}.{}.{:x}.tmp",
        std::process::id(),
        std::time::SystemTime::now()
            .duration_since(std::time::UNIX_EPOCH)
            .map(|d| d.as_nanos())
            .unwrap_or(0)
    );
    path.with_file_name(unique)
}

/// Writes one file atomically (temporary file in the same folder, then rename).
pub fn write_atomic(path: &Path, bytes: &[u8]) -> Result<(), ReportError> {
    write_all_atomic(&[(path.to_path_buf(), bytes.to_vec())])
}

/// Writes several files: all are written to temporaries first, and only when
/// every one succeeded are they renamed into place (temporaries are removed on failure).
pub fn write_all_atomic(files: &[(PathBuf, Vec<u8>)]) -> Result<(), ReportError> {
    use rayon::prelude::*;
    // Written and flushed to disk in parallel: each `sync_all` may wait for
    // the file system's journal, and one wait then serves them all.
    let written: Vec<std::io::Result<PathBuf>> = files
        .par_iter()
        .map(|(path, bytes)| {
            let tmp = temp_name(path);
            let res = std::fs::File::create(&tmp).and_then(|mut f| {
                f.write_all(bytes)?;
                f.sync_all()
            });
            match res {
                Ok(()) => Ok(tmp),
                Err(e) => {
                    let _ = std::fs::remove_file(&tmp);
                    Err(e)
                }
            }
        })
        .collect();
    let cleanup = |temps: &[PathBuf]| {
        for t in temps {
            let _ = std::fs::remove_file(t);
        }
    };
    let mut temps = Vec::with_capacity(files.len());
    let mut failed = None;
    for (k, r) in written.into_iter().enumerate() {
        match r {
            Ok(t) => temps.push(t),
            Err(e) => {
                failed.get_or_insert((k, e));
            }
        }
    }
    if let Some((k, e)) = failed {
        cleanup(&temps);
        return Err(io(&files[k].0, e));
    }
    for (k, ((path, _), tmp)) in files.iter().zip(&temps).enumerate() {
        if let Err(e) = std::fs::rename(tmp, path) {
            cleanup(&temps[k..]);
            return Err(io(path, e));
        }
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn writes_and_leaves_no_temporaries() {
        let dir = tempfile::tempdir().unwrap();
        let a = dir.path().join("a.csv");
        std::fs::write(&a, "old").unwrap();
        write_all_atomic(&[(a.clone(), b"new".to_vec())]).unwrap();
        assert_eq!(std::fs::read_to_string(&a).unwrap(), "new");
        // A file in a missing folder fails; the earlier file keeps its content and no temporaries remain.
        let bad = dir.path().join("missing").join("b.csv");
        assert!(write_all_atomic(&[(a.clone(), b"newer".to_vec()), (bad, b"x".to_vec())]).is_err());
        assert_eq!(std::fs::read_to_string(&a).unwrap(), "new");
        let names: Vec<_> = std::fs::read_dir(dir.path())
            .unwrap()
            .map(|e| e.unwrap().file_name())
            .collect();
        assert_eq!(names.len(), 1, "{names:?}");
    }
}
