//! Measuring and locating charts in pictures that are already in memory
//! (code values handed over by a caller such as the Python bindings, with no
//! file and no EXIF), and locating charts in photo files.
//!
//! [`decoded_from_samples`] checks the caller's samples and wraps them as a
//! [`Decoded`] photo (no conversion: only the measured region is ever turned
//! into linear light); [`measure_in_memory`] measures it exactly as
//! [`super::measure_file`] measures a decoded file; [`locate_file`] and
//! [`locate_in_memory`] find every chart of a target.

use super::{Failure, MeasureError, MeasureOptions, Measurement, load_target, measure_decoded};
use crate::locate::Located;
use crate::photo::decode::{Decoded, Samples, decode_file};
use crate::photo::exif::ExifFacts;
use crate::target::Target;
use std::path::Path;

/// Wraps row-major, pixel-interleaved code values of a `width`×`height` picture
/// with `channels` (1 = grey, 3 = RGB) samples per pixel as a decoded photo;
/// float samples must be finite (0 = black, 1 = white).
pub fn decoded_from_samples(
    width: usize,
    height: usize,
    channels: usize,
    samples: Samples,
) -> Result<Decoded, Failure> {
    if channels != 1 && channels != 3 {
        return Err(Failure::Options(format!(
            "a picture has 1 (grey) or 3 (RGB) samples per pixel, not {channels}"
        )));
    }
    if width == 0 || height == 0 {
        return Err(Failure::Options(format!(
            "the picture is empty ({width}×{height} pixels)"
        )));
    }
    let len = match &samples {
        Samples::U8(v) => v.len(),
        Samples::U16(v) => v.len(),
        Samples::F32(v) => v.len(),
    };
    if Some(len)
        != width
            .checked_mul(height)
            .and_then(|n| n.checked_mul(channels))
    {
        return Err(Failure::Options(format!(
            "{len} samples do not make a {width}×{height} picture with {channels} per pixel"
        )));
    }
    if let Samples::F32(v) = &samples
        && let Some(i) = v.iter().position(|x| !x.is_finite())
    {
        let (x, y) = ((i / channels) % width, i / channels / width);
        return Err(Failure::Options(format!(
            "the picture holds a non-finite value ({}) at pixel x={x}, y={y}",
            v[i]
        )));
    }
    Ok(Decoded {
        width,
        height,
        channels,
        samples,
        format: "array",
        rows: height,
        warnings: Vec::new(),
        declared_tone: None,
        jpeg_luma_quant: None,
    })
}

/// Measures a picture held in memory; `name` stands for it in messages. The
/// pixel pitch is `opts.pixel_pitch_mm` (there is no EXIF to read it from).
pub fn measure_in_memory(
    dec: &Decoded,
    name: &str,
    opts: &MeasureOptions,
) -> Result<Measurement, MeasureError> {
    let err = |failure: Failure| MeasureError {
        path: name.to_string(),
        failure,
    };
    let target = load_target(opts).map_err(err)?;
    let pitch = crate::photo::pitch::resolve(
        &ExifFacts::default(),
        dec.width,
        dec.height,
        opts.pixel_pitch_mm,
    );
    let o = MeasureOptions {
        pixel_pitch_mm: pitch.pitch_mm,
        ..opts.clone()
    };
    let mut m = measure_decoded(dec, name, target.as_ref(), &o)?;
    m.warnings.extend(pitch.warnings);
    m.notes.extend(pitch.notes);
    Ok(m)
}

/// Every copy of `target` in a picture held in memory, left to right
/// (searched on its linear luminance, default tone for its bit depth).
pub fn locate_in_memory(dec: &Decoded, target: &Target) -> Result<Vec<Located>, Failure> {
    crate::locate::find_charts(&super::region::grey_source(dec), target)
        .map_err(|e| Failure::Region(format!("automatic location failed: {e}")))
}

/// Every copy of `target` in a photo file (JPEG, PNG, TIFF or camera raw), left to right.
pub fn locate_file(path: &Path, target: &Target) -> Result<Vec<Located>, MeasureError> {
    let name = path.display().to_string();
    let err = |failure: Failure| MeasureError {
        path: name.clone(),
        failure,
    };
    if crate::photo::raw::is_raw_path(path) {
        let frame =
            crate::photo::raw::decode_raw(path).map_err(|e| err(Failure::Raw(e.to_string())))?;
        return crate::locate::find_charts(&frame.location_plane(), target)
            .map_err(|e| err(Failure::Region(format!("automatic location failed: {e}"))));
    }
    let dec = decode_file(path).map_err(|e| err(e.into()))?;
    locate_in_memory(&dec, target).map_err(err)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn samples_are_checked() {
        let ok = decoded_from_samples(2, 1, 3, Samples::U8(vec![0; 6])).unwrap();
        assert_eq!((ok.width, ok.height, ok.channels, ok.bits()), (2, 1, 3, 8));
        assert!(decoded_from_samples(2, 1, 3, Samples::U8(vec![0; 5])).is_err());
        assert!(decoded_from_samples(2, 1, 2, Samples::U8(vec![0; 4])).is_err());
        assert!(decoded_from_samples(0, 1, 1, Samples::U8(vec![])).is_err());
        let nan = decoded_from_samples(2, 2, 1, Samples::F32(vec![0.0, 0.5, f32::NAN, 1.0]));
        let msg = nan.unwrap_err().to_string();
        assert!(msg.contains("x=0, y=1"), "{msg}");
        // Huge sizes overflow the product instead of wrapping to a false match.
        assert!(decoded_from_samples(usize::MAX, 2, 1, Samples::U8(vec![0; 2])).is_err());
    }
}
