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
    // Truncation is the floor here (both are ≥ 0), without a call to libm's
    // `floor` (baseline x86-64 has no rounding instruction; `perf` put 0.6 %
    // of the target's whole run in it).
    let (i, j) = (fx as usize, fy as usize);
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
        // d > 0 outwards. The profile across the edge at d = −h_in + i·step
        // (i < nd), each value the mean of five samples along the edge.
        let nd = ((h_in + h_out) / step) as usize + 1;
        if nd < 8 {
            return None;
        }
        let d_at = |i: usize| -h_in + i as f64 * step;
        let point = |d: f64, e: f64| -> Point {
            [
                c[0] - d * inward[0] + e * dir[0],
                c[1] - d * inward[1] + e * dir[1],
            ]
        };
        let value = |i: usize| -> Option<f64> {
            let d = d_at(i);
            let mut acc = 0.0;
            for e in [-2.0, -1.0, 0.0, 1.0, 2.0] {
                let [x, y] = point(d, e);
                acc += plane.bilinear(x, y)?;
            }
            Some(acc / 5.0)
        };
        // The profile is wanted only where all of it lies in the photo. When
        // a slightly larger parallelogram's corners do (the readable region
        // is convex), every sample does, and the profile is read only where
        // needed: its two end quarters and about the predicted edge (the
        // nearest crossing), ≈ 60 of ≈ 110 places. Otherwise all of it is read.
        let (d0, d1) = (d_at(0) - 0.01, d_at(nd - 1) + 0.01);
        let lazy = [(d0, -2.01), (d0, 2.01), (d1, -2.01), (d1, 2.01)]
            .iter()
            .all(|&(d, e)| {
                let [x, y] = point(d, e);
                plane.bilinear(x, y).is_some()
            });
        let mut prof: Vec<Option<f64>> = vec![None; nd];
        let q = nd / 4;
        let eager = if lazy { 0..0 } else { 0..nd };
        for i in (0..q).chain(nd - q..nd).chain(eager) {
            if prof[i].is_none() {
                prof[i] = Some(value(i)?);
            }
        }
        let mean =
            |r: std::ops::Range<usize>| r.map(|i| prof[i].unwrap_or(0.0)).sum::<f64>() / q as f64;
        let inside = mean(0..q);
        let outside = mean(nd - q..nd);
        let step_h = outside - inside;
        if step_h.abs() < 0.03 * outside.abs().max(inside.abs()).max(1e-6) {
            return None;
        }
        let mid = 0.5 * (inside + outside);
        // The crossing of the mid level nearest the predicted edge (d = 0),
        // the first on a tie: the places from d = 0 outwards, until no
        // unread pair of places can hold a nearer crossing.
        let mut best: Option<(f64, usize)> = None;
        let pair = |i: usize,
                    prof: &mut Vec<Option<f64>>,
                    best: &mut Option<(f64, usize)>|
         -> Option<()> {
            for k in [i, i + 1] {
                if prof[k].is_none() {
                    prof[k] = Some(value(k)?);
                }
            }
            let (g0, g1) = (prof[i]? - mid, prof[i + 1]? - mid);
            if g0 == 0.0 || g0.signum() != g1.signum() {
                let d = d_at(i) + (d_at(i + 1) - d_at(i)) * g0 / (g0 - g1);
                let nearer =
                    best.is_none_or(|(b, j)| d.abs() < b.abs() || (d.abs() == b.abs() && i < j));
                if nearer && !d.is_nan() {
                    *best = Some((d, i));
                }
            }
            Some(())
        };
        // The pair (z, z + 1) holds d = 0; pairs beyond z + k are at
        // |d| ≥ d(z + k), pairs before z − k at |d| ≥ |d(z − k + 1)|.
        let z = (0..nd - 1).rfind(|&i| d_at(i) <= 0.0).unwrap_or(0);
        pair(z, &mut prof, &mut best)?;
        for k in 1..nd {
            let right = z + k < nd - 1;
            let left = k <= z;
            if !right && !left {
                break;
            }
            if best.is_some_and(|(b, _)| {
                let bound_r = if right { d_at(z + k) } else { f64::INFINITY };
                let bound_l = if left {
                    -d_at(z + 1 - k)
                } else {
                    f64::INFINITY
                };
                bound_r.min(bound_l) > b.abs()
            }) {
                break;
            }
            if right {
                pair(z + k, &mut prof, &mut best)?;
            }
            if left {
                pair(z - k, &mut prof, &mut best)?;
            }
        }
        let best = best.map(|b| b.0);
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

#[cfg(test)]
mod tests {
    use super::*;

    /// The search's plain definition (the code before the profile was read
    /// lazily): every place read; no profile where any sample is outside;
    /// the first crossing of the mid level with the least |d|.
    fn plain(
        plane: &dyn Sampler,
        (a, b): (Point, Point),
        (oa, ob): (Point, Point),
        depth_in: f64,
    ) -> Vec<Option<(Point, bool)>> {
        let len = (b[0] - a[0]).hypot(b[1] - a[1]);
        let at = |a: Point, b: Point, u: f64| [a[0] + u * (b[0] - a[0]), a[1] + u * (b[1] - a[1])];
        let (h_in, h_out, step) = ((0.45 * depth_in).clamp(2.0, 16.0), 12.0, 0.25);
        let n = ((len / 6.0) as usize).clamp(16, 400);
        (0..n)
            .map(|k| {
                let u = 0.04 + 0.92 * (k as f64 + 0.5) / n as f64;
                let c = at(a, b, u);
                let (p0, p1) = (at(a, b, u - 1e-3), at(a, b, u + 1e-3));
                let tl = (p1[0] - p0[0]).hypot(p1[1] - p0[1]).max(1e-12);
                let dir = [(p1[0] - p0[0]) / tl, (p1[1] - p0[1]) / tl];
                let towards = at(oa, ob, u);
                let mut inward = [-dir[1], dir[0]];
                if inward[0] * (towards[0] - c[0]) + inward[1] * (towards[1] - c[1]) < 0.0 {
                    inward = [-inward[0], -inward[1]];
                }
                let nd = ((h_in + h_out) / step) as usize + 1;
                let mut prof = Vec::new();
                for i in 0..nd {
                    let d = -h_in + i as f64 * step;
                    let mut acc = 0.0;
                    for e in [-2.0, -1.0, 0.0, 1.0, 2.0] {
                        let x = c[0] - d * inward[0] + e * dir[0];
                        let y = c[1] - d * inward[1] + e * dir[1];
                        acc += plane.bilinear(x, y)?;
                    }
                    prof.push((d, acc / 5.0));
                }
                let q = prof.len() / 4;
                let inside = prof[..q].iter().map(|p| p.1).sum::<f64>() / q as f64;
                let outside = prof[prof.len() - q..].iter().map(|p| p.1).sum::<f64>() / q as f64;
                let step_h = outside - inside;
                if step_h.abs() < 0.03 * outside.abs().max(inside.abs()).max(1e-6) {
                    return None;
                }
                let mid = 0.5 * (inside + outside);
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
            })
            .collect()
    }

    #[test]
    fn lazy_profiles_find_the_edges_the_whole_profiles_find() {
        // A dark band with noise and a printed sine inside it, turned any
        // way, searched from chords that miss the true edge by up to ±10 px
        // (several crossings: the pattern's, the noise's), some running off
        // the photo. Same points, bit for bit, as reading every place.
        let mut st = 99u64;
        let mut rnd = move || {
            st = st
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            (st >> 11) as f64 / (1u64 << 53) as f64
        };
        let (w, h) = (400usize, 300usize);
        let mut compared = 0;
        for _ in 0..24 {
            let ang = rnd() * std::f64::consts::TAU;
            let (ux, uy) = (ang.cos(), ang.sin());
            let (cx, cy) = (
                w as f64 * (0.3 + 0.4 * rnd()),
                h as f64 * (0.3 + 0.4 * rnd()),
            );
            let half = 20.0 + 40.0 * rnd();
            let (noise, period) = (0.02 * rnd(), 6.0 + 20.0 * rnd());
            let data: Vec<f32> = (0..w * h)
                .map(|k| {
                    let (x, y) = ((k % w) as f64 + 0.5, (k / w) as f64 + 0.5);
                    let (s, t) = (
                        (x - cx) * ux + (y - cy) * uy,
                        -(x - cx) * uy + (y - cy) * ux,
                    );
                    let inside = t.abs() < half;
                    let v = if inside {
                        0.3 + 0.15 * (std::f64::consts::TAU * s / period).sin()
                    } else {
                        0.8
                    };
                    (v + noise * (rnd() - 0.5)) as f32
                })
                .collect();
            let plane = Plane::full(w, h, data);
            let len = 150.0 + 300.0 * rnd();
            let end = |sgn: f64, off: f64| -> Point {
                [
                    cx + sgn * 0.5 * len * ux - (half + off) * uy,
                    cy + sgn * 0.5 * len * uy + (half + off) * ux,
                ]
            };
            let (e0, e1) = (10.0 * (rnd() - 0.5), 10.0 * (rnd() - 0.5));
            let (a, b) = (end(-1.0, e0), end(1.0, e1));
            let (oa, ob) = (end(-1.0, -2.0 * half), end(1.0, -2.0 * half));
            let want: Vec<(Point, bool)> = plain(&plane, (a, b), (oa, ob), 2.0 * half)
                .into_iter()
                .flatten()
                .collect();
            let up = want.iter().filter(|p| p.1).count();
            let major = up * 2 >= want.len();
            let want: Vec<Point> = want
                .into_iter()
                .filter(|p| p.1 == major)
                .map(|p| p.0)
                .collect();
            let (got, _) = edge_points(&plane, (a, b), (oa, ob), 2.0 * half, None, usize::MAX);
            assert_eq!(got, want);
            compared += got.len();
        }
        assert!(compared > 1000, "{compared}");
    }
}
