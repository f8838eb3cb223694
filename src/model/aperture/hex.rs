//! Regular hexagonal detector aperture with flat-to-flat width D.
//!
//! Side-up (the paper's orientation, eq. 33): flats at y = ±D/2, vertices at
//! (±D/√3, 0). Corner-up: the same rotated by 90° (flats at x = ±D/2), i.e.
//! u and v swapped. Evaluated as three rhombi (a zonogon tiling), which is
//! exact, real, and free of the 1/(uv) and 1/(u² − 3v²) of the printed form.

use super::guard::{check_length, far};
use super::zonogon::Zonogon;
use crate::model::{Factor, ModelError};
use num_complex::Complex64;

/// A regular hexagon of flat-to-flat width `d` (mm), side-up or corner-up.
#[derive(Debug, Clone)]
pub struct Hexagon {
    d: f64,
    corner_up: bool,
    tiles: Zonogon,
}

/// The side-up hexagon (flats at y = ±D/2) as a zonogon.
pub(crate) fn side_up_zonogon(d: f64) -> Zonogon {
    let s = d / 3f64.sqrt(); // side length = circumradius
    let h = 0.5 * d;
    Zonogon::from_edges(&[[0.5 * s, h], [-0.5 * s, h], [-s, 0.0]])
}

impl Hexagon {
    /// A side-up hexagon: flats at y = ±`d_mm`/2, vertices at (±`d_mm`/√3, 0).
    pub fn new(d_mm: f64) -> Result<Hexagon, ModelError> {
        let d = check_length("aperture hex", "D", d_mm)?;
        Ok(Hexagon {
            d,
            corner_up: false,
            tiles: side_up_zonogon(d),
        })
    }

    /// A corner-up hexagon: flats at x = ±`d_mm`/2, vertices at (0, ±`d_mm`/√3).
    pub fn corner_up(d_mm: f64) -> Result<Hexagon, ModelError> {
        let mut h = Hexagon::new(d_mm)?;
        h.corner_up = true;
        Ok(h)
    }

    /// Whether a vertex points up (flats at x = ±D/2).
    pub fn is_corner_up(&self) -> bool {
        self.corner_up
    }
}

impl Factor for Hexagon {
    fn name(&self) -> String {
        "aperture_hex".into()
    }

    fn otf(&self, u: f64, v: f64) -> Complex64 {
        if far(u, v, 0.25 * self.d) {
            return Complex64::new(0.0, 0.0);
        }
        let (u, v) = if self.corner_up { (v, u) } else { (u, v) };
        Complex64::new(self.tiles.otf(u, v), 0.0)
    }
}
