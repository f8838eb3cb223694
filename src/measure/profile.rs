//! The sweep profile: every sample centre of a strip, mapped through the
//! homography to the strip's own coordinate `s` (along the sweep) and binned
//! in sub-pixel bins, with a robust (3σ-clipped) mean per bin. No image
//! resampling: each bin's value is an average of real samples, and each bin
//! also records the mean and variance of its samples' `s` so the estimators
//! can work at the true sample positions and correct the tiny box blur of
//! binning exactly.

#![allow(clippy::needless_range_loop, clippy::neg_cmp_op_on_partial_ord)]

use crate::distortion::Lens;
use crate::geometry::{Homography, Point};
use crate::photo::Plane;
use rayon::prelude::*;

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

    /// How far (px) the photo's outline of region t ∈ [t0, t1] bows out of
    /// [`Strip::image_quad`] (0 without distortion).
    pub fn bow_px(&self, t0: f64, t1: f64) -> f64 {
        if self.lens.is_none() {
            return 0.0;
        }
        let q = self.image_quad(t0, t1);
        let l = self.length;
        let edges = [
            ([0.0, t0], [l, t0], 0),
            ([l, t0], [l, t1], 1),
            ([l, t1], [0.0, t1], 2),
            ([0.0, t1], [0.0, t0], 3),
        ];
        let mut worst = 0.0f64;
        for (a, b, k) in edges {
            let (p0, p1) = (q[k], q[(k + 1) % 4]);
            let len = (p1[0] - p0[0]).hypot(p1[1] - p0[1]).max(1e-9);
            for i in 1..32 {
                let u = i as f64 / 32.0;
                let p = self.to_photo([a[0] + u * (b[0] - a[0]), a[1] + u * (b[1] - a[1])]);
                let d = ((p1[0] - p0[0]) * (p[1] - p0[1]) - (p1[1] - p0[1]) * (p[0] - p0[0])) / len;
                worst = worst.max(d.abs());
            }
        }
        worst
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

/// How the strip is binned.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct BinOptions {
    /// Bin width in image pixels (at the strip's most magnified end).
    pub bin_px: f64,
    /// Fraction of the strip width left out along each long edge (0–0.45).
    pub margin: f64,
    /// Pixels left out at each short end of the strip.
    pub end_px: f64,
    /// Linear value at or above which a sample counts as clipped.
    pub clip_level: f32,
}

impl Default for BinOptions {
    fn default() -> Self {
        BinOptions {
            bin_px: 0.25,
            margin: 0.15,
            end_px: 1.0,
            clip_level: 0.999,
        }
    }
}

/// A binned profile along a strip (only non-empty bins, in increasing `s`).
#[derive(Debug, Clone, Default)]
pub struct Profile {
    /// Mean `s` of each bin's samples (strip units).
    pub s: Vec<f64>,
    /// Robust mean linear value of each bin.
    pub y: Vec<f64>,
    /// Samples averaged in each bin.
    pub count: Vec<f64>,
    /// Variance of the samples' `s` within each bin (strip units²).
    pub var_s: Vec<f64>,
    /// Bin width (strip units).
    pub bin: f64,
    /// Strip length (strip units).
    pub length: f64,
    /// Samples that fell inside the region.
    pub samples: usize,
    /// Samples at or above the clipping level.
    pub clipped_high: usize,
    /// Samples at or below zero (black clipping).
    pub clipped_low: usize,
}

impl Profile {
    /// Fraction of the region's samples that are clipped (white or black).
    pub fn clipped_fraction(&self) -> f64 {
        if self.samples == 0 {
            0.0
        } else {
            (self.clipped_high + self.clipped_low) as f64 / self.samples as f64
        }
    }
}

/// Bins one plane along a strip. Returns an empty profile when no sample falls inside.
pub fn bin_plane(plane: &Plane, strip: &Strip, opts: &BinOptions) -> Profile {
    bin_planes(&[plane], strip, opts)
}

/// Bins several planes of one colour (e.g. the two green sites of a Bayer
/// mosaic) together along a strip.
pub fn bin_planes(planes: &[&Plane], strip: &Strip, opts: &BinOptions) -> Profile {
    let Some(inv) = strip.to_image.inverse() else {
        return Profile::default();
    };
    let margin = opts.margin.clamp(0.0, 0.45);
    let (t0, t1) = (margin * strip.width, (1.0 - margin) * strip.width);
    let max_px_per_s = [0.0, 0.5, 1.0]
        .iter()
        .map(|f| 1.0 / strip.scale_at(f * strip.length).s_per_px)
        .fold(0.0, f64::max);
    let bin = opts.bin_px / max_px_per_s;
    let end = opts.end_px / max_px_per_s;
    let (s_lo, s_hi) = (end, strip.length - end);
    if !(bin > 0.0 && bin.is_finite() && s_hi > s_lo) {
        return Profile::default();
    }
    let nbins = ((strip.length / bin).ceil() as usize).max(1);
    if let Some(lens) = &strip.lens {
        let mut prof = bin_through_lens(
            planes,
            strip,
            lens,
            inv.m,
            (t0, t1, s_lo, s_hi),
            bin,
            nbins,
            opts.clip_level,
        );
        prof.bin = bin;
        prof.length = strip.length;
        return prof;
    }
    let quad = strip.image_quad(t0, t1);
    let ymin = quad.iter().map(|p| p[1]).fold(f64::INFINITY, f64::min);
    let ymax = quad.iter().map(|p| p[1]).fold(f64::NEG_INFINITY, f64::max);
    // Scale the inverse homography so its denominator is positive over the
    // region (a homography is defined up to scale, sign included).
    let mut m = inv.m;
    let c = strip
        .to_image
        .apply([0.5 * strip.length, 0.5 * strip.width]);
    if m[6] * c[0] + m[7] * c[1] + m[8] < 0.0 {
        m.iter_mut().for_each(|v| *v = -*v);
    }
    let region = Region {
        planes,
        m,
        ymin,
        ymax,
        t0,
        t1,
        s_lo,
        s_hi,
        bin,
        nbins,
    };
    let mut prof = Profile {
        bin,
        length: strip.length,
        ..Profile::default()
    };
    // First pass in parallel, split along the sweep into PASS_CHUNKS runs of
    // bins: each piece owns its bins (no merging, and the same split on any
    // machine, so results do not depend on threads). A piece visits the
    // region narrowed to its s-range (plus a hair, so no sample at a boundary
    // is lost to rounding) and keeps only the samples of its own bins.
    let b_first = ((s_lo / bin) as usize).min(nbins - 1);
    let b_end = ((s_hi / bin) as usize + 1).min(nbins);
    let runs: Vec<(usize, usize)> = (0..PASS_CHUNKS)
        .map(|k| {
            let n = b_end - b_first;
            (
                b_first + n * k / PASS_CHUNKS,
                b_first + n * (k + 1) / PASS_CHUNKS,
            )
        })
        .filter(|(b0, b1)| b1 > b0)
        .collect();
    let hair = 1e-6 * bin;
    let parts: Vec<(Vec<BinAcc>, [usize; 3])> = runs
        .par_iter()
        .map(|&(b0, b1)| {
            let piece = Region {
                s_lo: s_lo.max(b0 as f64 * bin - hair),
                s_hi: s_hi.min(b1 as f64 * bin + hair),
                ..region
            };
            let mut acc = vec![BinAcc::default(); b1 - b0];
            let mut count = [0usize; 3];
            for band in piece.bands() {
                piece.visit_band(&band, |b, s, v| {
                    if b >= b0 && b < b1 {
                        count[0] += 1;
                        count[1] += (v >= opts.clip_level) as usize;
                        count[2] += (v <= 0.0) as usize;
                        acc[b - b0].add(s, v);
                    }
                });
            }
            (acc, count)
        })
        .collect();
    let mut acc = vec![BinAcc::default(); b_first];
    let mut count = [0usize; 3];
    for (part, c) in parts {
        acc.extend(part);
        count.iter_mut().zip(c).for_each(|(x, y)| *x += y);
    }
    acc.resize(nbins, BinAcc::default());
    prof.samples = count[0];
    prof.clipped_high = count[1];
    prof.clipped_low = count[2];
    // Robust mean: drop samples more than 3σ (and more than a small floor)
    // from the bin mean. Each bin kept its EXTREMES most extreme samples on
    // either side, so the clipped sums need no second visit unless a bin has
    // that many outliers on one side (dust, a speck): only such bins are
    // visited again.
    let mut revisit = Vec::new();
    for (b, a) in acc.iter_mut().enumerate() {
        if a.n < 4 {
            continue;
        }
        let c = a.n as f64;
        let mu = a.sum / c;
        let lim = 3.0 * (a.sum2 / c - mu * mu).max(0.0).sqrt() + 1e-6;
        let out_hi = a.hi.iter().filter(|&&v| v as f64 - mu > lim).count();
        let out_lo = a.lo.iter().filter(|&&v| mu - v as f64 > lim).count();
        if out_hi == EXTREMES || out_lo == EXTREMES {
            revisit.push((b, mu, lim));
            continue;
        }
        a.rsum = a.sum;
        a.rn = a.n;
        for &v in a.hi[..out_hi].iter().chain(&a.lo[..out_lo]) {
            a.rsum -= v as f64;
            a.rn -= 1;
        }
    }
    if !revisit.is_empty() {
        let mut keep = vec![None; nbins];
        for &(b, mu, lim) in &revisit {
            keep[b] = Some((mu, lim));
        }
        let mut add = |b: usize, _: f64, v: f32| {
            if let Some((mu, lim)) = keep[b]
                && (v as f64 - mu).abs() <= lim
            {
                acc[b].rsum += v as f64;
                acc[b].rn += 1;
            }
        };
        // A few bins: look only around them; many (a dirty chart): one more full visit.
        if revisit.len() <= nbins / 32 {
            let bins: Vec<usize> = revisit.iter().map(|r| r.0).collect();
            region.visit_bins(&bins, &mut add);
        } else {
            region.visit(&mut add);
        }
    }
    for a in &acc {
        if a.n == 0 {
            continue;
        }
        let c = a.n as f64;
        let ms = a.ssum / c;
        prof.s.push(ms);
        prof.var_s.push((a.ssum2 / c - ms * ms).max(0.0));
        if a.n >= 4 && a.rn > 0 {
            prof.y.push(a.rsum / a.rn as f64);
            prof.count.push(a.rn as f64);
        } else {
            prof.y.push(a.sum / c);
            prof.count.push(c);
        }
    }
    prof
}

/// Binning through a lens model (the photo's iso-phase lines are curves):
/// every sample centre inside the region's photo outline is undistorted, then
/// mapped by the inverse homography `inv` to (s, t); bins take the plain
/// two-pass robust mean (3σ about the bin's mean, as the fast path). The rows
/// are read in parallel, the bins filled in row order (results do not depend
/// on threads).
#[allow(clippy::too_many_arguments)]
fn bin_through_lens(
    planes: &[&Plane],
    strip: &Strip,
    lens: &Lens,
    inv: [f64; 9],
    (t0, t1, s_lo, s_hi): (f64, f64, f64, f64),
    bin: f64,
    nbins: usize,
    clip_level: f32,
) -> Profile {
    let mut m = inv;
    let c = strip
        .to_image
        .apply([0.5 * strip.length, 0.5 * strip.width]);
    if m[6] * c[0] + m[7] * c[1] + m[8] < 0.0 {
        m.iter_mut().for_each(|v| *v = -*v);
    }
    // The region's outline in the photo, densely sampled (its edges are curves).
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
    let ymin = outline.iter().map(|p| p[1]).fold(f64::INFINITY, f64::min) - 1.0;
    let ymax = outline
        .iter()
        .map(|p| p[1])
        .fold(f64::NEG_INFINITY, f64::max)
        + 1.0;
    let last = nbins - 1;
    let inv_bin = 1.0 / bin;
    // (bin, s, value) of every sample inside, row by row.
    let mut rows: Vec<(usize, usize)> = Vec::new();
    for (p, plane) in planes.iter().enumerate() {
        let oy = plane.offset.1 as f64 + 0.5;
        let sy = plane.step.1 as f64;
        let j0 = ((ymin - oy) / sy).ceil().max(0.0) as usize;
        let j1 = (((ymax - oy) / sy).floor() + 1.0).clamp(0.0, plane.height as f64) as usize;
        rows.extend((j0..j1).map(|j| (p, j)));
    }
    let samples: Vec<Vec<(u32, f64, f32)>> = rows
        .par_iter()
        .map(|&(p, j)| {
            let plane = planes[p];
            let (sx, sy) = (plane.step.0 as f64, plane.step.1 as f64);
            let (ox, oy) = (plane.offset.0 as f64 + 0.5, plane.offset.1 as f64 + 0.5);
            let y = oy + j as f64 * sy;
            let mut out = Vec::new();
            let Some((xa, xb)) = outline_span(&outline, y) else {
                return out;
            };
            let i0 = (((xa - 1.5 - ox) / sx).floor().max(0.0) as usize).min(plane.width);
            let i1 = (((xb + 1.5 - ox) / sx).ceil().max(0.0) as usize + 1).min(plane.width);
            let row = &plane.data[j * plane.width..(j + 1) * plane.width];
            for i in i0..i1 {
                let x = ox + i as f64 * sx;
                let [xu, yu] = lens.undistort([x, y]);
                let w = m[6] * xu + m[7] * yu + m[8];
                if !(w > 0.0) {
                    continue;
                }
                let s = (m[0] * xu + m[1] * yu + m[2]) / w;
                let t = (m[3] * xu + m[4] * yu + m[5]) / w;
                if t >= t0 && t <= t1 && s >= s_lo && s <= s_hi {
                    out.push((((s * inv_bin) as usize).min(last) as u32, s, row[i]));
                }
            }
            out
        })
        .collect();
    #[derive(Clone, Copy, Default)]
    struct Sums {
        n: u32,
        sum: f64,
        sum2: f64,
        ssum: f64,
        ssum2: f64,
        rsum: f64,
        rn: u32,
    }
    let mut acc = vec![Sums::default(); nbins];
    let mut prof = Profile::default();
    for &(b, s, v) in samples.iter().flatten() {
        let a = &mut acc[b as usize];
        let vd = v as f64;
        a.n += 1;
        a.sum += vd;
        a.sum2 += vd * vd;
        a.ssum += s;
        a.ssum2 += s * s;
        prof.samples += 1;
        prof.clipped_high += (v >= clip_level) as usize;
        prof.clipped_low += (v <= 0.0) as usize;
    }
    let lims: Vec<(f64, f64)> = acc
        .iter()
        .map(|a| {
            let c = a.n.max(1) as f64;
            let mu = a.sum / c;
            (mu, 3.0 * (a.sum2 / c - mu * mu).max(0.0).sqrt() + 1e-6)
        })
        .collect();
    for &(b, _, v) in samples.iter().flatten() {
        let (mu, lim) = lims[b as usize];
        if (v as f64 - mu).abs() <= lim {
            acc[b as usize].rsum += v as f64;
            acc[b as usize].rn += 1;
        }
    }
    for a in &acc {
        if a.n == 0 {
            continue;
        }
        let c = a.n as f64;
        let ms = a.ssum / c;
        prof.s.push(ms);
        prof.var_s.push((a.ssum2 / c - ms * ms).max(0.0));
        if a.n >= 4 && a.rn > 0 {
            prof.y.push(a.rsum / a.rn as f64);
            prof.count.push(a.rn as f64);
        } else {
            prof.y.push(a.sum / c);
            prof.count.push(c);
        }
    }
    prof
}

/// The x-extent where the horizontal line at `y` crosses a closed polygon.
fn outline_span(poly: &[Point], y: f64) -> Option<(f64, f64)> {
    let (mut lo, mut hi) = (f64::INFINITY, f64::NEG_INFINITY);
    for k in 0..poly.len() {
        let (a, b) = (poly[k], poly[(k + 1) % poly.len()]);
        if (a[1] <= y && b[1] >= y) || (b[1] <= y && a[1] >= y) {
            let x = if (b[1] - a[1]).abs() < 1e-12 {
                lo = lo.min(a[0].min(b[0]));
                hi = hi.max(a[0].max(b[0]));
                continue;
            } else {
                a[0] + (b[0] - a[0]) * (y - a[1]) / (b[1] - a[1])
            };
            lo = lo.min(x);
            hi = hi.max(x);
        }
    }
    (lo <= hi).then_some((lo, hi))
}

/// How many of the most extreme samples each bin keeps on either side.
///
/// A bin whose kept extremes are all outliers is visited again (scattered
/// reads down the columns of its samples). With 3, a 24 MP raw's green
/// strip (350 samples a bin, ≈ 0.47 beyond 3σ on a side by chance) sent 65
/// of 16 000 bins back and binning took 12.7 ms; with 6 (chance ≈ 1e-5 a
/// bin) none, 8.5 ms, even though every sample then passes a longer network.
const EXTREMES: usize = 6;

/// How many runs of bins the first binning pass is split into (run in parallel).
const PASS_CHUNKS: usize = 8;

/// One bin's running sums, and its most extreme samples for the robust mean.
#[derive(Clone, Copy)]
struct BinAcc {
    sum: f64,
    sum2: f64,
    ssum: f64,
    ssum2: f64,
    rsum: f64,
    n: u32,
    rn: u32,
    /// The largest samples, descending (−∞ while unfilled).
    hi: [f32; EXTREMES],
    /// The smallest samples, ascending (+∞ while unfilled).
    lo: [f32; EXTREMES],
}

impl Default for BinAcc {
    fn default() -> Self {
        BinAcc {
            sum: 0.0,
            sum2: 0.0,
            ssum: 0.0,
            ssum2: 0.0,
            rsum: 0.0,
            n: 0,
            rn: 0,
            hi: [f32::NEG_INFINITY; EXTREMES],
            lo: [f32::INFINITY; EXTREMES],
        }
    }
}

/// The larger of two values, as one `maxss` (no NaN reaches here).
#[inline(always)]
fn fmax(a: f32, b: f32) -> f32 {
    if a > b { a } else { b }
}

/// The smaller of two values, as one `minss`.
#[inline(always)]
fn fmin(a: f32, b: f32) -> f32 {
    if a < b { a } else { b }
}

impl BinAcc {
    /// Adds a sample at position `s` with value `v` (branch-free insertion
    /// into the sorted extremes).
    #[inline(always)]
    fn add(&mut self, s: f64, v: f32) {
        let vd = v as f64;
        self.sum += vd;
        self.sum2 += vd * vd;
        self.ssum += s;
        self.ssum2 += s * s;
        self.n += 1;
        let (h, l) = (&mut self.hi, &mut self.lo);
        for k in (1..EXTREMES).rev() {
            h[k] = fmax(h[k], fmin(h[k - 1], v));
            l[k] = fmin(l[k], fmax(l[k - 1], v));
        }
        h[0] = fmax(h[0], v);
        l[0] = fmin(l[0], v);
    }
}

/// The sampled region of a strip, for visiting its samples.
#[derive(Clone, Copy)]
struct Region<'a> {
    planes: &'a [&'a Plane],
    /// Image → strip homography, scaled so its denominator is positive in the region.
    m: [f64; 9],
    ymin: f64,
    ymax: f64,
    t0: f64,
    t1: f64,
    s_lo: f64,
    s_hi: f64,
    bin: f64,
    nbins: usize,
}

impl Region<'_> {
    /// Whether the sample centre (x, y) lies inside the region; its s if so.
    #[inline]
    fn inside(&self, x: f64, y: f64) -> Option<f64> {
        let m = &self.m;
        let rw = 1.0 / (m[6] * x + m[7] * y + m[8]);
        let s = (m[0] * x + m[1] * y + m[2]) * rw;
        let t = (m[3] * x + m[4] * y + m[5]) * rw;
        (t >= self.t0 && t <= self.t1 && s >= self.s_lo && s <= self.s_hi).then_some(s)
    }

    /// Sample indices [i0, i1) of a row at height y (sample x = ox + i·sx)
    /// inside the region. Along a row each bound is a linear inequality in x.
    fn row_range(&self, y: f64, ox: f64, sx: f64, width: usize) -> (usize, usize) {
        let m = &self.m;
        let (ns, nt, w) = (m[1] * y + m[2], m[4] * y + m[5], m[7] * y + m[8]);
        // a·x + b ≥ 0 for each bound.
        let bounds = [
            (m[3] - self.t0 * m[6], nt - self.t0 * w),
            (self.t1 * m[6] - m[3], self.t1 * w - nt),
            (m[0] - self.s_lo * m[6], ns - self.s_lo * w),
            (self.s_hi * m[6] - m[0], self.s_hi * w - ns),
            // The denominator itself stays positive.
            (m[6], w),
        ];
        let (mut lo, mut hi) = (f64::NEG_INFINITY, f64::INFINITY);
        for (a, b) in bounds {
            if a > 0.0 {
                lo = lo.max(-b / a);
            } else if a < 0.0 {
                hi = hi.min(-b / a);
            } else if b < 0.0 {
                return (0, 0);
            }
        }
        if !(lo <= hi) {
            return (0, 0);
        }
        let idx = |x: f64| ((x - ox) / sx).clamp(-1.0, width as f64 + 1.0);
        let mut i0 = idx(lo).ceil() as i64;
        let mut i1 = idx(hi).floor() as i64 + 1;
        i0 = i0.clamp(0, width as i64);
        i1 = i1.clamp(i0, width as i64);
        // Make the ends agree exactly with the per-sample test.
        let at = |i: i64| self.inside(ox + i as f64 * sx, y).is_some();
        while i0 < i1 && !at(i0) {
            i0 += 1;
        }
        while i1 > i0 && !at(i1 - 1) {
            i1 -= 1;
        }
        while i0 > 0 && at(i0 - 1) {
            i0 -= 1;
        }
        while i1 < width as i64 && i1 > i0 && at(i1) {
            i1 += 1;
        }
        (i0 as usize, i1 as usize)
    }

    /// Calls f(bin, s, value) for every sample inside the region that falls
    /// in one of `bins` (sorted, few): on each row only the samples around
    /// those bins' ends are looked at.
    fn visit_bins<F: FnMut(usize, f64, f32)>(&self, bins: &[usize], mut f: F) {
        let m = &self.m;
        let inv_bin = 1.0 / self.bin;
        let last = self.nbins - 1;
        for band in self.bands() {
            let plane = self.planes[band.plane];
            let (sx, sy) = (plane.step.0 as f64, plane.step.1 as f64);
            let (ox, oy) = (plane.offset.0 as f64 + 0.5, plane.offset.1 as f64 + 0.5);
            for (dj, &(i0, i1)) in band.rows.iter().enumerate() {
                if i0 >= i1 {
                    continue;
                }
                let j = band.first + dj;
                let y = oy + j as f64 * sy;
                let (ns0, w0) = (m[1] * y + m[2], m[7] * y + m[8]);
                let s_of = |i: usize| {
                    let x = ox + i as f64 * sx;
                    (m[0] * x + ns0) / (m[6] * x + w0)
                };
                let bin_of = |s: f64| ((s * inv_bin) as usize).min(last);
                let (sa, sb) = (s_of(i0), s_of(i1 - 1));
                let (ba, bb) = (bin_of(sa.min(sb)), bin_of(sa.max(sb)));
                let from = bins.partition_point(|&b| b < ba);
                for &b in bins[from..].iter().take_while(|&&b| b <= bb) {
                    // x where s crosses the bin's ends (s is a Möbius function of x).
                    let x_at = |s: f64| (s * w0 - ns0) / (m[0] - s * m[6]);
                    let (xa, xb) = (x_at(b as f64 * self.bin), x_at((b + 1) as f64 * self.bin));
                    let (xa, xb) = (xa.min(xb), xa.max(xb));
                    let ia = (((xa - ox) / sx).floor() - 1.0).max(i0 as f64) as usize;
                    let ib = (((xb - ox) / sx).ceil() + 2.0).min(i1 as f64) as usize;
                    let row = &plane.data[j * plane.width..(j + 1) * plane.width];
                    for i in ia.max(i0)..ib.min(i1) {
                        let s = s_of(i);
                        if bin_of(s) == b {
                            f(b, s, row[i]);
                        }
                    }
                }
            }
        }
    }

    /// The region's sample rows in bands of TILE rows, with each row's sample range.
    fn bands(&self) -> Vec<Band> {
        let mut out = Vec::new();
        for (p, plane) in self.planes.iter().enumerate() {
            let (sx, sy) = (plane.step.0 as f64, plane.step.1 as f64);
            let (ox, oy) = (plane.offset.0 as f64 + 0.5, plane.offset.1 as f64 + 0.5);
            // Sample rows whose centres lie within the region's vertical extent.
            let j0 = ((self.ymin - oy) / sy).ceil().max(0.0) as usize;
            let j1 =
                (((self.ymax - oy) / sy).floor() + 1.0).clamp(0.0, plane.height as f64) as usize;
            let ranges: Vec<(usize, usize)> = (j0..j1)
                .map(|j| self.row_range(oy + j as f64 * sy, ox, sx, plane.width))
                .collect();
            for (k, rows) in ranges.chunks(TILE).enumerate() {
                if rows.iter().any(|r| r.0 < r.1) {
                    out.push(Band {
                        plane: p,
                        first: j0 + k * TILE,
                        rows: rows.to_vec(),
                    });
                }
            }
        }
        out
    }

    /// Calls f(bin, s, value) for every sample inside the region.
    fn visit<F: FnMut(usize, f64, f32)>(&self, mut f: F) {
        for band in self.bands() {
            self.visit_band(&band, &mut f);
        }
    }

    /// Calls f(bin, s, value) for every sample of one band, in blocks of
    /// TILE × TILE samples so that the bins a block touches stay in cache.
    #[inline]
    fn visit_band<F: FnMut(usize, f64, f32)>(&self, band: &Band, mut f: F) {
        let m = &self.m;
        let inv_bin = 1.0 / self.bin;
        let last = self.nbins - 1;
        let plane = self.planes[band.plane];
        let (sx, sy) = (plane.step.0 as f64, plane.step.1 as f64);
        let (ox, oy) = (plane.offset.0 as f64 + 0.5, plane.offset.1 as f64 + 0.5);
        let rows = &band.rows;
        let lo = rows.iter().filter(|r| r.0 < r.1).map(|r| r.0).min();
        let hi = rows.iter().map(|r| r.1).max().unwrap_or(0);
        let Some(lo) = lo else { return };
        for c0 in (lo..hi).step_by(TILE) {
            let c1 = (c0 + TILE).min(hi);
            for (dj, &(i0, i1)) in rows.iter().enumerate() {
                let (i0, i1) = (i0.max(c0), i1.min(c1));
                if i0 >= i1 {
                    continue;
                }
                let j = band.first + dj;
                let y = oy + j as f64 * sy;
                let row = &plane.data[j * plane.width + i0..j * plane.width + i1];
                // Along a row the homography's numerator and denominator are
                // linear in x. The positions are computed first, a run of at
                // most TILE at a time (a loop the compiler vectorises), then
                // the samples are handed out.
                let (ns0, w0) = (m[1] * y + m[2], m[7] * y + m[8]);
                let mut s_buf = [0.0f64; TILE];
                let s_run = &mut s_buf[..row.len()];
                for (k, s) in s_run.iter_mut().enumerate() {
                    let x = ox + (i0 + k) as f64 * sx;
                    *s = (m[0] * x + ns0) / (m[6] * x + w0);
                }
                for (&s, &v) in s_run.iter().zip(row) {
                    f(((s * inv_bin) as usize).min(last), s, v);
                }
            }
        }
    }
}

/// Rows and columns of a tile in [`Region::visit_band`].
const TILE: usize = 64;

/// Up to TILE consecutive sample rows of one plane, with each row's [i0, i1) range.
struct Band {
    plane: usize,
    first: usize,
    rows: Vec<(usize, usize)>,
}

/// The x-interval where the horizontal line at `y` crosses a convex quadrilateral.
pub fn row_span(q: &[Point; 4], y: f64) -> Option<(f64, f64)> {
    let mut lo = f64::INFINITY;
    let mut hi = f64::NEG_INFINITY;
    for k in 0..4 {
        let (a, b) = (q[k], q[(k + 1) % 4]);
        let (ya, yb) = (a[1].min(b[1]), a[1].max(b[1]));
        if y < ya || y > yb {
            continue;
        }
        if (b[1] - a[1]).abs() < 1e-12 {
            lo = lo.min(a[0].min(b[0]));
            hi = hi.max(a[0].max(b[0]));
        } else {
            let x = a[0] + (b[0] - a[0]) * (y - a[1]) / (b[1] - a[1]);
            lo = lo.min(x);
            hi = hi.max(x);
        }
    }
    (lo <= hi).then_some((lo, hi))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn strip_for(quad: [Point; 4], len: f64, wid: f64) -> Strip {
        let src = crate::geometry::rect_corners(0.0, 0.0, len, wid);
        Strip {
            lens: None,
            to_image: Homography::from_quads(&src, &quad).unwrap(),
            length: len,
            width: wid,
        }
    }

    #[test]
    fn bins_a_linear_ramp_exactly_under_rotation() {
        // Image value = 0.001·s for a strip rotated by 30°: every bin mean must
        // equal 0.001 × the bin's mean s (brute force: linear data, no blur).
        let (w, h) = (300, 200);
        let a = 30f64.to_radians();
        let (c, sn) = (a.cos(), a.sin());
        let o = [40.0, 30.0];
        let len = 200.0;
        let wid = 40.0;
        let quad = [
            o,
            [o[0] + len * c, o[1] + len * sn],
            [o[0] + len * c - wid * sn, o[1] + len * sn + wid * c],
            [o[0] - wid * sn, o[1] + wid * c],
        ];
        let strip = strip_for(quad, len, wid);
        let mut data = vec![0f32; w * h];
        for j in 0..h {
            for i in 0..w {
                let (x, y) = (i as f64 + 0.5 - o[0], j as f64 + 0.5 - o[1]);
                data[j * w + i] = (0.001 * (x * c + y * sn)) as f32;
            }
        }
        let plane = Plane::full(w, h, data);
        let p = bin_plane(&plane, &strip, &BinOptions::default());
        assert!(p.s.len() > 600, "{}", p.s.len());
        for k in 0..p.s.len() {
            assert!((p.y[k] - 0.001 * p.s[k]).abs() < 1e-6, "{k}");
            assert!(p.var_s[k].sqrt() <= p.bin);
        }
        // Samples inside: 70% of the strip area (margins 15% + 15%) minus the end pixels.
        let area = len * wid * 0.7;
        assert!(
            (p.samples as f64 - area).abs() < 0.03 * area,
            "{}",
            p.samples
        );
        let sc = strip.scale_at(100.0);
        assert!((sc.s_per_px - 1.0).abs() < 1e-9);
        assert!((sc.angle_rad - a).abs() < 1e-9);
    }

    #[test]
    fn sparse_plane_uses_its_own_sites() {
        // A Bayer-like plane with step 2 and offset (1, 0): site x = 2i + 1.5.
        let plane = Plane {
            width: 50,
            height: 20,
            step: (2, 2),
            offset: (1, 0),
            data: (0..1000).map(|k| (2 * (k % 50) + 1) as f32 + 0.5).collect(),
        };
        let strip = strip_for(
            crate::geometry::rect_corners(0.0, 0.0, 100.0, 40.0),
            100.0,
            40.0,
        );
        let p = bin_plane(&plane, &strip, &BinOptions::default());
        for k in 0..p.s.len() {
            assert!((p.y[k] - p.s[k]).abs() < 1e-9);
        }
    }

    /// The plain definition: every sample centre through the inverse
    /// homography, two passes, 3σ clip about each bin's plain mean.
    fn brute(plane: &Plane, strip: &Strip, o: &BinOptions) -> Vec<(f64, f64, f64)> {
        let inv = strip.to_image.inverse().unwrap();
        let m = o.margin;
        let scale = [0.0, 0.5, 1.0]
            .iter()
            .map(|f| 1.0 / strip.scale_at(f * strip.length).s_per_px)
            .fold(0.0, f64::max);
        let (bin, end) = (o.bin_px / scale, o.end_px / scale);
        let nb = (strip.length / bin).ceil() as usize;
        let mut by_bin: Vec<Vec<(f64, f64)>> = vec![Vec::new(); nb];
        for j in 0..plane.height {
            for i in 0..plane.width {
                let x = (plane.offset.0 + i * plane.step.0) as f64 + 0.5;
                let y = (plane.offset.1 + j * plane.step.1) as f64 + 0.5;
                let [s, t] = inv.apply([x, y]);
                if t >= m * strip.width
                    && t <= (1.0 - m) * strip.width
                    && s >= end
                    && s <= strip.length - end
                {
                    let b = ((s / bin) as usize).min(nb - 1);
                    by_bin[b].push((s, plane.data[j * plane.width + i] as f64));
                }
            }
        }
        by_bin
            .iter()
            .filter(|v| !v.is_empty())
            .map(|v| {
                let n = v.len() as f64;
                let ms = v.iter().map(|p| p.0).sum::<f64>() / n;
                let mu = v.iter().map(|p| p.1).sum::<f64>() / n;
                let var = v.iter().map(|p| (p.1 - mu).powi(2)).sum::<f64>() / n;
                let lim = 3.0 * var.sqrt() + 1e-6;
                let kept: Vec<f64> = v
                    .iter()
                    .map(|p| p.1)
                    .filter(|y| v.len() < 4 || (y - mu).abs() <= lim)
                    .collect();
                (
                    ms,
                    kept.iter().sum::<f64>() / kept.len() as f64,
                    kept.len() as f64,
                )
            })
            .collect()
    }

    #[test]
    fn robust_bins_equal_the_plain_two_pass_definition() {
        // Perspective, a sparse (Bayer-like) lattice, noise with heavy tails and
        // dust specks that put many outliers into single bins.
        let (w, h) = (180, 140);
        let quad = [[20.0, 30.0], [330.0, 12.0], [345.0, 250.0], [12.0, 200.0]];
        let strip = strip_for(quad, 300.0, 60.0);
        let mut st = 12345u64;
        let mut rnd = || {
            st = st
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            (st >> 11) as f64 / (1u64 << 53) as f64
        };
        let mut data = vec![0f32; w * h];
        for j in 0..h {
            for i in 0..w {
                let (x, y) = ((2 * i + 1) as f64 + 0.5, (2 * j) as f64 + 0.5);
                let mut v = 0.5 + 0.3 * (0.05 * x + 0.01 * y).sin() + 0.02 * (rnd() - 0.5);
                if rnd() < 0.01 {
                    v += 0.4 * (rnd() - 0.3); // heavy tail
                }
                if (x - 150.0).hypot(y - 120.0) < 9.0 || (x - 260.0).hypot(y - 60.0) < 4.0 {
                    v = 0.02; // dust
                }
                data[j * w + i] = v as f32;
            }
        }
        let plane = Plane {
            width: w,
            height: h,
            step: (2, 2),
            offset: (1, 0),
            data,
        };
        for bin_px in [0.25, 1.0, 3.0] {
            let o = BinOptions {
                bin_px,
                ..BinOptions::default()
            };
            let p = bin_plane(&plane, &strip, &o);
            let want = brute(&plane, &strip, &o);
            assert_eq!(p.s.len(), want.len(), "bin {bin_px}");
            for k in 0..want.len() {
                assert!((p.s[k] - want[k].0).abs() < 1e-9, "{bin_px} {k}");
                assert!(
                    (p.y[k] - want[k].1).abs() < 1e-9,
                    "{bin_px} {k}: {} vs {}",
                    p.y[k],
                    want[k].1
                );
                assert_eq!(p.count[k], want[k].2, "{bin_px} {k}");
            }
        }
    }
}
