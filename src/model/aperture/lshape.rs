//! L-shaped detector aperture (CMOS APS pixel with the readout circuit in one
//! corner, the paper's eq. 27): the box [−a, A−a]×[−b, B−b] minus the a×b notch
//! [−a, 0]×[−b, 0], so the origin sits at the L's inner corner and the notch is
//! lower-left. The OTF is complex.
//!
//! Evaluated as the sum of two disjoint rectangles (the strip [0, A−a]×[−b, 0]
//! and the strip [−a, A−a]×[0, B−b]) rather than box minus notch: both have
//! positive weight, so nothing cancels even when the notch nearly fills the box.

use super::guard::{check_length, far};
use crate::model::special::{sinc, sincospi};
use crate::model::{Factor, ModelError};
use num_complex::Complex64;

/// One rectangle of the L: its share of the area, size and centre (mm).
#[derive(Debug, Clone)]
struct Part {
    weight: f64,
    w: f64,
    h: f64,
    cx: f64,
    cy: f64,
}

impl Part {
    fn otf(&self, u: f64, v: f64) -> Complex64 {
        let mag = self.weight * sinc(self.w * u) * sinc(self.h * v);
        let phase = 2.0 * (u * self.cx + v * self.cy);
        let (s, c) = sincospi(phase);
        Complex64::new(mag * c, -mag * s)
    }
}

/// An L-shaped aperture: box `A`×`B` (mm) minus a lower-left notch `a`×`b` (mm).
#[derive(Debug, Clone)]
pub struct LShape {
    parts: [Part; 2],
    size: f64,
}

impl LShape {
    /// The box `a_mm`×`b_mm` minus the notch `notch_a_mm`×`notch_b_mm`, which must be
    /// strictly smaller in both directions; origin at the inner corner.
    pub fn new(
        a_mm: f64,
        b_mm: f64,
        notch_a_mm: f64,
        notch_b_mm: f64,
    ) -> Result<LShape, ModelError> {
        const F: &str = "aperture L";
        let big_a = check_length(F, "A", a_mm)?;
        let big_b = check_length(F, "B", b_mm)?;
        let a = check_length(F, "a", notch_a_mm)?;
        let b = check_length(F, "b", notch_b_mm)?;
        let too_big = |k: &str, n: f64, big: &str, m: f64| ModelError::Parameter {
            factor: F.into(),
            message: format!("notch {k} = {n} mm must be smaller than {big} = {m} mm"),
        };
        if a >= big_a {
            return Err(too_big("a", a, "A", big_a));
        }
        if b >= big_b {
            return Err(too_big("b", b, "B", big_b));
        }
        let (w1, h1) = (big_a - a, b);
        let (w2, h2) = (big_a, big_b - b);
        let (a1, a2) = (w1 * h1, w2 * h2);
        let total = a1 + a2;
        let parts = [
            Part {
                weight: a1 / total,
                w: w1,
                h: h1,
                cx: 0.5 * w1,
                cy: -0.5 * b,
            },
            Part {
                weight: a2 / total,
                w: w2,
                h: h2,
                cx: 0.5 * big_a - a,
                cy: 0.5 * h2,
            },
        ];
        let size = w1.min(h1).min(w2).min(h2) * 0.5;
        Ok(LShape { parts, size })
    }
}

impl Factor for LShape {
    fn name(&self) -> String {
        "aperture_L".into()
    }

    fn otf(&self, u: f64, v: f64) -> Complex64 {
        if far(u, v, self.size) {
            return Complex64::new(0.0, 0.0);
        }
        self.parts[0].otf(u, v) + self.parts[1].otf(u, v)
    }
}
