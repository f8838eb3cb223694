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
    stage(files)?.commit()
}

/// Files written in full and flushed to disk as temporaries beside their
/// final names, not yet in place: [`Staged::commit`] renames them all (in
/// order); dropped uncommitted, the temporaries are removed. Staging lets
/// the files that are ready be written while others are still being made.
#[derive(Debug, Default)]
pub struct Staged {
    /// (final path, temporary path) of each file.
    files: Vec<(PathBuf, PathBuf)>,
}

/// Writes `files` to synced temporaries, each on its own thread (not the
/// rayon pool's, which may be busy drawing a picture: each `sync_all` waits
/// for the file system's journal, and one wait then serves them all); on
/// any failure none is kept.
pub fn stage(files: &[(PathBuf, Vec<u8>)]) -> Result<Staged, ReportError> {
    let write = |(path, bytes): &(PathBuf, Vec<u8>)| -> std::io::Result<PathBuf> {
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
    };
    let written: Vec<std::io::Result<PathBuf>> = std::thread::scope(|scope| {
        let others: Vec<_> = files
            .iter()
            .skip(1)
            .map(|f| std::thread::Builder::new().spawn_scoped(scope, move || write(f)))
            .collect();
        let first = files.first().map(write);
        first
            .into_iter()
            .chain(others.into_iter().zip(files.iter().skip(1)).map(|(h, f)| {
                // No thread to spare (or a lost one): written here instead.
                match h {
                    Ok(h) => h
                        .join()
                        .unwrap_or_else(|_| Err(std::io::Error::other("a writer thread failed"))),
                    Err(_) => write(f),
                }
            }))
            .collect()
    });
    let mut staged = Staged::default();
    for ((path, _), r) in files.iter().zip(written) {
        // A failure drops `staged`, which removes the temporaries made so far.
        let tmp = r.map_err(|e| io(path, e))?;
        staged.files.push((path.clone(), tmp));
    }
    Ok(staged)
}

impl Staged {
    /// Splits off the files from `at` on (to be committed after others).
    pub fn split_off(&mut self, at: usize) -> Staged {
        Staged {
            files: self.files.split_off(at.min(self.files.len())),
        }
    }

    /// These files followed by `other`'s, to be committed together.
    pub fn then(mut self, mut other: Staged) -> Staged {
        self.files.append(&mut other.files);
        self
    }

    /// Renames every temporary over its final name, in order; on a failure
    /// the files not yet renamed are left as they were.
    pub fn commit(mut self) -> Result<(), ReportError> {
        let files = std::mem::take(&mut self.files);
        for (k, (path, tmp)) in files.iter().enumerate() {
            if let Err(e) = std::fs::rename(tmp, path) {
                self.files = files[k..].to_vec();
                return Err(io(path, e));
            }
        }
        Ok(())
    }
}

impl Drop for Staged {
    fn drop(&mut self) {
        for (_, tmp) in &self.files {
            let _ = std::fs::remove_file(tmp);
        }
    }
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

    #[test]
    fn staged_files_appear_only_on_commit_and_vanish_when_dropped() {
        let dir = tempfile::tempdir().unwrap();
        let (a, b) = (dir.path().join("a.csv"), dir.path().join("b.png"));
        std::fs::write(&a, "old").unwrap();
        let names = || {
            let mut v: Vec<String> = std::fs::read_dir(dir.path())
                .unwrap()
                .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
                .collect();
            v.sort();
            v
        };
        let first = stage(&[(a.clone(), b"new".to_vec())]).unwrap();
        let second = stage(&[(b.clone(), b"png".to_vec())]).unwrap();
        // Staged: the old file is untouched, the new one not yet there.
        assert_eq!(std::fs::read_to_string(&a).unwrap(), "old");
        assert!(!b.exists());
        assert_eq!(names().len(), 3, "{:?}", names());
        first.then(second).commit().unwrap();
        assert_eq!(std::fs::read_to_string(&a).unwrap(), "new");
        assert_eq!(std::fs::read_to_string(&b).unwrap(), "png");
        assert_eq!(names(), ["a.csv", "b.png"]);
        // Dropped without a commit: nothing changes, no temporaries remain.
        drop(stage(&[(a.clone(), b"newer".to_vec())]).unwrap());
        assert_eq!(std::fs::read_to_string(&a).unwrap(), "new");
        assert_eq!(names(), ["a.csv", "b.png"]);
        // A rename that fails (the final name is a folder) keeps the files
        // after it out of place and removes their temporaries.
        let c = dir.path().join("c.csv");
        std::fs::create_dir(dir.path().join("d")).unwrap();
        std::fs::write(dir.path().join("d").join("x"), "x").unwrap();
        let staged = stage(&[
            (dir.path().join("d"), b"d".to_vec()),
            (c.clone(), b"c".to_vec()),
        ])
        .unwrap();
        assert!(staged.commit().is_err());
        assert!(!c.exists());
        assert_eq!(names(), ["a.csv", "b.png", "d"]);
    }
}
