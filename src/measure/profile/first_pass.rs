//! The first binning pass's kernel (the body that `first_pass` compiles for
//! the baseline and for AVX2, and its sink that adds each sample of a run's
//! piece of the region to its bin) and the bins' split into runs (one per
//! parallel task).

use super::acc::BinAcc;
use super::region::{self, Region};

/// What [`first_pass`](fn@super::first_pass) does (inlined into each of its compilations).
#[inline(always)]
pub(super) fn first_pass_body<const AVX2: bool>(
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

/// How many runs of bins the first binning pass is split into (run in parallel).
const PASS_CHUNKS: usize = 8;

/// The bins of `acc` from the one holding `s_lo` to the one holding `s_hi`
/// (strip units; bins `bin` wide), split into [`PASS_CHUNKS`] runs: (first
/// bin, end bin, the run's own bins). The same split on any machine, so
/// results do not depend on threads.
pub(super) fn own_runs(
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
