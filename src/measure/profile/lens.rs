//! Binning through a lens model: the photo's iso-phase lines are curves, so
//! every sample centre is undistorted before the inverse homography.

use super::acc::BinAcc;
use super::region::TILE;
use super::{Profile, Strip};
use crate::distortion::Lens;
use crate::geometry::Point;
use crate::photo::PlaneRef;
use rayon::prelude::*;

/// Binning through a lens model (the photo's iso-phase lines are curves):
/// every sample centre inside the region's photo outline is undistorted, then
/// mapped by the inverse homography `m` (denominator positive) to (s, t).
///
/// The same shape as the fast path ([`super::region`]): the outline's rows
/// are cut into tiles of TILE × TILE samples, each with the range of s it can
/// hold; the bins are split into runs that fill their own bins in parallel,
/// each visiting only the tiles that reach its run; the robust mean comes from
/// each bin's kept extremes. No sample is stored (they were 16 bytes each: a
/// 5200 × 1700 px strip took 140 MB), and the bins fill in a fixed order
/// (results do not depend on threads).
#[allow(clippy::too_many_arguments)]
pub(super) fn bin_through_lens(
    planes: &[PlaneRef],
    strip: &Strip,
    lens: &Lens,
    m: [f64; 9],
    (t0, t1, s_lo, s_hi): (f64, f64, f64, f64),
    (bin, nbins): (f64, usize),
    steps: (usize, usize),
    clip_level: f32,
) -> Profile {
    let outline = photo_outline(strip, t0, t1);
    let map = Map {
        lens: Undistort::new(lens),
        m,
        t0,
        t1,
        s_lo,
        s_hi,
    };
    let tiles = tiles(planes, &outline, &map, bin, steps);
    let inv_bin = 1.0 / bin;
    let last = nbins - 1;
    let bin_of = |s: f64| ((s * inv_bin) as usize).min(last);
    let mut acc: Vec<BinAcc> = (0..nbins)
        .into_par_iter()
        .map(|_| BinAcc::default())
        .collect();
    let hair = 1e-6 * bin;
    let counts: Vec<[usize; 3]> = super::own_runs(&mut acc, s_lo, s_hi, bin)
        .into_par_iter()
        .map(|(b0, b1, acc)| {
            let mut count = [0usize; 3];
            let reach = [(b0 as f64 * bin - hair, b1 as f64 * bin + hair)];
            map.visit(planes, &tiles, &reach, |s, v, (x, y)| {
                let b = bin_of(s);
                if b >= b0 && b < b1 {
                    count[0] += 1;
                    count[1] += (v >= clip_level) as usize;
                    count[2] += (v <= 0.0) as usize;
                    acc[b - b0].add(s, v);
                    acc[b - b0].add_parity(x, y);
                }
            });
            count
        })
        .collect();
    let mut prof = Profile::default();
    for c in counts {
        prof.samples += c[0];
        prof.clipped_high += c[1];
        prof.clipped_low += c[2];
    }
    let revisit = super::acc::robust_from_extremes(&mut acc);
    if !revisit.is_empty() {
        let mut keep = vec![None; nbins];
        for &(b, mu, lim) in &revisit {
            keep[b] = Some((mu, lim));
        }
        // Only the tiles that reach those bins.
        let reach: Vec<(f64, f64)> = revisit
            .iter()
            .map(|r| (r.0 as f64 * bin - hair, (r.0 + 1) as f64 * bin + hair))
            .collect();
        map.visit(planes, &tiles, &reach, |s, v, _| {
            let b = bin_of(s);
            if let Some((mu, lim)) = keep[b]
                && (v as f64 - mu).abs() <= lim
            {
                acc[b].rsum += v as f64;
                acc[b].rn += 1;
            }
        });
    }
    super::acc::finish(&acc, &mut prof, super::wants_parity(planes), clip_level);
    prof
}

/// Photo → strip through the lens, and the part of the strip that is binned.
struct Map<'a> {
    lens: Undistort<'a>,
    /// Inverse homography (undistorted photo → strip), denominator positive.
    m: [f64; 9],
    t0: f64,
    t1: f64,
    s_lo: f64,
    s_hi: f64,
}

impl Map<'_> {
    /// (s, t, denominator) of photo position (x, y).
    #[inline(always)]
    fn strip_of(&self, x: f64, y: f64) -> (f64, f64, f64) {
        let m = &self.m;
        let [xu, yu] = self.lens.undistort([x, y]);
        let w = m[6] * xu + m[7] * yu + m[8];
        let rw = 1.0 / w;
        (
            (m[0] * xu + m[1] * yu + m[2]) * rw,
            (m[3] * xu + m[4] * yu + m[5]) * rw,
            w,
        )
    }

    /// s of the samples x0 + k·sx (k < s_run.len()) of row y, NaN for those
    /// outside the binned part: [`Map::strip_of`] a run at a time, in steps
    /// the compiler vectorises (all but the table's reads).
    #[inline]
    fn strip_row(&self, x0: f64, sx: f64, y: f64, s_run: &mut [f64]) {
        let n = s_run.len();
        let l = self.lens.lens;
        let dy = y - l.cy;
        let mut dx = [0.0f64; TILE];
        let mut k = [0.0f64; TILE];
        let (dx, k) = (&mut dx[..n], &mut k[..n]);
        for (i, (d, u)) in dx.iter_mut().zip(k.iter_mut()).enumerate() {
            *d = x0 + i as f64 * sx - l.cx;
            *u = (*d * *d + dy * dy).sqrt() * self.lens.per_px;
        }
        for (u, &d) in k.iter_mut().zip(dx.iter()) {
            *u = self.lens.ratio_at(*u, d, dy);
        }
        let m = &self.m;
        for ((s, &d), &kk) in s_run.iter_mut().zip(dx.iter()).zip(k.iter()) {
            let (xu, yu) = (l.cx + d * kk, l.cy + dy * kk);
            let w = m[6] * xu + m[7] * yu + m[8];
            let rw = 1.0 / w;
            let ss = (m[0] * xu + m[1] * yu + m[2]) * rw;
            let t = (m[3] * xu + m[4] * yu + m[5]) * rw;
            let inside =
                w > 0.0 && t >= self.t0 && t <= self.t1 && ss >= self.s_lo && ss <= self.s_hi;
            *s = if inside { ss } else { f64::NAN };
        }
    }

    /// Calls f(s, value, photo pixel) for every sample inside the binned part of the strip
    /// in the tiles whose s-range meets one of `reach` (sorted, disjoint
    /// s-intervals), tile by tile in order.
    fn visit<F: FnMut(f64, f32, (usize, usize))>(
        &self,
        planes: &[PlaneRef],
        tiles: &[Tile],
        reach: &[(f64, f64)],
        mut f: F,
    ) {
        let mut buf = [0.0f32; TILE];
        let mut picked = [0.0f32; TILE];
        let mut s_buf = [0.0f64; TILE];
        let meets = |t: &&Tile| {
            let k = reach.partition_point(|r| r.1 < t.s_min);
            reach.get(k).is_some_and(|r| r.0 <= t.s_max)
        };
        for tile in tiles.iter().filter(meets) {
            let plane = planes[tile.plane];
            let (ox, oy, sx, sy) = plane.centres();
            let cs = tile.col_step;
            for (dj, &(i0, i1)) in tile.rows.iter().enumerate() {
                // The samples at multiples of the column step.
                let i0 = i0.next_multiple_of(cs);
                if i0 >= i1 {
                    continue;
                }
                let j = tile.first + dj * tile.row_step;
                let y = oy + j as f64 * sy;
                let mut row = plane.values(j, i0, &mut buf[..i1 - i0]);
                if cs > 1 {
                    let n = (i1 - i0).div_ceil(cs);
                    for q in 0..n {
                        picked[q] = row[q * cs];
                    }
                    row = &picked[..n];
                }
                let s_run = &mut s_buf[..row.len()];
                self.strip_row(ox + i0 as f64 * sx, sx * cs as f64, y, s_run);
                let (px0, py) = (
                    plane.offset.0 + i0 * plane.step.0,
                    plane.offset.1 + j * plane.step.1,
                );
                for (k, (&s, &v)) in s_run.iter().zip(row).enumerate() {
                    if !s.is_nan() {
                        f(s, v, (px0 + k * cs * plane.step.0, py));
                    }
                }
            }
        }
    }
}

/// A lens's undistortion from a table of r_u / r_d against r_d (cubic
/// interpolation through four knots), for the millions of samples of a
/// strip: Newton's iterations for every sample were most of binning's time.
/// Beyond the table (never inside the frame) it falls back to the exact
/// inverse.
struct Undistort<'a> {
    lens: &'a Lens,
    /// Knots per pixel of radius.
    per_px: f64,
    /// r_u / r_d at r_d = i / per_r.
    k: Vec<f64>,
}

/// Knots of [`Undistort`]'s table: its error is < 1e-12 of the radius for
/// any lens [`Lens::check`] passes (the unit test holds it to 1e-9 px).
const UNDISTORT_KNOTS: usize = 4096;

impl<'a> Undistort<'a> {
    fn new(lens: &'a Lens) -> Self {
        // Out to beyond the frame's corners.
        let r_max = 1.25 * lens.corner_radius().max(1.0);
        let per_r = (UNDISTORT_KNOTS - 3) as f64 / r_max;
        let k = (0..UNDISTORT_KNOTS)
            .map(|i| {
                let rd = i as f64 / per_r;
                if i == 0 {
                    1.0 / lens.model.slope(0.0)
                } else {
                    lens.model.undistort_radius(rd) / rd
                }
            })
            .collect();
        Undistort {
            lens,
            per_px: per_r / lens.norm_px,
            k,
        }
    }

    /// Undistorted position of photo position `p` (as [`Lens::undistort`]).
    #[inline(always)]
    fn undistort(&self, p: [f64; 2]) -> [f64; 2] {
        let l = self.lens;
        let (dx, dy) = (p[0] - l.cx, p[1] - l.cy);
        let kk = self.ratio_at((dx * dx + dy * dy).sqrt() * self.per_px, dx, dy);
        [l.cx + dx * kk, l.cy + dy * kk]
    }

    /// r_u / r_d at `u` knots out (the point dx, dy px from the centre).
    #[inline(always)]
    fn ratio_at(&self, u: f64, dx: f64, dy: f64) -> f64 {
        let i = (u as usize).max(1);
        let Some(k) = self.k.get(i - 1..i + 3) else {
            let l = self.lens;
            let rd = dx.hypot(dy) / l.norm_px;
            return if rd < 1e-300 {
                1.0
            } else {
                l.model.undistort_radius(rd) / rd
            };
        };
        // Lagrange cubic through knots i − 1 … i + 2.
        let t = u - i as f64;
        let (tm, t1, t2) = (t + 1.0, t - 1.0, t - 2.0);
        let (a, b) = (t * t1, tm * t2);
        (a * (tm * k[3] - t2 * k[0]) + 3.0 * b * (t1 * k[1] - t * k[2])) * (1.0 / 6.0)
    }
}

/// Up to TILE rows (`row_step` apart) × TILE samples of one plane inside
/// the outline (those at multiples of `col_step`), and the strip positions
/// its samples can have.
struct Tile {
    plane: usize,
    first: usize,
    row_step: usize,
    col_step: usize,
    /// Each row's [i0, i1) sample range.
    rows: Vec<(usize, usize)>,
    s_min: f64,
    s_max: f64,
}

/// The tiles of the samples inside `outline` (plus 1.5 px), each with its
/// s-range: s at the tile's corners, edge midpoints and centre, widened by
/// 5 % of that spread and two bins (over 64 px, s departs from the plane
/// through those points by far less: a lens is smooth and has no turning
/// point inside the frame).
fn tiles(
    planes: &[PlaneRef],
    outline: &[Point],
    map: &Map,
    bin: f64,
    (row_step, col_step): (usize, usize),
) -> Vec<Tile> {
    let (row_step, col_step) = (row_step.max(1), col_step.max(1));
    let ymin = outline.iter().map(|p| p[1]).fold(f64::INFINITY, f64::min) - 1.0;
    let ymax = outline
        .iter()
        .map(|p| p[1])
        .fold(f64::NEG_INFINITY, f64::max)
        + 1.0;
    let mut bands = Vec::new();
    for (p, plane) in planes.iter().enumerate() {
        let (ox, oy, sx, sy) = plane.centres();
        let j0 = ((ymin - oy) / sy).ceil().max(0.0) as usize;
        let j1 = (((ymax - oy) / sy).floor() + 1.0).clamp(0.0, plane.height as f64) as usize;
        // Rows at multiples of the step (the same lattice as the plain path's).
        let j0 = j0.next_multiple_of(row_step);
        let spans: Vec<(usize, usize)> = (j0..j1)
            .step_by(row_step)
            .map(|j| {
                let Some((xa, xb)) = super::row_span(outline, oy + j as f64 * sy) else {
                    return (0, 0);
                };
                let i0 = (((xa - 1.5 - ox) / sx).floor().max(0.0) as usize).min(plane.width);
                let i1 = (((xb + 1.5 - ox) / sx).ceil().max(0.0) as usize + 1).min(plane.width);
                (i0, i1.max(i0))
            })
            .collect();
        for (k, rows) in spans.chunks(TILE).enumerate() {
            bands.push((p, j0 + k * TILE * row_step, rows.to_vec()));
        }
    }
    bands
        .par_iter()
        .flat_map_iter(|(p, first, rows)| {
            let plane = planes[*p];
            let (ox, oy, sx, sy) = plane.centres();
            let lo = rows.iter().filter(|r| r.0 < r.1).map(|r| r.0).min();
            let hi = rows.iter().map(|r| r.1).max().unwrap_or(0);
            let lo = lo.unwrap_or(hi);
            (lo..hi).step_by(TILE).filter_map(move |c0| {
                let c1 = (c0 + TILE).min(hi);
                let rows: Vec<(usize, usize)> = rows
                    .iter()
                    .map(|&(i0, i1)| (i0.max(c0), i1.min(c1).max(i0.max(c0))))
                    .collect();
                if rows.iter().all(|r| r.0 >= r.1) {
                    return None;
                }
                let (xa, xb) = (ox + c0 as f64 * sx, ox + (c1 - 1) as f64 * sx);
                let (ya, yb) = (
                    oy + *first as f64 * sy,
                    oy + (first + (rows.len() - 1) * row_step) as f64 * sy,
                );
                let (mut s_min, mut s_max) = (f64::INFINITY, f64::NEG_INFINITY);
                for x in [xa, 0.5 * (xa + xb), xb] {
                    for y in [ya, 0.5 * (ya + yb), yb] {
                        let (s, _, w) = map.strip_of(x, y);
                        if !(w > 0.0 && s.is_finite()) {
                            // Near the homography's horizon: no bound, every run looks here.
                            (s_min, s_max) = (f64::NEG_INFINITY, f64::INFINITY);
                        }
                        s_min = s_min.min(s);
                        s_max = s_max.max(s);
                    }
                }
                let pad = 0.05 * (s_max - s_min) + 2.0 * bin;
                Some(Tile {
                    plane: *p,
                    first: *first,
                    row_step,
                    col_step,
                    rows,
                    s_min: s_min - pad,
                    s_max: s_max + pad,
                })
            })
        })
        .collect()
}

/// The outline in the photo of the strip's part between t0 and t1, densely
/// sampled (under a lens its edges are curves): a closed polygon, image px.
pub(crate) fn photo_outline(strip: &Strip, t0: f64, t1: f64) -> Vec<Point> {
    let l = strip.length;
    let mut outline = Vec::new();
    let n_long = 128;
    for i in 0..n_long {
        outline.push(strip.to_photo([l * i as f64 / n_long as f64, t0]));
    }
    for i in 0..8 {
        outline.push(strip.to_photo([l, t0 + (t1 - t0) * i as f64 / 8.0]));
    }
    for i in 0..n_long {
        outline.push(strip.to_photo([l * (1.0 - i as f64 / n_long as f64), t1]));
    }
    for i in 0..8 {
        outline.push(strip.to_photo([0.0, t1 - (t1 - t0) * i as f64 / 8.0]));
    }
    outline
}
