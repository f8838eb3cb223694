//! Measurement of MTF from a photo of a sine chart: the region (`--roi`, with
//! or without a target description) → [`profile`] binning without resampling
//! → phase-law first guess ([`law_guess`]) and fit ([`law`]) → modulation ([`estimate`]) → MTF curve with
//! aliasing flags, normalisation and summary figures ([`curve`]); sine-patch
//! targets give one result per patch ([`patches`]).
//!
//! Entry points: [`measure_file`] (decode + measure; safe to call from many
//! threads), [`measure_bytes`] (the same for a file's bytes in memory), [`measure_decoded`] and [`measure_planes`] (for planes that
//! another decoder, e.g. camera raw, produced).

#![allow(clippy::needless_range_loop, clippy::neg_cmp_op_on_partial_ord)]

use crate::geometry::Point;
use crate::locate::{ConvertedCrop, sample::Gray};
use crate::photo::decode::{Decoded, decode_file};
use crate::photo::linearise::{Channel, file_tone, pixel_converter};
use crate::photo::{Plane, PlaneRef};
use crate::target::Target;
use std::path::Path;

pub mod chart_mtf;
pub mod curve;
pub mod estimate;
pub mod figures;
pub mod in_memory;
pub mod law;
pub mod law_guess;
pub mod lens_fit;
pub mod lens_mtf;
pub mod model_overlay;
pub mod moire;
pub mod patches;
pub mod profile;
pub mod sine_tone;
pub mod surround_leak;
pub mod synth;
pub mod synth_code_sharpen;
pub mod tone_black;
pub mod tone_unseen;

mod block_ripple;
mod curve_said;
mod frame;
mod frequency;
mod jpeg_deadzone;
mod lens_choice;
mod normalise;
mod options;
mod preview;
mod region;
mod result;
mod strip;
mod sweep_end;
mod tone;

pub use curve::{Figures, MtfPoint};
pub use estimate::Method;
pub use law::{LawKind, PhaseLaw};
pub use lens_fit::{DistortionFound, DistortionSource};
use options::check_options;
pub use options::{
    MAX_ACROSS, MAX_CHART_REL_ERR, MAX_LAW_RMS_CYCLES, MIN_ACROSS_PX, MeasureOptions,
    REFINE_SEARCH_PX, SweepChoice,
};
pub use patches::PatchResult;
pub use region::{charts_in, rect_strip, target_homography};
pub use result::{Curve, Failure, MeasureError, Measurement, Preview};
pub(crate) use result::{DAMAGE_MARK, Said};

use frame::{
    decode_bytes_with_pitch, decode_for_search, measure_decoded_at, measure_frame_at, read_photo,
};
use lens_choice::given_distortion;
use profile::BinOptions;
use rayon::prelude::*;
use region::{
    StripSpec, bbox_crop, found_said, full_grey, grey_source, grey_source_with, locate_region,
    location_failed, raw_read_window, refine_or_keep, resolve_roi, strips,
};
use strip::measure_strip;
/// A strip's curve and the note of how it was measured, if any.
type NotedCurve = (Curve, Option<String>);

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
    // The target's pattern (for verifying charts) is sampled while the photo is decoded.
    let (decoded, pattern) = rayon::join(
        || decode_for_search(path, &name, opts),
        || crate::locate::assign::Pattern::new(&target),
    );
    let (dec, o, said, reduced) = decoded?;
    let charts = found(crate::locate::find_charts_with(
        &grey_source_with(&dec, reduced.as_ref()),
        &target,
        &pattern,
    ))
    .map_err(|e| said.blame(e))?;
    let n = charts.len();
    charts
        .iter()
        .enumerate()
        .map(|(i, c)| {
            let w = found_said(c, i, n);
            let mut m = measure_decoded_at(&dec, &name, Some(&target), &o, &c.corners_px, w)
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
    measure_raw_frame(&frame, name, target, opts)
}

/// Measures a camera raw frame already decoded (whole, or at least the part
/// [`measure_raw`] would read), exactly as [`measure_raw`] measures its file;
/// `name` is used in messages and the outputs.
pub fn measure_raw_frame(
    frame: &crate::photo::raw::RawFrame,
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
                refine_or_keep(&Gray::of_plane(&plane), given, target, &mut said).map_err(err)?
            } else {
                given
            }
        }
    };
    measure_frame_at(frame, name, target, opts, &roi, said)
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
    let roi = match (opts.roi, target) {
        // No region but a target: find the chart from its fiducials.
        (None, Some(t)) => locate_region(&grey_source(dec), t, opts, &mut said).map_err(err)?,
        _ => {
            let given = resolve_roi(opts, dec.width, dec.height).map_err(err)?;
            if opts.refine_roi {
                // The region and the search band around it, converted only
                // where the edge searches read (a 24 MP strip's whole crop was
                // 38 MB of the peak memory and a third of the refinement's time).
                let crop = bbox_crop(&given, dec.width, dec.height, REFINE_SEARCH_PX + 8.0);
                let src = ConvertedCrop {
                    crop,
                    at: pixel_converter(dec, &file_tone(dec).0, Channel::Luma),
                };
                refine_or_keep(&src, given, target, &mut said).map_err(err)?
            } else {
                given
            }
        }
    };
    measure_decoded_at(dec, name, target, opts, &roi, said)
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
    let views = plane_views(groups);
    measure_planes_lens(
        &views,
        size,
        roi,
        target,
        opts,
        clip_level,
        distortion,
        strip::Coding::default(),
    )
}

/// Groups of planes as groups of views ([`PlaneRef`]).
fn plane_views<'a>(groups: &'a [(&'a str, Vec<Plane>)]) -> Vec<(&'a str, Vec<PlaneRef<'a>>)> {
    groups
        .iter()
        .map(|(name, planes)| (*name, planes.iter().map(PlaneRef::from).collect()))
        .collect()
}

/// [`measure_planes`] with the distortion already resolved and what the
/// planes' coding leaves for the strips to take out ([`strip::Coding`]).
#[allow(clippy::too_many_arguments)]
fn measure_planes_lens(
    groups: &[(&str, Vec<PlaneRef>)],
    size: (usize, usize),
    roi: &[Point; 4],
    target: Option<&Target>,
    opts: &MeasureOptions,
    clip_level: f32,
    distortion: Option<DistortionFound>,
    coding: strip::Coding,
) -> Result<Measurement, Failure> {
    let mut warnings = Vec::new();
    let mut notes = Vec::new();
    // Strips of a coarse JPEG whose bars lie square to its blocks, with their drift (px).
    let mut square: Vec<(String, f64)> = Vec::new();
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
        max_across: opts.max_across,
    };
    for (name, group) in groups {
        let plane_refs: &[PlaneRef] = group;
        if plane_refs.is_empty() {
            continue;
        }
        // The strips (a target has several) and the patches are measured
        // side by side; the results are taken in the target's order.
        let one = |(id, strip, tlaw, contrast): &StripSpec| {
            let measured = |seed: Option<PhaseLaw>| {
                measure_strip(
                    plane_refs, name, id, strip, *tlaw, seed, *contrast, opts, &bin_opts, coding,
                )
            };
            // A channel whose own crossings cannot be followed (red or blue
            // of a demosaicked mosaic, aliased from ¼ cy/px) is measured
            // along the law an earlier channel (luma) found on the same strip;
            // so is one whose own law gave a curve lost in noise (since a law
            // rising from 0 cy inside the strip is taken, session 36, blue's
            // aliased crossings can give one).
            let earlier = curves
                .iter()
                .find(|c: &&Curve| c.sweep_id == *id)
                .map(|c| (c.channel.clone(), c.law));
            match (measured(None), earlier) {
                (Ok(c), _) => Ok((c, None)),
                (
                    Err(
                        e @ (Failure::NoOscillation(_)
                        | Failure::ModulationUnknown(_)
                        | Failure::Unreliable(_)),
                    ),
                    Some((by, law)),
                ) if tlaw.is_none() => {
                    let why = e.to_string();
                    let c = measured(Some(law)).map_err(|_| e)?;
                    let note = format!(
                        "{name}/{id}: measured along {by}'s sweep law (its own failed: {why})"
                    );
                    Ok((c, Some(note)))
                }
                (Err(e), _) => Err(e),
            }
        };
        let patches = || match target {
            Some(t) if !t.patches.is_empty() => target_homography(t, roi)
                .map(|h| patches::measure_patches(plane_refs, name, &h, t, &bin_opts)),
            _ => Ok(Vec::new()),
        };
        let (measured, patched): (Vec<Result<NotedCurve, Failure>>, _) =
            rayon::join(|| specs.par_iter().map(one).collect(), patches);
        for r in measured {
            let (c, note) = r?;
            notes.extend(note);
            curve_said::of_curve(
                name,
                &c,
                opts,
                coding,
                &mut notes,
                &mut warnings,
                &mut square,
            );
            curves.push(c);
        }
        patch_rows.extend(patched?);
    }
    warnings.extend(curve_said::square_to_blocks(&square));
    if curves.is_empty() && patch_rows.is_empty() {
        return Err(Failure::Options(
            "the target describes neither sweeps nor sine patches".into(),
        ));
    }
    let colour_moire = moire::colour_moire(&curves);
    if opts.channel == Channel::All && !groups.iter().any(|g| g.0 == "r") {
        notes.push(
            "colour moiré not measured: the photo has one channel (grey), so there is no red or blue to compare"
                .into(),
        );
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
        colour_moire,
    })
}
