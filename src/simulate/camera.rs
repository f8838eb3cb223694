//! The simulated camera's settings: frame size and pixel pitch, where the chart
//! sits in the frame, illumination and exposure, noise, encoding, Bayer mosaic,
//! and the renderer's accuracy settings. Serialised into every shot's JSON.

use super::SimError;
use super::nuisance::{Chroma, LightGradient, Sharpen, check_colour};
use crate::distortion::{Lens, Ptlens};
use serde::{Deserialize, Serialize};
use std::fmt;
use std::str::FromStr;

/// How linear light is turned into stored code values.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(try_from = "String", into = "String")]
pub enum Encoding {
    /// The sRGB transfer curve (IEC 61966-2-1).
    Srgb,
    /// A pure power law: code = linear^(1/G).
    Gamma(f64),
    /// Code proportional to linear light.
    Linear,
}

impl Encoding {
    /// Encodes a linear value in [0, 1] to a code value in [0, 1].
    pub fn encode(&self, v: f64) -> f64 {
        let v = v.clamp(0.0, 1.0);
        match *self {
            Encoding::Linear => v,
            Encoding::Gamma(g) => v.powf(1.0 / g),
            Encoding::Srgb => {
                if v <= 0.003_130_8 {
                    12.92 * v
                } else {
                    1.055 * v.powf(1.0 / 2.4) - 0.055
                }
            }
        }
    }

    /// Decodes a code value in [0, 1] back to linear light (the inverse of [`Encoding::encode`]).
    pub fn decode(&self, c: f64) -> f64 {
        let c = c.clamp(0.0, 1.0);
        match *self {
            Encoding::Linear => c,
            Encoding::Gamma(g) => c.powf(g),
            Encoding::Srgb => {
                if c <= 0.040_45 {
                    c / 12.92
                } else {
                    ((c + 0.055) / 1.055).powf(2.4)
                }
            }
        }
    }
}

impl fmt::Display for Encoding {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Encoding::Srgb => write!(f, "srgb"),
            Encoding::Gamma(g) => write!(f, "gamma:{g}"),
            Encoding::Linear => write!(f, "linear"),
        }
    }
}

impl FromStr for Encoding {
    type Err = String;
    fn from_str(s: &str) -> Result<Self, String> {
        let t = s.trim().to_ascii_lowercase();
        match t.as_str() {
            "srgb" => Ok(Encoding::Srgb),
            "linear" => Ok(Encoding::Linear),
            _ => {
                let g = t
                    .strip_prefix("gamma:")
                    .and_then(|g| g.parse::<f64>().ok())
                    .ok_or_else(|| {
                        format!(
                            "encoding '{s}' is not one of srgb, linear, gamma:G (e.g. gamma:2.2)"
                        )
                    })?;
                if g.is_finite() && (0.1..=10.0).contains(&g) {
                    Ok(Encoding::Gamma(g))
                } else {
                    Err(format!("encoding '{s}': gamma must lie in 0.1–10"))
                }
            }
        }
    }
}

impl TryFrom<String> for Encoding {
    type Error = String;
    fn try_from(s: String) -> Result<Self, String> {
        s.parse()
    }
}

impl From<Encoding> for String {
    fn from(e: Encoding) -> String {
        e.to_string()
    }
}

/// The colour filter order of a Bayer mosaic, read left to right, top to bottom over a 2×2 cell.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "UPPERCASE")]
pub enum BayerOrder {
    /// R G / G B.
    Rggb,
    /// B G / G R.
    Bggr,
    /// G R / B G.
    Grbg,
    /// G B / R G.
    Gbrg,
}

impl BayerOrder {
    /// Colour index (0 = R, 1 = G, 2 = B) of the photosite at column `x`, row `y`.
    pub fn colour_at(&self, x: usize, y: usize) -> usize {
        let pattern: [usize; 4] = match self {
            BayerOrder::Rggb => [0, 1, 1, 2],
            BayerOrder::Bggr => [2, 1, 1, 0],
            BayerOrder::Grbg => [1, 0, 2, 1],
            BayerOrder::Gbrg => [1, 2, 0, 1],
        };
        pattern[(y % 2) * 2 + (x % 2)]
    }
}

impl fmt::Display for BayerOrder {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let s = match self {
            BayerOrder::Rggb => "RGGB",
            BayerOrder::Bggr => "BGGR",
            BayerOrder::Grbg => "GRBG",
            BayerOrder::Gbrg => "GBRG",
        };
        f.write_str(s)
    }
}

impl FromStr for BayerOrder {
    type Err = String;
    fn from_str(s: &str) -> Result<Self, String> {
        match s.trim().to_ascii_uppercase().as_str() {
            "RGGB" => Ok(BayerOrder::Rggb),
            "BGGR" => Ok(BayerOrder::Bggr),
            "GRBG" => Ok(BayerOrder::Grbg),
            "GBRG" => Ok(BayerOrder::Gbrg),
            _ => Err(format!(
                "Bayer order '{s}' is not one of RGGB, BGGR, GRBG, GBRG"
            )),
        }
    }
}

/// Whether the simulator integrates over the pixel area (the detector aperture).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize, Default)]
#[serde(rename_all = "lowercase")]
pub enum PixelAperture {
    /// A 100 % fill-factor square pixel, unless the system already holds an
    /// aperture factor (a factor whose name contains "aperture"), which then
    /// stands for the pixel aperture and is not applied twice.
    #[default]
    Auto,
    /// Always a 100 % fill-factor square pixel: sinc(pitch·u)·sinc(pitch·v).
    Square,
    /// Point sampling: the system's factors alone.
    None,
}

/// Accuracy settings of the optical renderer (see `render.rs` and the README table).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct RenderSettings {
    /// Fine-grid samples per pixel along each axis (≥ 1; even values keep the
    /// pixel aperture's first zero on the fine grid's Nyquist frequency).
    pub oversample: usize,
    /// Overlap of neighbouring tiles, pixels on each side (covers the PSF's support).
    pub margin_px: usize,
    /// FFT size of one tile along each axis, fine-grid samples (a power of two works best).
    pub fft_size: usize,
    /// Sub-samples per side of a fine cell that a hard edge crosses (area
    /// sampling of edges; 1 = point sampling everywhere).
    pub edge_subsamples: usize,
}

impl Default for RenderSettings {
    fn default() -> Self {
        RenderSettings {
            oversample: 2,
            margin_px: 16,
            fft_size: 512,
            edge_subsamples: 8,
        }
    }
}

impl RenderSettings {
    /// Output pixels per tile side (the FFT size in pixels less both margins).
    pub fn tile_px(&self) -> usize {
        (self.fft_size / self.oversample.max(1)).saturating_sub(2 * self.margin_px)
    }
}

/// Every setting of a simulated shot (lengths in the names' units; defaults via [`Default`]).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct Camera {
    /// Image width, pixels.
    pub width_px: usize,
    /// Image height, pixels.
    pub height_px: usize,
    /// Pixel pitch on the sensor, micrometres.
    pub pixel_pitch_um: f64,
    /// Width of the target frame in the image, pixels (before tilt); excludes `magnification`.
    pub chart_px: Option<f64>,
    /// Image size / chart size; with the pitch it gives the chart's size in pixels.
    pub magnification: Option<f64>,
    /// Rotation of the chart in the image, degrees, counter-clockwise as seen on screen.
    pub rotate_deg: f64,
    /// Perspective tilt of the chart plane, degrees (0 = facing the camera, < 90).
    pub tilt_deg: f64,
    /// Direction of the tilt axis in the chart plane, degrees from the chart's x axis
    /// (90 = about the vertical axis: left–right keystone; 0 = about the horizontal axis).
    pub tilt_axis_deg: f64,
    /// Focal length in pixels for the perspective; default: the frame's diagonal.
    pub focal_px: Option<f64>,
    /// Offset of the chart centre from the frame centre, pixels (x right, y down).
    pub offset_px: [f64; 2],
    /// Linear reflectance of the scene around the target frame.
    pub surround: f64,
    /// Illumination fall-off: relative loss of light at the frame's corners (0 = none),
    /// gain = 1 − falloff·(r/r_corner)².
    pub falloff: f64,
    /// Linear signal of paper white at the frame centre, as a fraction of clipping.
    pub exposure: f64,
    /// Full-well capacity, electrons at clipping; `None` = no photon shot noise.
    pub full_well_e: Option<f64>,
    /// Read noise, electrons RMS (needs `full_well_e`).
    pub read_noise_e: f64,
    /// Fixed-pattern (photo-response non-uniformity) noise: RMS relative gain spread.
    pub fpn: f64,
    /// Seed of the fixed pattern (a property of the sensor, kept across shots).
    pub fpn_seed: u64,
    /// Seed of the temporal noise.
    pub seed: u64,
    /// Transfer curve of the stored image (ignored for a Bayer mosaic: always linear).
    pub encoding: Encoding,
    /// Bits per stored sample, 8 or 16 (JPEG: 8; ignored for a Bayer mosaic: always 16).
    pub bits: u8,
    /// JPEG quality 1–100 when the photo is written as JPEG (default 90 there).
    pub jpeg_quality: Option<u8>,
    /// Write a Bayer colour-filter mosaic (16-bit linear) instead of a grey image.
    pub bayer: Option<BayerOrder>,
    /// Relative gains of the R, G, B photosites of the mosaic (white balance as shot).
    pub bayer_gains: [f64; 3],
    /// Demosaic the mosaic into an RGB photo (white-balanced, in `encoding` and
    /// `bits`, any format but DNG); `None` = write the raw mosaic.
    pub demosaic: Option<super::demosaic::Demosaic>,
    /// Radial lens distortion (PTLens form, radius normalised by half the
    /// frame's smaller side; see [`crate::distortion`]); `None` = a perfect
    /// rectilinear lens.
    pub distortion: Option<Ptlens>,
    /// Unsharp-mask sharpening in linear light, applied after the noise (as
    /// cameras sharpen); `None` = none.
    pub sharpen: Option<Sharpen>,
    /// Illumination gradient across the frame (on top of `falloff`); `None` = even.
    pub light_gradient: Option<LightGradient>,
    /// Colour of the light as R, G, B gains (white balance not corrected): the
    /// photo is then RGB, each channel with its own noise; `None` = grey.
    pub light_colour: Option<[f64; 3]>,
    /// Chroma sampling of a colour JPEG.
    pub chroma: Chroma,
    /// The print's own MTF: the chart's sines lose modulation by it at their
    /// chart frequency (cycles/mm of print); the truth stays the camera's MTF.
    /// `None` = a perfect print.
    pub print_blur: Option<crate::print_mtf::PrintMtf>,
    /// Whether and how the pixel area is integrated.
    pub pixel_aperture: PixelAperture,
    /// Renderer accuracy settings.
    pub render: RenderSettings,
}

impl Default for Camera {
    fn default() -> Self {
        Camera {
            width_px: 1200,
            height_px: 800,
            pixel_pitch_um: 4.3,
            chart_px: None,
            magnification: None,
            rotate_deg: 0.0,
            tilt_deg: 0.0,
            tilt_axis_deg: 90.0,
            focal_px: None,
            offset_px: [0.0, 0.0],
            surround: 0.2,
            falloff: 0.0,
            exposure: 0.8,
            full_well_e: None,
            read_noise_e: 0.0,
            fpn: 0.0,
            fpn_seed: 1,
            seed: 0,
            encoding: Encoding::Srgb,
            bits: 8,
            jpeg_quality: None,
            bayer: None,
            bayer_gains: [0.55, 1.0, 0.75],
            demosaic: None,
            distortion: None,
            sharpen: None,
            light_gradient: None,
            light_colour: None,
            chroma: Chroma::default(),
            print_blur: None,
            pixel_aperture: PixelAperture::Auto,
            render: RenderSettings::default(),
        }
    }
}

impl Camera {
    /// A noiseless, linear, 16-bit camera of the given frame size (for tests).
    pub fn noiseless(width_px: usize, height_px: usize) -> Camera {
        Camera {
            width_px,
            height_px,
            encoding: Encoding::Linear,
            bits: 16,
            ..Camera::default()
        }
    }

    /// Whether the photo is a raw Bayer mosaic (a mosaic not demosaicked).
    pub fn raw_mosaic(&self) -> bool {
        self.bayer.is_some() && self.demosaic.is_none()
    }

    /// Bits per stored sample: `bits`, or 16 for a raw Bayer mosaic.
    pub fn stored_bits(&self) -> u8 {
        if self.raw_mosaic() { 16 } else { self.bits }
    }

    /// The transfer curve actually stored: `encoding`, or linear for a raw Bayer mosaic.
    pub fn stored_encoding(&self) -> Encoding {
        if self.raw_mosaic() {
            Encoding::Linear
        } else {
            self.encoding
        }
    }

    /// Pixel pitch in millimetres.
    pub fn pitch_mm(&self) -> f64 {
        self.pixel_pitch_um * 1e-3
    }

    /// The distortion placed on this frame, when there is one (all-zero coefficients count as none).
    pub fn lens(&self) -> Option<Lens> {
        self.distortion
            .filter(|d| !d.is_zero())
            .map(|d| Lens::new(d, self.width_px, self.height_px))
    }

    /// Checks every setting's range; the error names the setting.
    pub fn validate(&self) -> Result<(), SimError> {
        let bad = |m: String| Err(SimError::Parameter(m));
        if self.width_px < 8 || self.height_px < 8 {
            return bad(format!(
                "image size {}×{} px is too small (at least 8×8)",
                self.width_px, self.height_px
            ));
        }
        if self.width_px.saturating_mul(self.height_px) > 400_000_000 {
            return bad(format!(
                "image size {}×{} px is too large (at most 400 megapixels)",
                self.width_px, self.height_px
            ));
        }
        if !(self.pixel_pitch_um.is_finite() && self.pixel_pitch_um > 0.0) {
            return bad(format!(
                "pixel pitch {} µm must be positive",
                self.pixel_pitch_um
            ));
        }
        if self.chart_px.is_some() && self.magnification.is_some() {
            return bad(
                "give either the chart size in pixels or the magnification, not both".into(),
            );
        }
        if let Some(n) = self.chart_px
            && !(n.is_finite() && n >= 4.0)
        {
            return bad(format!("chart size {n} px must be at least 4 px"));
        }
        if let Some(m) = self.magnification
            && !(m.is_finite() && m > 0.0)
        {
            return bad(format!("magnification {m} must be positive"));
        }
        if !(self.tilt_deg.is_finite() && self.tilt_deg.abs() < 90.0) {
            return bad(format!(
                "tilt {}° is impossible: it must lie strictly between −90° and 90°",
                self.tilt_deg
            ));
        }
        if !self.rotate_deg.is_finite()
            || !self.tilt_axis_deg.is_finite()
            || !self.offset_px.iter().all(|v| v.is_finite())
        {
            return bad("rotation, tilt axis and offset must be finite numbers".into());
        }
        if let Some(f) = self.focal_px
            && !(f.is_finite() && f > 0.0)
        {
            return bad(format!("focal length {f} px must be positive"));
        }
        if !(self.surround.is_finite() && (0.0..=1.0).contains(&self.surround)) {
            return bad(format!(
                "surround reflectance {} must lie in 0–1",
                self.surround
            ));
        }
        if !(self.falloff.is_finite() && (0.0..1.0).contains(&self.falloff)) {
            return bad(format!(
                "fall-off {} must lie in [0, 1) (the fraction of light lost at the corners)",
                self.falloff
            ));
        }
        if !(self.exposure.is_finite() && self.exposure > 0.0) {
            return bad(format!("exposure {} must be positive", self.exposure));
        }
        if let Some(n) = self.full_well_e
            && !(n.is_finite() && n >= 1.0)
        {
            return bad(format!("full-well count {n} must be at least 1 electron"));
        }
        if !(self.read_noise_e.is_finite() && self.read_noise_e >= 0.0) {
            return bad(format!(
                "read noise {} e⁻ must not be negative",
                self.read_noise_e
            ));
        }
        if self.read_noise_e > 0.0 && self.full_well_e.is_none() {
            return bad("read noise is given in electrons: give the full-well count too".into());
        }
        if !(self.fpn.is_finite() && (0.0..0.5).contains(&self.fpn)) {
            return bad(format!(
                "fixed-pattern noise {} must lie in [0, 0.5) (relative gain spread)",
                self.fpn
            ));
        }
        if self.bits != 8 && self.bits != 16 {
            return bad(format!("bits {} must be 8 or 16", self.bits));
        }
        if let Some(q) = self.jpeg_quality
            && !(1..=100).contains(&q)
        {
            return bad(format!("JPEG quality {q} must lie in 1–100"));
        }
        if self.demosaic.is_some() && self.bayer.is_none() {
            return bad("demosaicking needs a mosaic: give --bayer RGGB (or another order)".into());
        }
        if self.bayer.is_some() {
            if self.jpeg_quality.is_some() && self.demosaic.is_none() {
                return bad(
                    "a Bayer mosaic is written as 16-bit linear PNG or TIFF, not JPEG".into(),
                );
            }
            if !self
                .bayer_gains
                .iter()
                .all(|g| g.is_finite() && *g > 0.0 && *g <= 1.0)
            {
                return bad("Bayer gains must lie in (0, 1]".into());
            }
        }
        if let Encoding::Gamma(g) = self.encoding
            && !(g.is_finite() && g > 0.0)
        {
            return bad(format!("gamma {g} must be positive"));
        }
        if let Some(l) = self.lens() {
            l.check().map_err(SimError::Parameter)?;
        }
        if let Some(sh) = &self.sharpen {
            sh.check().map_err(SimError::Parameter)?;
        }
        if let Some(g) = &self.light_gradient {
            g.check().map_err(SimError::Parameter)?;
        }
        if let Some(c) = &self.light_colour {
            check_colour(c).map_err(SimError::Parameter)?;
        }
        if self.bayer.is_some() && (self.sharpen.is_some() || self.light_colour.is_some()) {
            return bad("a Bayer mosaic is raw data, neither sharpened nor tinted: \
                 leave out --sharpen and --light-colour"
                .into());
        }
        let r = &self.render;
        if !(1..=16).contains(&r.oversample) {
            return bad(format!("oversampling {} must lie in 1–16", r.oversample));
        }
        if !(1..=64).contains(&r.edge_subsamples) {
            return bad(format!(
                "edge sub-samples {} must lie in 1–64",
                r.edge_subsamples
            ));
        }
        if r.fft_size < 16 || r.tile_px() < 8 {
            return bad(format!(
                "render FFT size {} leaves no room for tiles with {}× oversampling and a {} px margin",
                r.fft_size, r.oversample, r.margin_px
            ));
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn srgb_round_trips_and_matches_reference_points() {
        let e = Encoding::Srgb;
        // Reference values of the sRGB curve (IEC 61966-2-1): 0.18 → 0.4613561, 0.5 → 0.7353570.
        assert!((e.encode(0.18) - 0.461_356_1).abs() < 1e-6);
        assert!((e.encode(0.5) - 0.735_357_0).abs() < 1e-6);
        for v in [0.0, 0.001, 0.003_130_8, 0.2, 1.0] {
            assert!((e.decode(e.encode(v)) - v).abs() < 1e-12);
        }
        let g: Encoding = "gamma:2.2".parse().unwrap();
        assert!((g.encode(0.5) - 0.5f64.powf(1.0 / 2.2)).abs() < 1e-15);
        assert!("gamma:x".parse::<Encoding>().is_err());
        assert_eq!("Linear".parse::<Encoding>().unwrap(), Encoding::Linear);
    }

    #[test]
    fn camera_serde_round_trip_and_validation() {
        let c = Camera {
            bayer: Some(BayerOrder::Grbg),
            encoding: Encoding::Gamma(1.8),
            ..Camera::default()
        };
        let j = serde_json::to_string(&c).unwrap();
        assert!(j.contains("\"gamma:1.8\"") && j.contains("\"GRBG\""), "{j}");
        let back: Camera = serde_json::from_str(&j).unwrap();
        assert_eq!(back, c);
        Camera::default().validate().unwrap();
        for bad in [
            Camera {
                tilt_deg: 90.0,
                ..Camera::default()
            },
            Camera {
                read_noise_e: -1.0,
                full_well_e: Some(1e4),
                ..Camera::default()
            },
            Camera {
                read_noise_e: 2.0,
                ..Camera::default()
            },
            Camera {
                bits: 12,
                ..Camera::default()
            },
            Camera {
                falloff: 1.0,
                ..Camera::default()
            },
        ] {
            assert!(bad.validate().is_err(), "{bad:?}");
        }
    }

    #[test]
    fn bayer_orders() {
        assert_eq!(BayerOrder::Rggb.colour_at(0, 0), 0);
        assert_eq!(BayerOrder::Rggb.colour_at(1, 1), 2);
        assert_eq!(BayerOrder::Gbrg.colour_at(0, 1), 0);
        assert_eq!(BayerOrder::Grbg.colour_at(1, 0), 0);
        assert_eq!(BayerOrder::Bggr.colour_at(1, 1), 0);
    }
}
