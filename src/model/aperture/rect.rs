//! Rectangular detector aperture |x| < A/2, |y| < B/2: OTF = sinc(Au)·sinc(Bv) (eq. 24).

use super::guard::{check_length, far};
use crate::model::special::sinc;
use crate::model::{Factor, ModelError};
use num_complex::Complex64;

/// A rectangle of width `a` (along x) and height `b` (along y), mm, centred on the origin.
#[derive(Debug, Clone)]
pub struct Rect {
    a: f64,
    b: f64,
}

impl Rect {
    /// A rectangle of width `a_mm` and height `b_mm` (both > 0).
    pub fn new(a_mm: f64, b_mm: f64) -> Result<Rect, ModelError> {
        Ok(Rect {
            a: check_length("aperture rect", "A", a_mm)?,
            b: check_length("aperture rect", "B", b_mm)?,
        })
    }
}

impl Factor for Rect {
    fn name(&self) -> String {
        "aperture_rect".into()
    }

    fn otf(&self, u: f64, v: f64) -> Complex64 {
        if far(u, v, self.a.min(self.b)) {
            return Complex64::new(0.0, 0.0);
        }
        Complex64::new(sinc(self.a * u) * sinc(self.b * v), 0.0)
    }
}
