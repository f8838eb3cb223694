//! Reading the photo about a strip's long printed edges: the sampler the
//! searches read through (a plane, or codes converted where read) and the
//! search for edge points along one edge.

use crate::distortion::Lens;
use crate::geometry::Point;
use crate::photo::Plane;
use rayon::prelude::*;

/// Linear luminance at any photo point, as the edge searches read it.
pub trait Sampler: Sync {
    /// Bilinear value at photo point (x, y) px (pixel centres at +0.5), if inside.
    fn bilinear(&self, x: f64, y: f64) -> Option<f64>;
}

impl Sampler for Plane {
    fn bilinear(&self, x: f64, y: f64) -> Option<f64> {
        let fx = (x - 0.5 - self.offset.0 as f64) / self.step.0 as f64;
        let fy = (y - 0.5 - self.offset.1 as f64) / self.step.1 as f64;
        blend(fx, fy, (self.width, self.height), |i, j| {
            self.data[j * self.width + i] as f64
        })
    }
}

/// Samples converted from the photo's codes where they are read (no plane is
/// kept): `at(x, y)` is pixel (x, y)'s linear value in an image `width` px
/// wide whose first `rows` rows hold the picture.
pub struct Converted<F> {
    /// One pixel's linear value (as [`crate::photo::linearise::pixel_converter`]).
    pub at: F,
    /// Image width, px.
    pub width: usize,
    /// Rows that hold the picture.
    pub rows: usize,
}

impl<F: Fn(usize, usize) -> f32 + Sync> Sampler for Converted<F> {
    fn bilinear(&self, x: f64, y: f64) -> Option<f64> {
        blend(x - 0.5, y - 0.5, (self.width, self.rows), |i, j| {
            f64::from((self.at)(i, j))
        })
    }
}

/// Bilinear blend at grid position (fx, fy) of a `size` (columns, rows) grid
/// whose node (i, j) holds `at(i, j)`; `None` outside.
fn blend(fx: f64, fy: f64, size: (usize, usize), at: impl Fn(usize, usize) -> f64) -> Option<f64> {
    if !(fx >= 0.0 && fy >= 0.0) {
        return None;
    }
    let (i, j) = (fx.floor() as usize, fy.floor() as usize);
    if i + 1 >= size.0 || j + 1 >= size.1 {
        return None;
    }
    let (u, v) = (fx - i as f64, fy - j as f64);
    Some(
        (1.0 - v) * ((1.0 - u) * at(i, j) + u * at(i + 1, j))
            + v * ((1.0 - u) * at(i, j + 1) + u * at(i + 1, j + 1)),
    )
}

/// Edge points along the long edge from photo corner `a` to `b`, searched
/// about the curve that `lens` predicts for it (the chord without one);
/// `towards` is a point inside the strip, `depth_in` how far (px) the strip
/// reaches inside.
pub(super) fn edge_points(
    plane: &dyn Sampler,
    (a, b): (Point, Point),
    (oa, ob): (Point, Point),
    depth_in: f64,
    lens: Option<&Lens>,
    most: usize,
) -> (Vec<Point>, usize) {
    let len = (b[0] - a[0]).hypot(b[1] - a[1]);
    let on = |a: Point, b: Point, u: f64| -> Point {
        let (ua, ub) = lens.map_or((a, b), |l| (l.undistort(a), l.undistort(b)));
        let p = [ua[0] + u * (ub[0] - ua[0]), ua[1] + u * (ub[1] - ua[1])];
        lens.map_or(p, |l| l.distort(p))
    };
    let at = |u: f64| on(a, b, u);
    let h_in = (0.45 * depth_in).clamp(2.0, 16.0);
    let h_out = 12.0;
    let step = 0.25;
    let n = ((len / 6.0) as usize).clamp(16, 400).min(most);
    // (edge point, sign of the step outside − inside), the places in parallel
    // (each reads a hundred-odd profile steps of five samples).
    let place = |k: usize| -> Option<(Point, bool)> {
        let u = 0.04 + 0.92 * (k as f64 + 0.5) / n as f64;
        let c = at(u);
        let (p0, p1) = (at(u - 1e-3), at(u + 1e-3));
        let tl = (p1[0] - p0[0]).hypot(p1[1] - p0[1]).max(1e-12);
        let dir = [(p1[0] - p0[0]) / tl, (p1[1] - p0[1]) / tl];
        let towards = on(oa, ob, u);
        let mut inward = [-dir[1], dir[0]];
        if inward[0] * (towards[0] - c[0]) + inward[1] * (towards[1] - c[1]) < 0.0 {
            inward = [-inward[0], -inward[1]];
        }
        // d > 0 outwards.
        let nd = ((h_in + h_out) / step) as usize + 1;
        let mut prof = Vec::with_capacity(nd);
        let mut ok = true;
        for i in 0..nd {
            let d = -h_in + i as f64 * step;
            let mut acc = 0.0;
            for e in [-2.0, -1.0, 0.0, 1.0, 2.0] {
                let x = c[0] - d * inward[0] + e * dir[0];
                let y = c[1] - d * inward[1] + e * dir[1];
                match plane.bilinear(x, y) {
                    Some(v) => acc += v,
                    None => {
                        ok = false;
                        break;
                    }
                }
            }
            if !ok {
                break;
            }
            prof.push((d, acc / 5.0));
        }
        if !ok || prof.len() < 8 {
            return None;
        }
        let q = prof.len() / 4;
        let inside = prof[..q].iter().map(|p| p.1).sum::<f64>() / q as f64;
        let outside = prof[prof.len() - q..].iter().map(|p| p.1).sum::<f64>() / q as f64;
        let step_h = outside - inside;
        if step_h.abs() < 0.03 * outside.abs().max(inside.abs()).max(1e-6) {
            return None;
        }
        let mid = 0.5 * (inside + outside);
        // The crossing of the mid level nearest the predicted edge.
        let mut best: Option<f64> = None;
        for w in prof.windows(2) {
            let (g0, g1) = (w[0].1 - mid, w[1].1 - mid);
            if g0 == 0.0 || g0.signum() != g1.signum() {
                let d = w[0].0 + (w[1].0 - w[0].0) * g0 / (g0 - g1);
                if best.is_none_or(|b| d.abs() < b.abs()) {
                    best = Some(d);
                }
            }
        }
        best.filter(|&d| d > -0.8 * h_in && d < 0.8 * h_out)
            .map(|d| ([c[0] - d * inward[0], c[1] - d * inward[1]], step_h > 0.0))
    };
    let out: Vec<(Point, bool)> = (0..n).into_par_iter().filter_map(place).collect();
    // A printed edge has one sign of step all along (the strip darker or
    // lighter than its surround); the pattern itself flips sign with its phase.
    let up = out.iter().filter(|p| p.1).count();
    let major = up * 2 >= out.len();
    let pts = out
        .into_iter()
        .filter(|p| p.1 == major)
        .map(|p| p.0)
        .collect();
    (pts, n)
}
