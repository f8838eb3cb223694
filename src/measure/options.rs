//! What a measurement is asked to do: [`MeasureOptions`] (the `measure`
//! flags as library values), the bounds it is held to, and their check.

use super::{Failure, Method};
use crate::distortion::Ptlens;
use crate::geometry::Point;
use crate::photo::linearise::Channel;
use serde::{Deserialize, Serialize};
use std::path::PathBuf;

/// Which sweep law to fit when no target description gives it.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize, Default)]
#[serde(rename_all = "lowercase")]
pub enum SweepChoice {
    /// Try linear and log, keep the better fit.
    #[default]
    Auto,
    /// Linear sweep.
    Linear,
    /// Logarithmic sweep.
    Log,
}

/// Options of a measurement (the CLI's flags, ready to use).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(default)]
pub struct MeasureOptions {
    /// Region corners in image pixels: one strip (without a target) or the whole target frame (with one).
    pub roi: Option<[Point; 4]>,
    /// Target description file (chart TOML or sineMTF tgt.txt).
    pub target: Option<PathBuf>,
    /// Modulation estimator.
    pub method: Method,
    /// Sweep law to fit without a target.
    pub sweep: SweepChoice,
    /// Power-law tone (`--gamma`); None = the default for the bit depth.
    pub gamma: Option<f64>,
    /// Tone curve from the target's grey patches (`--tone chart`).
    pub tone_chart: bool,
    /// Without `--gamma` or `--tone chart`: a camera's own tone curve on top
    /// of the file's is found from each strip's low-frequency periods and
    /// taken out ([`super::sine_tone`]; off: `--tone file`).
    pub tone_from_strip: bool,
    /// Channel(s) to measure.
    pub channel: Channel,
    /// Pixel pitch (mm), when known, for cycles/mm on the sensor.
    pub pixel_pitch_mm: Option<f64>,
    /// Bin width (pixels).
    pub bin_px: f64,
    /// Fraction of the strip width left out along each long edge.
    pub margin: f64,
    /// Estimator window (cycles).
    pub window_cycles: f64,
    /// Which chart to measure when automatic location finds several (0 = leftmost).
    pub chart_index: Option<usize>,
    /// Refine the given `roi` corners to the region's edges (corners good to about
    /// ±[`REFINE_SEARCH_PX`]); when the edges are not clearly seen, the corners are
    /// used as given, with a warning; a strip whose bars are seen clearly but
    /// slanted across its given ends farther than refining may turn them is
    /// refused ([`Failure::Unreliable`](super::Failure::Unreliable)).
    pub refine_roi: bool,
    /// Raw Bayer files: scale the second green lattice to the first's level
    /// before binning the greens together ([`crate::photo::raw::balance_greens`]).
    pub green_balance: bool,
    /// The lens's radial distortion, when known (PTLens a, b, c as Lensfun
    /// publishes them; [`crate::distortion`]). Photo corners are undistorted
    /// before the strip's homography and every pixel centre is binned
    /// through the model.
    pub distortion: Option<Ptlens>,
    /// Without `distortion`: estimate it from the strip's straight long edges
    /// ([`lens_fit`](super::lens_fit)) and use it only when the evidence is clear (default on;
    /// off measures as without distortion).
    pub estimate_distortion: bool,
    /// Look for where the printed sweep stops inside the region and leave
    /// the bins beyond out ([`super::sweep_end`]; default on; off keeps every
    /// bin up to the region's ends, as before session 35).
    pub find_print_ends: bool,
    /// Most sample lines binned across a strip (rows for a sweep along the
    /// rows, columns for one down them): a strip taller across is binned
    /// from evenly spaced lines, every k-th (k odd); 0 bins every line.
    pub max_across: usize,
}

/// [`MeasureOptions::max_across`]'s default. On the 24 MP speed check's
/// 5200 × 1700 px strip (1190 rows inside its margins, so every third
/// row): the whole measurement 1.52–1.56× → 1.35–1.38× djpeg (two
/// interleaved runs), the points' median `mtf_err` 0.00051 → 0.00060, MTF
/// moved by 0.0002 RMS;
/// strips up to 512 px across inside their margins are binned whole.
pub const MAX_ACROSS: usize = 512;

/// Quality gate: least strip width inside the margins (px) for a curve.
pub const MIN_ACROSS_PX: f64 = 3.0;
/// Quality gate: largest RMS phase residual of the fitted sweep law (cycles).
pub const MAX_LAW_RMS_CYCLES: f64 = 0.15;
/// Quality gate: largest relative uncertainty of an extrapolated chart modulation.
pub const MAX_CHART_REL_ERR: f64 = 0.03;

/// How far (px) `refine_roi` searches around each given corner.
pub const REFINE_SEARCH_PX: f64 = 8.0;

impl Default for MeasureOptions {
    fn default() -> Self {
        MeasureOptions {
            roi: None,
            target: None,
            method: Method::Fit,
            sweep: SweepChoice::Auto,
            gamma: None,
            tone_chart: false,
            tone_from_strip: true,
            channel: Channel::Luma,
            pixel_pitch_mm: None,
            bin_px: 0.25,
            margin: 0.15,
            window_cycles: 4.0,
            chart_index: None,
            refine_roi: false,
            green_balance: true,
            distortion: None,
            estimate_distortion: true,
            find_print_ends: true,
            max_across: MAX_ACROSS,
        }
    }
}

/// Checks the advanced options' ranges (bin width, margin, window, gamma, pixel pitch).
pub(super) fn check_options(o: &MeasureOptions) -> Result<(), Failure> {
    let bad = |m: String| Err(Failure::Options(m));
    if !(o.bin_px > 0.0 && o.bin_px <= 2.0) {
        return bad(format!("bin width {} px must be in (0, 2]", o.bin_px));
    }
    if !(0.0..=0.45).contains(&o.margin) {
        return bad(format!("margin {} must be in [0, 0.45]", o.margin));
    }
    if !(o.window_cycles >= 1.0 && o.window_cycles <= 64.0) {
        return bad(format!(
            "window {} cycles must be in [1, 64]",
            o.window_cycles
        ));
    }
    if let Some(g) = o.gamma
        && !(g > 0.0 && g <= 10.0)
    {
        return bad(format!("gamma {g} must be in (0, 10]"));
    }
    if let Some(p) = o.pixel_pitch_mm
        && !(p > 0.0 && p.is_finite())
    {
        return bad("pixel pitch must be positive".into());
    }
    Ok(())
}
