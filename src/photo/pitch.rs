//! Pixel pitch of a photo, for frequencies in cycles/mm on the sensor: from
//! the EXIF focal-plane resolution and its unit, rescaled when the stored
//! image is smaller than the frame the EXIF describes (a downscaled file),
//! sanity-checked against the sensors cameras have, and overridden by
//! `--pixel-pitch`. When the pitch is unknown or implausible the result says
//! so with warnings and the measurement stays in cycles/pixel. Also builds the
//! `auto` model (diffraction at the EXIF f-number × square pixel aperture).

use super::exif::{ExifFacts, ResolutionUnit};
use serde::Serialize;

/// Sensor pixel pitches outside this range (mm) are rejected as absurd (0.5–30 µm).
pub const PITCH_RANGE_MM: (f64, f64) = (0.5e-3, 30e-3);
/// Sensor diagonals outside this range (mm) are rejected as absurd.
pub const DIAGONAL_RANGE_MM: (f64, f64) = (2.0, 80.0);
/// FocalPlaneX and Y resolutions differing by more than this fraction are rejected.
pub const XY_TOLERANCE: f64 = 0.01;
/// Stored and EXIF sizes within this fraction are treated as the same frame.
pub const SIZE_TOLERANCE: f64 = 0.02;

/// Where a pixel pitch came from.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum PitchSource {
    /// Given by the user (`--pixel-pitch`).
    Override,
    /// EXIF focal-plane resolution, stored image at the size the EXIF describes.
    Exif,
    /// EXIF focal-plane resolution, scaled because the stored image was resized.
    ExifRescaled,
    /// No usable pitch: frequencies stay in cycles/pixel.
    None,
}

/// The pitch of the stored image's pixels, its source, and any warnings.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct PitchResult {
    /// Pitch of one stored image pixel in mm; `None` = unknown (cycles/pixel only).
    pub pitch_mm: Option<f64>,
    /// Where `pitch_mm` came from.
    pub source: PitchSource,
    /// The sensor's own pitch in mm from EXIF (before any rescaling), if readable.
    pub sensor_pitch_mm: Option<f64>,
    /// Factor applied to the sensor pitch for a resized image (EXIF width / stored width).
    pub scale: f64,
    /// Why the pitch was refused (something in the file looks wrong), one line each.
    pub warnings: Vec<String>,
    /// What was done or assumed (no pitch in the EXIF, rescaled, overridden), one line each.
    pub notes: Vec<String>,
}

impl PitchResult {
    /// `pitch_mm` in micrometres.
    pub fn pitch_um(&self) -> Option<f64> {
        self.pitch_mm.map(|p| p * 1e3)
    }
}

/// The pitch of the stored pixels of an `actual_width_px × actual_height_px`
/// image with EXIF `facts`; `override_mm` (from `--pixel-pitch`) wins.
pub fn resolve(
    facts: &ExifFacts,
    actual_width_px: usize,
    actual_height_px: usize,
    override_mm: Option<f64>,
) -> PitchResult {
    let mut warnings = Vec::new();
    let mut notes = Vec::new();
    let exif = from_exif(
        facts,
        actual_width_px,
        actual_height_px,
        &mut warnings,
        &mut notes,
    );
    let sensor_pitch_mm = exif.map(|(sensor, _)| sensor);
    if let Some(p) = override_mm {
        if p.is_finite() && p > 0.0 {
            let mut w = Vec::new();
            if let Some((sensor, scale)) = exif {
                let e = sensor * scale;
                if ((p - e) / e).abs() > XY_TOLERANCE {
                    w.push(format!(
                        "--pixel-pitch {:.4} um overrides the EXIF pitch {:.4} um",
                        p * 1e3,
                        e * 1e3
                    ));
                }
            }
            return PitchResult {
                pitch_mm: Some(p),
                source: PitchSource::Override,
                sensor_pitch_mm,
                scale: 1.0,
                warnings,
                notes: w,
            };
        }
        warnings.push(format!(
            "--pixel-pitch {p} mm is not a positive length: ignored"
        ));
    }
    match exif {
        Some((sensor, scale)) => PitchResult {
            pitch_mm: Some(sensor * scale),
            source: if scale == 1.0 {
                PitchSource::Exif
            } else {
                PitchSource::ExifRescaled
            },
            sensor_pitch_mm,
            scale,
            warnings,
            notes,
        },
        None => {
            notes.push(
                "pixel pitch unknown: frequencies in cycles/pixel only (give --pixel-pitch for lp/mm)"
                    .to_string(),
            );
            PitchResult {
                pitch_mm: None,
                source: PitchSource::None,
                sensor_pitch_mm,
                scale: 1.0,
                warnings,
                notes,
            }
        }
    }
}

/// (sensor pitch mm, scale for the stored image) from EXIF, or `None` with warnings.
fn from_exif(
    facts: &ExifFacts,
    aw: usize,
    ah: usize,
    warnings: &mut Vec<String>,
    notes: &mut Vec<String>,
) -> Option<(f64, f64)> {
    let Some(xres) = facts.focal_plane_x_res_px_per_unit else {
        if facts.focal_plane_y_res_px_per_unit.is_some() {
            warnings.push("EXIF has FocalPlaneYResolution but no X resolution".to_string());
        } else {
            notes.push("no FocalPlaneXResolution in the EXIF".to_string());
        }
        return None;
    };
    let unit = facts.focal_plane_unit.unwrap_or(ResolutionUnit::Inch);
    let Some(unit_mm) = unit.length_mm() else {
        warnings.push(format!(
            "EXIF FocalPlaneResolutionUnit is {unit:?}, not a physical length: no pitch"
        ));
        return None;
    };
    let pitch_x = unit_mm / xres;
    if let Some(yres) = facts.focal_plane_y_res_px_per_unit {
        let pitch_y = unit_mm / yres;
        if ((pitch_x - pitch_y) / pitch_x).abs() > XY_TOLERANCE {
            warnings.push(format!(
                "EXIF focal-plane pitch differs in x ({:.4} um) and y ({:.4} um) by more than {} %: not trusted",
                pitch_x * 1e3,
                pitch_y * 1e3,
                XY_TOLERANCE * 100.0
            ));
            return None;
        }
    }
    if !(pitch_x >= PITCH_RANGE_MM.0 && pitch_x <= PITCH_RANGE_MM.1) {
        warnings.push(format!(
            "EXIF focal-plane resolution gives a pixel pitch of {:.4} um, outside the {}–{} um of real sensors: not trusted",
            pitch_x * 1e3,
            PITCH_RANGE_MM.0 * 1e3,
            PITCH_RANGE_MM.1 * 1e3
        ));
        return None;
    }
    let scale = rescale(facts, aw, ah, warnings, notes)?;
    // The sensor's size: the EXIF frame if known, else the stored one scaled back.
    let (sw, sh) = match (facts.exif_width_px, facts.exif_height_px) {
        (Some(w), Some(h)) => (w as f64, h as f64),
        _ => (aw as f64 * scale, ah as f64 * scale),
    };
    let diagonal = pitch_x * sw.hypot(sh);
    if !(diagonal >= DIAGONAL_RANGE_MM.0 && diagonal <= DIAGONAL_RANGE_MM.1) {
        warnings.push(format!(
            "EXIF pitch {:.4} um × {}×{} px gives a {:.1} mm sensor diagonal, outside the {}–{} mm of real cameras: not trusted",
            pitch_x * 1e3,
            sw,
            sh,
            diagonal,
            DIAGONAL_RANGE_MM.0,
            DIAGONAL_RANGE_MM.1
        ));
        return None;
    }
    Some((pitch_x, scale))
}

/// Scale from sensor pixels to stored pixels (EXIF width / stored width), or
/// `None` when the stored image cannot be related to the EXIF frame.
fn rescale(
    facts: &ExifFacts,
    aw: usize,
    ah: usize,
    warnings: &mut Vec<String>,
    notes: &mut Vec<String>,
) -> Option<f64> {
    if facts.from_raw {
        // The raw frame is the sensor itself; EXIF sizes describe the camera's JPEG.
        return Some(1.0);
    }
    let Some(ew) = facts.exif_width_px else {
        return Some(1.0);
    };
    if aw == 0 || ah == 0 {
        return Some(1.0);
    }
    let (ew, eh) = (ew as f64, facts.exif_height_px.map(|h| h as f64));
    let (awf, ahf) = (aw as f64, ah as f64);
    let near = |a: f64, b: f64| ((a - b) / b).abs() <= SIZE_TOLERANCE;
    let (rx, ry) = match eh {
        Some(eh) => {
            let (rx, ry) = (ew / awf, eh / ahf);
            // A file rotated by software may have swapped its axes.
            let (sx, sy) = (eh / awf, ew / ahf);
            if !near(rx, ry) && near(sx, sy) && !near(ew, eh) {
                warnings.push(format!(
                    "stored image {aw}×{ah} px matches the EXIF frame {ew}×{eh} px turned by 90°"
                ));
                (sx, sy)
            } else {
                (rx, ry)
            }
        }
        None => (ew / awf, ew / awf),
    };
    if !near(rx, ry) {
        if near(rx.min(ry), 1.0) {
            warnings.push(format!(
                "stored image {aw}×{ah} px has another shape than the EXIF frame {}×{} px: taken as a crop, pitch not rescaled",
                ew,
                eh.unwrap_or(f64::NAN)
            ));
            return Some(1.0);
        }
        warnings.push(format!(
            "stored image {aw}×{ah} px is both resized and cropped relative to the EXIF frame {}×{} px: pitch unknown",
            ew,
            eh.unwrap_or(f64::NAN)
        ));
        return None;
    }
    if near(rx, 1.0) {
        return Some(1.0);
    }
    notes.push(format!(
        "stored image is {aw} px wide but the EXIF describes {ew} px: pixel pitch scaled by {ew}/{aw} = {rx:.4}"
    ));
    Some(rx)
}

/// The `auto` model as (kind, spec) pairs for `model::spec::parse_factor`:
/// diffraction at the EXIF f-number and `wavelength_mm`, and a square pixel
/// aperture of side `pitch_mm`. Fails when the f-number is missing or 0.
pub fn auto_model_specs(
    facts: &ExifFacts,
    pitch_mm: f64,
    wavelength_mm: f64,
) -> Result<Vec<(String, String)>, String> {
    let fnum = facts.f_number.ok_or_else(|| {
        "the EXIF has no usable f-number (FNumber missing or 0), so the auto model \
         cannot place diffraction; give --model SYSTEM.toml instead"
            .to_string()
    })?;
    if !(fnum.is_finite() && fnum > 0.0) {
        return Err(format!("f-number {fnum} is not positive"));
    }
    if !(pitch_mm.is_finite() && pitch_mm > 0.0) {
        return Err(format!(
            "pixel pitch {pitch_mm} mm is not a positive length; give --pixel-pitch"
        ));
    }
    if !(wavelength_mm.is_finite() && wavelength_mm > 0.0) {
        return Err(format!(
            "wavelength {wavelength_mm} mm is not a positive length"
        ));
    }
    let lambda = length_text(wavelength_mm, "nm", 1e6);
    let side = length_text(pitch_mm, "um", 1e3);
    Ok(vec![
        (
            "optics".to_string(),
            format!("diffraction:lambda={lambda},fnum={fnum}"),
        ),
        ("aperture".to_string(), format!("rect:A={side},B={side}")),
    ])
}

/// `value_mm` written in `unit` with the fewest decimals that read back
/// within 1e-12 (relative) through `units::parse_length_mm`.
fn length_text(value_mm: f64, unit: &str, per_mm: f64) -> String {
    let v = value_mm * per_mm;
    for decimals in 0..=17 {
        let mut t = format!("{v:.decimals$}");
        if t.contains('.') {
            t = t.trim_end_matches('0').trim_end_matches('.').to_string();
        }
        let text = format!("{t}{unit}");
        if let Ok(back) = crate::units::parse_length_mm(&text)
            && ((back - value_mm) / value_mm).abs() <= 1e-12
        {
            return text;
        }
    }
    format!("{value_mm}mm")
}

#[cfg(test)]
mod tests {
    use super::*;

    fn facts(xres: f64, yres: Option<f64>, w: Option<u32>, h: Option<u32>) -> ExifFacts {
        ExifFacts {
            focal_plane_x_res_px_per_unit: Some(xres),
            focal_plane_y_res_px_per_unit: yres,
            exif_width_px: w,
            exif_height_px: h,
            ..ExifFacts::default()
        }
    }

    #[test]
    fn units_inch_cm_mm() {
        // 4000 px/inch → 25.4/4000 mm = 6.35 um
        let f = facts(4000.0, Some(4000.0), Some(6000), Some(4000));
        let r = resolve(&f, 6000, 4000, None);
        assert_eq!(r.source, PitchSource::Exif);
        assert!((r.pitch_mm.unwrap() - 25.4 / 4000.0).abs() < 1e-15);
        let mut f = facts(1575.0, None, None, None);
        f.focal_plane_unit = Some(ResolutionUnit::Centimetre);
        let r = resolve(&f, 6000, 4000, None);
        assert!((r.pitch_mm.unwrap() - 10.0 / 1575.0).abs() < 1e-15);
        let mut f = facts(250.0, None, None, None);
        f.focal_plane_unit = Some(ResolutionUnit::Millimetre);
        assert!((resolve(&f, 6000, 4000, None).pitch_mm.unwrap() - 0.004).abs() < 1e-15);
    }

    #[test]
    fn unequal_xy_absurd_pitch_and_sensor_fall_back() {
        let r = resolve(&facts(4000.0, Some(4100.0), None, None), 6000, 4000, None);
        assert_eq!(r.pitch_mm, None);
        assert!(r.warnings.iter().any(|w| w.contains("differs in x")));
        // 100 px/inch → 254 um pitch
        let r = resolve(&facts(100.0, None, None, None), 600, 400, None);
        assert_eq!(r.pitch_mm, None);
        assert!(r.warnings.iter().any(|w| w.contains("outside")));
        // 5 um pitch on a 30000 px wide frame → 150 mm wide sensor
        let r = resolve(
            &facts(5080.0, None, Some(30000), Some(20000)),
            30000,
            20000,
            None,
        );
        assert_eq!(r.pitch_mm, None);
        assert!(r.warnings.iter().any(|w| w.contains("diagonal")));
        let mut f = facts(4000.0, None, None, None);
        f.focal_plane_unit = Some(ResolutionUnit::None);
        assert_eq!(resolve(&f, 6000, 4000, None).pitch_mm, None);
    }

    #[test]
    fn override_wins_and_bad_override_is_ignored() {
        let f = facts(4000.0, None, None, None);
        let r = resolve(&f, 6000, 4000, Some(0.004));
        assert_eq!(r.pitch_mm, Some(0.004));
        assert_eq!(r.source, PitchSource::Override);
        assert_eq!(r.notes.len(), 1, "{:?}", r.notes);
        assert!(r.warnings.is_empty(), "{:?}", r.warnings);
        let r = resolve(&f, 6000, 4000, Some(-1.0));
        assert_eq!(r.source, PitchSource::Exif);
        assert!(r.warnings[0].contains("ignored"));
        let r = resolve(&ExifFacts::default(), 600, 400, Some(0.0025));
        assert_eq!(r.pitch_mm, Some(0.0025));
    }

    #[test]
    fn downscaled_rotated_cropped_and_raw_frames() {
        // 6000×4000 sensor at 6.35 um stored at 1500×1000: 4× the pitch.
        let f = facts(4000.0, None, Some(6000), Some(4000));
        let r = resolve(&f, 1500, 1000, None);
        assert_eq!(r.source, PitchSource::ExifRescaled);
        assert!((r.pitch_mm.unwrap() - 4.0 * 25.4 / 4000.0).abs() < 1e-15);
        // turned by 90° and downscaled
        let r = resolve(&f, 1000, 1500, None);
        assert!((r.pitch_mm.unwrap() - 4.0 * 25.4 / 4000.0).abs() < 1e-15);
        // a crop: same pixels, no rescale
        let r = resolve(&f, 6000, 3000, None);
        assert_eq!(r.source, PitchSource::Exif);
        // resized and cropped: unknown
        let r = resolve(&f, 1500, 500, None);
        assert_eq!(r.pitch_mm, None);
        // a raw frame keeps the sensor pitch even if EXIF sizes describe the JPEG
        let mut f = facts(4000.0, None, Some(6000), Some(4000));
        f.from_raw = true;
        let r = resolve(&f, 6080, 4050, None);
        assert_eq!(r.source, PitchSource::Exif);
    }

    #[test]
    fn auto_specs_read_back_exactly() {
        let f = ExifFacts {
            f_number: Some(5.6),
            ..ExifFacts::default()
        };
        let specs = auto_model_specs(&f, 0.0043, 550e-6).unwrap();
        assert_eq!(specs[0].0, "optics");
        assert_eq!(specs[0].1, "diffraction:lambda=550nm,fnum=5.6");
        assert_eq!(specs[1].0, "aperture");
        assert_eq!(specs[1].1, "rect:A=4.3um,B=4.3um");
        // an awkward pitch must still read back to the same f64
        let p = 25.4 / (505679.0 / 60.0);
        let specs = auto_model_specs(&f, p, 550e-6).unwrap();
        let a = specs[1]
            .1
            .trim_start_matches("rect:A=")
            .split(',')
            .next()
            .unwrap();
        let back = crate::units::parse_length_mm(a).unwrap();
        assert!(((back - p) / p).abs() <= 1e-12, "{a}");
        assert!(auto_model_specs(&ExifFacts::default(), 0.004, 550e-6).is_err());
        assert!(auto_model_specs(&f, 0.0, 550e-6).is_err());
    }
}
