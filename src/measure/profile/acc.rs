//! One bin's running sums and its most extreme samples, for the robust mean.

use super::Profile;

/// How many of the most extreme samples each bin keeps on either side.
///
/// A bin whose kept extremes are all outliers is visited again (scattered
/// reads down the columns of its samples). With 3, a 24 MP raw's green
/// strip (350 samples a bin, ≈ 0.47 beyond 3σ on a side by chance) sent 65
/// of 16 000 bins back and binning took 12.7 ms; with 6 (chance ≈ 1e-5 a
/// bin) none, 8.5 ms, even though every sample then passes a longer network.
/// Now 8, all of the lanes the insertion keeps anyway: a strip binned through
/// a lens model that does not fit the photo (phases mixed within bins) sent
/// 195 of 21 200 bins back with 6.
pub(super) const EXTREMES: usize = LANES;

/// Lanes of the extremes' arrays: a whole number of 4-wide vectors, so that
/// an insertion is a few vector min/max.
pub(super) const LANES: usize = 8;

/// One bin's running sums, and its most extreme samples for the robust mean.
#[derive(Clone, Copy)]
pub(super) struct BinAcc {
    pub(super) sum: f64,
    pub(super) sum2: f64,
    pub(super) ssum: f64,
    pub(super) ssum2: f64,
    pub(super) rsum: f64,
    pub(super) n: u32,
    pub(super) rn: u32,
    /// Sums of the pixel-parity patterns (−1)^x, (−1)^y, (−1)^(x+y) over
    /// the bin's samples (exact integers, whatever the order).
    pub(super) parity: [i64; 3],
    /// The largest samples, descending (−∞ while unfilled); the first
    /// [`EXTREMES`] are the bin's.
    pub(super) hi: [f32; LANES],
    /// The smallest samples, ascending (+∞ while unfilled); the first
    /// [`EXTREMES`] are the bin's.
    pub(super) lo: [f32; LANES],
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
            parity: [0; 3],
            hi: [f32::NEG_INFINITY; LANES],
            lo: [f32::INFINITY; LANES],
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
    /// Adds the parity patterns of samples `q .. e` of a line starting at
    /// `start` (an odd number of pixels a sample): along the line one coordinate's sign
    /// alternates, so a run sums to its first sign when its length is odd and
    /// to 0 otherwise; the other coordinate's sign is the line's.
    #[inline(always)]
    pub(super) fn add_parity_run(&mut self, start: super::region::LineStart, q: usize, e: usize) {
        let len = (e - q) as i64;
        let (alt0, fixed) = if start.along_x {
            (start.x + q, start.y)
        } else {
            (start.y + q, start.x)
        };
        let alt = if len % 2 == 1 {
            super::parity_sign(alt0)
        } else {
            0
        };
        let f = super::parity_sign(fixed);
        let (sx, sy) = if start.along_x {
            (alt, f * len)
        } else {
            (f * len, alt)
        };
        self.parity[0] += sx;
        self.parity[1] += sy;
        self.parity[2] += f * alt;
    }

    /// Adds one sample's parity patterns, at photo pixel (x, y).
    #[inline(always)]
    pub(super) fn add_parity(&mut self, x: usize, y: usize) {
        let (px, py) = (super::parity_sign(x), super::parity_sign(y));
        self.parity[0] += px;
        self.parity[1] += py;
        self.parity[2] += px * py;
    }

    /// The bin's mean and its 3σ clipping distance (plus a small floor) for
    /// the robust mean: (mean, limit).
    pub(super) fn clip_limits(&self) -> (f64, f64) {
        let c = self.n.max(1) as f64;
        let mu = self.sum / c;
        (mu, 3.0 * (self.sum2 / c - mu * mu).max(0.0).sqrt() + 1e-6)
    }

    /// Adds a sample at position `s` with value `v` (branch-free insertion
    /// into the sorted extremes).
    #[inline(always)]
    pub(super) fn add(&mut self, s: f64, v: f32) {
        self.add_while::<false>(&[0], &[s], &[v], 0);
    }

    /// Adds samples `q ..` of a line (bins `b`, positions `s`, values `v`)
    /// while they are in this bin (`b[q]`'s), in order; returns the index of
    /// the first sample of another bin (or the line's length). The running
    /// values stay in registers; the extremes' insertion is in AVX2 when
    /// `AVX2` (only instantiated inside a function compiled for, and run on,
    /// a CPU with AVX2: `profile::first_pass`). The same values either way:
    /// no NaN reaches here.
    #[inline(always)]
    pub(super) fn add_while<const AVX2: bool>(
        &mut self,
        b: &[u32],
        s: &[f64],
        v: &[f32],
        q: usize,
    ) -> usize {
        #[cfg(target_arch = "x86_64")]
        if AVX2 {
            // SAFETY: `AVX2` is set only in code compiled for, and run on, a
            // CPU with AVX2 (`profile::first_pass`).
            return unsafe { add_while_avx2(self, b, s, v, q) };
        }
        let (n, bq) = (b.len().min(s.len()).min(v.len()), b[q]);
        let (mut sum, mut sum2, mut ssum, mut ssum2) = (self.sum, self.sum2, self.ssum, self.ssum2);
        let (mut h, mut l) = (self.hi, self.lo);
        let mut e = q;
        while e < n && b[e] == bq {
            let (s, v) = (s[e], v[e]);
            let vd = v as f64;
            sum += vd;
            sum2 += vd * vd;
            ssum += s;
            ssum2 += s * s;
            let sh = [f32::INFINITY, h[0], h[1], h[2], h[3], h[4], h[5], h[6]];
            let sl = [f32::NEG_INFINITY, l[0], l[1], l[2], l[3], l[4], l[5], l[6]];
            // Lane k takes the larger of itself and the smaller of lane k − 1
            // (before this sample) and v; lane 0 the larger of itself and v.
            for k in 0..LANES {
                h[k] = fmax(h[k], fmin(sh[k], v));
                l[k] = fmin(l[k], fmax(sl[k], v));
            }
            e += 1;
        }
        (self.sum, self.sum2, self.ssum, self.ssum2) = (sum, sum2, ssum, ssum2);
        (self.hi, self.lo) = (h, l);
        self.n += (e - q) as u32;
        e
    }
}

/// [`BinAcc::add_while`] with the extremes as eight-lane AVX2 vectors held
/// in registers over the run. Each insertion is the median of a lane, the
/// lane before it (±∞ before lane 0) and the value: `min(max(h, v), h
/// shifted up)` for the largest, which equals the plain code's `max(h, min(h
/// shifted up, v))` lane by lane on the sorted lanes, with one operation
/// fewer on the chain from one sample to the next (`vminps`/`vmaxps` are
/// [`fmin`]/[`fmax`] lane by lane; no NaN reaches here).
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2")]
#[inline]
fn add_while_avx2(a: &mut BinAcc, b: &[u32], s: &[f64], v: &[f32], q: usize) -> usize {
    use std::arch::x86_64::*;
    const _: () = assert!(LANES == 8);
    let up = _mm256_setr_epi32(0, 0, 1, 2, 3, 4, 5, 6);
    // SAFETY: [f32; 8] and __m256 have the same size; every bit pattern is valid in both.
    let (mut h, mut l) = unsafe {
        (
            std::mem::transmute::<[f32; LANES], __m256>(a.hi),
            std::mem::transmute::<[f32; LANES], __m256>(a.lo),
        )
    };
    let (pinf, ninf) = (
        _mm256_set1_ps(f32::INFINITY),
        _mm256_set1_ps(f32::NEG_INFINITY),
    );
    let (n, bq) = (b.len().min(s.len()).min(v.len()), b[q]);
    let (mut sum, mut sum2, mut ssum, mut ssum2) = (a.sum, a.sum2, a.ssum, a.ssum2);
    let mut e = q;
    while e < n && b[e] == bq {
        let (s, v) = (s[e], v[e]);
        let vd = v as f64;
        sum += vd;
        sum2 += vd * vd;
        ssum += s;
        ssum2 += s * s;
        let vv = _mm256_set1_ps(v);
        let sh = _mm256_blend_ps::<1>(_mm256_permutevar8x32_ps(h, up), pinf);
        let sl = _mm256_blend_ps::<1>(_mm256_permutevar8x32_ps(l, up), ninf);
        h = _mm256_min_ps(_mm256_max_ps(h, vv), sh);
        l = _mm256_max_ps(_mm256_min_ps(l, vv), sl);
        e += 1;
    }
    (a.sum, a.sum2, a.ssum, a.ssum2) = (sum, sum2, ssum, ssum2);
    a.n += (e - q) as u32;
    // SAFETY: as above.
    unsafe {
        a.hi = std::mem::transmute::<__m256, [f32; LANES]>(h);
        a.lo = std::mem::transmute::<__m256, [f32; LANES]>(l);
    }
    e
}

/// Sets each bin's robust sums (the samples within 3σ of its mean, plus a
/// small floor) from its kept extremes; returns the bins that have
/// [`EXTREMES`] or more outliers on one side (dust, a speck), to be visited
/// again: (bin, mean, clipping distance).
pub(super) fn robust_from_extremes(acc: &mut [BinAcc]) -> Vec<(usize, f64, f64)> {
    let mut revisit = Vec::new();
    for (b, a) in acc.iter_mut().enumerate() {
        if a.n < 4 {
            continue;
        }
        let (mu, lim) = a.clip_limits();
        let out_hi = a.hi[..EXTREMES]
            .iter()
            .filter(|&&v| v as f64 - mu > lim)
            .count();
        let out_lo = a.lo[..EXTREMES]
            .iter()
            .filter(|&&v| mu - v as f64 > lim)
            .count();
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
    revisit
}

/// Appends the non-empty bins of `acc` to `prof`: each bin's mean sample
/// position, its variance, and its robust mean (the plain mean for bins of
/// fewer than 4 samples); with `parity`, each bin's mean pixel-parity
/// patterns too; where `prof` counts clipped samples, whether each bin
/// holds one (its largest at `clip_level` or its smallest at or below 0).
pub(super) fn finish(acc: &[BinAcc], prof: &mut Profile, parity: bool, clip_level: f32) {
    let clipping = prof.clipped_high + prof.clipped_low > 0;
    for a in acc {
        if a.n == 0 {
            continue;
        }
        if clipping {
            prof.clipped.push(a.hi[0] >= clip_level || a.lo[0] <= 0.0);
        }
        let c = a.n as f64;
        if parity {
            prof.parity.push(a.parity.map(|p| p as f64 / c));
        }
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
}
