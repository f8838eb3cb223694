//! The sweep profile: every sample centre of a strip, mapped through the
//! homography to the strip's own coordinate `s` (along the sweep) and binned
//! in sub-pixel bins, with a robust (3σ-clipped) mean per bin. No image
//! resampling: each bin's value is an average of real samples, and each bin
//! also records the mean and variance of its samples' `s` so the estimators
//! can work at the true sample positions and correct the tiny box blur of
//! binning exactly.

#![allow(clippy::needless_range_loop, clippy::neg_cmp_op_on_partial_ord)]

mod acc;
mod lens;
mod region;

use crate::distortion::Lens;
use crate::geometry::{Homography, Point};
use crate::photo::{Plane, PlaneRef};
use acc::BinAcc;
pub(crate) use lens::photo_outline;
use rayon::prelude::*;
use region::Region;
pub use region::row_span;

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
    /// Whether each bin holds a clipped sample (at the clip level or at or
    /// below zero); empty when no sample of the profile is clipped.
    pub clipped: Vec<bool>,
    /// Each bin's mean of the pixel-parity patterns (−1)^x, (−1)^y and
    /// (−1)^(x+y) over its samples (x, y the photo pixel), for a single plane
    /// of step 1, where a demosaicked colour filter array leaves aliases
    /// locked to the pixel grid (see `wants_parity`); empty otherwise.
    pub parity: Vec<[f64; 3]>,
}

impl Profile {
    /// The indices of the bins whose `s` lies in [a, b) (strip units).
    pub fn bins_within(&self, a: f64, b: f64) -> std::ops::Range<usize> {
        let lo = self.s.partition_point(|&s| s < a);
        lo..self.s.partition_point(|&s| s < b).max(lo)
    }

    /// The mean of `g(value)` over the bins with `s` in [a, b); None when none.
    pub fn mean_within(&self, a: f64, b: f64, g: impl Fn(f64) -> f64) -> Option<f64> {
        let r = self.bins_within(a, b);
        (!r.is_empty())
            .then(|| self.y[r.clone()].iter().map(|&y| g(y)).sum::<f64>() / r.len() as f64)
    }

    /// Whether bin `k` holds a clipped sample: its mean is not the light's.
    pub fn is_clipped(&self, k: usize) -> bool {
        self.clipped.get(k).copied().unwrap_or(false)
    }

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
    bin_planes(&[plane.into()], strip, opts)
}

/// Bins several planes of one colour (e.g. the two green sites of a Bayer
/// mosaic) together along a strip.
pub fn bin_planes(planes: &[PlaneRef], strip: &Strip, opts: &BinOptions) -> Profile {
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
    if nbins > u32::MAX as usize {
        // Bins are numbered in 32 bits (and 2³² of them would not fit in memory).
        return Profile::default();
    }
    if let Some(lens) = &strip.lens {
        let mut prof = lens::bin_through_lens(
            planes,
            strip,
            lens,
            positive_inverse(strip, inv.m),
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
    let m = positive_inverse(strip, inv.m);
    let region = Region {
        by_columns: sweeps_across_columns(&m, &quad),
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
    // First pass in parallel, split along the sweep into runs of bins
    // ([`own_runs`]): each run fills its own slice of one vector of every
    // bin (made in parallel, so its pages fault in on both cores; nothing is
    // merged or copied into place). A run visits the region narrowed to its
    // s-range (plus a hair, so no sample at a boundary is lost to rounding)
    // and keeps only the samples of its own bins.
    let hair = 1e-6 * bin;
    let mut acc: Vec<BinAcc> = (0..nbins)
        .into_par_iter()
        .map(|_| BinAcc::default())
        .collect();
    let counts: Vec<[usize; 3]> = own_runs(&mut acc, s_lo, s_hi, bin)
        .into_par_iter()
        .map(|(b0, b1, acc)| {
            let piece = Region {
                s_lo: s_lo.max(b0 as f64 * bin - hair),
                s_hi: s_hi.min(b1 as f64 * bin + hair),
                ..region
            };
            first_pass(&piece, b0, acc, opts.clip_level)
        })
        .collect();
    let mut count = [0usize; 3];
    for c in counts {
        count.iter_mut().zip(c).for_each(|(x, y)| *x += y);
    }
    prof.samples = count[0];
    prof.clipped_high = count[1];
    prof.clipped_low = count[2];
    // Robust mean: drop samples more than 3σ (and more than a small floor)
    // from the bin mean, from each bin's kept extremes; only bins with that
    // many outliers on one side (dust, a speck) are visited again.
    let revisit = acc::robust_from_extremes(&mut acc);
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
    acc::finish(&acc, &mut prof, wants_parity(planes), opts.clip_level);
    prof
}

/// Whether a profile records its bins' pixel-parity patterns
/// ([`Profile::parity`]): a single plane of step 1, i.e. a photo whose every
/// pixel was made by demosaicking a 2×2 colour filter array (or could have
/// been). A demosaicked sine of frequency f holds, beside it, the sine times
/// (−1)^x, (−1)^y and (−1)^(x+y) (the CFA's aliases at f + ½ cy/px, locked to
/// the pixel grid). Where a strip runs along a pixel axis, each bin holds
/// pixels of one parity, the alias reaches the profile at ½ − f cy/px and a
/// window's sine fit near f = ¼ reads it as modulation (+8 % at 0.3 cy/px
/// on an MHC-demosaicked shot turned 0.4°). With each bin's mean patterns
/// the fit can model the aliases (`estimate::fit`). Raw planes (step 2) hold
/// one colour and need none.
fn wants_parity(planes: &[PlaneRef]) -> bool {
    planes.len() == 1 && planes[0].step == (1, 1)
}

/// +1 for an even pixel index, −1 for an odd one.
#[inline(always)]
fn parity_sign(i: usize) -> i64 {
    if i.is_multiple_of(2) { 1 } else { -1 }
}

/// The first binning pass over one run of bins (`acc`, from bin `b0` on):
/// every sample of `piece` in those bins added to its bin; returns the
/// (samples, clipped white, clipped black) counts. Compiled twice on x86-64,
/// for the baseline and for AVX2 (chosen when the CPU has it): the same
/// arithmetic in the same order, so the same sums bit for bit; the wider
/// vectors make the extremes' insertion a few instructions.
fn first_pass(piece: &Region, b0: usize, acc: &mut [BinAcc], clip_level: f32) -> [usize; 3] {
    #[cfg(target_arch = "x86_64")]
    if std::arch::is_x86_feature_detected!("avx2") {
        // SAFETY: the CPU has AVX2, checked just above.
        return unsafe { first_pass_avx2(piece, b0, acc, clip_level) };
    }
    first_pass_body::<false>(piece, b0, acc, clip_level)
}

/// [`first_pass_body`] compiled for AVX2.
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2")]
fn first_pass_avx2(piece: &Region, b0: usize, acc: &mut [BinAcc], clip_level: f32) -> [usize; 3] {
    first_pass_body::<true>(piece, b0, acc, clip_level)
}

/// What [`first_pass`] does (inlined into each of its compilations).
#[inline(always)]
fn first_pass_body<const AVX2: bool>(
    piece: &Region,
    b0: usize,
    acc: &mut [BinAcc],
    clip_level: f32,
) -> [usize; 3] {
    let mut pass = FirstPass::<AVX2> {
        b0,
        acc,
        clip_level,
        count: [0; 3],
    };
    for band in piece.bands() {
        piece.visit_band_lines(&band, &mut pass);
    }
    pass.count
}

/// The first pass's sink: one run of bins (from bin `b0` on) and its counts.
struct FirstPass<'a, const AVX2: bool> {
    b0: usize,
    acc: &'a mut [BinAcc],
    clip_level: f32,
    /// Samples, clipped white, clipped black.
    count: [usize; 3],
}

impl<const AVX2: bool> region::LineSink for FirstPass<'_, AVX2> {
    #[inline(always)]
    fn line(&mut self, b: &[u32], s: &[f64], v: &[f32], start: region::LineStart) {
        let clip = self.clip_level;
        let mut count = [v.len(), 0, 0];
        for &v in v {
            count[1] += (v >= clip) as usize;
            count[2] += (v <= 0.0) as usize;
        }
        let mut q = 0;
        while q < b.len() {
            match (b[q] as usize)
                .checked_sub(self.b0)
                .and_then(|k| self.acc.get_mut(k))
            {
                Some(a) => {
                    let e = a.add_while::<AVX2>(b, s, v, q);
                    a.add_parity_run(start, q, e);
                    q = e;
                }
                None => {
                    // Another run's bin: not counted here.
                    count[0] -= 1;
                    count[1] -= (v[q] >= clip) as usize;
                    count[2] -= (v[q] <= 0.0) as usize;
                    q += 1;
                }
            }
        }
        self.count.iter_mut().zip(count).for_each(|(c, k)| *c += k);
    }
}

/// The inverse homography `inv` (image → strip), scaled so its denominator
/// is positive over the strip (a homography is defined up to scale, sign
/// included).
fn positive_inverse(strip: &Strip, inv: [f64; 9]) -> [f64; 9] {
    let mut m = inv;
    let c = strip
        .to_image
        .apply([0.5 * strip.length, 0.5 * strip.width]);
    if m[6] * c[0] + m[7] * c[1] + m[8] < 0.0 {
        m.iter_mut().for_each(|v| *v = -*v);
    }
    m
}

/// Whether the strip position `s` (under the image → strip homography `m`)
/// changes faster along x than along y at the centre of `quad`.
fn sweeps_across_columns(m: &[f64; 9], quad: &[Point; 4]) -> bool {
    let x = quad.iter().map(|p| p[0]).sum::<f64>() / 4.0;
    let y = quad.iter().map(|p| p[1]).sum::<f64>() / 4.0;
    let num = m[0] * x + m[1] * y + m[2];
    let den = m[6] * x + m[7] * y + m[8];
    (m[0] * den - m[6] * num).abs() >= (m[1] * den - m[7] * num).abs()
}

/// How many runs of bins the first binning pass is split into (run in parallel).
const PASS_CHUNKS: usize = 8;

/// The bins of `acc` from the one holding `s_lo` to the one holding `s_hi`
/// (strip units; bins `bin` wide), split into [`PASS_CHUNKS`] runs: (first
/// bin, end bin, the run's own bins). The same split on any machine, so
/// results do not depend on threads.
fn own_runs(
    acc: &mut [BinAcc],
    s_lo: f64,
    s_hi: f64,
    bin: f64,
) -> Vec<(usize, usize, &mut [BinAcc])> {
    let nbins = acc.len();
    let b_first = ((s_lo / bin) as usize).min(nbins - 1);
    let b_end = ((s_hi / bin) as usize + 1).min(nbins);
    let mut rest = &mut acc[b_first..b_end];
    let mut runs = Vec::with_capacity(PASS_CHUNKS);
    let n = b_end - b_first;
    for k in 0..PASS_CHUNKS {
        let (b0, b1) = (
            b_first + n * k / PASS_CHUNKS,
            b_first + n * (k + 1) / PASS_CHUNKS,
        );
        let (own, tail) = std::mem::take(&mut rest).split_at_mut(b1 - b0);
        if b1 > b0 {
            runs.push((b0, b1, own));
        }
        rest = tail;
    }
    runs
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A deterministic uniform generator on [0, 1) from `seed`.
    fn uniform(mut st: u64) -> impl FnMut() -> f64 {
        move || {
            st = st
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            (st >> 11) as f64 / (1u64 << 53) as f64
        }
    }

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

    /// The first pass's bins as bits: sums, count and extremes.
    fn acc_bits(acc: &[BinAcc]) -> Vec<u64> {
        acc.iter()
            .flat_map(|a| {
                [a.sum, a.sum2, a.ssum, a.ssum2]
                    .map(f64::to_bits)
                    .into_iter()
                    .chain([a.n as u64])
                    .chain(a.hi.iter().chain(&a.lo).map(|v| v.to_bits() as u64))
            })
            .collect()
    }

    #[test]
    fn the_first_pass_equals_sample_by_sample_binning_in_either_walk_and_build() {
        // A turned, keystoned strip of 8-bit codes with noise, walked down the
        // columns and along the rows, in the baseline and (where the CPU has
        // it) the AVX2 build, against the plain per-sample reference: the
        // same counts and extremes; the sums in another order, so equal to
        // rounding.
        let (w, h) = (400, 300);
        let mut rnd = uniform(4242u64);
        let codes: Vec<u8> = (0..w * h)
            .map(|k| {
                let x = (k % w) as f64;
                (128.0 + 100.0 * (0.002 * x * x).sin() + 20.0 * (rnd() - 0.5)) as u8
            })
            .collect();
        let lut: Vec<f32> = (0..256).map(|c| (c as f32 / 255.0).powf(2.2)).collect();
        let mix = [(0usize, 1.0f32)];
        let plane = PlaneRef {
            width: w,
            height: h,
            step: (1, 1),
            offset: (0, 0),
            data: crate::photo::plane_ref::PlaneData::Codes8(crate::photo::plane_ref::Codes {
                codes: &codes,
                channels: 1,
                mix: &mix,
                lut: &lut,
            }),
        };
        let strip = strip_for(
            [[20.0, 40.0], [380.0, 60.0], [372.0, 260.0], [25.0, 230.0]],
            350.0,
            200.0,
        );
        let planes = [plane];
        let inv = positive_inverse(&strip, strip.to_image.inverse().unwrap().m);
        let quad = strip.image_quad(30.0, 170.0);
        assert!(sweeps_across_columns(&inv, &quad));
        let region = Region {
            planes: &planes,
            m: inv,
            ymin: quad.iter().map(|p| p[1]).fold(f64::INFINITY, f64::min),
            ymax: quad.iter().map(|p| p[1]).fold(f64::NEG_INFINITY, f64::max),
            t0: 30.0,
            t1: 170.0,
            s_lo: 1.0,
            s_hi: 349.0,
            bin: 0.25,
            nbins: 1400,
            by_columns: true,
        };
        let mut reference = vec![BinAcc::default(); 1400];
        let mut ref_count = [0usize; 3];
        // Every sample centre of the image, row by row, through the region's
        // own inside test (`Region::inside`'s arithmetic) and position
        // (`visit_band_lines`' arithmetic).
        let m = &region.m;
        for j in 0..h {
            let y = j as f64 + 0.5;
            if y < region.ymin || y > region.ymax {
                continue;
            }
            for i in 0..w {
                let x = i as f64 + 0.5;
                let rw = 1.0 / (m[6] * x + m[7] * y + m[8]);
                let (si, ti) = (
                    (m[0] * x + m[1] * y + m[2]) * rw,
                    (m[3] * x + m[4] * y + m[5]) * rw,
                );
                if !(ti >= region.t0 && ti <= region.t1 && si >= region.s_lo && si <= region.s_hi) {
                    continue;
                }
                let s = (m[0] * x + (m[1] * y + m[2])) / (m[6] * x + (m[7] * y + m[8]));
                let v = lut[codes[j * w + i] as usize];
                ref_count[0] += 1;
                ref_count[1] += (v >= 0.999) as usize;
                ref_count[2] += (v <= 0.0) as usize;
                let r = &mut reference[((s * 4.0) as usize).min(1399)];
                r.add(s, v);
                r.add_parity(i, j);
            }
        }
        assert!(ref_count[0] > 30_000, "{ref_count:?}");
        let run = |by_columns: bool, avx2: bool| {
            let piece = Region {
                by_columns,
                ..region
            };
            let mut acc = vec![BinAcc::default(); 1400];
            let count = if avx2 {
                #[cfg(target_arch = "x86_64")]
                {
                    // SAFETY: only called where the CPU has AVX2.
                    unsafe { first_pass_avx2(&piece, 0, &mut acc, 0.999) }
                }
                #[cfg(not(target_arch = "x86_64"))]
                unreachable!()
            } else {
                first_pass_body::<false>(&piece, 0, &mut acc, 0.999)
            };
            (count, acc)
        };
        for by_columns in [true, false] {
            let (count, acc) = run(by_columns, false);
            assert_eq!(count, ref_count);
            for (a, r) in acc.iter().zip(&reference) {
                assert_eq!((a.n, a.hi, a.lo), (r.n, r.hi, r.lo));
                // The pixel-parity sums, a run at a time, exactly.
                assert_eq!(a.parity, r.parity, "by columns {by_columns}");
                for (x, y) in [
                    (a.sum, r.sum),
                    (a.sum2, r.sum2),
                    (a.ssum, r.ssum),
                    (a.ssum2, r.ssum2),
                ] {
                    assert!((x - y).abs() <= 1e-12 * y.abs(), "{x} {y}");
                }
            }
            #[cfg(target_arch = "x86_64")]
            if std::arch::is_x86_feature_detected!("avx2") {
                let (count2, acc2) = run(by_columns, true);
                assert_eq!(count2, count);
                assert!(acc_bits(&acc2) == acc_bits(&acc));
            }
        }
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

    /// The plain definition: every sample centre through the lens's exact
    /// undistortion (if any) and the inverse homography, two passes, 3σ clip
    /// about each bin's plain mean.
    /// Every bin by definition, sample by sample: (mean s, robust mean,
    /// count, mean pixel-parity patterns).
    fn brute(plane: &Plane, strip: &Strip, o: &BinOptions) -> Vec<(f64, f64, f64, [f64; 3])> {
        let inv = strip.to_image.inverse().unwrap();
        let m = o.margin;
        let scale = [0.0, 0.5, 1.0]
            .iter()
            .map(|f| 1.0 / strip.scale_at(f * strip.length).s_per_px)
            .fold(0.0, f64::max);
        let (bin, end) = (o.bin_px / scale, o.end_px / scale);
        let nb = (strip.length / bin).ceil() as usize;
        let mut by_bin: Vec<Vec<(f64, f64, [f64; 3])>> = vec![Vec::new(); nb];
        for j in 0..plane.height {
            for i in 0..plane.width {
                let x = (plane.offset.0 + i * plane.step.0) as f64 + 0.5;
                let y = (plane.offset.1 + j * plane.step.1) as f64 + 0.5;
                let [x, y] = match &strip.lens {
                    Some(l) => l.undistort([x, y]),
                    None => [x, y],
                };
                let [s, t] = inv.apply([x, y]);
                if t >= m * strip.width
                    && t <= (1.0 - m) * strip.width
                    && s >= end
                    && s <= strip.length - end
                {
                    let b = ((s / bin) as usize).min(nb - 1);
                    let (px, py) = (
                        parity_sign(plane.offset.0 + i * plane.step.0) as f64,
                        parity_sign(plane.offset.1 + j * plane.step.1) as f64,
                    );
                    by_bin[b].push((s, plane.data[j * plane.width + i] as f64, [px, py, px * py]));
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
                let par = |q: usize| v.iter().map(|p| p.2[q]).sum::<f64>() / n;
                (
                    ms,
                    kept.iter().sum::<f64>() / kept.len() as f64,
                    kept.len() as f64,
                    [par(0), par(1), par(2)],
                )
            })
            .collect()
    }

    #[test]
    fn bins_through_a_lens_equal_the_plain_definition() {
        // A strip near a frame edge through strong barrel and pincushion
        // (its edges bow by pixels), noise with dust: every bin as the brute
        // force through the exact undistortion gives it.
        let (w, h) = (400, 300);
        for b in [-0.06, 0.05] {
            let lens = Lens::new(
                crate::distortion::Ptlens {
                    a: 0.01,
                    b,
                    c: -0.01,
                },
                w,
                h,
            );
            lens.check().unwrap();
            let quad = [[15.0, 200.0], [385.0, 205.0], [380.0, 290.0], [20.0, 285.0]];
            let mut strip = strip_for(quad, 370.0, 85.0);
            strip.lens = Some(lens);
            let mut rnd = uniform(777u64);
            let data = (0..w * h)
                .map(|k| {
                    let (x, y) = ((k % w) as f64, (k / w) as f64);
                    let dust = (x - 200.0).hypot(y - 250.0) < 6.0;
                    if dust {
                        0.01
                    } else {
                        (0.5 + 0.3 * (0.004 * x * x).sin() + 0.03 * (rnd() - 0.5)) as f32
                    }
                })
                .collect();
            let plane = Plane::full(w, h, data);
            for bin_px in [0.25, 2.0] {
                let o = BinOptions {
                    bin_px,
                    ..BinOptions::default()
                };
                let p = bin_plane(&plane, &strip, &o);
                let want = brute(&plane, &strip, &o);
                assert_eq!(
                    p.s.len(),
                    want.len(),
                    "b {b} bin {bin_px}: {} {}",
                    p.s.len(),
                    want.len()
                );
                for k in 0..want.len() {
                    assert!((p.s[k] - want[k].0).abs() < 1e-9, "{b} {bin_px} {k}");
                    assert!(
                        (p.y[k] - want[k].1).abs() < 1e-9,
                        "{b} {bin_px} {k}: {} vs {}",
                        p.y[k],
                        want[k].1
                    );
                    assert_eq!(p.count[k], want[k].2, "{b} {bin_px} {k}");
                    assert_eq!(p.parity[k], want[k].3, "{b} {bin_px} {k}");
                }
            }
        }
    }

    #[test]
    fn lens_binning_holds_on_random_geometry() {
        // Random lenses (a, b, c mixed, up to ±12 % at the corner), strips
        // turned any way, keystoned, partly outside the frame, tiny or long:
        // no panic, and every bin as the brute force gives it.
        let (w, h) = (160, 120);
        let mut rnd = uniform(99u64);
        let data: Vec<f32> = (0..w * h)
            .map(|k| (0.5 + 0.4 * ((k % w) as f64 * 0.37 + (k / w) as f64 * 0.11).sin()) as f32)
            .collect();
        let plane = Plane::full(w, h, data);
        let mut checked = 0;
        for case in 0..400 {
            let b = 0.12 * (2.0 * rnd() - 1.0) / 2.25;
            let model = crate::distortion::Ptlens {
                a: 0.3 * b * (2.0 * rnd() - 1.0),
                b,
                c: 0.2 * b * (2.0 * rnd() - 1.0),
            };
            let lens = Lens::new(model, w, h);
            if lens.check().is_err() {
                continue;
            }
            let (cx, cy) = (w as f64 * rnd(), h as f64 * rnd());
            let (len, wid) = (2.0 + 180.0 * rnd(), 1.0 + 60.0 * rnd());
            let a = std::f64::consts::TAU * rnd();
            let key = 0.5 + rnd();
            let (c, sn) = (a.cos(), a.sin());
            let quad = [
                [-0.5, -0.5],
                [0.5, -0.5 / key],
                [0.5, 0.5 / key],
                [-0.5, 0.5],
            ]
            .map(|[x, y]| {
                let (x, y) = (x * len, y * wid);
                [cx + c * x - sn * y, cy + sn * x + c * y]
            });
            // As a measurement makes it: corners clicked inside the photo,
            // undistorted, the strip's edges then bowing between them.
            if quad
                .iter()
                .any(|p| !(0.0..=w as f64).contains(&p[0]) || !(0.0..=h as f64).contains(&p[1]))
            {
                continue;
            }
            let Ok(h_) = Homography::from_quads(
                &crate::geometry::rect_corners(0.0, 0.0, len, wid),
                &quad.map(|p| lens.undistort(p)),
            ) else {
                continue;
            };
            let strip = Strip {
                lens: Some(lens),
                to_image: h_,
                length: len,
                width: wid,
            };
            let o = BinOptions {
                bin_px: [0.25, 1.0, 2.0][case % 3],
                ..BinOptions::default()
            };
            let p = bin_plane(&plane, &strip, &o);
            let want = brute(&plane, &strip, &o);
            assert_eq!(p.s.len(), want.len(), "case {case}");
            for k in 0..want.len() {
                assert!((p.s[k] - want[k].0).abs() < 1e-9, "case {case} bin {k}");
                assert!((p.y[k] - want[k].1).abs() < 1e-9, "case {case} bin {k}");
                assert_eq!(p.count[k], want[k].2, "case {case} bin {k}");
            }
            checked += 1;
        }
        assert!(checked >= 40, "{checked}");
    }

    #[test]
    fn robust_bins_equal_the_plain_two_pass_definition() {
        // Perspective, a sparse (Bayer-like) lattice, noise with heavy tails and
        // dust specks that put many outliers into single bins; the strip swept
        // across the image (binned down the columns) and, transposed, down it
        // (binned along the rows).
        for down in [false, true] {
            robust_bins_case(down);
        }
    }

    fn robust_bins_case(down: bool) {
        let (w, h) = (180, 180);
        let mut quad = [[20.0, 30.0], [330.0, 12.0], [345.0, 250.0], [12.0, 200.0]];
        if down {
            quad.iter_mut().for_each(|p| p.swap(0, 1));
        }
        let strip = strip_for(quad, 300.0, 60.0);
        let inv = positive_inverse(&strip, strip.to_image.inverse().unwrap().m);
        assert_eq!(sweeps_across_columns(&inv, &quad), !down);
        let mut rnd = uniform(12345u64);
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
