//! What a measurement gives: [`Measurement`] with its [`Curve`]s and
//! [`Preview`], or a [`MeasureError`] naming the file and the [`Failure`];
//! and the messages gathered on the way ([`Said`]).

use super::{DistortionFound, Figures, Method, MtfPoint, PatchResult, PhaseLaw, moire};
use crate::geometry::Point;
use crate::photo::decode::DecodeError;
use crate::target::TargetError;
use serde::Serialize;
use thiserror::Error;

/// Why a measurement failed (the cause; [`MeasureError`] adds the file).
#[derive(Debug, Error)]
pub enum Failure {
    /// The photo could not be decoded.
    #[error("{0}")]
    Decode(#[from] DecodeError),
    /// A camera raw file could not be decoded (the message names the file).
    #[error("{0}")]
    Raw(String),
    /// The target description could not be used.
    #[error("{0}")]
    Target(#[from] TargetError),
    /// An option value is unusable.
    #[error("{0}")]
    Options(String),
    /// No region was given and it cannot be found automatically.
    #[error("no --roi given and automatic location is not available")]
    NoRoi,
    /// The region is unusable (outside the image, degenerate, self-crossing).
    #[error("region unusable: {0}")]
    Region(String),
    /// The region is too small for a measurement.
    #[error("region too small: {0}")]
    TooSmall(String),
    /// Too much of the region is clipped.
    #[error(
        "the sweep is clipped: {percent:.1} % of the region's samples are at white or black clipping"
    )]
    Clipped {
        /// Percentage of clipped samples.
        percent: f64,
    },
    /// No sweep oscillation was found.
    #[error("no oscillation found: {0}")]
    NoOscillation(String),
    /// The chart's modulation is neither given nor estimable.
    #[error("chart modulation unknown: {0}")]
    ModulationUnknown(String),
    /// A curve was measured but fails the quality gate (too few samples per
    /// bin, a poorly fitting phase law, or modulation lost in noise).
    #[error("curve refused: {0}")]
    Unreliable(String),
    /// A failure in a photo whose decoder reported damaged data (the likely cause).
    #[error("{failure} (the photo itself is damaged: {damage})")]
    Damaged {
        /// The failure itself.
        failure: Box<Failure>,
        /// What the decoder or the scan check found damaged.
        damage: String,
    },
}

/// A failed measurement: the file and the cause, displayed as one line.
#[derive(Debug, Error)]
#[error("{}", if matches!(self.failure, Failure::Decode(_) | Failure::Raw(_)) { self.failure.to_string() } else { format!("{}: {}", self.path, self.failure) })]
pub struct MeasureError {
    /// The photo.
    pub path: String,
    /// The cause.
    pub failure: Failure,
}

/// One measured MTF curve (one channel, one sweep).
#[derive(Debug, Clone, Serialize)]
pub struct Curve {
    /// Channel name (`luma`, `grey`, `r`, …).
    pub channel: String,
    /// Sweep name (from the target; `strip` without one).
    pub sweep_id: String,
    /// The fitted phase law (strip units).
    pub law: PhaseLaw,
    /// Strip units: "mm" with a target, "px" (along the strip's edge) without.
    pub strip_unit: &'static str,
    /// Length of the strip in strip units (chart mm with a target; without one,
    /// px: the mean of the region's two long edges, corners 1→2 and 4→3).
    pub strip_length: f64,
    /// Points in increasing frequency.
    pub points: Vec<MtfPoint>,
    /// Chart modulation used for normalisation.
    pub chart_modulation: f64,
    /// One-sigma uncertainty of `chart_modulation` (0 when printed on the target).
    pub chart_modulation_err: f64,
    /// Where the chart modulation came from.
    pub chart_modulation_source: String,
    /// Summary figures.
    pub figures: Figures,
    /// Lowest aliased frequency (cycles/pixel), if any point is aliased.
    pub aliasing_from_cy_px: Option<f64>,
    /// Where a JPEG's quantiser rounds the sine away, from here to the
    /// curve's end (cycles/pixel): the MTF there is the file's, not the lens's.
    pub rounded_away_from_cy_px: Option<f64>,
    /// Fraction of the region's samples at clipping.
    pub clipped_fraction: f64,
    /// Image corners of the binned region.
    pub region_px: [Point; 4],
    /// The binned region's outline in the photo (a closed polyline, px) when
    /// a lens model bends its long edges; empty when they are straight (the
    /// quad `region_px` is the outline then). Drawn in the region picture and
    /// the GUI; not in the summary.
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub outline_px: Vec<Point>,
    /// The bands of paper read for a tone curve's black level
    /// ([`super::tone_black`]), each a closed outline in the photo (px);
    /// empty where none were read. Drawn in the region picture and the GUI;
    /// not in the summary.
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub paper_bands_px: Vec<Vec<Point>>,
    /// Image segment across the strip where aliasing starts.
    pub alias_line_px: Option<[Point; 2]>,
    /// Image segment across the strip at the lowest and highest measured points.
    pub measured_lines_px: [[Point; 2]; 2],
    /// How far inside the region's low- and high-frequency ends the printed
    /// sweep was found to stop (image px; its bins beyond were left out),
    /// None where it runs to the end ([`super::sweep_end`]).
    pub print_ends_inside_px: [Option<f64>; 2],
    /// The camera tone curve found in the strip's shape, if it was looked for
    /// ([`super::sine_tone`]); in the summary JSON as `tone_correction`.
    #[serde(skip)]
    pub tone_fix: Option<super::sine_tone::ToneFix>,
}

/// A small RGB picture of the measured area, for the region plot.
#[derive(Debug, Clone, Default)]
pub struct Preview {
    /// Image x of the preview's left edge (pixels).
    pub x0: f64,
    /// Image y of the preview's top edge (pixels).
    pub y0: f64,
    /// Image pixels per preview pixel.
    pub scale: f64,
    /// Preview width.
    pub width: usize,
    /// Preview height.
    pub height: usize,
    /// RGB8 data, row-major.
    pub rgb: Vec<u8>,
}

/// The result of measuring one photo.
#[derive(Debug, Clone)]
pub struct Measurement {
    /// The photo (as given).
    pub source: String,
    /// Image width (pixels).
    pub image_width: usize,
    /// Image height (pixels).
    pub image_height: usize,
    /// Bits per sample of the file.
    pub bits: u32,
    /// Method used.
    pub method: Method,
    /// Description of the tone linearisation.
    pub tone: String,
    /// Raw Bayer greens: the gain the second green lattice was multiplied by
    /// to bring it to the first's level (Gb to Gr on RGGB), when balanced.
    pub green_gain: Option<f64>,
    /// Pixel pitch (mm), when known.
    pub pixel_pitch_mm: Option<f64>,
    /// The region corners used (image pixels).
    pub roi: [Point; 4],
    /// Sweep curves.
    pub curves: Vec<Curve>,
    /// Sine-patch results.
    pub patches: Vec<PatchResult>,
    /// Warnings: something may be wrong with the result (one line each).
    pub warnings: Vec<String>,
    /// Notes: what was done or assumed (one line each; the CLI shows them with `-v`).
    pub notes: Vec<String>,
    /// The lens distortion given or estimated (None: not looked for, e.g. with a target).
    pub distortion: Option<DistortionFound>,
    /// Picture of the measured area.
    pub preview: Preview,
    /// Colour moiré (R−B spread) of each sweep measured in red and blue (`--channel all`; [`moire`]).
    pub colour_moire: Vec<moire::ColourMoire>,
}

/// Messages gathered around a measurement before its result exists: warnings
/// (something may be wrong with the result) and notes (what was done or assumed).
#[derive(Clone, Debug, Default)]
pub(crate) struct Said {
    /// Warnings, one line each.
    pub warnings: Vec<String>,
    /// Notes, one line each.
    pub notes: Vec<String>,
}

impl Said {
    /// Puts these messages before the measurement's own.
    pub(crate) fn put_before(self, m: &mut Measurement) {
        let Said {
            mut warnings,
            mut notes,
        } = self;
        warnings.append(&mut m.warnings);
        notes.append(&mut m.notes);
        m.warnings = warnings;
        m.notes = notes;
    }

    /// The failure `e` of a photo these messages say is damaged, with the
    /// damage named as its likely cause; `e` itself otherwise.
    pub(crate) fn blame(&self, e: MeasureError) -> MeasureError {
        match self.warnings.iter().find(|w| w.contains(DAMAGE_MARK)) {
            Some(w) => MeasureError {
                path: e.path,
                failure: Failure::Damaged {
                    failure: Box::new(e.failure),
                    damage: w.clone(),
                },
            },
            None => e,
        }
    }

    /// Adds these messages after the measurement's own.
    pub(crate) fn add_to(self, m: &mut Measurement) {
        m.warnings.extend(self.warnings);
        m.notes.extend(self.notes);
    }
}

/// The words every damaged-data warning carries (see [`Said::blame`]).
pub(crate) const DAMAGE_MARK: &str = "scan data";
