//! Gaussian residual blur (`--gaussian sigma=..` or `sigma_x=..,sigma_y=..`):
//! a PSF exp(−x²/2σx² − y²/2σy²), whose OTF is exp(−2π²(σx²u² + σy²v²)),
//! real and positive. Stands in for lens aberrations, residual defocus and
//! vibration lumped together.

use super::params::Params;
use super::{Factor, ModelError};
use num_complex::Complex64;
use std::f64::consts::PI;

/// Gaussian blur with standard deviations σx, σy (mm).
#[derive(Debug, Clone)]
pub struct Gaussian {
    /// σ along x, mm.
    pub sigma_x: f64,
    /// σ along y, mm.
    pub sigma_y: f64,
}

impl Factor for Gaussian {
    fn name(&self) -> String {
        "gaussian".into()
    }
    fn otf(&self, u: f64, v: f64) -> Complex64 {
        let a = self.sigma_x * u;
        let b = self.sigma_y * v;
        // Squares overflow to +inf for huge frequencies, and exp(−inf) = 0.
        Complex64::new((-2.0 * PI * PI * (a * a + b * b)).exp(), 0.0)
    }
}

/// Parses a `--gaussian` spec: `sigma=..` or `sigma_x=..,sigma_y=..`.
pub fn parse(spec: &str) -> Result<Box<dyn Factor>, ModelError> {
    let p = Params::parse("gaussian", spec)?;
    let g = if p.has("sigma") {
        let s = p.positive_length("sigma")?;
        if p.has("sigma_x") || p.has("sigma_y") {
            return Err(p.error("give either sigma=.. or sigma_x=..,sigma_y=.., not both"));
        }
        Gaussian {
            sigma_x: s,
            sigma_y: s,
        }
    } else {
        Gaussian {
            sigma_x: p.positive_length("sigma_x")?,
            sigma_y: p.positive_length("sigma_y")?,
        }
    };
    p.finish(&["sigma", "sigma_x", "sigma_y"])?;
    Ok(Box::new(g))
}
