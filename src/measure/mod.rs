//! Measurement of MTF from a photo of a sine chart: the region (`--roi`, with
//! or without a target description) → [`profile`] binning without resampling
//! → phase-law fit ([`law`]) → modulation ([`estimate`]) → MTF curve with
//! aliasing flags, normalisation and summary figures ([`curve`]); sine-patch
//! targets give one result per patch ([`patches`]).
//!
//! Entry points: [`measure_file`] (decode + measure; safe to call from many
//! threads), [`measure_decoded`] and [`measure_planes`] (for planes that
//! another decoder, e.g. camera raw, produced).

#![allow(clippy::needless_range_loop, clippy::neg_cmp_op_on_partial_ord)]

use crate::geometry::{GeometryError, Homography, Point, check_quad, rect_corners};
use crate::photo::Plane;
use crate::photo::decode::{DecodeError, Decoded, Samples, decode_bytes, decode_file};
use crate::photo::linearise::{
    Channel, Crop, Tone, ToneCurve, default_tone, plane_names, planes, planes_within,
};
use crate::target::{Direction, Sweep, SweepLaw, Target, TargetError};
use rayon::prelude::*;
use serde::{Deserialize, Serialize};
use std::path::{Path, PathBuf};
use thiserror::Error;

pub mod curve;
pub mod estimate;
pub mod law;
pub mod model_overlay;
pub mod patches;
pub mod profile;
pub mod synth;

pub use curve::{Figures, MtfPoint};
pub use estimate::Method;
pub use law::{LawKind, PhaseLaw};
pub use patches::PatchResult;

use estimate::fit::{PhaseTable, local_fit};
use profile::{BinOptions, Profile, Strip, bin_plane, bin_planes};

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
}

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
    /// Points in increasing frequency.
    pub points: Vec<MtfPoint>,
    /// Chart modulation used for normalisation.
    pub chart_modulation: f64,
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
    /// Picture of the measured area.
    pub preview: Preview,
}

/// Refuse when more than this fraction of the region is clipped.
const CLIP_REFUSE: f64 = 0.02;

/// Decodes a photo and measures it.
pub fn measure_file(path: &Path, opts: &MeasureOptions) -> Result<Measurement, MeasureError> {
    let name = path.display().to_string();
    let target = load_target(opts).map_err(|f| MeasureError {
        path: name.clone(),
        failure: f,
    })?;
    let located = opts.roi.is_none() && target.is_some();
    if crate::photo::raw::is_raw_path(path) {
        let mut m = measure_raw(path, &name, target.as_ref(), opts)?;
        if located {
            m.notes.insert(0, FOUND_NOTE.into());
        }
        return Ok(m);
    }
    let (dec, o, pitch_warnings, pitch_notes) = decode_with_pitch(path, &name, opts)?;
    let mut m = measure_decoded(&dec, &name, target.as_ref(), &o)?;
    m.warnings.extend(pitch_warnings);
    if located {
        m.notes.insert(0, FOUND_NOTE.into());
    }
    m.notes.extend(pitch_notes);
    Ok(m)
}

/// The note of a region found from the target's fiducials.
const FOUND_NOTE: &str = "region found automatically from the target's fiducials";

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
    let located = |plane: &Plane| {
        crate::locate::find_charts(plane, &target).map_err(|e| err(location_failed(e)))
    };
    if crate::photo::raw::is_raw_path(path) {
        let frame =
            crate::photo::raw::decode_raw(path).map_err(|e| err(Failure::Raw(e.to_string())))?;
        let charts = located(&frame.location_plane())?;
        let n = charts.len();
        return charts
            .iter()
            .enumerate()
            .map(|(i, c)| {
                let w = found_warnings(c, i, n);
                let mut m = measure_frame_at(&frame, &name, Some(&target), opts, &c.corners_px, w)?;
                m.notes.splice(0..0, found_notes(i, n));
                Ok(name_chart(m, i, n))
            })
            .collect();
    }
    let (dec, o, pitch_warnings, pitch_notes) = decode_with_pitch(path, &name, opts)?;
    let charts = located(&full_grey(&dec)[0])?;
    let n = charts.len();
    charts
        .iter()
        .enumerate()
        .map(|(i, c)| {
            let w = found_warnings(c, i, n);
            let mut m = measure_decoded_at(&dec, &name, Some(&target), &o, &c.corners_px, None, w)?;
            m.warnings.extend(pitch_warnings.iter().cloned());
            m.notes.splice(0..0, found_notes(i, n));
            m.notes.extend(pitch_notes.iter().cloned());
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

/// The chart `opts.chart_index` picks in `plane` (see [`crate::locate::find_chart`]):
/// its corners (image px), the search's warnings added to `warnings`.
fn locate_region(
    plane: &Plane,
    target: &Target,
    opts: &MeasureOptions,
    warnings: &mut Vec<String>,
) -> Result<[Point; 4], Failure> {
    let loc =
        crate::locate::find_chart(plane, target, opts.chart_index).map_err(location_failed)?;
    warnings.extend(found_warnings(&loc, 0, 1));
    Ok(loc.corners_px)
}

/// The failure of automatic location.
fn location_failed(e: crate::locate::LocateError) -> Failure {
    Failure::Region(format!("automatic location failed: {e}"))
}

/// The warnings of a chart found automatically: the search's own.
fn found_warnings(c: &crate::locate::Located, _i: usize, _n: usize) -> Vec<String> {
    c.warnings.clone()
}

/// The notes of chart `i` of `n` found automatically: how it was found and,
/// with several, which one (left to right) it is.
fn found_notes(i: usize, n: usize) -> Vec<String> {
    let mut notes = vec![FOUND_NOTE.to_string()];
    if n > 1 {
        notes.push(format!("chart index {i} of the {n} found (left to right)"));
    }
    notes
}

/// Reads and decodes a photo (not a raw), and resolves its pixel pitch from
/// EXIF and the options: the photo, the options with the pitch, the
/// warnings (the pitch's, damaged JPEG scan data) and the pitch's notes.
#[allow(clippy::type_complexity)]
fn decode_with_pitch(
    path: &Path,
    name: &str,
    opts: &MeasureOptions,
) -> Result<(Decoded, MeasureOptions, Vec<String>, Vec<String>), MeasureError> {
    let name = name.to_string();
    let bytes = std::fs::read(path).map_err(|source| MeasureError {
        path: name.clone(),
        failure: DecodeError::Io {
            path: name.clone(),
            source,
        }
        .into(),
    })?;
    let dec = decode_bytes(&bytes, &name).map_err(|e| MeasureError {
        path: name.clone(),
        failure: e.into(),
    })?;
    let facts = crate::photo::exif::facts_from_bytes(&bytes);
    let damage = crate::photo::jpeg_check::scan_damage(&bytes);
    drop(bytes);
    let mut pitch =
        crate::photo::pitch::resolve(&facts, dec.width, dec.height, opts.pixel_pitch_mm);
    if let Some(d) = damage {
        pitch.warnings.insert(
            0,
            format!("damaged JPEG scan data ({d}): the picture may be partly grey"),
        );
    }
    let o = MeasureOptions {
        pixel_pitch_mm: pitch.pitch_mm,
        ..opts.clone()
    };
    Ok((dec, o, pitch.warnings, pitch.notes))
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
    let mut warnings = Vec::new();
    let roi = match (opts.roi, target) {
        // No region but a target: find the chart from its fiducials.
        (None, Some(t)) => {
            locate_region(&frame.location_plane(), t, opts, &mut warnings).map_err(err)?
        }
        _ => {
            let given = resolve_roi(opts, frame.width, frame.height).map_err(err)?;
            if opts.refine_roi {
                // Only the region and the search band around it are converted.
                let c = bbox_crop(&given, frame.width, frame.height, REFINE_SEARCH_PX + 8.0);
                let plane = frame.location_plane_within((c.x0, c.y0, c.x1, c.y1));
                refine_or_keep(&plane, given, target, &mut warnings)
            } else {
                given
            }
        }
    };
    measure_frame_at(&frame, name, target, opts, &roi, warnings)
}

/// The part of [`measure_raw`] after the region is known: `roi` (frame px)
/// and the warnings so far.
fn measure_frame_at(
    frame: &crate::photo::raw::RawFrame,
    name: &str,
    target: Option<&Target>,
    opts: &MeasureOptions,
    roi: &[Point; 4],
    mut warnings: Vec<String>,
) -> Result<Measurement, MeasureError> {
    use crate::photo::raw::RawChannel;
    let err = |failure: Failure| MeasureError {
        path: name.to_string(),
        failure,
    };
    let roi = *roi;
    if let Some(o) = frame.facts.orientation.filter(|&o| o != 1) {
        warnings.push(format!(
            "raw file with EXIF orientation {o}: region and plots are in the stored sensor frame ({}×{} px, not turned)",
            frame.width, frame.height
        ));
    }
    let rc = match opts.channel {
        Channel::Luma => {
            warnings.push(
                "raw file: measuring the green sites (luminance would need demosaicing); \
                 use --channel r, g, b or all to choose"
                    .to_string(),
            );
            RawChannel::G
        }
        Channel::R => RawChannel::R,
        Channel::G => RawChannel::G,
        Channel::B => RawChannel::B,
        Channel::All => RawChannel::All,
    };
    if opts.gamma.is_some() || opts.tone_chart {
        warnings.push("raw data is linear: --gamma and --tone are ignored".to_string());
    }
    // Only what binning reads is converted to f32.
    let (crop, span) =
        read_set(&roi, target, opts.margin, frame.width, frame.height).map_err(err)?;
    let mut groups = frame.channel_groups_within(rc, (crop.x0, crop.y0, crop.x1, crop.y1), &span);
    let (greens, green_gain) = if opts.green_balance {
        balance_green_group(frame, &mut groups, RAW_CLIP)
    } else {
        (
            "; greens as recorded (--no-green-balance)".to_string(),
            None,
        )
    };
    let pitch =
        crate::photo::pitch::resolve(&frame.facts, frame.width, frame.height, opts.pixel_pitch_mm);
    let o = MeasureOptions {
        pixel_pitch_mm: pitch.pitch_mm,
        ..opts.clone()
    };
    let mut m = measure_planes(
        &groups,
        (frame.width, frame.height),
        &roi,
        target,
        &o,
        RAW_CLIP,
    )
    .map_err(err)?;
    drop(groups);
    m.preview = raw_preview(frame, &roi);
    m.source = name.to_string();
    m.bits = frame.bits_per_sample as u32;
    m.tone = format!("linear raw (black level removed, white level = 1{greens})");
    m.green_gain = green_gain;
    warnings.extend(pitch.warnings);
    warnings.append(&mut m.warnings);
    m.warnings = warnings;
    m.notes.extend(pitch.notes);
    Ok(m)
}

/// Linear raw level at and above which a sample counts as clipped (white = 1).
const RAW_CLIP: f32 = 0.9999;

/// Brings the second green lattice of a Bayer mosaic's green group to the
/// first's level ([`crate::photo::raw::balance_greens`]); returns what the
/// summary's tone line says about it ("" when nothing was balanced) and the gain.
fn balance_green_group(
    frame: &crate::photo::raw::RawFrame,
    groups: &mut [(&'static str, Vec<Plane>)],
    clip: f32,
) -> (String, Option<f64>) {
    let (Some(cfa), Some((_, planes))) = (&frame.cfa, groups.iter_mut().find(|g| g.0 == "g"))
    else {
        return (String::new(), None);
    };
    let [first, second] = planes.as_mut_slice() else {
        return (String::new(), None);
    };
    let Some(b) = crate::photo::raw::balance_greens(first, second, clip) else {
        return (String::new(), None);
    };
    let (w, h) = cfa.size();
    let name = |p: &Plane| crate::photo::raw::green_name(cfa, (p.offset.0 % w, p.offset.1 % h));
    let line = format!(
        "; {} × {:.4} to {}'s level, from {} sites",
        name(second),
        b.gain,
        name(first),
        b.sites
    );
    (line, Some(b.gain))
}

/// The image rectangle a raw measurement with the corners `roi` reads (frame
/// pixels, unclamped): the corners' bounding box padded by the refinement's
/// reach (moves of up to √2·search + 2 px plus a strip's inward trim, and the
/// search band around the moved edges) and by the preview's context (as in
/// [`preview_from`], from the corners as refined, so with some slack).
fn raw_read_window(roi: &[Point; 4]) -> Crop {
    let xmin = roi.iter().map(|p| p[0]).fold(f64::INFINITY, f64::min);
    let xmax = roi.iter().map(|p| p[0]).fold(f64::NEG_INFINITY, f64::max);
    let ymin = roi.iter().map(|p| p[1]).fold(f64::INFINITY, f64::min);
    let ymax = roi.iter().map(|p| p[1]).fold(f64::NEG_INFINITY, f64::max);
    let reach = 4.0 * REFINE_SEARCH_PX + 16.0;
    let pad = 0.08 * ((xmax - xmin).max(ymax - ymin) + 2.0 * reach) + 8.0 + reach;
    let lo = |v: f64| (v - pad).floor().max(0.0) as usize;
    let hi = |v: f64| (v + pad).ceil().clamp(0.0, usize::MAX as f64) as usize;
    Crop {
        x0: lo(xmin),
        y0: lo(ymin),
        x1: hi(xmax),
        y1: hi(ymax),
    }
}

/// The given corners refined to the edges seen in `plane`, or as given (with
/// a warning saying why) when the edges are not clearly seen.
fn refine_or_keep(
    plane: &Plane,
    given: [Point; 4],
    target: Option<&Target>,
    warnings: &mut Vec<String>,
) -> [Point; 4] {
    match crate::locate::refine_roi(plane, given, target, REFINE_SEARCH_PX) {
        Ok(refined) => {
            let moved = given
                .iter()
                .zip(&refined)
                .map(|(a, b)| (a[0] - b[0]).hypot(a[1] - b[1]))
                .fold(0.0, f64::max);
            warnings.push(format!(
                "region corners refined to the edges (moved up to {moved:.2} px)"
            ));
            refined
        }
        Err(e) => {
            warnings.push(format!("region corners used as given: {e}"));
            given
        }
    }
}

/// Reads the target description named in the options, if any.
pub fn load_target(opts: &MeasureOptions) -> Result<Option<Target>, Failure> {
    match &opts.target {
        Some(p) => Ok(Some(Target::load(p)?)),
        None => Ok(None),
    }
}

/// The whole photo as one linear luminance plane (default tone), for chart location.
fn full_grey(dec: &Decoded) -> Vec<Plane> {
    let full = Crop {
        x0: 0,
        y0: 0,
        x1: dec.width,
        y1: dec.height,
    };
    planes(dec, full, &default_tone(dec.bits()).0, Channel::Luma)
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
    let mut warnings = Vec::new();
    // The luminance plane refinement converted, kept for the measurement when it can serve.
    let mut seen: Option<(Crop, Plane)> = None;
    let roi = match (opts.roi, target) {
        // No region but a target: find the chart from its fiducials.
        (None, Some(t)) => {
            locate_region(&full_grey(dec)[0], t, opts, &mut warnings).map_err(err)?
        }
        _ => {
            let given = resolve_roi(opts, dec.width, dec.height).map_err(err)?;
            if opts.refine_roi {
                // Only the region and the search band around it are converted.
                let crop = bbox_crop(&given, dec.width, dec.height, REFINE_SEARCH_PX + 8.0);
                let grey = planes(dec, crop, &default_tone(dec.bits()).0, Channel::Luma);
                let refined = refine_or_keep(&grey[0], given, target, &mut warnings);
                seen = grey.into_iter().next().map(|p| (crop, p));
                refined
            } else {
                given
            }
        }
    };
    measure_decoded_at(dec, name, target, opts, &roi, seen, warnings)
}

/// The part of [`measure_decoded`] after the region is known: `roi` (image
/// px), the refinement's luminance plane `seen` (reused when it holds what
/// the measurement reads) and the warnings so far.
fn measure_decoded_at(
    dec: &Decoded,
    name: &str,
    target: Option<&Target>,
    opts: &MeasureOptions,
    roi: &[Point; 4],
    seen: Option<(Crop, Plane)>,
    mut warnings: Vec<String>,
) -> Result<Measurement, MeasureError> {
    let err = |failure: Failure| MeasureError {
        path: name.to_string(),
        failure,
    };
    let roi = *roi;
    let mut tone_note = None;
    // Crop: the region's bounding box (+2 px).
    let crop = bbox_crop(&roi, dec.width, dec.height, 2.0);
    let (tone, tone_desc) = if opts.tone_chart {
        let t = target.ok_or_else(|| {
            err(Failure::Options(
                "--tone chart needs --target with grey or density patches".into(),
            ))
        })?;
        let raw = planes(dec, crop, &Tone::Gamma(1.0), opts.channel);
        let curve = chart_tone(&raw[0], t, &roi).map_err(err)?;
        let n = curve.code.len();
        (
            Tone::Curve(curve),
            format!("tone curve from {n} grey levels of the target"),
        )
    } else if let Some(g) = opts.gamma {
        (Tone::Gamma(g), format!("power law, gamma {g}"))
    } else {
        let (t, notice) = default_tone(dec.bits());
        tone_note = notice;
        let d = match t {
            Tone::Srgb => "sRGB curve (8-bit default)".to_string(),
            _ => "linear (16-bit default)".to_string(),
        };
        (t, d)
    };
    let clip_level = (tone.apply(1.0) * 0.999) as f32;
    // Convert only what binning reads.
    let (crop, span) = read_set(&roi, target, opts.margin, dec.width, dec.height).map_err(err)?;
    // The refinement's plane already holds these samples when the measurement
    // wants default-tone luminance (or the photo is grey) inside its crop.
    let same_samples = !opts.tone_chart
        && opts.gamma.is_none()
        && (opts.channel == Channel::Luma || dec.channels == 1);
    let reuse = seen.filter(|(c, _)| {
        same_samples && c.x0 <= crop.x0 && c.y0 <= crop.y0 && c.x1 >= crop.x1 && c.y1 >= crop.y1
    });
    let (ps, preview) = match reuse {
        Some((_, plane)) => (vec![plane], make_preview(dec, &roi)),
        None => rayon::join(
            || planes_within(dec, crop, &tone, opts.channel, &span),
            || make_preview(dec, &roi),
        ),
    };
    let names = plane_names(opts.channel, dec.channels);
    let groups: Vec<(&str, Vec<Plane>)> = names
        .into_iter()
        .zip(ps.into_iter().map(|p| vec![p]))
        .collect();
    let mut m = measure_planes(
        &groups,
        (dec.width, dec.height),
        &roi,
        target,
        opts,
        clip_level,
    )
    .map_err(err)?;
    m.source = name.to_string();
    m.bits = dec.bits();
    m.tone = tone_desc;
    m.preview = preview;
    warnings.append(&mut m.warnings);
    m.warnings = warnings;
    m.notes.extend(tone_note);
    Ok(m)
}

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

fn resolve_roi(opts: &MeasureOptions, w: usize, h: usize) -> Result<[Point; 4], Failure> {
    // Without --target there is nothing to locate (measure_decoded calls `locate` when a target is given).
    let roi = opts.roi.ok_or(Failure::NoRoi)?;
    check_quad(&roi).map_err(|e| match e {
        GeometryError::SelfCrossing => {
            Failure::Region("the corners cross over; give them in order round the region".into())
        }
        other => Failure::Region(other.to_string()),
    })?;
    for (i, p) in roi.iter().enumerate() {
        if p[0] < 0.0 || p[1] < 0.0 || p[0] > w as f64 || p[1] > h as f64 {
            return Err(Failure::Region(format!(
                "corner {} ({}, {}) lies outside the {w}×{h} image",
                i + 1,
                p[0],
                p[1]
            )));
        }
    }
    Ok(roi)
}

fn bbox_crop(q: &[Point; 4], w: usize, h: usize, pad: f64) -> Crop {
    let xmin = q.iter().map(|p| p[0]).fold(f64::INFINITY, f64::min) - pad;
    let xmax = q.iter().map(|p| p[0]).fold(f64::NEG_INFINITY, f64::max) + pad;
    let ymin = q.iter().map(|p| p[1]).fold(f64::INFINITY, f64::min) - pad;
    let ymax = q.iter().map(|p| p[1]).fold(f64::NEG_INFINITY, f64::max) + pad;
    let x0 = (xmin.floor().max(0.0) as usize).min(w - 1);
    let y0 = (ymin.floor().max(0.0) as usize).min(h - 1);
    Crop {
        x0,
        y0,
        x1: (xmax.ceil().max(0.0) as usize).clamp(x0 + 1, w),
        y1: (ymax.ceil().max(0.0) as usize).clamp(y0 + 1, h),
    }
}

/// The strips to measure: (id, strip, law from the target, chart modulation from the target).
type StripSpec = (String, Strip, Option<PhaseLaw>, Option<f64>);

fn strips(roi: &[Point; 4], target: Option<&Target>) -> Result<Vec<StripSpec>, Failure> {
    match target {
        None => {
            let d = |a: Point, b: Point| (a[0] - b[0]).hypot(a[1] - b[1]);
            let len = 0.5 * (d(roi[0], roi[1]) + d(roi[3], roi[2]));
            let wid = 0.5 * (d(roi[0], roi[3]) + d(roi[1], roi[2]));
            let h = Homography::from_quads(&rect_corners(0.0, 0.0, len, wid), roi)
                .map_err(|e| Failure::Region(e.to_string()))?;
            Ok(vec![(
                "strip".into(),
                Strip {
                    to_image: h,
                    length: len,
                    width: wid,
                },
                None,
                None,
            )])
        }
        Some(t) => {
            let h = target_homography(t, roi)?;
            Ok(t.sweeps
                .iter()
                .map(|sw| {
                    (
                        sw.id.clone(),
                        sweep_strip(&h, sw),
                        Some(target_law(sw)),
                        Some(sw.contrast),
                    )
                })
                .collect())
        }
    }
}

/// The image quadrilaterals binning reads: each strip and sine patch inside
/// its long-edge margins.
fn binned_quads(
    roi: &[Point; 4],
    target: Option<&Target>,
    margin: f64,
) -> Result<Vec<[Point; 4]>, Failure> {
    let m = margin.clamp(0.0, 0.45);
    let inner = |st: &Strip| st.image_quad(m * st.width, (1.0 - m) * st.width);
    let mut quads: Vec<[Point; 4]> = strips(roi, target)?.iter().map(|sp| inner(&sp.1)).collect();
    if let Some(t) = target
        && !t.patches.is_empty()
    {
        let h = target_homography(t, roi)?;
        quads.extend(
            t.patches
                .iter()
                .map(|p| inner(&rect_strip(&h, &p.rect, p.direction))),
        );
    }
    Ok(quads)
}

/// What a measurement reads: the crop around the binned regions, and for each
/// image row y the columns [a, b) to convert (the regions' span over y ± 2 px,
/// widened by 2 px, 3 on the right).
#[allow(clippy::type_complexity)]
fn read_set(
    roi: &[Point; 4],
    target: Option<&Target>,
    margin: f64,
    width: usize,
    height: usize,
) -> Result<(Crop, impl Fn(usize) -> (usize, usize) + Sync), Failure> {
    let quads = binned_quads(roi, target, margin)?;
    let crop = quads
        .iter()
        .map(|q| bbox_crop(q, width, height, 3.0))
        .reduce(|a, b| Crop {
            x0: a.x0.min(b.x0),
            y0: a.y0.min(b.y0),
            x1: a.x1.max(b.x1),
            y1: a.y1.max(b.y1),
        })
        .unwrap_or_else(|| bbox_crop(roi, width, height, 2.0));
    let span = move |y: usize| -> (usize, usize) {
        let yc = y as f64 + 0.5;
        let mut lo = f64::INFINITY;
        let mut hi = f64::NEG_INFINITY;
        for q in &quads {
            for dy in [-2.0, 0.0, 2.0] {
                if let Some((a, b)) = profile::row_span(q, yc + dy) {
                    lo = lo.min(a);
                    hi = hi.max(b);
                }
            }
        }
        if lo > hi {
            (0, 0)
        } else {
            ((lo - 2.0).max(0.0) as usize, (hi + 3.0).max(0.0) as usize)
        }
    };
    Ok((crop, span))
}

/// The homography from the target frame (mm) to the image, given the target's corners in the image.
pub fn target_homography(t: &Target, roi: &[Point; 4]) -> Result<Homography, Failure> {
    Homography::from_quads(&rect_corners(0.0, 0.0, t.width_mm, t.height_mm), roi)
        .map_err(|e| Failure::Region(e.to_string()))
}

/// A strip frame for a rectangle on the chart whose sine runs along `dir`.
pub fn rect_strip(h: &Homography, rect: &crate::target::Rect, dir: Direction) -> Strip {
    let (len, wid, s) = match dir {
        Direction::X => (
            rect.width_mm,
            rect.height_mm,
            Homography {
                m: [1.0, 0.0, rect.x_mm, 0.0, 1.0, rect.y_mm, 0.0, 0.0, 1.0],
            },
        ),
        Direction::Y => (
            rect.height_mm,
            rect.width_mm,
            Homography {
                m: [0.0, 1.0, rect.x_mm, 1.0, 0.0, rect.y_mm, 0.0, 0.0, 1.0],
            },
        ),
    };
    Strip {
        to_image: h.compose(&s),
        length: len,
        width: wid,
    }
}

fn sweep_strip(h: &Homography, sw: &Sweep) -> Strip {
    rect_strip(h, &sw.rect, sw.direction)
}

fn target_law(sw: &Sweep) -> PhaseLaw {
    let l = sw.length_mm();
    match sw.law {
        SweepLaw::Linear => PhaseLaw {
            kind: LawKind::Linear,
            c0: 0.0,
            c1: sw.f_min_cy_mm,
            c2: (sw.f_max_cy_mm - sw.f_min_cy_mm) / (2.0 * l),
        },
        SweepLaw::Log => PhaseLaw {
            kind: LawKind::Log,
            c0: 0.0,
            c1: sw.f_min_cy_mm,
            c2: (sw.f_max_cy_mm / sw.f_min_cy_mm).ln() / l,
        },
    }
}

fn chart_tone(raw: &Plane, t: &Target, roi: &[Point; 4]) -> Result<ToneCurve, Failure> {
    if t.greys.len() < 2 {
        return Err(Failure::Options(
            "--tone chart needs at least two grey or density patches in the target".into(),
        ));
    }
    let h = target_homography(t, roi)?;
    let opts = BinOptions {
        bin_px: 2.0,
        margin: 0.2,
        end_px: 0.0,
        clip_level: f32::INFINITY,
    };
    let mut pairs = Vec::new();
    for g in &t.greys {
        // Inner 60 % of the patch, away from its edges' blur.
        let strip = rect_strip(&h, &g.rect, Direction::X);
        let end = 0.2 * strip.length / strip.scale_at(0.0).s_per_px;
        let prof = bin_plane(
            raw,
            &strip,
            &BinOptions {
                end_px: end,
                ..opts
            },
        );
        let n: f64 = prof.count.iter().sum();
        if n > 0.0 {
            let mean = prof
                .y
                .iter()
                .zip(&prof.count)
                .map(|(y, c)| y * c)
                .sum::<f64>()
                / n;
            pairs.push((mean, g.reflectance));
        }
    }
    ToneCurve::from_patches(&pairs).map_err(Failure::Options)
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
    let mut warnings = Vec::new();
    let specs = strips(roi, target)?;
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
        notes: Vec::new(),
        preview: Preview::default(),
    })
}

/// Measures one strip of one plane.
#[allow(clippy::too_many_arguments)]
fn measure_strip(
    planes: &[&Plane],
    channel: &str,
    id: &str,
    strip: &Strip,
    target_law: Option<PhaseLaw>,
    contrast: Option<f64>,
    opts: &MeasureOptions,
    bin_opts: &BinOptions,
) -> Result<Curve, Failure> {
    let scale_mid = strip.scale_at(0.5 * strip.length);
    let len_px = strip.length / scale_mid.s_per_px;
    let wid_px = strip.width * (1.0 - 2.0 * opts.margin) / scale_mid.s_per_px;
    if len_px < 20.0 || wid_px < 1.0 {
        return Err(Failure::TooSmall(format!(
            "the strip is {len_px:.0}×{wid_px:.1} px inside its margins; it cannot hold 5 cycles"
        )));
    }
    let prof = bin_planes(planes, strip, bin_opts);
    if prof.s.len() < 20 {
        return Err(Failure::TooSmall(format!(
            "only {} bins fall inside the region",
            prof.s.len()
        )));
    }
    let clipped = prof.clipped_fraction();
    if clipped > CLIP_REFUSE {
        return Err(Failure::Clipped {
            percent: 100.0 * clipped,
        });
    }
    let s_per_px = |s: f64| strip.scale_at(s).s_per_px;
    let lattice = curve::Lattice::of(planes);
    // Highest frequency (cy/px) at s that stays inside the lattice's band in the sweep's direction.
    let band_limit = |s: f64| lattice.band_limit(strip.scale_at(s).angle_rad);
    let ymax = prof.y.iter().cloned().fold(f64::NEG_INFINITY, f64::max);
    let ymin = prof.y.iter().cloned().fold(f64::INFINITY, f64::min);
    if !(ymax > 0.0) || (ymax - ymin) < 1e-4 * ymax.abs().max(1e-6) {
        return Err(Failure::NoOscillation(format!(
            "{channel}/{id}: the region is blank (no variation)"
        )));
    }
    // Phase law: from the target (then refined) or from zero crossings.
    let kind = match (target_law, opts.sweep) {
        (Some(l), _) => Some(l.kind),
        (None, SweepChoice::Linear) => Some(LawKind::Linear),
        (None, SweepChoice::Log) => Some(LawKind::Log),
        (None, SweepChoice::Auto) => None,
    };
    let mut laws: Vec<PhaseLaw> = Vec::new();
    if let Some(l) = target_law {
        laws.push(l);
    } else {
        let kinds: &[LawKind] = match &kind {
            Some(k) => std::slice::from_ref(k),
            None => &[LawKind::Linear, LawKind::Log],
        };
        if let Some((found, _)) = law::initial_laws(&prof, kinds, s_per_px, 0.3) {
            // A family that fits the crossings 4× worse than the best is not refined.
            let best = found.iter().map(|f| f.1).fold(f64::INFINITY, f64::min);
            laws.extend(
                found
                    .into_iter()
                    .filter(|(_, rms)| *rms <= 4.0 * best.max(1e-3))
                    .map(|(l, _)| l),
            );
        }
    }
    if laws.is_empty() {
        return Err(Failure::NoOscillation(format!(
            "{channel}/{id}: fewer than 5 regular cycles found along the strip"
        )));
    }
    // Refine each candidate; keep the one explaining the most phase with the least residual.
    let mut best: Option<(PhaseLaw, f64, usize)> = None;
    let refined: Vec<_> = laws
        .par_iter()
        .filter_map(|&l| refine_law(&prof, l, &s_per_px, &band_limit))
        .collect();
    for r in refined {
        let better = match &best {
            None => true,
            Some(b) => r.2 > b.2 + b.2 / 10 || (r.2 + r.2 / 10 >= b.2 && r.1 < b.1),
        };
        if better {
            best = Some(r);
        }
    }
    let Some((law, _, n_resolved)) = best else {
        return Err(Failure::NoOscillation(format!(
            "{channel}/{id}: the oscillation is too weak or irregular to follow"
        )));
    };
    let total_cycles = law.phase(prof.length) - law.phase(0.0);
    if total_cycles < 5.0 || n_resolved < 5 {
        return Err(Failure::TooSmall(format!(
            "{channel}/{id}: the strip holds {total_cycles:.1} cycles; at least 5 are needed"
        )));
    }
    if law.freq(0.0) <= 0.0 || law.freq(prof.length) <= law.freq(0.0) {
        return Err(Failure::NoOscillation(format!(
            "{channel}/{id}: the frequency does not rise along the strip (corners 1 and 4 must be on the low-frequency edge)"
        )));
    }
    let grid = output_grid(&law, prof.s[0], prof.s[prof.s.len() - 1]);
    let est = opts.method.estimator(opts.window_cycles);
    // The modulation, and beside it the data-based aliasing check (the
    // image's local frequency versus the law).
    // Both tabulate the law over the bins: once, shared.
    let table = PhaseTable::new(&prof, &law);
    let (mods, dev) = rayon::join(
        || est.estimate_tabulated(&prof, &law, &table, &grid),
        || local_freq_deviation(&prof, &table, &law, &grid),
    );
    drop(table);
    let mut points: Vec<MtfPoint> = mods
        .iter()
        .map(|m| {
            let f_chart = law.freq(m.s);
            let f_px = f_chart * s_per_px(m.s);
            let d = dev_at(&dev, m.s);
            MtfPoint {
                s: m.s,
                freq_cy_px: f_px,
                freq_chart: f_chart,
                modulation: m.modulation,
                mtf: m.modulation,
                mtf_err: m.err,
                aliased: f_px > band_limit(m.s) || d.is_some_and(|d| d.abs() > 0.05),
            }
        })
        .filter(|p| p.modulation.is_finite() && p.freq_cy_px.is_finite())
        .collect();
    points.sort_by(|a, b| a.freq_cy_px.total_cmp(&b.freq_cy_px));
    // Once aliased, everything above is aliased too (a sweep only rises).
    if let Some(i) = points
        .iter()
        .position(|p| p.aliased && p.freq_cy_px > 0.25 * band_limit(p.s))
    {
        points[i..].iter_mut().for_each(|p| p.aliased = true);
    }
    points
        .iter_mut()
        .filter(|p| p.freq_cy_px <= 0.25 * band_limit(p.s))
        .for_each(|p| p.aliased = false);
    if points.iter().filter(|p| !p.aliased).count() < 5 {
        return Err(Failure::NoOscillation(format!(
            "{channel}/{id}: fewer than 5 usable modulation points"
        )));
    }
    let (m_chart, source) = match contrast {
        Some(c) => (c, format!("target: printed contrast {c}")),
        None => {
            let (a, lo, hi) = curve::extrapolate_chart_modulation(&points)
                .map_err(|e| Failure::ModulationUnknown(format!("{channel}/{id}: {e}")))?;
            (
                a,
                format!("extrapolated to 0 cy/px from {lo:.4}–{hi:.4} cy/px"),
            )
        }
    };
    for p in points.iter_mut() {
        p.mtf = p.modulation / m_chart;
        p.mtf_err /= m_chart;
    }
    let figures = curve::figures(&points);
    let aliasing_from = points.iter().find(|p| p.aliased).map(|p| p.freq_cy_px);
    let across = |s: f64| -> [Point; 2] {
        [
            strip.to_image.apply([s, opts.margin * strip.width]),
            strip.to_image.apply([s, (1.0 - opts.margin) * strip.width]),
        ]
    };
    let alias_line = points.iter().find(|p| p.aliased).map(|p| across(p.s));
    let (s_first, s_last) = (
        points.iter().map(|p| p.s).fold(f64::INFINITY, f64::min),
        points.iter().map(|p| p.s).fold(f64::NEG_INFINITY, f64::max),
    );
    Ok(Curve {
        channel: channel.to_string(),
        sweep_id: id.to_string(),
        law,
        strip_unit: if target_law.is_some() { "mm" } else { "px" },
        points,
        chart_modulation: m_chart,
        chart_modulation_source: source,
        figures,
        aliasing_from_cy_px: aliasing_from,
        clipped_fraction: clipped,
        region_px: strip.image_quad(opts.margin * strip.width, (1.0 - opts.margin) * strip.width),
        alias_line_px: alias_line,
        measured_lines_px: [across(s_first), across(s_last)],
    })
}

/// Refines a phase law from local sine fits over the well-resolved part of the
/// strip (contiguous from the low-frequency end, signal-to-noise ≥ 8, below
/// 0.85 of the band limit). Returns the law, its RMS phase residual (cycles)
/// and the number of fits that support it.
fn refine_law(
    prof: &Profile,
    start: PhaseLaw,
    s_per_px: &impl Fn(f64) -> f64,
    band_limit: &impl Fn(f64) -> f64,
) -> Option<(PhaseLaw, f64, usize)> {
    let mut law = start;
    let (s_lo, s_hi) = (prof.s[0], prof.s[prof.s.len() - 1]);
    let mut result = None;
    for _ in 0..3 {
        if !(law.freq(s_lo).is_finite() && law.freq(s_lo) > 0.0) {
            return result;
        }
        let table = PhaseTable::new(prof, &law);
        // One fit per cycle up to 0.85 of the band limit, computed in parallel,
        // then accepted in order while the phase shift stays continuous.
        let (p_lo, p_hi) = (law.phase(s_lo), law.phase(s_hi));
        let mut at = Vec::new();
        let mut p = p_lo + 1.5;
        while p < p_hi - 1.5 {
            let s = law.s_at_phase(p, s_lo, s_hi);
            if law.freq(s) * s_per_px(s) > 0.85 * band_limit(s) {
                break;
            }
            at.push((p, s));
            p += 1.0;
        }
        let fits: Vec<_> = at
            .par_iter()
            .map(|&(p, s)| (p, s, local_fit(prof, &table, &law, s, 2.0)))
            .collect();
        let mut pts = Vec::new();
        let mut prev_shift: Option<f64> = None;
        for (p, s, fit) in fits {
            let Some(fit) = fit else {
                continue;
            };
            let snr = fit.amp / fit.amp_var.sqrt().max(1e-12);
            if snr < 8.0 {
                if pts.len() >= 8 {
                    break;
                }
                continue;
            }
            let mut shift = fit.phase_shift;
            if let Some(prev) = prev_shift {
                shift -= (shift - prev).round();
                if (shift - prev).abs() > 0.2 {
                    break;
                }
            }
            prev_shift = Some(shift);
            pts.push((s, p + shift, snr.min(1e3).powi(2)));
        }
        if pts.len() < 6 {
            return result;
        }
        let (l, rms) = law::fit_law(&pts, law.kind)?;
        // Converged when the new law moves no fitted point's phase by 1/1000 cycle.
        let moved = pts
            .iter()
            .map(|&(s, _, _)| (l.phase(s) - law.phase(s)).abs())
            .fold(0.0, f64::max);
        law = l;
        result = Some((law, rms, pts.len()));
        if moved < 1e-3 {
            break;
        }
    }
    result
}

/// Output positions: at least one cycle apart and at most ~1/300 of the frequency range apart.
fn output_grid(law: &PhaseLaw, s_lo: f64, s_hi: f64) -> Vec<f64> {
    let (f_lo, f_hi) = (law.freq(s_lo), law.freq(s_hi));
    let df = (f_hi - f_lo) / 300.0;
    let mut out = Vec::new();
    let mut s = law.s_at_phase(law.phase(s_lo) + 0.5, s_lo, s_hi);
    let p_end = law.phase(s_hi) - 0.5;
    while law.phase(s) <= p_end && out.len() < 5000 {
        out.push(s);
        let by_cycle = law.s_at_phase(law.phase(s) + 1.0, s_lo, s_hi);
        let target_f = law.freq(s) + df;
        // s where the frequency reaches target_f (bisection; frequency rises).
        let (mut a, mut b) = (s, s_hi);
        for _ in 0..60 {
            let m = 0.5 * (a + b);
            if law.freq(m) < target_f {
                a = m;
            } else {
                b = m;
            }
        }
        let next = by_cycle.max(0.5 * (a + b));
        if next <= s + 1e-12 {
            break;
        }
        s = next;
    }
    out
}

/// Relative deviation of the image's local frequency from the law, (s, deviation) at grid points with a clear signal.
fn local_freq_deviation(
    prof: &Profile,
    table: &PhaseTable,
    law: &PhaseLaw,
    grid: &[f64],
) -> Vec<(f64, f64)> {
    let fits: Vec<(f64, f64, f64)> = grid
        .par_iter()
        .filter_map(|&s| {
            let f = local_fit(prof, table, law, s, 2.0)?;
            let snr = f.amp / f.amp_var.sqrt().max(1e-12);
            (snr > 15.0).then_some((s, law.phase(s), f.phase_shift))
        })
        .collect();
    // Pair each fit with the next one at least 4 cycles on (phase noise ~1/(2π·SNR) per fit).
    let mut out = Vec::new();
    for i in 0..fits.len() {
        let j = fits[i..].partition_point(|f| f.1 < fits[i].1 + 4.0) + i;
        if let Some(fj) = fits.get(j)
            && fj.1 - fits[i].1 < 12.0
        {
            let mut d = fj.2 - fits[i].2;
            d -= d.round();
            out.push((0.5 * (fits[i].0 + fj.0), d / (fj.1 - fits[i].1)));
        }
    }
    out
}

fn dev_at(dev: &[(f64, f64)], s: f64) -> Option<f64> {
    let i = dev.partition_point(|d| d.0 < s);
    let cand = [i.checked_sub(1), Some(i)];
    cand.iter()
        .flatten()
        .filter_map(|&k| dev.get(k))
        .min_by(|a, b| (a.0 - s).abs().total_cmp(&(b.0 - s).abs()))
        .map(|d| d.1)
}

fn make_preview(dec: &Decoded, roi: &[Point; 4]) -> Preview {
    preview_from(roi, dec.width, dec.height, |x, y| {
        let mut px = [0u8; 3];
        for (c, out) in px.iter_mut().enumerate() {
            let cc = if dec.channels == 1 { 0 } else { c };
            let k = (y * dec.width + x) * dec.channels + cc;
            *out = match &dec.samples {
                Samples::U8(v) => v[k],
                Samples::U16(v) => (v[k] >> 8) as u8,
            };
        }
        px
    })
}

/// The image rectangle a preview of the region shows (the region plus a
/// margin) and its step (image px per preview px, so that the long side is at
/// most ~1200 px).
fn preview_window(roi: &[Point; 4], width: usize, height: usize) -> (Crop, usize) {
    let xmin = roi.iter().map(|p| p[0]).fold(f64::INFINITY, f64::min);
    let xmax = roi.iter().map(|p| p[0]).fold(f64::NEG_INFINITY, f64::max);
    let ymin = roi.iter().map(|p| p[1]).fold(f64::INFINITY, f64::min);
    let ymax = roi.iter().map(|p| p[1]).fold(f64::NEG_INFINITY, f64::max);
    let pad = 0.08 * (xmax - xmin).max(ymax - ymin) + 8.0;
    let crop = bbox_crop(roi, width, height, pad);
    let (cw, ch) = (crop.x1 - crop.x0, crop.y1 - crop.y0);
    let step = ((cw.max(ch) as f64 / 1200.0).ceil() as usize).max(1);
    (crop, step)
}

/// A raw frame's preview of the region: on a Bayer mosaic one green lattice
/// (an even step, so every preview pixel is a green site and the picture
/// shows no CFA checkerboard), otherwise the first sample of each pixel;
/// through the sRGB curve (a table) for display. Converted a row at a time
/// in parallel, straight from the decoded samples.
fn raw_preview(frame: &crate::photo::raw::RawFrame, roi: &[Point; 4]) -> Preview {
    let (crop, step) = preview_window(roi, frame.width, frame.height);
    let (offset, step) = match frame.green_site() {
        Some(g) => {
            let step = step.next_multiple_of(2);
            // The first green site at or after the crop's corner.
            let first = |lo: usize, g: usize| lo + (g + 2 - lo % 2) % 2;
            ((first(crop.x0, g.0), first(crop.y0, g.1)), step)
        }
        None => ((crop.x0, crop.y0), step),
    };
    let sample = if frame.samples_per_pixel == 3 { 1 } else { 0 };
    let plane = frame.lattice_plane(
        offset,
        (step, step),
        sample,
        (crop.x0, crop.y0, crop.x1, crop.y1),
    );
    const LEVELS: usize = 4096;
    let srgb: Vec<u8> = (0..LEVELS)
        .map(|i| {
            let v = i as f64 / (LEVELS - 1) as f64;
            (255.0 * crate::photo::linearise::linear_to_srgb(v)).round() as u8
        })
        .collect();
    let rgb = plane
        .data
        .iter()
        .flat_map(|&v| {
            let c = srgb[(v.clamp(0.0, 1.0) * (LEVELS - 1) as f32 + 0.5) as usize];
            [c, c, c]
        })
        .collect();
    Preview {
        x0: plane.offset.0 as f64,
        y0: plane.offset.1 as f64,
        scale: step as f64,
        width: plane.width,
        height: plane.height,
        rgb,
    }
}

/// A preview of the region (plus a margin), at most ~1200 px on its long side.
fn preview_from(
    roi: &[Point; 4],
    width: usize,
    height: usize,
    pixel: impl Fn(usize, usize) -> [u8; 3],
) -> Preview {
    let (crop, step) = preview_window(roi, width, height);
    let (cw, ch) = (crop.x1 - crop.x0, crop.y1 - crop.y0);
    let (pw, ph) = (cw.div_ceil(step), ch.div_ceil(step));
    let mut rgb = Vec::with_capacity(pw * ph * 3);
    for j in 0..ph {
        for i in 0..pw {
            rgb.extend(pixel(crop.x0 + i * step, crop.y0 + j * step));
        }
    }
    Preview {
        x0: crop.x0 as f64,
        y0: crop.y0 as f64,
        scale: step as f64,
        width: pw,
        height: ph,
        rgb,
    }
}
