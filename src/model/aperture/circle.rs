//! Circular detector aperture of diameter D: OTF = 2J₁(πDρ)/(πDρ), ρ = √(u²+v²)
//! (eq. 40 with the correct jinc; the definition printed under eq. 40 is wrong).

use super::guard::{check_length, far};
use crate::model::special::jinc;
use crate::model::{Factor, ModelError};
use num_complex::Complex64;
use std::f64::consts::PI;

/// A disk of diameter `d` (mm) centred on the origin.
#[derive(Debug, Clone)]
pub struct Circle {
    d: f64,
}

impl Circle {
    /// A disk of diameter `d_mm` (> 0).
    pub fn new(d_mm: f64) -> Result<Circle, ModelError> {
        Ok(Circle {
            d: check_length("aperture circle", "D", d_mm)?,
        })
    }
}

impl Factor for Circle {
    fn name(&self) -> String {
        "aperture_circle".into()
    }

    fn otf(&self, u: f64, v: f64) -> Complex64 {
        if far(u, v, 0.25 * self.d) {
            return Complex64::new(0.0, 0.0);
        }
        Complex64::new(jinc(PI * self.d * u.hypot(v)), 0.0)
    }
}
