//! EXIF facts a measurement needs (exposure, optics, camera, focal-plane
//! resolution and the image size the EXIF describes), read from JPEG, TIFF,
//! PNG or HEIF files with kamadak-exif and from camera raws through the raw
//! adapter ([`super::raw`]). Missing EXIF gives empty facts, never an error;
//! absurd values (an f-number of 0, a zero denominator) are dropped with a
//! warning instead of turning into nonsense downstream.

use serde::Serialize;
use std::io::{BufReader, Cursor, Read, Seek, SeekFrom};
use std::path::Path;
use thiserror::Error;

/// Why EXIF facts could not be read at all (only I/O: missing EXIF is not an error).
#[derive(Debug, Clone, PartialEq, Error)]
pub enum ExifError {
    /// The file could not be opened or read.
    #[error("{path}: cannot read: {cause}")]
    Io {
        /// The file.
        path: String,
        /// The operating system's reason.
        cause: String,
    },
}

/// The unit of EXIF FocalPlaneX/YResolution (tag 0xA210; absent means inch).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(rename_all = "lowercase")]
pub enum ResolutionUnit {
    /// Code 2 (also the EXIF default when the tag is absent): pixels per inch.
    Inch,
    /// Code 3: pixels per centimetre.
    Centimetre,
    /// Code 4 (TIFF/EP, used by some cameras): pixels per millimetre.
    Millimetre,
    /// Code 5 (TIFF/EP): pixels per micrometre.
    Micrometre,
    /// Code 1: no absolute unit; no physical pitch can be derived.
    None,
    /// Any other code, kept as written.
    Unknown(u16),
}

impl ResolutionUnit {
    /// The unit for an EXIF/TIFF code.
    pub fn from_code(code: u16) -> ResolutionUnit {
        match code {
            1 => ResolutionUnit::None,
            2 => ResolutionUnit::Inch,
            3 => ResolutionUnit::Centimetre,
            4 => ResolutionUnit::Millimetre,
            5 => ResolutionUnit::Micrometre,
            c => ResolutionUnit::Unknown(c),
        }
    }

    /// The unit's length in millimetres, if it is an absolute unit.
    pub fn length_mm(&self) -> Option<f64> {
        match self {
            ResolutionUnit::Inch => Some(25.4),
            ResolutionUnit::Centimetre => Some(10.0),
            ResolutionUnit::Millimetre => Some(1.0),
            ResolutionUnit::Micrometre => Some(1e-3),
            ResolutionUnit::None | ResolutionUnit::Unknown(_) => None,
        }
    }
}

/// The EXIF facts of one photo; `None` = absent or rejected as absurd (see `warnings`).
#[derive(Debug, Clone, Default, PartialEq, Serialize)]
pub struct ExifFacts {
    /// Camera maker (EXIF Make).
    pub make: Option<String>,
    /// Camera model (EXIF Model).
    pub model: Option<String>,
    /// Lens model (EXIF LensModel).
    pub lens_model: Option<String>,
    /// Aperture f-number N (EXIF FNumber), dimensionless.
    pub f_number: Option<f64>,
    /// Focal length in mm (EXIF FocalLength, not the 35 mm equivalent).
    pub focal_length_mm: Option<f64>,
    /// Exposure time in seconds (EXIF ExposureTime).
    pub exposure_time_s: Option<f64>,
    /// ISO speed (EXIF PhotographicSensitivity / ISOSpeedRatings).
    pub iso: Option<u32>,
    /// EXIF Orientation code 1–8 (1 = stored pixels are upright).
    pub orientation: Option<u16>,
    /// FocalPlaneXResolution, pixels per `focal_plane_unit` along the image width.
    pub focal_plane_x_res_px_per_unit: Option<f64>,
    /// FocalPlaneYResolution, pixels per `focal_plane_unit` along the image height.
    pub focal_plane_y_res_px_per_unit: Option<f64>,
    /// FocalPlaneResolutionUnit as written; `None` = tag absent (EXIF default: inch).
    pub focal_plane_unit: Option<ResolutionUnit>,
    /// Image width in pixels that the EXIF describes (PixelXDimension, else ImageWidth).
    pub exif_width_px: Option<u32>,
    /// Image height in pixels that the EXIF describes (PixelYDimension, else ImageLength).
    pub exif_height_px: Option<u32>,
    /// True when the facts come from a camera raw (the stored frame is the sensor itself).
    pub from_raw: bool,
    /// Values dropped as absent or absurd, and why, one line each.
    pub warnings: Vec<String>,
}

impl ExifFacts {
    /// One human line for plot captions: "Canon X, f/5.6, 57 mm, 1/100 s, ISO 100".
    pub fn describe(&self) -> String {
        let mut parts = Vec::new();
        let camera = match (&self.make, &self.model) {
            (Some(mk), Some(md)) if md.starts_with(mk.as_str()) => md.clone(),
            (Some(mk), Some(md)) => format!("{mk} {md}"),
            (Some(mk), None) => mk.clone(),
            (None, Some(md)) => md.clone(),
            (None, None) => String::new(),
        };
        if !camera.is_empty() {
            parts.push(camera);
        }
        if let Some(l) = &self.lens_model {
            parts.push(l.clone());
        }
        if let Some(n) = self.f_number {
            parts.push(format!("f/{}", trim_number(n, 1)));
        }
        if let Some(f) = self.focal_length_mm {
            parts.push(format!("{} mm", trim_number(f, 1)));
        }
        if let Some(t) = self.exposure_time_s {
            parts.push(if t < 0.5 && t > 0.0 {
                format!("1/{} s", trim_number(1.0 / t, 0))
            } else {
                format!("{} s", trim_number(t, 2))
            });
        }
        if let Some(iso) = self.iso {
            parts.push(format!("ISO {iso}"));
        }
        parts.join(", ")
    }

    /// Sets `f_number`, rejecting 0, negatives and values no lens has (0.5 < N ≤ 512).
    pub fn set_f_number(&mut self, value: Option<f64>) {
        self.f_number = self.checked("FNumber", value, 0.5, 512.0);
    }

    /// Sets `focal_length_mm`, rejecting 0, negatives and values above 10 m.
    pub fn set_focal_length_mm(&mut self, value: Option<f64>) {
        self.focal_length_mm = self.checked("FocalLength", value, 0.0, 10_000.0);
    }

    /// Sets `exposure_time_s`, rejecting 0, negatives and values above a day.
    pub fn set_exposure_time_s(&mut self, value: Option<f64>) {
        self.exposure_time_s = self.checked("ExposureTime", value, 0.0, 86_400.0);
    }

    /// Sets `iso`, rejecting 0.
    pub fn set_iso(&mut self, value: Option<u32>) {
        self.iso = match value {
            Some(0) => {
                self.warnings
                    .push("ISO is 0 in the EXIF: ignored as absent".to_string());
                None
            }
            v => v,
        };
    }

    /// Sets a focal-plane resolution (`x` or `y`), rejecting 0, negatives and NaN.
    pub fn set_focal_plane_res(&mut self, axis: char, value: Option<f64>) {
        let name = format!("FocalPlane{}Resolution", axis.to_ascii_uppercase());
        let v = self.checked(&name, value, 0.0, f64::INFINITY);
        if axis.eq_ignore_ascii_case(&'x') {
            self.focal_plane_x_res_px_per_unit = v;
        } else {
            self.focal_plane_y_res_px_per_unit = v;
        }
    }

    fn checked(&mut self, name: &str, value: Option<f64>, low: f64, high: f64) -> Option<f64> {
        let v = value?;
        if v.is_nan() {
            self.warnings.push(format!(
                "{name} in the EXIF is not a number (zero denominator?): ignored as absent"
            ));
            None
        } else if v == 0.0 {
            let hint = if name == "FNumber" || name == "FocalLength" {
                ", e.g. a manual lens or an adapter"
            } else {
                ""
            };
            self.warnings.push(format!(
                "{name} is 0 in the EXIF (not recorded{hint}): ignored as absent"
            ));
            None
        } else if !(v > low && v <= high) {
            self.warnings.push(format!(
                "{name} = {v} in the EXIF is outside ({low}, {high}]: ignored as absurd"
            ));
            None
        } else {
            Some(v)
        }
    }

    /// Fills every absent field of `self` from `other` (warnings are appended).
    pub fn fill_from(&mut self, other: ExifFacts) {
        macro_rules! fill {
            ($($f:ident),*) => { $( if self.$f.is_none() { self.$f = other.$f; } )* };
        }
        fill!(
            make,
            model,
            lens_model,
            f_number,
            focal_length_mm,
            exposure_time_s,
            iso,
            orientation,
            focal_plane_x_res_px_per_unit,
            focal_plane_y_res_px_per_unit,
            focal_plane_unit,
            exif_width_px,
            exif_height_px
        );
        for w in other.warnings {
            if !self.warnings.contains(&w) {
                self.warnings.push(w);
            }
        }
    }
}

/// `n` with at most `decimals` decimals and no trailing zeros.
fn trim_number(n: f64, decimals: usize) -> String {
    let s = format!("{n:.decimals$}");
    if s.contains('.') {
        s.trim_end_matches('0').trim_end_matches('.').to_string()
    } else {
        s
    }
}

/// Reads the EXIF facts of any photo: raws through rawler's metadata (plus the
/// TIFF EXIF where the container is TIFF-based), other files through
/// kamadak-exif. A file without EXIF (or with unreadable EXIF) gives empty
/// facts with a warning; only a file that cannot be read at all is an error.
pub fn read_facts(path: &Path) -> Result<ExifFacts, ExifError> {
    if super::raw::is_raw_path(path) {
        return super::raw::read_raw_facts(path).map_err(|e| ExifError::Io {
            path: path.display().to_string(),
            cause: match e {
                super::raw::RawError::Io { cause, .. } => cause,
                other => other.to_string(),
            },
        });
    }
    let io = |e: std::io::Error| ExifError::Io {
        path: path.display().to_string(),
        cause: e.to_string(),
    };
    let mut file = std::fs::File::open(path).map_err(io)?;
    // A JPEG's EXIF is in its headers: the first HEAD_READ bytes usually hold
    // them all, and the rest of the file is not read.
    let mut head = Vec::new();
    (&mut file)
        .take(HEAD_READ)
        .read_to_end(&mut head)
        .map_err(io)?;
    if let Some(h) = jpeg_headers(&head) {
        return Ok(facts_from_reader(&mut Cursor::new(h)));
    }
    file.seek(SeekFrom::Start(0)).map_err(io)?;
    Ok(facts_from_reader(&mut BufReader::new(file)))
}

/// How much of a file [`read_facts`] reads first, bytes.
const HEAD_READ: u64 = 256 << 10;

/// A JPEG's headers up to its first scan, closed with an end-of-image marker,
/// when `bytes` hold them all: where kamadak-exif looks for EXIF. Given the
/// whole file, it reads on through the scan data to the end looking for
/// markers (1.1 ms for a 24 MP JPEG without EXIF, before any decoding).
fn jpeg_headers(bytes: &[u8]) -> Option<Vec<u8>> {
    let (_, sos, _) = super::jpeg::header_segments(bytes).find(|s| s.0 == 0xDA)?;
    let mut h = bytes[..sos].to_vec();
    h.extend_from_slice(&[0xFF, 0xD9]);
    Some(h)
}

/// EXIF facts from the bytes of a JPEG/TIFF/PNG/HEIF/WebP file (empty facts with a warning when absent).
pub fn facts_from_bytes(bytes: &[u8]) -> ExifFacts {
    let headers = jpeg_headers(bytes);
    facts_from_reader(&mut Cursor::new(headers.as_deref().unwrap_or(bytes)))
}

/// EXIF facts from a TIFF-based or other container kamadak-exif knows; `None` if it finds none.
pub(crate) fn try_facts_from_bytes(bytes: &[u8]) -> Option<ExifFacts> {
    ::exif::Reader::new()
        .read_from_container(&mut Cursor::new(bytes))
        .ok()
        .map(|ex| facts_from_exif(&ex))
}

fn facts_from_reader<R: std::io::BufRead + std::io::Seek>(reader: &mut R) -> ExifFacts {
    match ::exif::Reader::new().read_from_container(reader) {
        Ok(ex) => facts_from_exif(&ex),
        Err(::exif::Error::NotFound(_)) => ExifFacts::default(),
        Err(e) => ExifFacts {
            warnings: vec![format!("EXIF not readable ({e}): no camera facts")],
            ..ExifFacts::default()
        },
    }
}

fn field(ex: &::exif::Exif, tag: ::exif::Tag) -> Option<&::exif::Value> {
    ex.get_field(tag, ::exif::In::PRIMARY).map(|f| &f.value)
}

/// The first value of a rational/integer/float field as f64 (NaN for a zero denominator).
fn number(v: &::exif::Value) -> Option<f64> {
    use ::exif::Value as V;
    match v {
        V::Rational(r) => r.first().map(|r| {
            if r.denom == 0 {
                f64::NAN
            } else {
                r.num as f64 / r.denom as f64
            }
        }),
        V::SRational(r) => r.first().map(|r| {
            if r.denom == 0 {
                f64::NAN
            } else {
                r.num as f64 / r.denom as f64
            }
        }),
        V::Float(f) => f.first().map(|&x| x as f64),
        V::Double(f) => f.first().copied(),
        _ => v.get_uint(0).map(|u| u as f64),
    }
}

fn text(v: &::exif::Value) -> Option<String> {
    match v {
        ::exif::Value::Ascii(parts) => {
            let s: String = parts
                .iter()
                .map(|p| String::from_utf8_lossy(p).to_string())
                .collect::<Vec<_>>()
                .join(" ");
            clean_text(&s)
        }
        _ => None,
    }
}

/// Trims NULs and spaces; empty text is `None`.
pub(crate) fn clean_text(s: &str) -> Option<String> {
    let t = s.trim_matches(|c: char| c == '\0' || c.is_whitespace());
    (!t.is_empty()).then(|| t.to_string())
}

fn facts_from_exif(ex: &::exif::Exif) -> ExifFacts {
    use ::exif::Tag;
    let mut f = ExifFacts {
        make: field(ex, Tag::Make).and_then(text),
        model: field(ex, Tag::Model).and_then(text),
        lens_model: field(ex, Tag::LensModel).and_then(text),
        orientation: field(ex, Tag::Orientation)
            .and_then(|v| v.get_uint(0))
            .map(|u| u as u16),
        ..ExifFacts::default()
    };
    f.set_f_number(field(ex, Tag::FNumber).and_then(number));
    f.set_focal_length_mm(field(ex, Tag::FocalLength).and_then(number));
    f.set_exposure_time_s(field(ex, Tag::ExposureTime).and_then(number));
    f.set_iso(field(ex, Tag::PhotographicSensitivity).and_then(|v| v.get_uint(0)));
    f.set_focal_plane_res('x', field(ex, Tag::FocalPlaneXResolution).and_then(number));
    f.set_focal_plane_res('y', field(ex, Tag::FocalPlaneYResolution).and_then(number));
    f.focal_plane_unit = field(ex, Tag::FocalPlaneResolutionUnit)
        .and_then(|v| v.get_uint(0))
        .map(|c| ResolutionUnit::from_code(c as u16));
    // ImageWidth of IFD0 is the image's own size only when IFD0 is the main
    // image (NewSubfileType absent or 0), not a DNG thumbnail.
    let ifd0_is_main = field(ex, Tag(::exif::Context::Tiff, 0x00fe))
        .and_then(|v| v.get_uint(0))
        .is_none_or(|t| t == 0);
    let dim = |pixel: Tag, tiff: Tag| {
        field(ex, pixel)
            .and_then(|v| v.get_uint(0))
            .or_else(|| {
                ifd0_is_main
                    .then(|| field(ex, tiff).and_then(|v| v.get_uint(0)))
                    .flatten()
            })
            .filter(|&w| w > 0)
    };
    f.exif_width_px = dim(Tag::PixelXDimension, Tag::ImageWidth);
    f.exif_height_px = dim(Tag::PixelYDimension, Tag::ImageLength);
    f
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_jpegs_headers_hold_the_same_facts_as_the_whole_file() {
        // kamadak-exif over the whole file is the reference; the real files
        // are three cameras' JPEGs (one with a large maker note).
        let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("testdata/real/exif_jpeg");
        let mut n = 0;
        for e in std::fs::read_dir(dir).unwrap() {
            let p = e.unwrap().path();
            if p.extension().is_none_or(|x| x != "jpg") {
                continue;
            }
            let bytes = std::fs::read(&p).unwrap();
            let whole = ::exif::Reader::new()
                .read_from_container(&mut Cursor::new(&bytes))
                .unwrap();
            let want = format!("{:?}", facts_from_exif(&whole));
            assert!(jpeg_headers(&bytes).is_some(), "{}", p.display());
            assert_eq!(format!("{:?}", facts_from_bytes(&bytes)), want);
            assert_eq!(format!("{:?}", read_facts(&p).unwrap()), want);
            n += 1;
        }
        assert_eq!(n, 3);
        // Cut short before its first scan: the whole (short) file is read as before.
        let b =
            std::fs::read(Path::new(env!("CARGO_MANIFEST_DIR")).join("testdata/a4_log_shot.jpg"))
                .unwrap();
        assert!(jpeg_headers(&b[..100]).is_none());
        assert!(facts_from_bytes(&b[..100]).f_number.is_none());
    }

    #[test]
    fn zero_and_nan_values_become_absent_with_a_warning() {
        let mut f = ExifFacts::default();
        f.set_f_number(Some(0.0));
        f.set_focal_length_mm(Some(f64::NAN));
        f.set_exposure_time_s(Some(-1.0));
        f.set_iso(Some(0));
        assert_eq!(f.f_number, None);
        assert_eq!(f.focal_length_mm, None);
        assert_eq!(f.exposure_time_s, None);
        assert_eq!(f.iso, None);
        assert_eq!(f.warnings.len(), 4, "{:?}", f.warnings);
        f.set_f_number(Some(2.8));
        assert_eq!(f.f_number, Some(2.8));
    }

    #[test]
    fn resolution_units_have_their_lengths() {
        assert_eq!(ResolutionUnit::from_code(2).length_mm(), Some(25.4));
        assert_eq!(ResolutionUnit::from_code(3).length_mm(), Some(10.0));
        assert_eq!(ResolutionUnit::from_code(4).length_mm(), Some(1.0));
        assert_eq!(ResolutionUnit::from_code(1).length_mm(), None);
        assert_eq!(ResolutionUnit::from_code(9).length_mm(), None);
    }

    #[test]
    fn describe_reads_like_a_caption() {
        let f = ExifFacts {
            make: Some("Canon".into()),
            model: Some("Canon PowerShot S40".into()),
            f_number: Some(5.6),
            focal_length_mm: Some(57.0),
            exposure_time_s: Some(0.01),
            iso: Some(100),
            ..ExifFacts::default()
        };
        assert_eq!(
            f.describe(),
            "Canon PowerShot S40, f/5.6, 57 mm, 1/100 s, ISO 100"
        );
    }

    #[test]
    fn garbage_bytes_give_empty_facts_with_a_warning() {
        let f = facts_from_bytes(b"this is not an image at all");
        assert_eq!(f.f_number, None);
        assert_eq!(f.warnings.len(), 1);
    }
}
