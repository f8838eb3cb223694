//! Measurement of MTF from a photo of a sine chart: the region (`--roi`, with
//! or without a target description) → [`profile`] binning without resampling
//! → phase-law fit ([`law`]) → modulation ([`estimate`]) → MTF curve with
//! aliasing flags, normalisation and summary figures ([`curve`]); sine-patch
//! targets give one result per patch ([`patches`]).
//!
//! Entry points: [`measure_file`] (decode + measure; safe to call from many
//! threads), [`measure_bytes`] (the same for a file's bytes in memory), [`measure_decoded`] and [`measure_planes`] (for planes that
//! another decoder, e.g. camera raw, produced).

#![allow(clippy::needless_range_loop, clippy::neg_cmp_op_on_partial_ord)]

use crate::distortion::{Lens, Ptlens};
use crate::geometry::Point;
use crate::photo::Plane;
use crate::photo::decode::{DecodeError, Decoded, decode_file};
use crate::photo::linearise::{Channel, Crop, file_tone, planes};
use crate::target::{Target, TargetError};
use serde::{Deserialize, Serialize};
use std::path::{Path, PathBuf};
use thiserror::Error;

pub mod chart_mtf;
pub mod curve;
pub mod estimate;
pub mod figures;
pub mod in_memory;
pub mod law;
pub mod lens_fit;
pub mod lens_mtf;
pub mod model_overlay;
pub mod patches;
pub mod profile;
pub mod synth;

mod frame;
mod frequency;
mod normalise;
mod preview;
mod region;
mod strip;
mod tone;

pub use curve::{Figures, MtfPoint};
pub use estimate::Method;
pub use law::{LawKind, PhaseLaw};
pub use lens_fit::{DistortionFound, DistortionSource};
pub use patches::PatchResult;
pub use region::{rect_strip, target_homography};

use frame::{
    decode_bytes_with_pitch, decode_with_pitch, measure_decoded_at, measure_frame_at, read_photo,
};
use profile::BinOptions;
use region::{
    bbox_crop, found_said, full_grey, grey_source, locate_region, location_failed, raw_read_window,
    refine_or_keep, resolve_roi, strips,
};
use strip::measure_strip;
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
    /// used as given, with a warning.
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
    /// ([`lens_fit`]) and use it only when the evidence is clear (default on;
    /// off measures as without distortion).
    pub estimate_distortion: bool,
}

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
        }
    }
}

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
    /// Fraction of the region's samples at clipping.
    pub clipped_fraction: f64,
    /// Image corners of the binned region.
    pub region_px: [Point; 4],
    /// Image segment across the strip where aliasing starts.
    pub alias_line_px: Option<[Point; 2]>,
    /// Image segment across the strip at the lowest and highest measured points.
    pub measured_lines_px: [[Point; 2]; 2],
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

/// Decodes a photo and measures it.
pub fn measure_file(path: &Path, opts: &MeasureOptions) -> Result<Measurement, MeasureError> {
    let name = path.display().to_string();
    let target = load_target(opts).map_err(|f| MeasureError {
        path: name.clone(),
        failure: f,
    })?;
    if crate::photo::raw::is_raw_path(path) {
        return measure_raw(path, &name, target.as_ref(), opts);
    }
    // The compressed bytes are dropped once decoded (EXIF and the scan check
    // read them first): a 24 MP JPEG's ≈ 10 MB need not live through the measurement.
    let bytes = read_photo(path, &name)?;
    let decoded = decode_bytes_with_pitch(&bytes, &name, opts)?;
    drop(bytes);
    measure_said(decoded, &name, target.as_ref())
}

/// Measures a decoded photo with its resolved options and what decoding said.
fn measure_said(
    (dec, o, said): (Decoded, MeasureOptions, Said),
    name: &str,
    target: Option<&Target>,
) -> Result<Measurement, MeasureError> {
    let mut m = measure_decoded(&dec, name, target, &o).map_err(|e| said.blame(e))?;
    said.add_to(&mut m);
    Ok(m)
}

/// Measures a photo file (JPEG, PNG or TIFF, not a raw) whose bytes are
/// already in memory, exactly as [`measure_file`] measures it from disk
/// (same decoding, EXIF pixel pitch and warnings); `name` is used in
/// messages and the outputs, `target` stands for `opts.target`.
pub fn measure_bytes(
    bytes: &[u8],
    name: &str,
    target: Option<&Target>,
    opts: &MeasureOptions,
) -> Result<Measurement, MeasureError> {
    measure_said(decode_bytes_with_pitch(bytes, name, opts)?, name, target)
}

/// Decodes a photo and measures every chart in it: with `--target` and
/// neither a region nor a chart index, each chart found from the fiducials
/// (left to right; the photo is decoded and searched once); otherwise the
/// one [`measure_file`] measures.
pub fn measure_file_each(
    path: &Path,
    opts: &MeasureOptions,
) -> Result<Vec<Measurement>, MeasureError> {
    if opts.roi.is_some() || opts.chart_index.is_some() || opts.target.is_none() {
        return measure_file(path, opts).map(|m| vec![m]);
    }
    let name = path.display().to_string();
    let err = |failure: Failure| MeasureError {
        path: name.clone(),
        failure,
    };
    let target = load_target(opts).map_err(err)?.ok_or(err(Failure::NoRoi))?;
    check_options(opts).map_err(err)?;
    let found = |r: Result<_, _>| r.map_err(|e| err(location_failed(e)));
    if crate::photo::raw::is_raw_path(path) {
        let frame =
            crate::photo::raw::decode_raw(path).map_err(|e| err(Failure::Raw(e.to_string())))?;
        let charts = found(crate::locate::find_charts(&frame.location_plane(), &target))?;
        let n = charts.len();
        return charts
            .iter()
            .enumerate()
            .map(|(i, c)| {
                let w = found_said(c, i, n);
                let m = measure_frame_at(&frame, &name, Some(&target), opts, &c.corners_px, w)?;
                Ok(name_chart(m, i, n))
            })
            .collect();
    }
    let (dec, o, said) = decode_with_pitch(path, &name, opts)?;
    let charts = found(crate::locate::find_charts(&grey_source(&dec), &target))
        .map_err(|e| said.blame(e))?;
    let n = charts.len();
    charts
        .iter()
        .enumerate()
        .map(|(i, c)| {
            let w = found_said(c, i, n);
            let mut m = measure_decoded_at(&dec, &name, Some(&target), &o, &c.corners_px, None, w)
                .map_err(|e| said.blame(e))?;
            said.clone().add_to(&mut m);
            Ok(name_chart(m, i, n))
        })
        .collect()
}

/// With several charts, the measurement's source names its chart: "photo.jpg [chart 1]".
fn name_chart(mut m: Measurement, i: usize, n: usize) -> Measurement {
    if n > 1 {
        m.source = format!("{} [chart {i}]", m.source);
    }
    m
}

/// Measures a camera raw file: linear CFA planes, no demosaicing, no tone curve.
///
/// The region is `--roi` (stored-sensor-frame pixels), or found from the
/// target's fiducials on a green lattice when only a target is given. Only
/// the region's rows are converted to f32 (no whole-frame copy).
pub fn measure_raw(
    path: &Path,
    name: &str,
    target: Option<&Target>,
    opts: &MeasureOptions,
) -> Result<Measurement, MeasureError> {
    use crate::photo::raw::decode_raw_within;
    let err = |failure: Failure| MeasureError {
        path: name.to_string(),
        failure,
    };
    check_options(opts).map_err(err)?;
    // With corners given, only what the region, its refinement search and its
    // preview read is decoded (DNGs are read windowed; see `decode_raw_within`).
    let want = opts.roi.map(|r| {
        let c = raw_read_window(&r);
        (c.x0, c.y0, c.x1, c.y1)
    });
    let frame = decode_raw_within(path, want).map_err(|e| err(Failure::Raw(e.to_string())))?;
    let mut said = Said::default();
    let roi = match (opts.roi, target) {
        // No region but a target: find the chart from its fiducials.
        (None, Some(t)) => {
            locate_region(&frame.location_plane(), t, opts, &mut said).map_err(err)?
        }
        _ => {
            let given = resolve_roi(opts, frame.width, frame.height).map_err(err)?;
            if opts.refine_roi {
                // Only the region and the search band around it are converted.
                let c = bbox_crop(&given, frame.width, frame.height, REFINE_SEARCH_PX + 8.0);
                let plane = frame.location_plane_within((c.x0, c.y0, c.x1, c.y1));
                refine_or_keep(&plane, given, target, &mut said)
            } else {
                given
            }
        }
    };
    measure_frame_at(&frame, name, target, opts, &roi, said)
}

/// Reads the target description named in the options, if any.
pub fn load_target(opts: &MeasureOptions) -> Result<Option<Target>, Failure> {
    match &opts.target {
        Some(p) => Ok(Some(Target::load(p)?)),
        None => Ok(None),
    }
}

/// The picture of what automatic location saw (candidate marks, charts found) in a
/// photo, for `STEM.roi.png` when no chart was found; `None` when it cannot be made.
pub fn location_picture(path: &Path, opts: &MeasureOptions) -> Option<image::RgbImage> {
    let target = load_target(opts).ok()??;
    let dec = decode_file(path).ok()?;
    let grey = full_grey(&dec);
    let (candidates, charts) = match crate::locate::search(&grey[0], &target) {
        Ok(seen) => (seen.candidates, seen.charts),
        Err(crate::locate::LocateError::NotFound { candidates, .. }) => (candidates, Vec::new()),
        Err(_) => return None,
    };
    Some(crate::locate::debug_image(&grey[0], &candidates, &charts))
}

/// Measures a decoded photo; `name` is used in messages.
pub fn measure_decoded(
    dec: &Decoded,
    name: &str,
    target: Option<&Target>,
    opts: &MeasureOptions,
) -> Result<Measurement, MeasureError> {
    let err = |failure: Failure| MeasureError {
        path: name.to_string(),
        failure,
    };
    check_options(opts).map_err(err)?;
    let mut said = Said::default();
    // The luminance plane refinement converted, kept for the measurement when it can serve.
    let mut seen: Option<(Crop, Plane)> = None;
    let roi = match (opts.roi, target) {
        // No region but a target: find the chart from its fiducials.
        (None, Some(t)) => locate_region(&grey_source(dec), t, opts, &mut said).map_err(err)?,
        _ => {
            let given = resolve_roi(opts, dec.width, dec.height).map_err(err)?;
            if opts.refine_roi {
                // Only the region and the search band around it are converted.
                let crop = bbox_crop(&given, dec.width, dec.height, REFINE_SEARCH_PX + 8.0);
                let grey = planes(dec, crop, &file_tone(dec).0, Channel::Luma);
                let refined = refine_or_keep(&grey[0], given, target, &mut said);
                seen = grey.into_iter().next().map(|p| (crop, p));
                refined
            } else {
                given
            }
        }
    };
    measure_decoded_at(dec, name, target, opts, &roi, seen, said)
}

/// Checks the advanced options' ranges (bin width, margin, window, gamma, pixel pitch).
fn check_options(o: &MeasureOptions) -> Result<(), Failure> {
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

/// Measures linear planes of an image of `size` (w, h) pixels: one group per
/// channel, (name, planes binned together — e.g. both green sites of a Bayer
/// mosaic). A sample at or above `clip_level` counts as clipped.
pub fn measure_planes(
    groups: &[(&str, Vec<Plane>)],
    size: (usize, usize),
    roi: &[Point; 4],
    target: Option<&Target>,
    opts: &MeasureOptions,
    clip_level: f32,
) -> Result<Measurement, Failure> {
    let distortion = given_distortion(opts, roi, size.0, size.1)?;
    measure_planes_lens(groups, size, roi, target, opts, clip_level, distortion)
}

/// The distortion the user gave, checked against the image size (exit 2 with the allowed range).
fn given_distortion(
    opts: &MeasureOptions,
    roi: &[Point; 4],
    width: usize,
    height: usize,
) -> Result<Option<DistortionFound>, Failure> {
    let Some(model) = opts.distortion.filter(|d| !d.is_zero()) else {
        return Ok(None);
    };
    Lens::new(model, width, height)
        .check()
        .map_err(Failure::Options)?;
    Ok(Some(lens_fit::given(model, roi, width, height)))
}

/// The distortion of a shot: as given, or estimated from the strip's edges in
/// `luma` (a plane reaching [`lens_fit::search_pad_px`] beyond the region),
/// or none (with a target, or when estimating is off).
fn resolve_distortion(
    opts: &MeasureOptions,
    roi: &[Point; 4],
    target: Option<&Target>,
    size: (usize, usize),
    luma: impl FnOnce() -> Plane,
) -> Result<Option<DistortionFound>, Failure> {
    if opts.distortion.is_some() {
        return given_distortion(opts, roi, size.0, size.1);
    }
    if !opts.estimate_distortion || target.is_some() {
        return Ok(None);
    }
    Ok(Some(lens_fit::estimate(&luma(), roi, size.0, size.1)))
}

/// [`measure_planes`] with the distortion already resolved.
fn measure_planes_lens(
    groups: &[(&str, Vec<Plane>)],
    size: (usize, usize),
    roi: &[Point; 4],
    target: Option<&Target>,
    opts: &MeasureOptions,
    clip_level: f32,
    distortion: Option<DistortionFound>,
) -> Result<Measurement, Failure> {
    let mut warnings = Vec::new();
    let mut notes = Vec::new();
    let lens = distortion.and_then(|d| d.lens(size.0, size.1));
    if let Some(d) = &distortion {
        notes.push(d.note());
    }
    let specs = strips(roi, target, lens.as_ref())?;
    let mut curves = Vec::new();
    let mut patch_rows = Vec::new();
    let bin_opts = BinOptions {
        bin_px: opts.bin_px,
        margin: opts.margin,
        end_px: 1.0,
        clip_level,
    };
    for (name, group) in groups {
        let plane_refs: Vec<&Plane> = group.iter().collect();
        if plane_refs.is_empty() {
            continue;
        }
        for (id, strip, tlaw, contrast) in &specs {
            let c = measure_strip(
                &plane_refs,
                name,
                id,
                strip,
                *tlaw,
                *contrast,
                opts,
                &bin_opts,
            )?;
            if c.clipped_fraction > 0.0 {
                warnings.push(format!(
                    "{name}/{id}: {:.2} % of the region's samples are clipped",
                    100.0 * c.clipped_fraction
                ));
            }
            if c.chart_modulation_source.starts_with("extrapolated") {
                warnings.push(format!(
                    "{name}/{id}: chart modulation {:.4} {}",
                    c.chart_modulation, c.chart_modulation_source
                ));
            }
            curves.push(c);
        }
        if let Some(t) = target
            && !t.patches.is_empty()
        {
            let h = target_homography(t, roi)?;
            patch_rows.extend(patches::measure_patches(
                &plane_refs,
                name,
                &h,
                t,
                &bin_opts,
            ));
        }
    }
    if curves.is_empty() && patch_rows.is_empty() {
        return Err(Failure::Options(
            "the target describes neither sweeps nor sine patches".into(),
        ));
    }
    Ok(Measurement {
        source: String::new(),
        image_width: size.0,
        image_height: size.1,
        bits: 0,
        method: opts.method,
        tone: String::new(),
        green_gain: None,
        pixel_pitch_mm: opts.pixel_pitch_mm,
        roi: *roi,
        curves,
        patches: patch_rows,
        warnings,
        notes,
        distortion,
        preview: Preview::default(),
    })
}
