//! A grey raster with its mapping to image pixel coordinates, and bilinear
//! sampling on it. Used both for the reduced search image and (borrowed, no
//! copy) for the full-resolution [`Plane`].

use crate::geometry::Point;
use crate::photo::Plane;
use std::borrow::Cow;

/// A grey raster (row-major) whose sample `(i, j)` covers grid square
/// `[i, i+1) × [j, j+1)`; grid point `c` lies at image px `origin + scale·c`.
#[derive(Debug, Clone)]
pub struct Gray<'a> {
    /// Columns.
    pub w: usize,
    /// Rows.
    pub h: usize,
    /// Linear values, row-major.
    pub data: Cow<'a, [f32]>,
    /// Image px of grid point (0, 0).
    pub origin: Point,
    /// Image px per grid unit (x, y).
    pub scale: Point,
}

impl<'a> Gray<'a> {
    /// A borrowed view of a plane (no copy).
    pub fn of_plane(p: &'a Plane) -> Gray<'a> {
        let (sx, sy) = (p.step.0 as f64, p.step.1 as f64);
        Gray {
            w: p.width,
            h: p.height,
            data: Cow::Borrowed(&p.data[..p.width * p.height]),
            origin: [
                p.offset.0 as f64 + 0.5 - 0.5 * sx,
                p.offset.1 as f64 + 0.5 - 0.5 * sy,
            ],
            scale: [sx, sy],
        }
    }

    /// Image px of a grid point.
    pub fn to_img(&self, c: Point) -> Point {
        [
            self.origin[0] + self.scale[0] * c[0],
            self.origin[1] + self.scale[1] * c[1],
        ]
    }

    /// Grid point of an image px position.
    pub fn to_grid(&self, p: Point) -> Point {
        [
            (p[0] - self.origin[0]) / self.scale[0],
            (p[1] - self.origin[1]) / self.scale[1],
        ]
    }

    /// Value of sample (i, j).
    #[inline]
    pub fn at(&self, i: usize, j: usize) -> f32 {
        self.data[j * self.w + i]
    }

    /// Bilinear value at a grid point (sample centres at i + 0.5), `None` outside.
    #[inline]
    pub fn bilinear(&self, c: Point) -> Option<f64> {
        let x = c[0] - 0.5;
        let y = c[1] - 0.5;
        if !(x >= 0.0 && y >= 0.0) {
            return None;
        }
        let (i, j) = (x as usize, y as usize);
        if i + 1 >= self.w || j + 1 >= self.h {
            return None;
        }
        let (fx, fy) = (x - i as f64, y - j as f64);
        let r0 = j * self.w + i;
        let r1 = r0 + self.w;
        let d = &self.data;
        let top = d[r0] as f64 * (1.0 - fx) + d[r0 + 1] as f64 * fx;
        let bot = d[r1] as f64 * (1.0 - fx) + d[r1 + 1] as f64 * fx;
        Some(top * (1.0 - fy) + bot * fy)
    }

    /// Bilinear value at an image px position, `None` outside.
    pub fn at_img(&self, p: Point) -> Option<f64> {
        self.bilinear(self.to_grid(p))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn plane_view_maps_pixel_centres() {
        // Red sites of an RGGB mosaic: step 2, offset 0; sample (1, 2) sits at px (2.5, 4.5).
        let p = Plane {
            width: 4,
            height: 4,
            step: (2, 2),
            offset: (1, 0),
            data: (0..16).map(|v| v as f32).collect(),
        };
        let g = Gray::of_plane(&p);
        let c = g.to_img([1.5, 2.5]);
        let (x, y) = p.centre(1, 2);
        assert!((c[0] - x).abs() < 1e-12 && (c[1] - y).abs() < 1e-12);
        assert_eq!(g.at_img([x, y]), Some(p.get(1, 2) as f64));
        // Halfway between samples (1,2) and (2,2).
        let v = g.at_img([x + 1.0, y]).unwrap();
        assert!((v - 0.5 * (p.get(1, 2) + p.get(2, 2)) as f64).abs() < 1e-9);
    }
}
