//! The dark masks the blob search labels: samples darker than a fraction of
//! their neighbourhood's mean, and darker than half its white level.

use super::blobs::DARK_FRACTION;
use super::sample::Gray;
use rayon::prelude::*;

/// Dark mask: value < 0.5 × the local white level (maximum over a window of side ≈ 7 %
/// of the short side, taken on a grid of b×b block maxima); keeps thin dark rings whole
/// where the mean is pulled down by a dark neighbourhood.
pub(super) fn dark_mask_white(g: &Gray<'_>) -> Vec<bool> {
    let (w, h) = (g.w, g.h);
    let r = ((0.035 * w.min(h) as f64).round() as usize).clamp(3, 100);
    let b = (r / 4).max(1);
    let (bw, bh) = (w.div_ceil(b), h.div_ceil(b));
    let mut blocks = vec![f32::NEG_INFINITY; bw * bh];
    blocks
        .par_chunks_mut(bw)
        .zip(g.data[..w * h].par_chunks(b * w))
        .for_each(|(brow, rows)| {
            for row in rows.chunks(w) {
                for (m, cols) in brow.iter_mut().zip(row.chunks(b)) {
                    for &v in cols {
                        if v > *m {
                            *m = v;
                        }
                    }
                }
            }
        });
    let rb = r.div_ceil(b);
    let mut rows = Vec::with_capacity(bw * bh);
    for j in 0..bh {
        rows.extend(sliding_max(&blocks[j * bw..(j + 1) * bw], rb));
    }
    let mut white = vec![0.0f32; bw * bh];
    let mut col = vec![0.0f32; bh];
    for i in 0..bw {
        for j in 0..bh {
            col[j] = rows[j * bw + i];
        }
        for (j, v) in sliding_max(&col, rb).into_iter().enumerate() {
            white[j * bw + i] = v;
        }
    }
    let mut mask = vec![false; w * h];
    mask.par_chunks_mut(w).enumerate().for_each(|(j, m)| {
        let wrow = &white[(j / b) * bw..(j / b + 1) * bw];
        let row = &g.data[j * w..(j + 1) * w];
        for ((ms, vs), &white) in m.chunks_mut(b).zip(row.chunks(b)).zip(wrow) {
            let thr = 0.5 * white;
            for (mv, &v) in ms.iter_mut().zip(vs) {
                *mv = v < thr;
            }
        }
    });
    mask
}

/// Maximum over [i−r, i+r] (clamped), van Herk / Gil–Werman.
fn sliding_max(x: &[f32], r: usize) -> Vec<f32> {
    let n = x.len();
    let k = 2 * r + 1;
    let mut fwd = vec![f32::NEG_INFINITY; n];
    let mut bwd = vec![f32::NEG_INFINITY; n];
    for i in 0..n {
        fwd[i] = if i % k == 0 {
            x[i]
        } else {
            fwd[i - 1].max(x[i])
        };
    }
    for i in (0..n).rev() {
        bwd[i] = if i % k == k - 1 || i == n - 1 {
            x[i]
        } else {
            bwd[i + 1].max(x[i])
        };
    }
    (0..n)
        .map(|i| {
            let lo = i.saturating_sub(r);
            let hi = (i + r).min(n - 1);
            if lo / k == hi / k {
                // One block (a window clipped at an end): direct.
                x[lo..=hi].iter().cloned().fold(f32::NEG_INFINITY, f32::max)
            } else {
                bwd[lo].max(fwd[hi])
            }
        })
        .collect()
}

/// Dark mask: value < DARK_FRACTION × box mean over a window of side ≈ 15 % of the short side.
///
/// The box sums come from the image's integral image, of which only the
/// 2r + 2 rows a mask row's window spans are kept (a ring): the whole
/// table, 5.3 MB of f64 for a 24 MP photo's search image, was ≈ 1 300 fresh
/// pages faulted in on every measurement. Its rows are the same sums, made
/// in the same order, so the mask is the same bit for bit.
pub(super) fn dark_mask(g: &Gray<'_>) -> Vec<bool> {
    let (w, h) = (g.w, g.h);
    let r = ((0.07 * w.min(h) as f64).round() as usize).clamp(4, 200);
    let w1 = w + 1;
    // Integral-image row y (y = 0..=h) sits in slot y % ring; row 0 is zeros.
    let ring = (2 * r + 2).min(h + 1);
    let mut rows = vec![0.0f64; ring * w1];
    let mut made = 0; // rows 0..=made are made
    let mut mask = vec![false; w * h];
    for (j, row) in mask.chunks_mut(w).enumerate() {
        let y0 = j.saturating_sub(r);
        let y1 = (j + r + 1).min(h);
        while made < y1 {
            // Row y: the running sums of image row y − 1, plus row y − 1.
            let y = made + 1;
            let (prev, cur) = if y % ring == 0 {
                let (cur, rest) = rows.split_at_mut(w1);
                (&rest[(ring - 2) * w1..], cur)
            } else {
                let (before, after) = rows.split_at_mut((y % ring) * w1);
                (&before[(y % ring - 1) * w1..], &mut after[..w1])
            };
            let mut run = 0.0f64;
            cur[0] = 0.0;
            for (o, &v) in cur[1..].iter_mut().zip(&g.data[(y - 1) * w..y * w]) {
                run += v as f64;
                *o = run;
            }
            if y > 1 {
                for (o, &a) in cur.iter_mut().zip(prev) {
                    *o += a;
                }
            }
            made = y;
        }
        let (t0, t1) = (
            &rows[(y0 % ring) * w1..][..w1],
            &rows[(y1 % ring) * w1..][..w1],
        );
        let v = &g.data[j * w..(j + 1) * w];
        let at = |i: usize| {
            let x0 = i.saturating_sub(r);
            let x1 = (i + r + 1).min(w);
            let s = t1[x1] - t0[x1] - t1[x0] + t0[x0];
            let mean = s / ((x1 - x0) * (y1 - y0)) as f64;
            (v[i] as f64) < DARK_FRACTION as f64 * mean
        };
        // Columns whose window is not clipped, [r, w − r): one area, the same
        // sums as `at` (vectorised).
        let (lo, hi) = (r.min(w), w.saturating_sub(r).max(r.min(w)));
        let n = hi - lo;
        if n > 0 {
            let area = ((2 * r + 1) * (y1 - y0)) as f64;
            let (ahead, behind) = (lo + r + 1..lo + r + 1 + n, lo - r..lo - r + n);
            let sums = t1[ahead.clone()]
                .iter()
                .zip(&t0[ahead])
                .zip(&t1[behind.clone()])
                .zip(&t0[behind]);
            for ((m, &x), (((&a1, &a0), &b1), &b0)) in
                row[lo..hi].iter_mut().zip(&v[lo..hi]).zip(sums)
            {
                let s = a1 - a0 - b1 + b0;
                *m = (x as f64) < DARK_FRACTION as f64 * (s / area);
            }
        }
        for i in (0..lo).chain(hi..w) {
            row[i] = at(i);
        }
    }
    mask
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::borrow::Cow;

    #[test]
    fn sliding_max_matches_brute_force() {
        let x: Vec<f32> = (0..57).map(|i| ((i * 37) % 23) as f32).collect();
        for r in [0, 1, 3, 10, 60] {
            let got = sliding_max(&x, r);
            for (i, &g) in got.iter().enumerate() {
                let lo = i.saturating_sub(r);
                let hi = (i + r).min(x.len() - 1);
                let want = x[lo..=hi].iter().cloned().fold(f32::NEG_INFINITY, f32::max);
                assert_eq!(g, want, "r {r} i {i}");
            }
        }
    }

    /// The per-sample mean mask the vectorised one replaced (the oracle).
    fn dark_mask_plain(g: &Gray<'_>) -> Vec<bool> {
        let (w, h) = (g.w, g.h);
        let r = ((0.07 * w.min(h) as f64).round() as usize).clamp(4, 200);
        let mut ii = vec![0.0f64; (w + 1) * (h + 1)];
        for j in 0..h {
            let mut run = 0.0f64;
            for i in 0..w {
                run += g.data[j * w + i] as f64;
                ii[(j + 1) * (w + 1) + i + 1] = ii[j * (w + 1) + i + 1] + run;
            }
        }
        let mut mask = vec![false; w * h];
        for j in 0..h {
            let y0 = j.saturating_sub(r);
            let y1 = (j + r + 1).min(h);
            for i in 0..w {
                let x0 = i.saturating_sub(r);
                let x1 = (i + r + 1).min(w);
                let s = ii[y1 * (w + 1) + x1] - ii[y0 * (w + 1) + x1] - ii[y1 * (w + 1) + x0]
                    + ii[y0 * (w + 1) + x0];
                let mean = s / ((x1 - x0) * (y1 - y0)) as f64;
                mask[j * w + i] = (g.data[j * w + i] as f64) < DARK_FRACTION as f64 * mean;
            }
        }
        mask
    }

    #[test]
    fn mean_mask_equals_the_per_sample_one() {
        // Windows wider than the image, as wide, and narrower (interior columns).
        for (w, h) in [(9, 7), (60, 40), (333, 211), (700, 480)] {
            let data: Vec<f32> = (0..w * h)
                .map(|i| {
                    let (x, y) = ((i % w) as f32, (i / w) as f32);
                    0.5 + 0.45 * (0.37 * x).sin() * (0.23 * y + 0.001 * x * y).cos()
                })
                .collect();
            let g = Gray {
                w,
                h,
                data: Cow::Owned(data),
                origin: [0.0, 0.0],
                scale: [1.0, 1.0],
            };
            assert_eq!(dark_mask(&g), dark_mask_plain(&g), "{w}×{h}");
        }
    }
}
