//! The model beside the measurement (`measure --model SYSTEM.toml|auto`): the
//! theoretical presampling MTF of a model system evaluated at each measured
//! point's image frequency along the sweep direction, the model's MTF50, and
//! the measured/modelled MTF50 ratio. Sampling-grid factors (a factor with a
//! Nyquist frequency that is not an aperture) are left out, as in the
//! simulator: a sweep measures the presampling MTF, not the phase-averaged
//! sampling MTF. Image frequencies (cycles/pixel, x right, y down) become model
//! frequencies (cycles/mm, y up) through the pixel pitch: u = fx/p, v = −fy/p.
//! Sine patches: the model along each patch's sine at its measured frequency,
//! and measured/model over the patches (median, furthest patch).

use super::{Curve, Measurement, PatchResult};
use crate::model::system_file::SystemFile;
use crate::model::{ModelError, System, spec::parse_factor};
use crate::photo::exif::ExifFacts;
use num_complex::Complex64;
use std::path::Path;
use thiserror::Error;

/// Why the model overlay could not be built.
#[derive(Debug, Error)]
pub enum OverlayError {
    /// A missing fact (pixel pitch, f-number) or a bad option: a usage error.
    #[error("--model: {0}")]
    Usage(String),
    /// The system file could not be read or built: an input error.
    #[error("--model: {0}")]
    Model(#[from] ModelError),
}

/// Which model to draw.
#[derive(Debug, Clone)]
pub enum ModelSource {
    /// A system file, already read and built.
    File {
        /// Display name (the file's `name`, else its file name).
        name: String,
        /// One line: the factors as kind spec, joined by ×.
        description: String,
        /// The factors.
        system: std::sync::Arc<System>,
    },
    /// Diffraction at the EXIF f-number × a square pixel aperture of the pitch.
    Auto,
}

impl ModelSource {
    /// Reads a system file (errors name the file).
    pub fn from_file(path: &Path) -> Result<ModelSource, OverlayError> {
        let origin = path.display().to_string();
        let file = SystemFile::read(path)?;
        let system = file.build(&origin)?;
        let name = file.name.clone().unwrap_or_else(|| {
            path.file_name()
                .map(|n| n.to_string_lossy().into_owned())
                .unwrap_or(origin.clone())
        });
        let description = describe(
            file.factor
                .iter()
                .map(|f| (f.kind.as_str(), f.spec.as_str())),
        );
        Ok(ModelSource::File {
            name,
            description,
            system: std::sync::Arc::new(system),
        })
    }
}

fn describe<'a>(specs: impl Iterator<Item = (&'a str, &'a str)>) -> String {
    specs
        .map(|(k, s)| format!("{k} {s}"))
        .collect::<Vec<_>>()
        .join(" × ")
}

/// A model system ready to evaluate at image frequencies.
#[derive(Debug)]
pub struct ModelOverlay {
    /// Display name (plot legend: "model: `<name>`").
    pub name: String,
    /// The factors as `kind spec`, joined by " × ".
    pub description: String,
    /// Names of sampling-grid factors left out (a sweep measures the presampling MTF).
    pub left_out: Vec<String>,
    /// Pixel pitch (mm) converting cycles/pixel to cycles/mm.
    pub pitch_mm: f64,
    system: std::sync::Arc<System>,
    used: Vec<bool>,
}

impl ModelOverlay {
    /// Builds the overlay: needs the pixel pitch (mm); `auto` also needs the EXIF f-number.
    pub fn build(
        source: ModelSource,
        facts: &ExifFacts,
        pitch_mm: Option<f64>,
        wavelength_mm: f64,
    ) -> Result<ModelOverlay, OverlayError> {
        let pitch_mm = match pitch_mm {
            Some(p) if p.is_finite() && p > 0.0 => p,
            _ => {
                return Err(OverlayError::Usage(
                    "the model needs the pixel pitch to turn cycles/pixel into cycles/mm, \
                     and the photo's EXIF gives none; give --pixel-pitch (e.g. 4.3um)"
                        .into(),
                ));
            }
        };
        let (name, description, system) = match source {
            ModelSource::File {
                name,
                description,
                system,
            } => (name, description, system),
            ModelSource::Auto => {
                let specs = crate::photo::pitch::auto_model_specs(facts, pitch_mm, wavelength_mm)
                    .map_err(|e| OverlayError::Usage(format!("auto: {e}")))?;
                let mut factors = Vec::new();
                for (k, s) in &specs {
                    factors.push(parse_factor(k, s)?);
                }
                let fnum = facts.f_number.unwrap_or(f64::NAN);
                (
                    format!(
                        "auto (diffraction f/{fnum} at {:.0} nm × {:.2} µm pixel)",
                        wavelength_mm * 1e6,
                        pitch_mm * 1e3
                    ),
                    describe(specs.iter().map(|(k, s)| (k.as_str(), s.as_str()))),
                    std::sync::Arc::new(System { factors }),
                )
            }
        };
        let is_aperture = |n: &str| n.to_ascii_lowercase().contains("aperture");
        let used: Vec<bool> = system
            .factors
            .iter()
            .map(|f| is_aperture(&f.name()) || f.nyquist().is_none())
            .collect();
        let left_out = system
            .factors
            .iter()
            .zip(&used)
            .filter(|(_, u)| !**u)
            .map(|(f, _)| f.name())
            .collect();
        Ok(ModelOverlay {
            name,
            description,
            left_out,
            pitch_mm,
            system,
            used,
        })
    }

    /// Presampling MTF at image frequency `f_cy_px` along the unit image direction `dir` (x right, y down).
    pub fn mtf_cy_px(&self, dir: [f64; 2], f_cy_px: f64) -> f64 {
        let (u, v) = (
            f_cy_px * dir[0] / self.pitch_mm,
            -f_cy_px * dir[1] / self.pitch_mm,
        );
        self.system
            .factors
            .iter()
            .zip(&self.used)
            .filter(|(_, u)| **u)
            .fold(Complex64::new(1.0, 0.0), |acc, (f, _)| acc * f.otf(u, v))
            .norm()
    }

    /// First frequency (cycles/pixel, up to 4) where the model MTF along `dir` falls to 0.5.
    pub fn mtf50_cy_px(&self, dir: [f64; 2]) -> Option<f64> {
        let step = 1e-3;
        let mut lo = 0.0;
        let mut f = step;
        while f <= 4.0 {
            if self.mtf_cy_px(dir, f) <= 0.5 {
                let mut hi = f;
                for _ in 0..60 {
                    let mid = 0.5 * (lo + hi);
                    if self.mtf_cy_px(dir, mid) > 0.5 {
                        lo = mid;
                    } else {
                        hi = mid;
                    }
                }
                return Some(0.5 * (lo + hi));
            }
            lo = f;
            f += step;
        }
        None
    }
}

/// The unit image direction (x right, y down) in which a curve's frequency rises:
/// from the middle of its lowest-frequency line to the middle of its highest.
pub fn sweep_direction(c: &Curve) -> [f64; 2] {
    let mid = |l: [[f64; 2]; 2]| [0.5 * (l[0][0] + l[1][0]), 0.5 * (l[0][1] + l[1][1])];
    let (a, b) = (mid(c.measured_lines_px[0]), mid(c.measured_lines_px[1]));
    let d = [b[0] - a[0], b[1] - a[1]];
    let n = d[0].hypot(d[1]);
    if n.is_finite() && n > 1e-9 {
        [d[0] / n, d[1] / n]
    } else {
        [1.0, 0.0]
    }
}

/// The model beside one measured curve.
#[derive(Debug, Clone, PartialEq)]
pub struct CurveModel {
    /// Unit image direction of the sweep (x right, y down).
    pub direction: [f64; 2],
    /// Model MTF at each measured point's frequency, in the curve's point order.
    pub mtf_model: Vec<f64>,
    /// Model MTF50 along the sweep (cycles/pixel).
    pub mtf50_model_cy_px: Option<f64>,
    /// Measured MTF50 / modelled MTF50 (dimensionless).
    pub mtf50_ratio: Option<f64>,
}

/// Evaluates the model beside every curve of a measurement.
pub fn evaluate(m: &Measurement, model: &ModelOverlay) -> Vec<CurveModel> {
    m.curves
        .iter()
        .map(|c| {
            let dir = sweep_direction(c);
            let mtf_model = c
                .points
                .iter()
                .map(|p| model.mtf_cy_px(dir, p.freq_cy_px))
                .collect();
            let f50 = model.mtf50_cy_px(dir);
            let ratio = match (c.figures.mtf50_cy_px, f50) {
                (Some(a), Some(b)) if b > 0.0 => Some(a / b),
                _ => None,
            };
            CurveModel {
                direction: dir,
                mtf_model,
                mtf50_model_cy_px: f50,
                mtf50_ratio: ratio,
            }
        })
        .collect()
}

/// The unit image direction (x right, y down) of a patch's sine, from its
/// binned region's corners ((0, t0), (l, t0), (l, t1), (0, t1) in the strip frame).
pub fn patch_direction(p: &PatchResult) -> [f64; 2] {
    let q = p.region_px;
    let d = [
        0.5 * (q[1][0] + q[2][0] - q[0][0] - q[3][0]),
        0.5 * (q[1][1] + q[2][1] - q[0][1] - q[3][1]),
    ];
    let n = d[0].hypot(d[1]);
    if n.is_finite() && n > 1e-9 {
        [d[0] / n, d[1] / n]
    } else {
        [1.0, 0.0]
    }
}

/// Model MTF at each sine patch's image frequency, along the patch's own sine
/// direction in the image (from its binned region's corners), in patch order.
pub fn evaluate_patches(m: &Measurement, model: &ModelOverlay) -> Vec<f64> {
    m.patches
        .iter()
        .map(|p| model.mtf_cy_px(patch_direction(p), p.freq_cy_px))
        .collect()
}

/// Smallest model MTF a patch may have to enter the measured/model ratios:
/// below it (near or beyond the model's cutoff) the ratio of two small numbers
/// mostly measures noise, and at 0 it is undefined.
pub const MIN_MODEL_FOR_RATIO: f64 = 0.05;

/// Measured over modelled MTF across the sine patches, in one figure.
#[derive(Debug, Clone, PartialEq)]
pub struct PatchComparison {
    /// Patches that entered the ratios (not aliased, finite measured MTF ≥ 0, model ≥ [`MIN_MODEL_FOR_RATIO`]).
    pub n_used: usize,
    /// Patches left out (aliased, model below the floor or not finite, measured MTF not finite).
    pub n_left_out: usize,
    /// Median of measured/model over the patches used (dimensionless).
    pub median_ratio: f64,
    /// Index (in patch order) of the patch whose ratio is furthest from 1 (largest |ln ratio|).
    pub worst_index: usize,
    /// That patch's measured/model ratio (dimensionless).
    pub worst_ratio: f64,
}

/// Compares measured and modelled MTF over the sine patches (`model` in patch
/// order, as from [`evaluate_patches`]); `None` when no patch can enter the ratio.
pub fn compare_patches(patches: &[PatchResult], model: &[f64]) -> Option<PatchComparison> {
    let mut used: Vec<(usize, f64)> = Vec::new();
    let mut left_out = 0;
    for (i, (p, &v)) in patches.iter().zip(model).enumerate() {
        if p.aliased || !v.is_finite() || v < MIN_MODEL_FOR_RATIO || !p.mtf.is_finite() {
            left_out += 1;
            continue;
        }
        used.push((i, p.mtf.max(0.0) / v));
    }
    left_out += patches.len().saturating_sub(model.len());
    if used.is_empty() {
        return None;
    }
    // Distance from 1 on a log scale; a measured 0 is infinitely far (and thus worst).
    let far = |r: f64| if r > 0.0 { r.ln().abs() } else { f64::INFINITY };
    let &(worst_index, worst_ratio) = used
        .iter()
        .fold(&used[0], |a, b| if far(b.1) > far(a.1) { b } else { a });
    let mut r: Vec<f64> = used.iter().map(|u| u.1).collect();
    r.sort_by(f64::total_cmp);
    let k = r.len();
    let median_ratio = if k % 2 == 1 {
        r[k / 2]
    } else {
        0.5 * (r[k / 2 - 1] + r[k / 2])
    };
    Some(PatchComparison {
        n_used: k,
        n_left_out: left_out,
        median_ratio,
        worst_index,
        worst_ratio,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    fn auto(fnum: f64, pitch_mm: f64) -> ModelOverlay {
        let facts = ExifFacts {
            f_number: Some(fnum),
            ..ExifFacts::default()
        };
        ModelOverlay::build(ModelSource::Auto, &facts, Some(pitch_mm), 550e-6).unwrap()
    }

    /// Auto model against closed forms: diffraction (2/π)(acos s − s√(1−s²)), s = fλN, × |sinc(f)|.
    #[test]
    fn auto_matches_closed_form_along_x_and_diagonal() {
        let (n, p, lam) = (4.0, 0.0043, 550e-6);
        let o = auto(n, p);
        let sinc = |x: f64| {
            if x == 0.0 {
                1.0
            } else {
                (std::f64::consts::PI * x).sin() / (std::f64::consts::PI * x)
            }
        };
        let diff = |f_mm: f64| {
            let s = f_mm * lam * n;
            if s >= 1.0 {
                0.0
            } else {
                2.0 / std::f64::consts::PI * (s.acos() - s * (1.0 - s * s).sqrt())
            }
        };
        for f in [0.0, 0.05, 0.2, 0.5, 0.9] {
            let want = diff(f / p) * sinc(f).abs();
            assert!((o.mtf_cy_px([1.0, 0.0], f) - want).abs() < 1e-9, "{f}");
            let h = std::f64::consts::FRAC_1_SQRT_2;
            let want_d = diff(f / p) * (sinc(f * h) * sinc(f * h)).abs();
            assert!((o.mtf_cy_px([h, h], f) - want_d).abs() < 1e-9, "{f}");
        }
        let f50 = o.mtf50_cy_px([1.0, 0.0]).unwrap();
        let want = diff(f50 / p) * sinc(f50);
        assert!((want - 0.5).abs() < 1e-9, "{want}");
    }

    fn patch(id: &str, mtf: f64, aliased: bool) -> PatchResult {
        PatchResult {
            channel: "grey".into(),
            patch_id: id.into(),
            freq_chart_cy_mm: 1.0,
            freq_cy_px: 0.1,
            modulation: mtf * 0.8,
            chart_modulation: 0.8,
            mtf,
            mtf_err: 0.01,
            aliased,
            region_px: [[0.0, 0.0], [10.0, 0.0], [10.0, 5.0], [0.0, 5.0]],
        }
    }

    /// Ratios worked out by hand: 0.9/1.0, 0.8/0.8, 0.3/0.2 enter (median 1.0,
    /// worst 1.5 since |ln 1.5| = 0.405 > |ln 0.9| = 0.105); NaN model, model 0
    /// (beyond cutoff), model 0.04 (under the floor) and an aliased patch stay out.
    #[test]
    fn patch_ratio_summary_by_hand() {
        let ps = [
            patch("a", 0.9, false),
            patch("b", 0.8, false),
            patch("c", 0.3, false),
            patch("d", 0.5, false),
            patch("e", 0.1, false),
            patch("f", 0.05, false),
            patch("g", 0.7, true),
        ];
        let model = [1.0, 0.8, 0.2, f64::NAN, 0.0, 0.04, 0.6];
        let c = compare_patches(&ps, &model).unwrap();
        assert_eq!((c.n_used, c.n_left_out), (3, 4));
        assert!((c.median_ratio - 1.0).abs() < 1e-12, "{}", c.median_ratio);
        assert_eq!(c.worst_index, 2);
        assert!((c.worst_ratio - 1.5).abs() < 1e-12);
        assert!(c.median_ratio.is_finite() && c.worst_ratio.is_finite());

        // Even count: 0.4/0.5 = 0.8 and 0.6/0.5 = 1.2, median 1.0; 0.8 is
        // further from 1 (|ln 0.8| = 0.223 > |ln 1.2| = 0.182).
        let c = compare_patches(
            &[patch("x", 0.4, false), patch("y", 0.6, false)],
            &[0.5, 0.5],
        )
        .unwrap();
        assert!((c.median_ratio - 1.0).abs() < 1e-12);
        assert_eq!((c.worst_index, c.n_left_out), (0, 0));
        assert!((c.worst_ratio - 0.8).abs() < 1e-12);

        // A measured 0 is the worst possible patch, not a division by zero.
        let c = compare_patches(
            &[patch("x", 0.0, false), patch("y", 2.0, false)],
            &[0.5, 0.5],
        )
        .unwrap();
        assert_eq!((c.worst_index, c.worst_ratio), (0, 0.0));

        // Nothing usable: no comparison at all.
        assert!(compare_patches(&ps[3..], &model[3..]).is_none());
        assert!(compare_patches(&[], &[]).is_none());
    }

    #[test]
    fn missing_pitch_and_fnumber_are_usage_errors() {
        let facts = ExifFacts::default();
        let e = ModelOverlay::build(ModelSource::Auto, &facts, None, 550e-6).unwrap_err();
        assert!(matches!(e, OverlayError::Usage(_)), "{e}");
        let e = ModelOverlay::build(ModelSource::Auto, &facts, Some(0.004), 550e-6).unwrap_err();
        assert!(e.to_string().contains("f-number"), "{e}");
    }

    #[test]
    fn missing_file_is_a_model_error() {
        let e = ModelSource::from_file(Path::new("/nonexistent/sys.toml")).unwrap_err();
        assert!(matches!(e, OverlayError::Model(_)), "{e}");
        assert!(e.to_string().contains("/nonexistent/sys.toml"), "{e}");
    }
}
