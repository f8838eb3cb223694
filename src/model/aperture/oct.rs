//! Regular octagonal detector aperture, side-up: flats at x = ±D/2, y = ±D/2
//! and on the diagonals, side length D(√2 − 1) (the paper's eqs. 36/37).
//!
//! Eq. 36 cancels catastrophically as v → 0; here the octagon is tiled by two
//! squares and four 45° rhombi (a zonogon tiling), a sum of positive-weight
//! sinc·sinc·cos terms with no 1/u or 1/v anywhere.

use super::guard::{check_length, far};
use super::zonogon::Zonogon;
use crate::model::{Factor, ModelError};
use num_complex::Complex64;

/// A regular octagon of flat-to-flat width `d` (mm), flats parallel to the axes.
#[derive(Debug, Clone)]
pub struct Octagon {
    d: f64,
    tiles: Zonogon,
}

impl Octagon {
    /// A side-up regular octagon with flats at x = ±`d_mm`/2 and y = ±`d_mm`/2.
    pub fn new(d_mm: f64) -> Result<Octagon, ModelError> {
        let d = check_length("aperture oct", "D", d_mm)?;
        let h = 0.5 * d;
        let t = h * (std::f64::consts::SQRT_2 - 1.0); // half side length
        let tiles = Zonogon::from_edges(&[
            [h - t, h - t],
            [0.0, 2.0 * t],
            [t - h, h - t],
            [-2.0 * t, 0.0],
        ]);
        Ok(Octagon { d, tiles })
    }
}

impl Factor for Octagon {
    fn name(&self) -> String {
        "aperture_oct".into()
    }

    fn otf(&self, u: f64, v: f64) -> Complex64 {
        if far(u, v, 0.25 * self.d) {
            return Complex64::new(0.0, 0.0);
        }
        Complex64::new(self.tiles.otf(u, v), 0.0)
    }
}
