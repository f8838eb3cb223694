//! Resumable runs. A shot is complete when every output it listed exists and
//! its marker `STEM.done.json` — written last, atomically — records the same
//! settings fingerprint and the same input file (path shown, size, mtime).
//! A rerun reuses the record stored in a complete shot's marker and skips the
//! shot; anything else (no marker, changed settings, changed file, a missing
//! output) is measured again. The marker is removed before a shot is redone,
//! so a run killed half-way through a shot leaves it incomplete, never stale.

use super::record::ShotRecord;
use serde::{Deserialize, Serialize};
use std::fs;
use std::path::{Path, PathBuf};
use std::time::UNIX_EPOCH;

/// Suffix of a shot's completion marker.
pub const MARKER_SUFFIX: &str = ".done.json";

/// Version of the marker format.
const MARKER_VERSION: u32 = 1;

/// 64-bit FNV-1a hash of `text` as 16 hex digits (stable across builds and
/// platforms, unlike the standard library's hasher).
pub fn fingerprint_hash(text: &str) -> String {
    let mut h: u64 = 0xcbf2_9ce4_8422_2325;
    for b in text.as_bytes() {
        h ^= u64::from(*b);
        h = h.wrapping_mul(0x0000_0100_0000_01b3);
    }
    format!("{h:016x}")
}

/// Identity of an input file: its size and modification time.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
pub struct InputStamp {
    /// Size in bytes.
    pub size: u64,
    /// Modification time, whole seconds since the Unix epoch.
    pub mtime_s: i64,
    /// Modification time, nanoseconds within the second.
    pub mtime_ns: u32,
}

impl InputStamp {
    /// Reads the stamp of `path`.
    pub fn of(path: &Path) -> std::io::Result<InputStamp> {
        let m = fs::metadata(path)?;
        let (s, ns) = match m.modified() {
            Ok(t) => match t.duration_since(UNIX_EPOCH) {
                Ok(d) => (d.as_secs() as i64, d.subsec_nanos()),
                Err(e) => (
                    -(e.duration().as_secs() as i64),
                    e.duration().subsec_nanos(),
                ),
            },
            Err(_) => (0, 0),
        };
        Ok(InputStamp {
            size: m.len(),
            mtime_s: s,
            mtime_ns: ns,
        })
    }
}

/// The completion marker of one shot.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Marker {
    /// Marker format version.
    pub version: u32,
    /// Hash of the settings that produced the outputs.
    pub settings_hash: String,
    /// The input file's stamp when it was measured.
    pub input: InputStamp,
    /// The shot's summary row (its outputs are listed in `record.result`).
    pub record: ShotRecord,
}

impl Marker {
    /// A marker for a finished shot.
    pub fn new(settings_hash: String, input: InputStamp, record: ShotRecord) -> Marker {
        Marker {
            version: MARKER_VERSION,
            settings_hash,
            input,
            record,
        }
    }
}

/// Path of the marker of shot `stem` in `shots_dir`.
pub fn marker_path(shots_dir: &Path, stem: &str) -> PathBuf {
    shots_dir.join(format!("{stem}{MARKER_SUFFIX}"))
}

/// Reads a marker; `None` when it is missing or unreadable (then the shot is
/// simply redone).
pub fn read_marker(shots_dir: &Path, stem: &str) -> Option<Marker> {
    let text = fs::read(marker_path(shots_dir, stem)).ok()?;
    let m: Marker = serde_json::from_slice(&text).ok()?;
    (m.version == MARKER_VERSION).then_some(m)
}

/// Writes a marker atomically (the last file of a shot; renamed into place,
/// not flushed, like the shot's other files).
pub fn write_marker(shots_dir: &Path, m: &Marker) -> std::io::Result<()> {
    let bytes = serde_json::to_vec_pretty(m).map_err(std::io::Error::other)?;
    super::atomic::write_all_atomic_unsynced(&[(marker_path(shots_dir, &m.record.stem), bytes)])
}

/// Removes a shot's marker (before redoing it); a missing marker is fine.
pub fn clear_marker(shots_dir: &Path, stem: &str) -> std::io::Result<()> {
    match fs::remove_file(marker_path(shots_dir, stem)) {
        Err(e) if e.kind() != std::io::ErrorKind::NotFound => Err(e),
        _ => Ok(()),
    }
}

/// Whether every output listed in the marker exists in `shots_dir` and is
/// not empty (an empty file is what a power loss can leave).
pub fn outputs_present(shots_dir: &Path, m: &Marker) -> bool {
    m.record
        .result
        .outputs
        .iter()
        .all(|o| std::fs::metadata(shots_dir.join(o)).is_ok_and(|md| md.is_file() && md.len() > 0))
}

/// The stored record of shot `stem` when the shot is complete for this
/// file (`file` as shown, its current `stamp`) and these settings.
pub fn complete_record(
    shots_dir: &Path,
    stem: &str,
    file: &str,
    stamp: &InputStamp,
    settings_hash: &str,
) -> Option<ShotRecord> {
    let m = read_marker(shots_dir, stem)?;
    (m.settings_hash == settings_hash
        && m.input == *stamp
        && m.record.file == file
        && outputs_present(shots_dir, &m))
    .then_some(m.record)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn fnv1a_matches_reference_vectors() {
        // Published FNV-1a 64 test vectors.
        assert_eq!(fingerprint_hash(""), "cbf29ce484222325");
        assert_eq!(fingerprint_hash("a"), "af63dc4c8601ec8c");
        assert_eq!(fingerprint_hash("foobar"), "85944171f73967e8");
    }
}
