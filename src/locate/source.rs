//! Where the search reads the photo: the reduced search image, and
//! full-resolution windows near the marks. A linear [`Plane`] already in
//! memory serves both; a photo still in its decoded codes ([`Converted`]) is
//! converted to linear values only a band of rows at a time for the reduced
//! image and only inside the windows asked for (issue 16: a 24 MP frame is
//! never converted whole), with values identical to the plane's.

use super::downscale::{factor, reduce_for_search};
use super::sample::Gray;
use crate::photo::Plane;
use crate::photo::linearise::Crop;
use rayon::prelude::*;
use std::borrow::Cow;

/// Full-resolution samples of an image rectangle, for the marks' edge fits.
#[derive(Debug, Clone)]
pub struct Window<'a> {
    /// The samples (grid ↔ image px as for the whole image).
    pub gray: Gray<'a>,
    /// Whether each side (left, top, right, bottom) is a cut inside the image
    /// (reads across it would see samples the window lacks); `false` where the
    /// window reaches the image's own edge.
    pub cut: [bool; 4],
}

impl Window<'_> {
    /// Whether every bilinear read inside the grid box `reach` ([x0, y0, x1, y1],
    /// grid units of `gray`) gives what the whole image gives.
    pub fn holds(&self, reach: [f64; 4]) -> bool {
        let (w, h) = (self.gray.w as f64, self.gray.h as f64);
        // A read at x needs samples floor(x − 0.5) and the one after it; keep a sample spare.
        (!self.cut[0] || reach[0] >= 1.5)
            && (!self.cut[1] || reach[1] >= 1.5)
            && (!self.cut[2] || reach[2] <= w - 1.5)
            && (!self.cut[3] || reach[3] <= h - 1.5)
    }
}

/// What the search reads: a reduced image and full-resolution windows.
pub trait Source: Sync {
    /// Samples across and down at full resolution.
    fn size(&self) -> (usize, usize);
    /// The reduced search image ([`reduce_for_search`]).
    fn reduced(&self) -> Gray<'_>;
    /// Full-resolution samples covering at least the image px rectangle `want`
    /// (clamped to the image); may return more, up to the whole image.
    fn window(&self, want: Crop) -> Window<'_>;
    /// Whether the samples are all there (a plane's data may be short).
    fn complete(&self) -> bool {
        true
    }
}

impl Source for Plane {
    fn size(&self) -> (usize, usize) {
        (self.width, self.height)
    }

    fn reduced(&self) -> Gray<'_> {
        reduce_for_search(self)
    }

    fn window(&self, _want: Crop) -> Window<'_> {
        Window {
            gray: Gray::of_plane(self),
            cut: [false; 4],
        }
    }

    fn complete(&self) -> bool {
        self.data.len() >= self.width * self.height
    }
}

/// A photo converted to linear values on demand: `convert(y, x0, out)` fills
/// `out` with the linear values of image row `y` from column `x0` on.
pub struct Converted<F> {
    /// Image width (px).
    pub width: usize,
    /// Image height (px).
    pub height: usize,
    /// Converts part of a row of the photo to linear values.
    pub convert: F,
}

/// Reduced rows made per parallel task.
pub(super) const BAND: usize = 8;

impl<F: Fn(usize, usize, &mut [f32]) + Sync> Source for Converted<F> {
    fn size(&self) -> (usize, usize) {
        (self.width, self.height)
    }

    /// The same k×k box average as [`super::downscale::box_reduce`] (same
    /// summation order, so the same values), made a row at a time.
    fn reduced(&self) -> Gray<'_> {
        let k = factor(self.width, self.height);
        if k == 1 {
            return self.window(self.whole()).gray;
        }
        let (w, h) = (self.width / k, self.height / k);
        let inv = 1.0 / (k * k) as f32;
        let mut out = vec![0.0f32; w * h];
        out.par_chunks_mut((w * BAND).max(1))
            .enumerate()
            .for_each(|(b, rows)| {
                let mut line = vec![0.0f32; w * k];
                let mut acc = vec![0.0f32; w];
                for (jj, row) in rows.chunks_mut(w).enumerate() {
                    let j = b * BAND + jj;
                    acc.iter_mut().for_each(|a| *a = 0.0);
                    for r in 0..k {
                        (self.convert)(j * k + r, 0, &mut line);
                        super::downscale::add_box_sums(&mut acc, &line, k);
                    }
                    for (o, a) in row.iter_mut().zip(&acc) {
                        *o = a * inv;
                    }
                }
            });
        Gray {
            w,
            h,
            data: Cow::Owned(out),
            origin: [0.0, 0.0],
            scale: [k as f64, k as f64],
        }
    }

    fn window(&self, want: Crop) -> Window<'_> {
        let x1 = want.x1.min(self.width);
        let y1 = want.y1.min(self.height);
        let c = Crop {
            x0: want.x0.min(x1.saturating_sub(1)),
            y0: want.y0.min(y1.saturating_sub(1)),
            x1,
            y1,
        };
        let w = c.x1 - c.x0;
        let mut data = crate::photo::hugebuf::zeroed::<f32>(w * (c.y1 - c.y0));
        data.par_chunks_mut(w.max(1))
            .enumerate()
            .for_each(|(j, row)| (self.convert)(c.y0 + j, c.x0, row));
        Window {
            gray: Gray {
                w,
                h: c.y1 - c.y0,
                data: Cow::Owned(data),
                origin: [c.x0 as f64, c.y0 as f64],
                scale: [1.0, 1.0],
            },
            cut: [c.x0 > 0, c.y0 > 0, c.x1 < self.width, c.y1 < self.height],
        }
    }
}

impl<F> Converted<F> {
    /// The whole image as a crop.
    fn whole(&self) -> Crop {
        Crop {
            x0: 0,
            y0: 0,
            x1: self.width,
            y1: self.height,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn ramp(w: usize, h: usize) -> Plane {
        let data = (0..w * h)
            .map(|i| ((i % w) as f32 * 0.37 + (i / w) as f32 * 1.1).sin())
            .collect();
        Plane::full(w, h, data)
    }

    fn converted(p: &Plane) -> Converted<impl Fn(usize, usize, &mut [f32]) + Sync + '_> {
        Converted {
            width: p.width,
            height: p.height,
            convert: move |y: usize, x0: usize, out: &mut [f32]| {
                let a = y * p.width + x0;
                out.copy_from_slice(&p.data[a..a + out.len()]);
            },
        }
    }

    #[test]
    fn reduced_from_bands_equals_the_planes_reduction() {
        // 1931×1297 → factor 2 with odd trailing rows and columns; and a factor-1 image.
        for (w, h) in [(1931, 1297), (3850, 1925), (700, 500)] {
            let p = ramp(w, h);
            let a = reduce_for_search(&p);
            let c = converted(&p);
            let b = c.reduced();
            assert_eq!((a.w, a.h, a.scale, a.origin), (b.w, b.h, b.scale, b.origin));
            assert!(a.data.iter().zip(b.data.iter()).all(|(x, y)| x == y));
        }
    }

    #[test]
    fn window_reads_equal_the_whole_image_inside_and_say_where_cut() {
        let p = ramp(300, 200);
        let c = converted(&p);
        let win = c.window(Crop {
            x0: 50,
            y0: 0,
            x1: 120,
            y1: 400,
        });
        assert_eq!(win.cut, [true, false, true, false]);
        let whole = Gray::of_plane(&p);
        for q in [[60.3, 10.7], [119.0, 199.0], [50.6, 0.6]] {
            assert_eq!(win.gray.at_img(q), whole.at_img(q), "{q:?}");
        }
        assert!(win.holds([1.5, 0.0, 68.5, 200.0]));
        assert!(!win.holds([1.0, 0.0, 60.0, 200.0]));
        assert!(!win.holds([2.0, 0.0, 69.0, 200.0]));
    }
}
