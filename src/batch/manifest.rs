//! `OUT/batch.json`: the run's plan (which shots this run or shard owns and
//! their output stems), written atomically before any shot is measured, so
//! `merge` knows which shots a folder should hold even when its run was
//! stopped before the end.

use super::runner::PlannedShot;
use super::{BatchError, atomic};
use serde::{Deserialize, Serialize};
use std::path::Path;

/// File name of the manifest in an output folder.
pub const MANIFEST_FILE: &str = "batch.json";

/// One planned shot as listed in the manifest.
#[derive(Debug, Clone, PartialEq, Eq, Serialize, Deserialize)]
pub struct ManifestShot {
    /// Position in the full sorted file list.
    pub index: usize,
    /// Path shown to the user.
    pub file: String,
    /// Output stem.
    pub stem: String,
}

/// The plan of one batch run (or of a merge).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Manifest {
    /// sweepmtf version that wrote it.
    pub sweepmtf_version: String,
    /// The shard this folder holds (`K/N`), or `merged`.
    pub shard: String,
    /// Number of shots in the full, unsharded list.
    pub total_shots: usize,
    /// The shots this folder holds.
    pub shots: Vec<ManifestShot>,
}

impl Manifest {
    /// The manifest of a run over `shots` (of `total` in the full list).
    pub fn of_run(shard: String, total: usize, shots: &[PlannedShot]) -> Manifest {
        Manifest {
            sweepmtf_version: env!("CARGO_PKG_VERSION").to_string(),
            shard,
            total_shots: total,
            shots: shots
                .iter()
                .map(|s| ManifestShot {
                    index: s.index,
                    file: s.file.clone(),
                    stem: s.stem.clone(),
                })
                .collect(),
        }
    }

    /// Reads the manifest of output folder `dir`.
    pub fn read(dir: &Path) -> Result<Manifest, BatchError> {
        let path = dir.join(MANIFEST_FILE);
        let bytes = std::fs::read(&path).map_err(|e| BatchError::Input {
            path: dir.display().to_string(),
            cause: format!("not a batch output folder (cannot read {MANIFEST_FILE}: {e})"),
        })?;
        serde_json::from_slice(&bytes).map_err(|e| BatchError::Input {
            path: path.display().to_string(),
            cause: format!("not a valid batch manifest: {e}"),
        })
    }

    /// Writes the manifest into output folder `dir` atomically.
    pub fn write(&self, dir: &Path) -> Result<(), BatchError> {
        let path = dir.join(MANIFEST_FILE);
        let bytes = serde_json::to_vec_pretty(self)
            .map_err(|e| BatchError::output(&path, std::io::Error::other(e)))?;
        atomic::write_atomic(&path, &bytes).map_err(|e| BatchError::output(&path, e))
    }
}
