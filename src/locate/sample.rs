//! A grey raster with its mapping to image pixel coordinates, and bilinear
//! sampling on it. Used both for the reduced search image and (borrowed, no
//! copy) for the full-resolution [`Plane`].

use crate::geometry::Point;
use crate::photo::Plane;
use crate::photo::linearise::Crop;
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
        let d = &self.data;
        let w = self.w;
        blend4(c, (self.w, self.h), |i, j| d[j * w + i])
    }

    /// Bilinear value at an image px position, `None` outside.
    pub fn at_img(&self, p: Point) -> Option<f64> {
        self.bilinear(self.to_grid(p))
    }
}

/// The bilinear blend at grid point `c` of a `size` (w, h) grid whose sample
/// (i, j) is `at(i, j)` (sample centres at i + 0.5), `None` outside.
#[inline(always)]
fn blend4(c: Point, (w, h): (usize, usize), at: impl Fn(usize, usize) -> f32) -> Option<f64> {
    let x = c[0] - 0.5;
    let y = c[1] - 0.5;
    if !(x >= 0.0 && y >= 0.0) {
        return None;
    }
    let (i, j) = (x as usize, y as usize);
    if i + 1 >= w || j + 1 >= h {
        return None;
    }
    let (fx, fy) = (x - i as f64, y - j as f64);
    let top = at(i, j) as f64 * (1.0 - fx) + at(i + 1, j) as f64 * fx;
    let bot = at(i, j + 1) as f64 * (1.0 - fx) + at(i + 1, j + 1) as f64 * fx;
    Some(top * (1.0 - fy) + bot * fy)
}

/// Linear values at image positions, as the corner refinement reads them.
pub trait AtImage: Sync {
    /// Bilinear value at image px position `p` (pixel centres at +0.5), `None`
    /// outside the samples held.
    fn at_img(&self, p: Point) -> Option<f64>;
}

impl AtImage for Gray<'_> {
    fn at_img(&self, p: Point) -> Option<f64> {
        Gray::at_img(self, p)
    }
}

impl AtImage for Plane {
    fn at_img(&self, p: Point) -> Option<f64> {
        Gray::of_plane(self).at_img(p)
    }
}

/// A full-resolution crop of a photo read pixel by pixel, converted where read
/// (`at(x, y)`: the linear value of image pixel (x, y)): the values and bounds
/// of the crop's converted plane, without converting the crop (the corner
/// refinement reads bands about the edges and a few lines along the strip).
pub struct ConvertedCrop<F> {
    /// The crop (image px).
    pub crop: Crop,
    /// Linear value of an image pixel.
    pub at: F,
}

impl<F: Fn(usize, usize) -> f32 + Sync> AtImage for ConvertedCrop<F> {
    fn at_img(&self, p: Point) -> Option<f64> {
        let Crop { x0, y0, x1, y1 } = self.crop;
        // As `Gray::of_plane` of the crop's plane: grid = image px − the crop's corner.
        let c = [p[0] - x0 as f64, p[1] - y0 as f64];
        blend4(c, (x1 - x0, y1 - y0), |i, j| (self.at)(x0 + i, y0 + j))
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
