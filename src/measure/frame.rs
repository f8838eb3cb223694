//! Frame: from a decoded photo or a raw frame, with its region known, to the
//! linear samples that binning reads (a photo's integer codes read in place
//! through the tone's table, float codes and raws converted over the read set
//! only; the tone chosen in [`super::tone`]; raw greens balanced), then
//! [`super::measure_planes`],
//! with the source, bit depth, tone line, pixel pitch, preview and warnings
//! filled in. Also the photo's decoding with its pixel pitch resolved.

use super::lens_choice::resolve_distortion;
use super::preview::{make_preview, raw_preview};
use super::region::{bbox_crop, read_set};
use super::tone::photo_tone;
use super::{Failure, MeasureError, MeasureOptions, Measurement, Said, measure_planes_lens};
use crate::geometry::Point;
use crate::locate::row_reduction::{ReducedSearch, SharedReduction};
use crate::photo::decode::{DecodeError, Decoded, decode_bytes_observed};
use crate::photo::jpeg::{JpegWant, ObserverFor};
use crate::photo::linearise::{Channel, coded, default_tone, plane_names, planes_within};
use crate::photo::{Plane, PlaneRef};
use crate::target::Target;
use std::path::Path;

/// Reads and decodes a photo (not a raw) the target will be searched for,
/// and resolves its pixel pitch from EXIF and the options: the photo, the
/// options with the pitch, the messages of decoding (damaged scan data) and
/// of the pitch, and the search image if it was summed from a JPEG's rows as
/// they were decoded, on the decoder's second thread (`None` otherwise: the
/// search then reduces the photo itself).
pub(super) fn decode_for_search(
    path: &Path,
    name: &str,
    opts: &MeasureOptions,
) -> Result<(Decoded, MeasureOptions, Said, Option<ReducedSearch>), MeasureError> {
    let shared = SharedReduction::default();
    // The table the search reads a JPEG's luma through (an 8-bit file's
    // default tone); a file that declares another is reduced later.
    let lut = default_tone(8).0.lut(256);
    let make = |w: usize, h: usize| shared.observer(w, h, &lut);
    let bytes = read_photo(path, name)?;
    let (dec, o, said) = decode_bytes_with(&bytes, name, opts, Some(&make))?;
    // A decode with warnings may be a lenient retry, which the observer did not see.
    let reduced = shared.finish().filter(|_| dec.warnings.is_empty());
    Ok((dec, o, said, reduced))
}

/// Reads a photo file's bytes (`name` in the error).
pub(super) fn read_photo(path: &Path, name: &str) -> Result<Vec<u8>, MeasureError> {
    std::fs::read(path).map_err(|source| MeasureError {
        path: name.to_string(),
        failure: DecodeError::Io {
            path: name.to_string(),
            source,
        }
        .into(),
    })
}

/// A photo file's bytes already in memory, decoded as by [`decode_for_search`] (no search image).
pub(super) fn decode_bytes_with_pitch(
    bytes: &[u8],
    name: &str,
    opts: &MeasureOptions,
) -> Result<(Decoded, MeasureOptions, Said), MeasureError> {
    decode_bytes_with(bytes, name, opts, None)
}

/// [`decode_bytes_with_pitch`], a JPEG's rows shown to `observe`'s observer.
fn decode_bytes_with(
    bytes: &[u8],
    name: &str,
    opts: &MeasureOptions,
    observe: Option<ObserverFor<'_>>,
) -> Result<(Decoded, MeasureOptions, Said), MeasureError> {
    // The EXIF and the scan check read the bytes on the second core while
    // the decoder (one core) runs.
    let (dec, (facts, damage)) = rayon::join(
        || decode_bytes_observed(bytes, name, jpeg_want(opts), observe),
        || {
            (
                crate::photo::exif::facts_from_bytes(bytes),
                crate::photo::jpeg_check::scan_damage(bytes),
            )
        },
    );
    let dec = dec.map_err(|e| MeasureError {
        path: name.to_string(),
        failure: e.into(),
    })?;
    let pitch = crate::photo::pitch::resolve(&facts, dec.width, dec.height, opts.pixel_pitch_mm);
    let o = MeasureOptions {
        pixel_pitch_mm: pitch.pitch_mm,
        ..opts.clone()
    };
    let mut warnings = dec.warnings.clone();
    // The decoder's own report of damage, else the scan check's (which also
    // sees damage the lenient decoder passes over, such as stray restart markers).
    let decoder_saw_it = warnings.iter().any(|w| w.contains(super::DAMAGE_MARK));
    if let Some(d) = damage.filter(|_| !decoder_saw_it) {
        warnings.push(format!(
            "damaged JPEG scan data ({d}): the picture may be partly grey"
        ));
    }
    warnings.extend(pitch.warnings);
    Ok((
        dec,
        o,
        Said {
            warnings,
            notes: pitch.notes,
        },
    ))
}

/// Rows below the region's lowest corner that a measurement may still read
/// (corner refinement's search and crop, the binned rows' padding), px.
const ROWS_BELOW_ROI: f64 = 64.0;

/// What of a JPEG the measurement reads: with corners given, the rows down
/// to just below the region; for a luminance measurement without a tone
/// curve from the chart, the luma plane alone (see `photo::jpeg`).
fn jpeg_want(opts: &MeasureOptions) -> JpegWant {
    JpegWant {
        rows: opts.roi.map(|q| {
            let ymax = q.iter().map(|p| p[1]).fold(0.0, f64::max);
            (ymax + ROWS_BELOW_ROI).ceil().max(0.0) as usize
        }),
        luma_only: opts.channel == Channel::Luma && !opts.tone_chart,
    }
}

/// The part of [`measure_raw`] after the region is known: `roi` (frame px)
/// and the warnings so far.
pub(super) fn measure_frame_at(
    frame: &crate::photo::raw::RawFrame,
    name: &str,
    target: Option<&Target>,
    opts: &MeasureOptions,
    roi: &[Point; 4],
    mut said: Said,
) -> Result<Measurement, MeasureError> {
    use crate::photo::raw::RawChannel;
    let warnings = &mut said.warnings;
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
    // The distortion as given, or estimated from the strip's (or the target's
    // strips') long edges in one green lattice (the edge search samples
    // bilinearly in the lattice's own steps), read only about those edges.
    let (w, h) = (frame.width, frame.height);
    let distortion = resolve_distortion(opts, &roi, target, (w, h), false, |q| {
        let pad = super::lens_fit::search_pad_px(q, w, h);
        let c = bbox_crop(q, w, h, pad);
        let band = |y: usize| super::lens_fit::edge_band_span(q, pad + 2.0, y);
        let groups = frame.channel_groups_within(RawChannel::G, (c.x0, c.y0, c.x1, c.y1), &band);
        // A damaged file's colour pattern may hold no green site (found by
        // the fuzzer: it panicked here): an empty plane, in which no edge is
        // found, so no distortion is applied.
        let green = groups
            .into_iter()
            .next()
            .and_then(|g| g.1.into_iter().next());
        Box::new(green.unwrap_or_else(|| crate::photo::Plane::full(0, 0, Vec::new())))
    })
    .map_err(err)?;
    let roi = distortion.and_then(|d| d.snapped).map_or(roi, |s| s.0);
    let lens = distortion.and_then(|d| d.lens(frame.width, frame.height));
    // Only what binning reads is converted to f32.
    let (crop, span) = read_set(
        &roi,
        target,
        opts.margin,
        lens.as_ref(),
        frame.width,
        frame.height,
    )
    .map_err(err)?;
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
    let mut m = measure_planes_lens(
        &super::plane_views(&groups),
        (frame.width, frame.height),
        &roi,
        target,
        &o,
        RAW_CLIP,
        distortion,
        Default::default(),
    )
    .map_err(err)?;
    drop(groups);
    m.preview = raw_preview(frame, &roi);
    m.source = name.to_string();
    m.bits = frame.bits_per_sample as u32;
    m.tone = format!("linear raw (black level removed, white level = 1{greens})");
    m.green_gain = green_gain;
    said.warnings.extend(pitch.warnings);
    said.notes.extend(pitch.notes);
    said.put_before(&mut m);
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

/// The part of [`measure_decoded`] after the region is known: `roi` (image
/// px) and the warnings so far.
pub(super) fn measure_decoded_at(
    dec: &Decoded,
    name: &str,
    target: Option<&Target>,
    opts: &MeasureOptions,
    roi: &[Point; 4],
    mut said: Said,
) -> Result<Measurement, MeasureError> {
    let err = |failure: Failure| MeasureError {
        path: name.to_string(),
        failure,
    };
    let roi = *roi;
    // Crop: the region's bounding box (+2 px).
    let crop = bbox_crop(&roi, dec.width, dec.height, 2.0);
    let (tone, tone_desc) =
        photo_tone(dec, target, opts, crop, &roi, &mut said.notes).map_err(err)?;
    let clip_level = (tone.apply(1.0) * 0.999) as f32;
    // The preview (one core, ≈ 2 ms on 24 MP) is drawn beside the distortion
    // estimate and the strips rather than before them.
    let (m, preview) = rayon::join(
        || measure_coded(dec, target, opts, &roi, &tone, clip_level),
        || make_preview(dec, &roi),
    );
    let mut m = m.map_err(err)?;
    m.source = name.to_string();
    m.bits = dec.bits();
    m.tone = tone_desc;
    m.preview = preview;
    said.warnings
        .extend(coarse_jpeg_quality(dec).map(coarse_jpeg_warning));
    said.put_before(&mut m);
    Ok(m)
}

/// The part of [`measure_decoded_at`] after the tone is known: the
/// distortion, the linear samples binning reads, and the measurement.
fn measure_coded(
    dec: &Decoded,
    target: Option<&Target>,
    opts: &MeasureOptions,
    roi: &[Point; 4],
    tone: &crate::photo::linearise::Tone,
    clip_level: f32,
) -> Result<Measurement, Failure> {
    let roi = *roi;
    // The edge searches read a few thousand places about the long edges:
    // converted where read, so no plane is kept for them (on a 24 MP strip
    // the bands were 17.5 MB of the peak memory).
    let at = crate::photo::linearise::pixel_converter(dec, tone, Channel::Luma);
    let distortion = resolve_distortion(opts, &roi, target, (dec.width, dec.height), true, |_| {
        Box::new(super::lens_fit::Converted {
            at: &at,
            width: dec.width,
            rows: dec.rows,
        })
    })?;
    let roi = distortion.and_then(|d| d.snapped).map_or(roi, |s| s.0);
    let lens = distortion.and_then(|d| d.lens(dec.width, dec.height));
    // Integer codes are binned in place through the tone's table (no
    // converted copy: on a 24 MP strip that was 35 MB); float codes are
    // converted where binning reads.
    let coded = coded(dec, tone, opts.channel);
    let converted = match coded {
        Some(_) => Vec::new(),
        None => {
            let (crop, span) = read_set(
                &roi,
                target,
                opts.margin,
                lens.as_ref(),
                dec.width,
                dec.height,
            )?;
            planes_within(dec, crop, tone, opts.channel, &span)
        }
    };
    let views = match &coded {
        Some(c) => c.planes(dec),
        None => converted.iter().map(PlaneRef::from).collect(),
    };
    let names = plane_names(opts.channel, dec.channels);
    let groups: Vec<(&str, Vec<PlaneRef>)> = names
        .into_iter()
        .zip(views.into_iter().map(|p| vec![p]))
        .collect();
    measure_planes_lens(
        &groups,
        (dec.width, dec.height),
        &roi,
        target,
        opts,
        clip_level,
        distortion,
        super::strip::Coding {
            block_ripple: coarse_jpeg_quality(dec).is_some(),
            tone: strip_may_correct(opts, tone).then_some(tone),
            jpeg_luma: dec
                .jpeg_luma_quant
                .as_deref()
                .filter(|_| dec.bits() == 8)
                .map(|t| (t, tone)),
        },
    )
}

/// Whether a strip may find a camera's own tone curve on top of `tone` from
/// its shape: not when the user chose the tone (`--gamma`, `--tone chart`
/// or `--tone file`), nor on linear data.
fn strip_may_correct(opts: &MeasureOptions, tone: &crate::photo::linearise::Tone) -> bool {
    use crate::photo::linearise::Tone;
    opts.tone_from_strip
        && opts.gamma.is_none()
        && !opts.tone_chart
        && !matches!(tone, Tone::Gamma(g) if *g == 1.0)
}

/// Below this IJG quality a JPEG's block quantisation visibly moves its MTF.
const COARSE_JPEG_QUALITY: f64 = 90.0;

/// The IJG quality of a JPEG whose luma table is coarse (below
/// [`COARSE_JPEG_QUALITY`]): its 8×8 quantisation is part of the file's MTF.
fn coarse_jpeg_quality(dec: &Decoded) -> Option<f64> {
    let q = crate::photo::jpeg_quant::ijg_quality(dec.jpeg_luma_quant.as_deref()?);
    (q < COARSE_JPEG_QUALITY).then_some(q)
}

/// The warning for a coarse JPEG. Simulated q75 shots (coloured light,
/// exposure 0.5–0.9, Gaussian lenses σ 0.45–0.7 px, turned 0.1–5°;
/// `examples/coarse_jpeg_study.rs`): ripples of ±0.015 at 0.25–0.45 cy/px
/// (smoothed out, [`super::strip`]) and MTF50 off the optics' by up to
/// ±1.1 % either way, with no trend a correction could follow; square to the
/// block grid (0°) by up to ±2.5 %, said separately per strip. q90 moves
/// MTF50 by less than 0.05 %.
fn coarse_jpeg_warning(q: f64) -> String {
    format!(
        "JPEG quality ≈ {q:.0} (luma table): its 8×8 block quantisation is part of this MTF \
         (simulated q75: MTF50 within ±1.1 % of the optics', either way; its ripple is smoothed \
         by a twiced local quadratic over σ ≤ 0.06 cy/px); shoot at quality ≥ 90 or raw for the lens's \
         own MTF"
    )
}
