//! From modulation samples to the MTF curve: image frequency from the fitted
//! sweep law and the strip's local scale, aliasing flags (frequency outside
//! the sampling lattice's band in the sweep's direction, or the image's local
//! frequency departing from the law), normalisation by the chart's own
//! modulation; the summary figures are in [`super::figures`].

#![allow(clippy::needless_range_loop, clippy::neg_cmp_op_on_partial_ord)]

use serde::{Deserialize, Serialize};

pub use super::figures::{Figures, crossing, figures, mtf_at, mtf50_sigma};

mod chart_modulation;

pub use chart_modulation::{
    ChartModulation, diffraction_beyond_quadratic, extrapolate_chart_modulation,
};

/// One point of a measured MTF curve.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct MtfPoint {
    /// Position along the strip (strip units: mm on the chart with a target, else fraction of the strip).
    pub s: f64,
    /// Image frequency (cycles/pixel).
    pub freq_cy_px: f64,
    /// Chart frequency (cycles per strip unit: cycles/mm with a target).
    pub freq_chart: f64,
    /// Measured modulation of the image (amplitude / mean, linear light).
    pub modulation: f64,
    /// MTF = modulation / chart modulation.
    pub mtf: f64,
    /// One-sigma uncertainty of the MTF.
    pub mtf_err: f64,
    /// True where the frequency is aliased: the value is not an MTF.
    pub aliased: bool,
    /// True where a JPEG's quantiser, not the photo's noise, is the larger
    /// part of `mtf_err`, or has rounded the sine away: the value there is
    /// more the file's than the lens's.
    #[serde(default)]
    pub jpeg_limited: bool,
}

/// The sampling lattice of the planes binned together for one curve, as far
/// as aliasing goes: a frequency inside its band (the Voronoi cell of the
/// reciprocal lattice) has no alias that binning along the sweep could mistake for it.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Lattice {
    /// Rectangular with steps (sx, sy) pixels: band |fx|·sx ≤ ½ and |fy|·sy ≤ ½.
    Rect(usize, usize),
    /// Two (2, 2) lattices offset by (1, 1), the chequerboard of a Bayer
    /// mosaic's two greens: band |fx| + |fy| ≤ ½ (0.5 cy/px along the axes,
    /// 0.35 cy/px diagonally).
    Quincunx,
}

impl Lattice {
    /// The lattice of a group of planes: a quincunx for two (2, 2) planes
    /// whose offsets differ by (1, 1), else the first plane's steps.
    pub fn of(planes: &[crate::photo::PlaneRef]) -> Lattice {
        match planes {
            [a, b]
                if a.step == (2, 2)
                    && b.step == (2, 2)
                    && a.offset.0.abs_diff(b.offset.0) % 2 == 1
                    && a.offset.1.abs_diff(b.offset.1) % 2 == 1 =>
            {
                Lattice::Quincunx
            }
            [a, ..] => Lattice::Rect(a.step.0, a.step.1),
            [] => Lattice::Rect(1, 1),
        }
    }

    /// Highest frequency (cycles/pixel) inside the band in direction `angle` (radians).
    pub fn band_limit(&self, angle: f64) -> f64 {
        let (c, s) = (angle.cos().abs(), angle.sin().abs());
        match *self {
            Lattice::Rect(sx, sy) => 0.5 / (c * sx as f64).max(s * sy as f64),
            Lattice::Quincunx => 0.5 / (c + s),
        }
    }

    /// Whether frequency `f` (cycles/pixel) in direction `angle` lies outside the band.
    pub fn outside(&self, f: f64, angle: f64) -> bool {
        let (fx, fy) = ((f * angle.cos()).abs(), (f * angle.sin()).abs());
        match *self {
            Lattice::Rect(sx, sy) => fx * sx as f64 > 0.5 + 1e-9 || fy * sy as f64 > 0.5 + 1e-9,
            Lattice::Quincunx => fx + fy > 0.5 + 1e-9,
        }
    }
}

/// Solves a 3×3 linear system by Gaussian elimination with partial pivoting.
pub(crate) fn solve3(a: [[f64; 3]; 3], r: [f64; 3]) -> Option<[f64; 3]> {
    crate::linalg::solve(a, r, 1e-300)
}

#[cfg(test)]
mod tests;
