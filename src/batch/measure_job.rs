//! Glue between the batch runner and the single-shot measurement: the
//! [`ShotJob`] that measures one photo as `sweepmtf measure` would and writes
//! its per-shot files. Until the measurement lands in this build, every shot
//! fails with a clear "not available" row.

use super::record::{FailKind, ShotFailure, ShotResult};
use super::roi_file::RoiTable;
use super::runner::{PlannedShot, ShotJob};
use std::path::Path;

/// Measures each shot with the same options, and a region from the table
/// when it lists the shot.
#[derive(Debug, Clone, Default)]
pub struct MeasureJob {
    /// The measurement options serialised (part of the settings fingerprint).
    pub options_json: String,
    /// Per-shot regions.
    pub rois: RoiTable,
}

impl ShotJob for MeasureJob {
    fn fingerprint(&self, shot: &PlannedShot) -> String {
        format!(
            "sweepmtf {} measure {} roi {:?}",
            env!("CARGO_PKG_VERSION"),
            self.options_json,
            self.rois.lookup(&shot.file)
        )
    }

    fn run(&self, _shot: &PlannedShot, _shots_dir: &Path) -> Result<ShotResult, ShotFailure> {
        Err(ShotFailure::new(
            FailKind::Measure,
            "the single-shot measurement is not available in this build",
        ))
    }
}
