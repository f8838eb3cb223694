//! Atomic file writing: every batch file is written to a temporary file in
//! the same folder and renamed over its final name, so a run killed at any
//! moment leaves either the old file, the new file, or no file — never a
//! half-written one. Temporary names start with [`TEMP_PREFIX`] so the next
//! run can remove leftovers of a killed run.

use std::fs;
use std::io::Write;
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicU64, Ordering};

/// Prefix of temporary files written by the batch (hidden, never a result).
pub const TEMP_PREFIX: &str = ".sweepmtf-tmp-";

static COUNTER: AtomicU64 = AtomicU64::new(0);

fn temp_path(path: &Path) -> PathBuf {
    let dir = path.parent().unwrap_or_else(|| Path::new("."));
    let name = path
        .file_name()
        .map(|n| n.to_string_lossy().into_owned())
        .unwrap_or_default();
    let n = COUNTER.fetch_add(1, Ordering::Relaxed);
    dir.join(format!("{TEMP_PREFIX}{}-{n}-{name}", std::process::id()))
}

/// Writes `bytes` to `path` atomically (temporary file in the same folder,
/// flushed to disk, then renamed over `path`).
pub fn write_atomic(path: &Path, bytes: &[u8]) -> std::io::Result<()> {
    write_atomic_with(path, |f| f.write_all(bytes))
}

/// Writes `path` atomically through a closure that fills the temporary file.
pub fn write_atomic_with(
    path: &Path,
    fill: impl FnOnce(&mut fs::File) -> std::io::Result<()>,
) -> std::io::Result<()> {
    let tmp = temp_path(path);
    let result = (|| {
        let mut f = fs::File::create(&tmp)?;
        fill(&mut f)?;
        f.sync_all()?;
        drop(f);
        fs::rename(&tmp, path)
    })();
    if result.is_err() {
        let _ = fs::remove_file(&tmp);
    }
    result
}

/// Writes several files atomically without flushing them to disk: each goes
/// to a temporary file first, and only when all are written are they renamed
/// into place (temporaries removed on failure). Renaming is what makes a
/// killed process leave whole files; the per-shot files skip `fsync`, which
/// on a busy disk costs more than the measurement itself (a power loss can
/// leave an empty file, which resume treats as missing).
pub fn write_all_atomic_unsynced(files: &[(PathBuf, Vec<u8>)]) -> std::io::Result<()> {
    let mut temps: Vec<PathBuf> = Vec::new();
    let cleanup = |t: &[PathBuf]| {
        for p in t {
            let _ = fs::remove_file(p);
        }
    };
    for (path, bytes) in files {
        let tmp = temp_path(path);
        if let Err(e) = fs::write(&tmp, bytes) {
            let _ = fs::remove_file(&tmp);
            cleanup(&temps);
            return Err(e);
        }
        temps.push(tmp);
    }
    for (k, (path, _)) in files.iter().enumerate() {
        if let Err(e) = fs::rename(&temps[k], path) {
            cleanup(&temps[k..]);
            return Err(e);
        }
    }
    Ok(())
}

/// Copies `from` to `to` atomically.
pub fn copy_atomic(from: &Path, to: &Path) -> std::io::Result<()> {
    write_atomic_with(to, |f| {
        let mut src = fs::File::open(from)?;
        std::io::copy(&mut src, f).map(|_| ())
    })
}

/// Whether `name` is a temporary file of a killed write: ours
/// ([`TEMP_PREFIX`]) or the measurement report's (`.NAME.PID.N.tmp`).
pub fn is_temp_name(name: &str) -> bool {
    name.starts_with(TEMP_PREFIX) || (name.starts_with('.') && name.ends_with(".tmp"))
}

/// Removes temporary files left in `dir` by a killed run; returns how many.
/// `owned`: the batch owns the folder (the shots folder), so the report's
/// temporaries go too; otherwise only files with [`TEMP_PREFIX`].
pub fn remove_stale_temps(dir: &Path, owned: bool) -> std::io::Result<usize> {
    let mut n = 0;
    let entries = match fs::read_dir(dir) {
        Ok(e) => e,
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => return Ok(0),
        Err(e) => return Err(e),
    };
    for entry in entries {
        let entry = entry?;
        let name = entry.file_name().to_string_lossy().into_owned();
        let temp = if owned {
            is_temp_name(&name)
        } else {
            name.starts_with(TEMP_PREFIX)
        };
        if temp && entry.file_type()?.is_file() {
            fs::remove_file(entry.path())?;
            n += 1;
        }
    }
    Ok(n)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn writes_and_replaces_without_leaving_temps() {
        let dir = tempfile::tempdir().unwrap();
        let p = dir.path().join("a.txt");
        write_atomic(&p, b"one").unwrap();
        write_atomic(&p, b"two").unwrap();
        assert_eq!(fs::read(&p).unwrap(), b"two");
        assert_eq!(fs::read_dir(dir.path()).unwrap().count(), 1);
    }

    #[test]
    fn failed_fill_keeps_old_file_and_no_temp() {
        let dir = tempfile::tempdir().unwrap();
        let p = dir.path().join("a.txt");
        write_atomic(&p, b"old").unwrap();
        let r = write_atomic_with(&p, |f| {
            f.write_all(b"half")?;
            Err(std::io::Error::other("disk full"))
        });
        assert!(r.is_err());
        assert_eq!(fs::read(&p).unwrap(), b"old");
        assert_eq!(fs::read_dir(dir.path()).unwrap().count(), 1);
    }

    #[test]
    fn removes_only_its_own_temps() {
        let dir = tempfile::tempdir().unwrap();
        fs::write(dir.path().join(format!("{TEMP_PREFIX}1-0-x.csv")), b"x").unwrap();
        fs::write(dir.path().join("x.csv"), b"x").unwrap();
        fs::write(dir.path().join(".x.csv.123.abc.tmp"), b"x").unwrap();
        fs::write(dir.path().join(".hidden"), b"x").unwrap();
        assert_eq!(remove_stale_temps(dir.path(), false).unwrap(), 1);
        fs::write(dir.path().join(format!("{TEMP_PREFIX}1-0-x.csv")), b"x").unwrap();
        assert_eq!(remove_stale_temps(dir.path(), true).unwrap(), 2);
        assert_eq!(fs::read_dir(dir.path()).unwrap().count(), 2);
    }
}
