//! The sweep profile: every sample centre of a strip, mapped through the
//! homography to the strip's own coordinate `s` (along the sweep) and binned
//! in sub-pixel bins, with a robust (3σ-clipped) mean per bin. No image
//! resampling: each bin's value is an average of real samples, and each bin
//! also records the mean and variance of its samples' `s` so the estimators
//! can work at the true sample positions and correct the tiny box blur of
//! binning exactly.

#![allow(clippy::needless_range_loop, clippy::neg_cmp_op_on_partial_ord)]

mod acc;
mod binned;
mod first_pass;
mod lens;
mod region;
mod strip;

use crate::geometry::Point;
use crate::photo::{Plane, PlaneRef};
use acc::BinAcc;
pub use binned::{BinOptions, Profile};
use first_pass::{first_pass_body, own_runs};
pub(crate) use lens::photo_outline;
use rayon::prelude::*;
use region::Region;
pub use region::row_span;
pub use strip::{LocalScale, Strip};

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
    let (bin, end) = bin_and_end(strip, opts);
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
        let steps = line_steps(
            strip,
            t1 - t0,
            planes,
            lens_along_rows(strip, bin),
            opts.max_across,
        );
        let mut prof = lens::bin_through_lens(
            planes,
            strip,
            lens,
            positive_inverse(strip, inv.m),
            (t0, t1, s_lo, s_hi),
            (bin, nbins),
            steps,
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
    // Where the strip is taller across than `max_across` samples, every
    // k-th sample row (a sweep along the rows) or column (along the columns).
    let by_columns = sweeps_across_columns(&m, &quad);
    let (row_step, col_step) = line_steps(strip, t1 - t0, planes, by_columns, opts.max_across);
    let region = Region {
        by_columns,
        row_step,
        col_step,
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

/// The bin width and the cut at each short end (strip units) `opts` asks
/// for, in pixels at the strip's most magnified end.
fn bin_and_end(strip: &Strip, opts: &BinOptions) -> (f64, f64) {
    let max_px_per_s = [0.0, 0.5, 1.0]
        .iter()
        .map(|f| 1.0 / strip.scale_at(f * strip.length).s_per_px)
        .fold(0.0, f64::max);
    (opts.bin_px / max_px_per_s, opts.end_px / max_px_per_s)
}

/// Whether a strip under a lens sweeps along the photo's rows at its
/// middle (a step of `bin`, strip units, along it).
fn lens_along_rows(strip: &Strip, bin: f64) -> bool {
    let (l, w) = (strip.length, strip.width);
    let (a, b) = (
        strip.to_photo([0.5 * l, 0.5 * w]),
        strip.to_photo([0.5 * l + bin, 0.5 * w]),
    );
    (b[0] - a[0]).abs() >= (b[1] - a[1]).abs()
}

/// The (row, column) steps that leave at most `max_across` sample rows
/// (`along_rows`: a sweep along the rows) or columns across a strip
/// `across` (strip units) wide (0: all of them); the step across is odd,
/// so that a line of samples still alternates its pixel parity.
fn line_steps(
    strip: &Strip,
    across: f64,
    planes: &[PlaneRef],
    along_rows: bool,
    max_across: usize,
) -> (usize, usize) {
    let lattice = planes
        .iter()
        .map(|p| if along_rows { p.step.1 } else { p.step.0 })
        .max()
        .unwrap_or(1)
        .max(1) as f64;
    let lines = across * strip.px_per_t(0.5 * strip.length) / lattice;
    let k = if max_across == 0 || !(lines > max_across as f64) {
        1
    } else {
        ((lines / max_across as f64).ceil().min(1e6) as usize) | 1
    };
    if along_rows { (k, 1) } else { (1, k) }
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

#[cfg(test)]
mod tests;
