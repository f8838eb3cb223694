//! Camera simulator: renders a target description through a modelled camera
//! and writes the exact truth beside the photo.
//!
//! [`render`](fn@render) places the chart in the frame ([`placement`]), renders the
//! chart's reflectance through the system OTF and the pixel aperture
//! ([`render`](mod@render)), applies exposure, illumination fall-off and sensor
//! noise ([`noise`]), and computes the truth ([`truth`]); [`write_shot`] encodes
//! the photo ([`encode`]) and writes `STEM.truth.csv` and `STEM.json` beside
//! it, atomically. [`quick_shot`] makes a small noiseless shot for tests.
//!
//! Which OTF is applied: every system factor except sampling-grid factors (a
//! factor that defines a Nyquist frequency and is not named an aperture: the
//! simulator samples for real, so the statistical sampling MTF would count
//! twice), times a 100 % fill-factor square pixel aperture
//! sinc(pitch·u)·sinc(pitch·v) unless the system already holds an aperture
//! factor (see [`PixelAperture`]). The truth is |that OTF| at the image's local
//! frequency vector along the sweep.

pub mod camera;
pub mod demo;
pub mod demosaic;
pub mod dng;
pub mod encode;
pub mod noise;
pub mod nuisance;
pub mod placement;
pub mod render;
pub mod truth;

pub use camera::{BayerOrder, Camera, Encoding, PixelAperture, RenderSettings};
pub use demosaic::Demosaic;
pub use encode::PhotoFormat;
pub use nuisance::{Chroma, LightGradient, Sharpen};
pub use truth::{PatchTruth, SweepTruth, TruthRow, mtf_at};

use crate::geometry::{Homography, rect_corners};
use crate::model::System;
use crate::target::{Target, TargetError};
use rayon::prelude::*;
use serde_json::json;
use std::path::{Path, PathBuf};
use thiserror::Error;

/// Why a shot could not be simulated or written.
#[derive(Debug, Error)]
pub enum SimError {
    /// A camera setting is out of range.
    #[error("{0}")]
    Parameter(String),
    /// The chart cannot be placed as asked (outside the frame, behind the camera).
    #[error("{0}")]
    Placement(String),
    /// The target description is invalid.
    #[error(transparent)]
    Target(#[from] TargetError),
    /// Encoding the photo failed.
    #[error("cannot encode the photo: {0}")]
    Encode(String),
    /// Writing an output file failed.
    #[error("{path}: cannot write: {source}")]
    Io {
        /// The file.
        path: String,
        /// The cause.
        source: std::io::Error,
    },
    /// A bug.
    #[error("internal error: {0}")]
    Internal(String),
}

/// A simulated shot: the linear images, the placement and the truth.
#[derive(Debug, Clone)]
pub struct Shot {
    /// The settings it was made with.
    pub camera: Camera,
    /// Image width, pixels.
    pub width: usize,
    /// Image height, pixels.
    pub height: usize,
    /// Noiseless, unclipped linear signal (1.0 = clipping), row-major; for a
    /// mosaic, with the photosites' colour gains applied; sharpened when the
    /// camera sharpens; without the light's colour.
    pub signal: Vec<f32>,
    /// The recorded linear image: signal with noise (then sharpened), clipped
    /// to [0, 1]; what is encoded (for a colour or demosaicked shot: its green channel).
    pub linear: Vec<f32>,
    /// A colour shot's recorded linear R, G, B planes (as `linear`; a
    /// demosaicked mosaic's after white balance); `None` = grey.
    pub colour: Option<[Vec<f32>; 3]>,
    /// Chart (mm) → image (px) before lens distortion (see `camera.distortion`).
    pub chart_to_image: Homography,
    /// The target frame's corners (0,0),(w,0),(w,h),(0,h) in image pixels (where they land in the photo).
    pub target_corners: [f64; 8],
    /// The target's name.
    pub target_name: String,
    /// Truth of every sweep (the first is the shot's `roi`).
    pub sweeps: Vec<SweepTruth>,
    /// Truth of every sine patch.
    pub patches: Vec<PatchTruth>,
    /// Names of the OTF factors applied ("pixel" = the square pixel aperture).
    pub factors_applied: Vec<String>,
    /// Names of system factors skipped (sampling-grid factors).
    pub factors_skipped: Vec<String>,
    /// Things a user should know (e.g. sweep content above the renderer's band).
    pub warnings: Vec<String>,
}

impl Shot {
    /// The first sweep's strip corners in pixels (corners 1 and 4 on its low-frequency edge).
    pub fn roi(&self) -> Option<[f64; 8]> {
        self.sweeps.first().map(|s| s.roi)
    }

    /// The first sweep's truth curve.
    pub fn truth(&self) -> Option<&SweepTruth> {
        self.sweeps.first()
    }

    /// The photo encoded in `format`.
    pub fn encode(&self, format: PhotoFormat) -> Result<Vec<u8>, SimError> {
        match &self.colour {
            Some(rgb) => encode::encode_rgb(&self.camera, rgb, format),
            None => encode::encode(&self.camera, &self.linear, format),
        }
    }

    /// The settings and geometry as the `STEM.json` document (`photo`: the photo's file name).
    pub fn settings_json(&self, photo: &str) -> serde_json::Value {
        let c = &self.camera;
        json!({
            "photo": photo,
            "width_px": self.width,
            "height_px": self.height,
            "pixel_pitch_um": c.pixel_pitch_um,
            "target": self.target_name,
            "roi": self.roi(),
            "roi_sweep": self.sweeps.first().map(|s| s.id.clone()),
            "target_corners": self.target_corners,
            "homography_chart_to_image": self.chart_to_image.m,
            "chart_modulation": self.sweeps.first().map(|s| s.chart_contrast),
            "bayer": c.bayer.map(|b| b.to_string()),
            "demosaic": c.demosaic.map(|d| d.to_string()),
            "distortion": c.distortion.map(|d| d.to_string()),
            "distortion_corner_percent": c.lens().map(|l| l.corner_percent()),
            "encoding": c.stored_encoding().to_string(),
            "bits": c.stored_bits(),
            "factors_applied": self.factors_applied,
            "factors_skipped": self.factors_skipped,
            "sweeps": self.sweeps.iter().map(|s| json!({
                "id": s.id,
                "roi": s.roi,
                "chart_contrast": s.chart_contrast,
                "truth_csv": truth_csv_name(photo, s, &self.sweeps),
                "freq_cy_px_start": s.rows.first().map(|r| r.freq_cy_px),
                "freq_cy_px_end": s.rows.last().map(|r| r.freq_cy_px),
            })).collect::<Vec<_>>(),
            "patches": self.patches,
            "patches_csv": (!self.patches.is_empty()).then(|| {
                let stem = Path::new(photo).file_stem().map(|s| s.to_string_lossy().into_owned()).unwrap_or_default();
                format!("{stem}.patches.csv")
            }),
            "warnings": self.warnings,
            "camera": c,
        })
    }
}

/// File name of a sweep's truth CSV: `STEM.truth.csv` for the first, `STEM.truth.ID.csv` for others.
fn truth_csv_name(photo: &str, s: &SweepTruth, all: &[SweepTruth]) -> String {
    let stem = Path::new(photo)
        .file_stem()
        .map(|s| s.to_string_lossy().into_owned())
        .unwrap_or_default();
    if all.first().is_some_and(|f| std::ptr::eq(f, s)) {
        format!("{stem}.truth.csv")
    } else {
        format!("{stem}.truth.{}.csv", s.id)
    }
}

/// Photographs `target` through `system` with `camera`: placement, optics, exposure, noise, truth.
pub fn render(target: &Target, system: &System, camera: &Camera) -> Result<Shot, SimError> {
    camera.validate()?;
    target.validate()?;
    let placement = placement::place(camera, target)?;
    let optics = render::Optics::new(system, camera);
    let (w, h) = (camera.width_px, camera.height_px);
    let mut signal = render::render_reflectance(target, placement.image_to_chart, &optics, camera)?;
    // Exposure, illumination fall-off (applied at the pixel: it varies slowly), mosaic gains.
    let r_corner2 = (w as f64 / 2.0).powi(2) + (h as f64 / 2.0).powi(2);
    signal.par_chunks_mut(w).enumerate().for_each(|(y, row)| {
        let dy = y as f64 + 0.5 - h as f64 / 2.0;
        for (x, v) in row.iter_mut().enumerate() {
            let dx = x as f64 + 0.5 - w as f64 / 2.0;
            let mut g = camera.exposure * (1.0 - camera.falloff * (dx * dx + dy * dy) / r_corner2);
            if let Some(lg) = &camera.light_gradient {
                g *= lg.gain(x as f64 + 0.5, y as f64 + 0.5, w, h);
            }
            if let Some(order) = camera.bayer {
                g *= camera.bayer_gains[order.colour_at(x, y)];
            }
            *v = (*v as f64 * g) as f32;
        }
    });
    let (mut linear, mut colour) = record(camera, &signal);
    if let (Some(order), Some(Demosaic::Bilinear)) = (camera.bayer, camera.demosaic) {
        let rgb = demosaic::bilinear(&linear, w, order, camera.bayer_gains);
        linear = rgb[1].clone();
        colour = Some(rgb);
    }
    if let Some(sh) = &camera.sharpen {
        sh.apply(&mut signal, w);
    }
    let lens = camera.lens();
    let (sweeps, patches) = truth::truths(
        target,
        &placement.chart_to_image,
        lens.as_ref(),
        &optics,
        camera.sharpen.as_ref(),
        camera.print_blur.as_ref(),
    );
    let mut warnings = Vec::new();
    let band = camera.render.oversample as f64 / 2.0;
    for s in &sweeps {
        let fmax = s.rows.iter().map(|r| r.freq_cy_px).fold(0.0, f64::max);
        if fmax > band {
            warnings.push(format!(
                "sweep '{}' reaches {fmax:.2} cy/px, above the renderer's band ({band} cy/px at {}× oversampling): content there is aliased",
                s.id, camera.render.oversample
            ));
        }
    }
    let clipped = signal.iter().filter(|&&v| v >= 1.0).count();
    if clipped > 0 {
        warnings.push(format!(
            "{:.2} % of the pixels clip (exposure {})",
            100.0 * clipped as f64 / signal.len() as f64,
            camera.exposure
        ));
    }
    Ok(Shot {
        camera: camera.clone(),
        width: w,
        height: h,
        signal,
        linear,
        colour,
        chart_to_image: placement.chart_to_image,
        target_corners: truth::quad_px_lens(
            &placement.chart_to_image,
            lens.as_ref(),
            rect_corners(0.0, 0.0, target.width_mm, target.height_mm),
        ),
        target_name: target.name.clone(),
        sweeps,
        patches,
        factors_applied: optics.applied(),
        factors_skipped: optics.skipped(),
        warnings,
    })
}

/// The recorded linear image(s) of the noiseless `signal`: noise, sharpening
/// (on the noisy image, as cameras do), clipping to [0, 1]; for a colour light,
/// three channels (each scaled by its gain, with its own noise) and the green
/// one again as the grey image.
fn record(camera: &Camera, signal: &[f32]) -> (Vec<f32>, Option<[Vec<f32>; 3]>) {
    let w = camera.width_px;
    let one = |gain: f64, stream: u64| {
        let model = noise::NoiseModel {
            full_well_e: camera.full_well_e,
            read_noise_e: camera.read_noise_e,
            fpn: camera.fpn,
            fpn_seed: camera
                .fpn_seed
                .wrapping_add(stream.wrapping_mul(0x9E37_79B9)),
            seed: camera.seed.wrapping_add(stream.wrapping_mul(0x9E37_79B9)),
        };
        let mut out = if gain == 1.0 {
            noise::apply_unclipped(&model, signal, w)
        } else {
            let tinted: Vec<f32> = signal.iter().map(|&v| (v as f64 * gain) as f32).collect();
            noise::apply_unclipped(&model, &tinted, w)
        };
        if let Some(sh) = &camera.sharpen {
            sh.apply(&mut out, w);
        }
        out.iter_mut().for_each(|v| *v = v.clamp(0.0, 1.0));
        out
    };
    match camera.light_colour {
        None => (one(1.0, 0), None),
        Some([r, g, b]) => {
            let rgb = [one(r, 1), one(g, 0), one(b, 2)];
            (rgb[1].clone(), Some(rgb))
        }
    }
}

/// A small noiseless linear 16-bit shot of `target` through `system`, `width`×`height` px,
/// rotated by `rotate_deg` (counter-clockwise), for tests of other modules.
pub fn quick_shot(
    target: &Target,
    system: &System,
    width: usize,
    height: usize,
    rotate_deg: f64,
) -> Result<Shot, SimError> {
    let camera = Camera {
        rotate_deg,
        ..Camera::noiseless(width, height)
    };
    render(target, system, &camera)
}

/// The paths `write_shot` writes for photo `path`: the photo, `STEM.truth.csv`, `STEM.json`.
pub fn output_paths(path: &Path) -> (PathBuf, PathBuf, PathBuf) {
    let stem = path.with_extension("");
    let with = |suffix: &str| {
        let mut s = stem.clone().into_os_string();
        s.push(suffix);
        PathBuf::from(s)
    };
    (path.to_path_buf(), with(".truth.csv"), with(".json"))
}

/// Writes bytes to `path` atomically (a temporary file in the same folder, then a rename).
fn write_atomic(path: &Path, bytes: &[u8]) -> Result<(), SimError> {
    let io = |source| SimError::Io {
        path: path.display().to_string(),
        source,
    };
    let dir = path
        .parent()
        .filter(|d| !d.as_os_str().is_empty())
        .unwrap_or(Path::new("."));
    let name = path
        .file_name()
        .ok_or_else(|| io(std::io::Error::other("not a file name")))?;
    let tmp = dir.join(format!(
        ".{}.tmp{}",
        name.to_string_lossy(),
        std::process::id()
    ));
    std::fs::write(&tmp, bytes).map_err(io)?;
    std::fs::rename(&tmp, path).map_err(|e| {
        let _ = std::fs::remove_file(&tmp);
        io(e)
    })
}

/// Checks that `camera`'s encoding can be written under the name `path` (before rendering).
pub fn check_output(camera: &Camera, path: &Path) -> Result<PhotoFormat, SimError> {
    let format = PhotoFormat::from_path(path)?;
    let shown = path.display();
    match format {
        PhotoFormat::Jpeg if camera.raw_mosaic() => Err(SimError::Parameter(format!(
            "{shown}: a Bayer mosaic is written as 16-bit linear PNG or TIFF, not JPEG (or give --demosaic bilinear)"
        ))),
        PhotoFormat::Dng if camera.demosaic.is_some() => Err(SimError::Parameter(format!(
            "{shown}: a DNG holds the raw mosaic; leave out --demosaic or write .png, .tif or .jpg"
        ))),
        PhotoFormat::Jpeg if camera.bits != 8 => Err(SimError::Parameter(format!(
            "{shown}: JPEG stores 8 bits; use --bits 8 or a .png/.tif name"
        ))),
        PhotoFormat::Dng if camera.bayer.is_none() => Err(SimError::Parameter(format!(
            "{shown}: a DNG holds a Bayer mosaic; give --bayer RGGB (or BGGR, GRBG, GBRG)"
        ))),
        PhotoFormat::Png | PhotoFormat::Tiff | PhotoFormat::Dng
            if camera.jpeg_quality.is_some() =>
        {
            Err(SimError::Parameter(format!(
                "{shown}: a JPEG quality was given but the name does not end in .jpg"
            )))
        }
        f => Ok(f),
    }
}

/// Writes the photo to `path` (format from its extension), `STEM.truth.csv`
/// (first sweep; others as `STEM.truth.ID.csv`), `STEM.patches.csv` (when the
/// target has sine patches) and `STEM.json`, each atomically; everything is
/// encoded before the first file is written. Returns the paths written.
pub fn write_shot(shot: &Shot, path: &Path) -> Result<Vec<PathBuf>, SimError> {
    check_output(&shot.camera, path)?;
    let format = PhotoFormat::from_path(path)?;
    let photo = shot.encode(format)?;
    let (_, csv_path, json_path) = output_paths(path);
    let photo_name = path
        .file_name()
        .map(|n| n.to_string_lossy().into_owned())
        .unwrap_or_default();
    let internal = |e: csv::Error| SimError::Internal(e.to_string());
    let mut files = vec![(path.to_path_buf(), photo)];
    for (i, s) in shot.sweeps.iter().enumerate() {
        let csv = truth::truth_csv(s).map_err(internal)?;
        let p = if i == 0 {
            csv_path.clone()
        } else {
            path.with_file_name(truth_csv_name(&photo_name, s, &shot.sweeps))
        };
        files.push((p, csv));
    }
    if !shot.patches.is_empty() {
        let csv = truth::patches_csv(&shot.patches, shot.camera.pitch_mm()).map_err(internal)?;
        files.push((path.with_extension("patches.csv"), csv));
    }
    let json = serde_json::to_vec_pretty(&shot.settings_json(&photo_name))
        .map_err(|e| SimError::Internal(e.to_string()))?;
    files.push((json_path, json));
    for (p, bytes) in &files {
        write_atomic(p, bytes)?;
    }
    Ok(files.into_iter().map(|(p, _)| p).collect())
}
