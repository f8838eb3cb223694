//! One shot's result as the batch keeps it: what a per-shot job returns
//! ([`ShotResult`]), how a job fails ([`ShotFailure`]), and the row of the
//! summary table ([`ShotRecord`]) that the runner builds from either.

use serde::{Deserialize, Serialize};

/// What a successful per-shot job reports: the summary numbers, the camera
/// facts and the per-shot files it wrote. Every field is optional; unknown
/// values stay empty in the summary.
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
#[serde(default)]
pub struct ShotResult {
    /// Frequency where the MTF falls to 0.5, in cycles/pixel.
    pub mtf50_cy_px: Option<f64>,
    /// MTF50 in cycles/mm on the sensor (when the pixel pitch is known).
    pub mtf50_cy_mm: Option<f64>,
    /// MTF50 in line widths per picture height.
    pub mtf50_lw_ph: Option<f64>,
    /// One-sigma uncertainty of MTF50, in cycles/pixel.
    pub mtf50_err_cy_px: Option<f64>,
    /// Frequency where the MTF falls to 0.2, in cycles/pixel.
    pub mtf20_cy_px: Option<f64>,
    /// Frequency where the MTF falls to 0.1, in cycles/pixel.
    pub mtf10_cy_px: Option<f64>,
    /// Frequency above the peak where the MTF falls to 50 % of the peak, in cycles/pixel.
    pub mtf50p_cy_px: Option<f64>,
    /// Frequency above the peak where the MTF falls to 20 % of the peak, in cycles/pixel.
    pub mtf20p_cy_px: Option<f64>,
    /// Frequency above the peak where the MTF falls to 10 % of the peak, in cycles/pixel.
    pub mtf10p_cy_px: Option<f64>,
    /// Peak MTF, dimensionless (1 when the curve does not rise above its low-frequency value).
    pub mtf_peak: Option<f64>,
    /// Frequency of the peak, in cycles/pixel (0 when the peak is the low-frequency value).
    pub mtf_peak_cy_px: Option<f64>,
    /// MTF at the Nyquist frequency (0.5 cycles/pixel), dimensionless.
    pub mtf_nyquist: Option<f64>,
    /// Modulation estimator used (`extrema`, `fit`, `envelope`, ...).
    pub method: Option<String>,
    /// Aperture f-number from the EXIF data.
    pub f_number: Option<f64>,
    /// Focal length in mm from the EXIF data.
    pub focal_length_mm: Option<f64>,
    /// ISO speed from the EXIF data.
    pub iso: Option<f64>,
    /// Exposure time in seconds from the EXIF data.
    pub exposure_time_s: Option<f64>,
    /// Camera maker.
    pub make: Option<String>,
    /// Camera model.
    pub model: Option<String>,
    /// Lens model.
    pub lens: Option<String>,
    /// Name (in the shots folder) of the per-shot curve CSV with columns
    /// `freq_cy_px,mtf` (and optionally `aliased`), used for the overlay plot.
    pub curve_file: Option<String>,
    /// Every per-shot file the job wrote, names relative to the shots folder.
    pub outputs: Vec<String>,
    /// Warnings worth showing beside the row.
    pub warnings: Vec<String>,
}

/// Why a shot failed, mapped from the measurement's error layers.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum FailKind {
    /// The file is unreadable, corrupt, empty or of an unsupported format.
    Input,
    /// The chart or region was not found.
    Locate,
    /// The measurement is impossible on this shot.
    Measure,
    /// A per-shot output could not be written (retried on the next run).
    Output,
    /// The job panicked (a decoder or measurement bug).
    Panic,
}

impl FailKind {
    /// Whether a failure of this kind is final for unchanged input and
    /// settings (so a rerun keeps the error row instead of retrying).
    pub fn is_deterministic(self) -> bool {
        !matches!(self, FailKind::Output)
    }
}

/// A failed shot: the kind of failure and one line naming the cause.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct ShotFailure {
    /// Kind of failure.
    pub kind: FailKind,
    /// One line naming the cause (without the file name; the row has it).
    pub message: String,
}

impl ShotFailure {
    /// A failure of a kind with a message.
    pub fn new(kind: FailKind, message: impl Into<String>) -> Self {
        ShotFailure {
            kind,
            message: message.into(),
        }
    }
}

/// Outcome of a shot in the summary.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum Status {
    /// Measured.
    Ok,
    /// Failed; see the error column.
    Error,
}

impl Status {
    /// The word written in the summary's `status` column.
    pub fn as_str(self) -> &'static str {
        match self {
            Status::Ok => "ok",
            Status::Error => "error",
        }
    }
}

/// One row of the summary: which shot, its status, and its result or error.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct ShotRecord {
    /// Position of the shot in the full (unsharded) sorted file list.
    pub index: usize,
    /// The shot's path as shown to the user (relative to its input folder,
    /// prefixed by the folder's name when several folders were given).
    pub file: String,
    /// Stem of the shot's per-shot outputs in the shots folder.
    pub stem: String,
    /// ok or error.
    pub status: Status,
    /// Failure kind when the status is error.
    pub error_kind: Option<FailKind>,
    /// One-line cause when the status is error.
    pub error: Option<String>,
    /// Result fields (empty on error).
    pub result: ShotResult,
    /// Wall-clock time spent on this shot, in seconds.
    pub run_time_s: f64,
}

impl ShotRecord {
    /// Whether the shot was measured.
    pub fn is_ok(&self) -> bool {
        self.status == Status::Ok
    }
}
