//! A strip on the chart: its own frame `(s, t)`, where that frame lies in the
//! photo (homography and lens) and its local scale there.

use crate::distortion::Lens;
use crate::geometry::{Homography, Point};

/// A strip on the chart: its own frame `(s, t)` (s along the sweep from the
/// low-frequency edge, t across) and where that frame lies in the image.
#[derive(Debug, Clone)]
pub struct Strip {
    /// Maps strip coordinates (s, t) to image pixel coordinates (undistorted
    /// ones when `lens` is given).
    pub to_image: Homography,
    /// Lens distortion from undistorted to photo pixel coordinates, if any.
    pub lens: Option<Lens>,
    /// Length along the sweep (strip units: mm with a target, else 1).
    pub length: f64,
    /// Width across the sweep (strip units).
    pub width: f64,
}

/// Local scale of a strip in the image.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct LocalScale {
    /// |∇s| in strip units per image pixel (multiply a frequency in cycles per strip unit by this to get cycles/pixel).
    pub s_per_px: f64,
    /// Direction of increasing s in the image (radians from +x towards +y).
    pub angle_rad: f64,
}

impl Strip {
    /// Where strip point (s, t) lies in the photo (pixels).
    pub fn to_photo(&self, p: Point) -> Point {
        let q = self.to_image.apply(p);
        self.lens.as_ref().map_or(q, |l| l.distort(q))
    }

    /// The four photo corners of the strip region t ∈ [t0, t1] over its whole length.
    pub fn image_quad(&self, t0: f64, t1: f64) -> [Point; 4] {
        let l = self.length;
        [[0.0, t0], [l, t0], [l, t1], [0.0, t1]].map(|p| self.to_photo(p))
    }

    /// Image pixels (undistorted) per strip unit across the strip (along t), at distance `s` along its centre line.
    pub fn px_per_t(&self, s: f64) -> f64 {
        let j = self.to_image.jacobian([s, 0.5 * self.width]);
        j[0][1].hypot(j[1][1])
    }

    /// Scale and direction of the sweep in the image at distance `s` along the strip's centre line.
    pub fn scale_at(&self, s: f64) -> LocalScale {
        let mut j = self.to_image.jacobian([s, 0.5 * self.width]);
        if let Some(l) = &self.lens {
            let d = l.jacobian(self.to_image.apply([s, 0.5 * self.width]));
            j = [
                [
                    d[0][0] * j[0][0] + d[0][1] * j[1][0],
                    d[0][0] * j[0][1] + d[0][1] * j[1][1],
                ],
                [
                    d[1][0] * j[0][0] + d[1][1] * j[1][0],
                    d[1][0] * j[0][1] + d[1][1] * j[1][1],
                ],
            ];
        }
        // Inverse Jacobian: d(s,t)/d(x,y); its first row is ∇s.
        let det = j[0][0] * j[1][1] - j[0][1] * j[1][0];
        let gx = j[1][1] / det;
        let gy = -j[0][1] / det;
        LocalScale {
            s_per_px: gx.hypot(gy),
            angle_rad: gy.atan2(gx),
        }
    }
}
