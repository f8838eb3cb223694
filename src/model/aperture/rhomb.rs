//! Rhombic detector aperture |x|/A + |y|/B < 1/2 (A, B the diagonals along x and y).
//!
//! The rhomb is the image of the unit square under (s, t) ↦ (A(s+t)/2, B(s−t)/2),
//! so OTF = sinc((Au + Bv)/2)·sinc((Au − Bv)/2), the paper's eq. 30 in product form.

use super::guard::{check_length, far};
use crate::model::special::sinc;
use crate::model::{Factor, ModelError};
use num_complex::Complex64;

/// A rhomb with diagonals `a` along x and `b` along y, mm, centred on the origin.
#[derive(Debug, Clone)]
pub struct Rhomb {
    a: f64,
    b: f64,
}

impl Rhomb {
    /// A rhomb with diagonals `a_mm` (x) and `b_mm` (y), both > 0.
    pub fn new(a_mm: f64, b_mm: f64) -> Result<Rhomb, ModelError> {
        Ok(Rhomb {
            a: check_length("aperture rhomb", "A", a_mm)?,
            b: check_length("aperture rhomb", "B", b_mm)?,
        })
    }
}

impl Factor for Rhomb {
    fn name(&self) -> String {
        "aperture_rhomb".into()
    }

    fn otf(&self, u: f64, v: f64) -> Complex64 {
        if far(u, v, 0.5 * self.a.min(self.b)) {
            return Complex64::new(0.0, 0.0);
        }
        let (p, q) = (0.5 * self.a * u, 0.5 * self.b * v);
        Complex64::new(sinc(p + q) * sinc(p - q), 0.0)
    }
}
