//! The advisory lock on a batch output folder: `batch` and `merge` hold an
//! exclusive OS file lock on `OUT/.sweepmtf.lock` for the whole run, with the
//! holder's process id written inside, so a second run into the same folder
//! stops at once and names the holder instead of deleting the first run's
//! temporary files under it. The OS drops the lock when its process ends, so
//! a lock file left by a killed run is stale: the next run locks it and takes
//! it over. Uses `std::fs::File::try_lock` (flock on Unix, LockFileEx on
//! Windows; stable since Rust 1.89), so no lock crate is needed.

use super::BatchError;
use std::fs::{File, OpenOptions};
use std::io::{Read, Seek, SeekFrom, Write};
use std::path::{Path, PathBuf};

/// Name of the lock file inside the output folder.
pub const LOCK_FILE: &str = ".sweepmtf.lock";

/// An exclusive lock on an output folder, held until dropped.
#[derive(Debug)]
pub struct FolderLock {
    file: File,
    path: PathBuf,
    /// Process id written by an earlier run that no longer holds the lock (a stale lock taken over).
    pub took_over_from: Option<String>,
}

impl FolderLock {
    /// Locks output folder `dir` (which must exist) for this process, or fails
    /// with [`BatchError::Locked`] naming the process that holds it.
    pub fn acquire(dir: &Path) -> Result<FolderLock, BatchError> {
        let path = dir.join(LOCK_FILE);
        let mut file = OpenOptions::new()
            .read(true)
            .write(true)
            .create(true)
            .truncate(false)
            .open(&path)
            .map_err(|e| BatchError::output(&path, e))?;
        let mut earlier = String::new();
        let _ = file.read_to_string(&mut earlier);
        let earlier = earlier.trim().to_string();
        match file.try_lock() {
            Ok(()) => {}
            Err(std::fs::TryLockError::WouldBlock) => {
                // The holder writes its pid just after locking: a run that
                // read the file in between waits briefly (≤ 100 ms) to name it.
                let mut holder = earlier;
                for _ in 0..20 {
                    if !holder.is_empty() {
                        break;
                    }
                    std::thread::sleep(std::time::Duration::from_millis(5));
                    holder.clear();
                    let _ = file.seek(SeekFrom::Start(0));
                    let _ = file.read_to_string(&mut holder);
                    holder = holder.trim().to_string();
                }
                return Err(BatchError::Locked {
                    dir: dir.display().to_string(),
                    holder: holder_text(&holder),
                });
            }
            Err(std::fs::TryLockError::Error(e)) => {
                return Err(BatchError::output(&path, e));
            }
        }
        // Ours now: write our pid (an earlier pid in the file is a stale lock).
        let write = (|| {
            file.set_len(0)?;
            file.seek(SeekFrom::Start(0))?;
            writeln!(file, "{}", std::process::id())?;
            file.flush()
        })();
        write.map_err(|e| BatchError::output(&path, e))?;
        Ok(FolderLock {
            file,
            path,
            took_over_from: (!earlier.is_empty()).then_some(earlier),
        })
    }

    /// The lock file's path.
    pub fn path(&self) -> &Path {
        &self.path
    }
}

impl Drop for FolderLock {
    fn drop(&mut self) {
        // Empty the file so no pid outlives the run; the file itself stays
        // (removing it would let two later runs lock two different files).
        let _ = self.file.set_len(0);
        let _ = self.file.unlock();
    }
}

/// "process 1234" from the lock file's text (the pid a holder wrote).
fn holder_text(text: &str) -> String {
    match text.lines().next().map(str::trim) {
        Some(pid) if !pid.is_empty() && pid.chars().all(|c| c.is_ascii_digit()) => {
            format!("process {pid}")
        }
        // Locked but not yet written (a run just starting).
        _ => "another process".to_string(),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn second_lock_names_the_holder_and_stale_file_is_taken_over() {
        let dir = tempfile::tempdir().unwrap();
        // A stale file from a killed run: a pid but no OS lock.
        std::fs::write(dir.path().join(LOCK_FILE), "999999999\n").unwrap();
        let first = FolderLock::acquire(dir.path()).unwrap();
        assert_eq!(first.took_over_from.as_deref(), Some("999999999"));
        let text = std::fs::read_to_string(first.path()).unwrap();
        assert_eq!(text.trim(), std::process::id().to_string());
        // flock locks belong to the open file, so a second open in the same
        // process conflicts just as another process would.
        match FolderLock::acquire(dir.path()) {
            Err(BatchError::Locked { holder, .. }) => {
                assert_eq!(holder, format!("process {}", std::process::id()))
            }
            other => panic!("expected Locked, got {other:?}"),
        }
        drop(first);
        let again = FolderLock::acquire(dir.path()).unwrap();
        assert_eq!(again.took_over_from, None);
    }
}
