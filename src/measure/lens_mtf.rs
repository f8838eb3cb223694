//! Lens MTF (`measure --lens-mtf`): the measured system MTF divided by the
//! sensor part of a model, so lenses can be compared across bodies.
//!
//! The sensor part is, from a system file, the product of its detector
//! aperture factors (any factor named `aperture…`) and OLPF factors; without
//! one (or with `--model auto`), a 100 % fill-factor square pixel aperture,
//! |sinc(f·dx)·sinc(f·dy)| for frequency f (cy/px) along the unit sweep
//! direction (dx, dy) in the image. Other factors (diffusion, CTE, Gaussian
//! blur) stay in the lens MTF. Where the divisor falls below
//! [`MIN_DIVISOR`] the quotient is mostly noise (and infinite at the
//! aperture's zeros): those points get no lens MTF (NaN) and are flagged, as
//! are aliased points.

use super::Curve;
use super::model_overlay::sweep_direction;
use crate::model::System;
use num_complex::Complex64;
use std::sync::Arc;

/// Smallest sensor MTF (divisor, dimensionless) a point's lens MTF is given for.
pub const MIN_DIVISOR: f64 = 0.2;

/// The sensor part of the camera that the system MTF is divided by.
#[derive(Debug, Clone)]
pub enum SensorPart {
    /// A 100 % fill-factor square pixel aperture, |sinc(fx)·sinc(fy)| in cycles/pixel.
    SquarePixel,
    /// The aperture and OLPF factors of a system (frequencies converted with the pixel pitch).
    Model {
        /// The whole system (only the factors marked in `used` are applied).
        system: Arc<System>,
        /// Which factors form the sensor part (aperture, OLPF).
        used: Vec<bool>,
        /// Pixel pitch (mm) converting cycles/pixel to cycles/mm.
        pitch_mm: f64,
    },
}

/// Why a sensor part could not be built.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum SensorError {
    /// The system has neither an aperture nor an OLPF factor.
    #[error(
        "--lens-mtf: the system has no aperture or olpf factor to divide by (factors: {0}); \
         leave out --model to divide by a square pixel"
    )]
    NoSensorFactor(String),
    /// The pixel pitch is unknown or not positive.
    #[error(
        "--lens-mtf: the model's sensor part needs the pixel pitch; give --pixel-pitch (e.g. 4.3um)"
    )]
    NoPitch,
}

/// Whether a factor (by name) belongs to the sensor part: a detector aperture or an OLPF.
pub fn is_sensor_factor(name: &str) -> bool {
    let n = name.to_ascii_lowercase();
    n.contains("aperture") || n.contains("olpf")
}

impl SensorPart {
    /// The sensor part of `system` at pixel pitch `pitch_mm` (mm).
    pub fn from_system(system: Arc<System>, pitch_mm: Option<f64>) -> Result<Self, SensorError> {
        let used: Vec<bool> = system
            .factors
            .iter()
            .map(|f| is_sensor_factor(&f.name()))
            .collect();
        if !used.iter().any(|&u| u) {
            let names: Vec<String> = system.factors.iter().map(|f| f.name()).collect();
            return Err(SensorError::NoSensorFactor(names.join(", ")));
        }
        let pitch_mm = pitch_mm
            .filter(|p| p.is_finite() && *p > 0.0)
            .ok_or(SensorError::NoPitch)?;
        Ok(SensorPart::Model {
            system,
            used,
            pitch_mm,
        })
    }

    /// One line naming the divisor (for the JSON summary and the plot legend).
    pub fn describe(&self) -> String {
        match self {
            SensorPart::SquarePixel => "square pixel aperture, 100 % fill".into(),
            SensorPart::Model { system, used, .. } => system
                .factors
                .iter()
                .zip(used)
                .filter(|(_, u)| **u)
                .map(|(f, _)| f.name())
                .collect::<Vec<_>>()
                .join(" × "),
        }
    }

    /// Sensor MTF (dimensionless) at `f_cy_px` cycles/pixel along the unit image direction `dir` (x right, y down).
    pub fn mtf_cy_px(&self, dir: [f64; 2], f_cy_px: f64) -> f64 {
        match self {
            SensorPart::SquarePixel => (sinc(f_cy_px * dir[0]) * sinc(f_cy_px * dir[1])).abs(),
            SensorPart::Model {
                system,
                used,
                pitch_mm,
            } => {
                let (u, v) = (f_cy_px * dir[0] / pitch_mm, -f_cy_px * dir[1] / pitch_mm);
                system
                    .factors
                    .iter()
                    .zip(used)
                    .filter(|(_, u)| **u)
                    .fold(Complex64::new(1.0, 0.0), |acc, (f, _)| acc * f.otf(u, v))
                    .norm()
            }
        }
    }
}

/// sin(πx)/(πx), 1 at x = 0 (and within 1e-8 of it, where the series' next term is below 1e-16).
pub fn sinc(x: f64) -> f64 {
    if x.abs() < 1e-8 {
        1.0
    } else {
        let px = std::f64::consts::PI * x;
        px.sin() / px
    }
}

/// Why a point has no lens MTF.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum LensFlag {
    /// Lens MTF given.
    Ok,
    /// The sensor MTF there is below [`MIN_DIVISOR`].
    SmallDivisor,
    /// The point is aliased (not an MTF to begin with).
    Aliased,
}

impl LensFlag {
    /// The CSV word: `ok`, `small_divisor`, `aliased`.
    pub fn as_str(self) -> &'static str {
        match self {
            LensFlag::Ok => "ok",
            LensFlag::SmallDivisor => "small_divisor",
            LensFlag::Aliased => "aliased",
        }
    }
}

/// The lens MTF of one curve, one entry per point in the curve's order.
#[derive(Debug, Clone, PartialEq)]
pub struct LensCurve {
    /// Unit image direction of the sweep (x right, y down).
    pub direction: [f64; 2],
    /// Sensor MTF (the divisor) at each point, dimensionless.
    pub sensor_mtf: Vec<f64>,
    /// Lens MTF = MTF / sensor MTF (NaN where flagged), dimensionless.
    pub lens_mtf: Vec<f64>,
    /// One-sigma uncertainty of the lens MTF (NaN where flagged).
    pub lens_mtf_err: Vec<f64>,
    /// Why a point has no lens MTF (or `Ok`).
    pub flag: Vec<LensFlag>,
}

impl LensCurve {
    /// The (frequency cy/px, lens MTF) pairs that are given (flag `Ok`), for plots.
    pub fn given<'a>(&'a self, c: &'a Curve) -> impl Iterator<Item = (f64, f64)> + 'a {
        c.points
            .iter()
            .zip(self.lens_mtf.iter().zip(&self.flag))
            .filter(|(_, (_, f))| **f == LensFlag::Ok)
            .map(|(p, (v, _))| (p.freq_cy_px, *v))
    }
}

/// Divides a curve's MTF by the sensor part along the curve's sweep direction.
pub fn lens_curve(c: &Curve, sensor: &SensorPart) -> LensCurve {
    let dir = sweep_direction(c);
    let n = c.points.len();
    let mut out = LensCurve {
        direction: dir,
        sensor_mtf: Vec::with_capacity(n),
        lens_mtf: Vec::with_capacity(n),
        lens_mtf_err: Vec::with_capacity(n),
        flag: Vec::with_capacity(n),
    };
    for p in &c.points {
        let d = sensor.mtf_cy_px(dir, p.freq_cy_px);
        let flag = if p.aliased {
            LensFlag::Aliased
        } else if !(d >= MIN_DIVISOR) {
            LensFlag::SmallDivisor
        } else {
            LensFlag::Ok
        };
        let ok = flag == LensFlag::Ok;
        out.sensor_mtf.push(d);
        out.lens_mtf.push(if ok { p.mtf / d } else { f64::NAN });
        out.lens_mtf_err
            .push(if ok { p.mtf_err / d } else { f64::NAN });
        out.flag.push(flag);
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::model::spec::parse_factor;

    #[test]
    fn sinc_at_its_singular_point_and_zeros() {
        assert_eq!(sinc(0.0), 1.0);
        assert!((sinc(1e-9) - 1.0).abs() < 1e-12);
        assert!((sinc(1e-6) - (1.0 - (std::f64::consts::PI * 1e-6).powi(2) / 6.0)).abs() < 1e-15);
        assert!(sinc(1.0).abs() < 1e-15 && sinc(2.0).abs() < 1e-15);
        assert!((sinc(0.5) - 2.0 / std::f64::consts::PI).abs() < 1e-15);
    }

    /// A file's 100 % rect aperture of the pitch equals the default square pixel, along x and diagonally.
    #[test]
    fn model_aperture_of_the_pitch_equals_the_square_pixel() {
        let p = 0.0043;
        let sys = System {
            factors: vec![
                parse_factor("gaussian", "sigma=2um").unwrap(),
                parse_factor("aperture", "rect:A=4.3um,B=4.3um").unwrap(),
            ],
        };
        let m = SensorPart::from_system(Arc::new(sys), Some(p)).unwrap();
        assert_eq!(m.describe(), "aperture_rect");
        let h = std::f64::consts::FRAC_1_SQRT_2;
        for f in [0.0, 0.1, 0.3, 0.5, 0.9] {
            for d in [[1.0, 0.0], [h, h], [0.6, -0.8]] {
                let a = m.mtf_cy_px(d, f);
                let b = SensorPart::SquarePixel.mtf_cy_px(d, f);
                assert!((a - b).abs() < 1e-9, "{f} {d:?}: {a} {b}");
            }
        }
    }

    /// An OLPF in the file is divided out too: 2-spot split d → |cos(π u d)|.
    #[test]
    fn olpf_is_part_of_the_sensor() {
        let p = 0.004;
        let sys = System {
            factors: vec![
                parse_factor("olpf", "2spot:d=3um").unwrap(),
                parse_factor("aperture", "rect:A=4um,B=4um").unwrap(),
            ],
        };
        let m = SensorPart::from_system(Arc::new(sys), Some(p)).unwrap();
        let f = 0.3;
        let want = (std::f64::consts::PI * f / p * 0.003).cos().abs() * sinc(f);
        assert!((m.mtf_cy_px([1.0, 0.0], f) - want).abs() < 1e-9);
    }

    #[test]
    fn systems_without_sensor_factors_or_pitch_are_refused() {
        let optics = || System {
            factors: vec![parse_factor("gaussian", "sigma=2um").unwrap()],
        };
        let e = SensorPart::from_system(Arc::new(optics()), Some(0.004)).unwrap_err();
        assert!(e.to_string().contains("gaussian"), "{e}");
        let sys = System {
            factors: vec![parse_factor("aperture", "rect:A=4um,B=4um").unwrap()],
        };
        assert_eq!(
            SensorPart::from_system(Arc::new(sys), None).unwrap_err(),
            SensorError::NoPitch
        );
    }
}
