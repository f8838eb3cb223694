//! The strip's bars sampled into bands of constant v and each window's
//! residual slant, the measurement [`super::align_ends`] fits its slant line to.

use super::super::sample::AtImage;
use crate::geometry::Homography;
use rayon::prelude::*;

/// Sample step along the strip (image px).
pub(super) const STEP_PX: f64 = 0.25;
/// Across-strip range sampled (v), inside the long edges.
pub(super) const V_RANGE: (f64, f64) = (0.15, 0.85);
/// Bands the sampled lines are grouped into.
pub(super) const BANDS: usize = 12;
/// Windows along the strip (half-overlapping).
pub(super) const WINDOWS: usize = 24;
/// Most samples of a window searched (its centre part; 120 px).
pub(super) const WIN_MAX: usize = 480;

/// Slant model: `s(u0) = a + b·u0` (u per unit v).
#[derive(Debug, Clone, Copy)]
pub(super) struct Slant {
    pub(super) a: f64,
    pub(super) b: f64,
}

impl Slant {
    pub(super) fn at(&self, u0: f64) -> f64 {
        self.a + self.b * u0
    }
}

/// The lines of constant v, sampled along the bars of slant `s`, averaged into bands.
pub(super) struct Bands {
    /// Band profiles on the u0 grid (NaN where outside the image).
    pub(super) prof: Vec<Vec<f64>>,
    /// Mean v of each band, minus ½.
    pub(super) dv: Vec<f64>,
    /// Grid step in u.
    pub(super) du: f64,
}

/// Window `w` of a grid of `n` samples: its range (a, z) and the centre part
/// (i0, i1) of at most [`WIN_MAX`] samples that is searched.
pub(super) fn window_range(w: usize, n: usize) -> (usize, usize, usize, usize) {
    let len = 2 * n / (WINDOWS + 1);
    let start = w * len / 2;
    let (a, z) = (start, (start + len).min(n));
    let cut = (z - a).saturating_sub(WIN_MAX) / 2;
    (a, z, a + cut, z - cut)
}

/// Which grid samples the search of `windows` reads, shifts of up to
/// ±`range_px` across the strip included (a bound: |v − ½| ≤ ½).
pub(super) fn needed(h: &Homography, n: usize, windows: &[usize], range_px: f64) -> Vec<bool> {
    let du = 1.0 / (n - 1) as f64;
    let mut keep = vec![false; n];
    for &w in windows {
        let (a, z, i0, i1) = window_range(w, n);
        let uc = (a + z) as f64 * 0.5 * du;
        let (p, q) = (h.apply([uc - 0.01, 0.5]), h.apply([uc + 0.01, 0.5]));
        let px_per_u = (q[0] - p[0]).hypot(q[1] - p[1]) / 0.02;
        let reach = (0.5 * range_px / (px_per_u * du)).ceil() as usize + 3;
        keep[i0.saturating_sub(reach)..(i1 + reach).min(n)].fill(true);
    }
    keep
}

/// Samples the bands where `keep` says (NaN elsewhere).
pub(super) fn sample_bands<S: AtImage + ?Sized>(
    g: &S,
    h: &Homography,
    n: usize,
    lines: usize,
    s: Slant,
    keep: &[bool],
) -> Bands {
    let du = 1.0 / (n - 1) as f64;
    let bands = BANDS.min(lines);
    let level = |j: usize| V_RANGE.0 + (V_RANGE.1 - V_RANGE.0) * (j as f64 + 0.5) / lines as f64;
    let out: Vec<(Vec<f64>, f64)> = (0..bands)
        .into_par_iter()
        .map(|b| {
            let mine: Vec<usize> = (0..lines).filter(|&j| j * bands / lines == b).collect();
            let mut row = vec![0.0; n];
            // Grid positions are computed a run of RUN samples at a time first
            // (branch-free, so the compiler vectorises the divisions), then read.
            const RUN: usize = 64;
            let mut grid = [[0.0f64; 2]; RUN];
            for &j in &mine {
                let v = level(j);
                for (c, (accs, keeps)) in row.chunks_mut(RUN).zip(keep.chunks(RUN)).enumerate() {
                    if !keeps.iter().any(|&k| k) {
                        accs.fill(f64::NAN);
                        continue;
                    }
                    for (k, q) in grid[..accs.len()].iter_mut().enumerate() {
                        let u0 = (c * RUN + k) as f64 * du;
                        *q = h.apply([u0 + (v - 0.5) * s.at(u0), v]);
                    }
                    for ((acc, &keep), &q) in accs.iter_mut().zip(keeps).zip(&grid) {
                        *acc = if keep {
                            *acc + g.at_img(q).unwrap_or(f64::NAN)
                        } else {
                            f64::NAN
                        };
                    }
                }
            }
            let c = mine.len().max(1) as f64;
            row.iter_mut().for_each(|x| *x /= c);
            let dv = mine.iter().map(|&j| level(j) - 0.5).sum::<f64>() / c;
            (row, dv)
        })
        .collect();
    let (prof, dv) = out.into_iter().unzip();
    Bands { prof, dv, du }
}

/// One window's best residual slant.
#[derive(Debug, Clone, Copy)]
pub(super) struct WinSlant {
    /// Window index.
    pub(super) idx: usize,
    /// Window centre (u0).
    pub(super) u: f64,
    /// Residual slant (px across the whole strip height).
    pub(super) d_px: f64,
    /// Image px per unit u at the window.
    pub(super) px_per_u: f64,
    /// Curvature of the energy at its peak, relative to incoherence (weight).
    pub(super) w: f64,
    /// Dominant frequency of the aligned bands (cycles/px along the strip).
    pub(super) freq_cy_px: f64,
}

/// Energy of the bands' sum over grid indices `i0..i1` (every `stride`-th) with
/// each band shifted by `dv·d` (d in grid steps), each band's window mean removed.
pub(super) fn energy(
    b: &Bands,
    means: &[f64],
    (i0, i1, stride): (usize, usize, usize),
    d: f64,
) -> f64 {
    aligned_sums(b, means, &band_shifts(b, d), (i0, i1, stride))
        .iter()
        .map(|v| v * v)
        .sum()
}

/// The bands' sums at grid indices `i0..i1` (every `stride`-th), each band
/// shifted by `shifts` (linear interpolation) and its window mean removed;
/// accumulated a band at a time over all indices (contiguous reads the
/// compiler vectorises).
pub(super) fn aligned_sums(
    b: &Bands,
    means: &[f64],
    shifts: &[(usize, f64)],
    (i0, i1, stride): (usize, usize, usize),
) -> Vec<f64> {
    let n = (i1 - i0).div_ceil(stride);
    let mut sums = vec![-0.0; n];
    for ((p, &(k, f)), &m) in b.prof.iter().zip(shifts).zip(means) {
        let j0 = i0.wrapping_add(k);
        let (here, next) = (&p[j0..], &p[j0 + 1..]);
        for ((acc, &x0), &x1) in sums
            .iter_mut()
            .zip(here.iter().step_by(stride))
            .zip(next.iter().step_by(stride))
        {
            *acc += x0 * (1.0 - f) + x1 * f - m;
        }
    }
    sums
}

/// Each band's shift `dv·d` (d in grid steps) as whole steps (wrapping for
/// negative shifts) and the fraction of a step.
pub(super) fn band_shifts(b: &Bands, d: f64) -> Vec<(usize, f64)> {
    b.dv.iter()
        .map(|dv| {
            let x = dv * d;
            let f = x.floor();
            (f as isize as usize, x - f)
        })
        .collect()
}

/// Energy the bands' sum would have with no alignment at all (no cross terms),
/// over the same samples as [`energy`].
pub(super) fn incoherent(b: &Bands, means: &[f64], (i0, i1, stride): (usize, usize, usize)) -> f64 {
    b.prof
        .iter()
        .zip(means)
        .map(|(p, m)| {
            p[i0..i1]
                .iter()
                .step_by(stride)
                .map(|v| (v - m).powi(2))
                .sum::<f64>()
        })
        .sum()
}

/// Dominant frequency (cycles per grid step) of the bands' sum aligned with shift `d`.
pub(super) fn dominant_freq(b: &Bands, means: &[f64], i0: usize, i1: usize, d: f64) -> f64 {
    let n = i1 - i0;
    let mut sum = aligned_sums(b, means, &band_shifts(b, d), (i0, i1, 1));
    for (k, v) in sum.iter_mut().enumerate() {
        *v *= 0.5 - 0.5 * (std::f64::consts::TAU * (k as f64 + 0.5) / n as f64).cos();
    }
    // Frequencies from 1.5 cycles per window to a quarter of the grid rate.
    let (lo, hi) = (1.5 / n as f64, 0.25);
    let steps = 96;
    let mut best = (0.0, lo);
    for k in 0..=steps {
        let f = lo + (hi - lo) * k as f64 / steps as f64;
        let (mut re, mut im) = (0.0, 0.0);
        let (c, s) = (
            (std::f64::consts::TAU * f).cos(),
            (std::f64::consts::TAU * f).sin(),
        );
        let (mut cr, mut ci) = (1.0, 0.0);
        for v in &sum {
            re += v * cr;
            im += v * ci;
            let t = cr * c - ci * s;
            ci = cr * s + ci * c;
            cr = t;
        }
        let p = re * re + im * im;
        if p > best.0 {
            best = (p, f);
        }
    }
    best.1
}

/// Searches each window (all, or those in `only`) for the residual slant
/// (±`range_px`, steps of `step_px`); windows without one clear peak are left out.
/// With `freq`, each window's dominant frequency is measured too (else 0).
pub(super) fn window_slants(
    b: &Bands,
    h: &Homography,
    range_px: f64,
    step_px: f64,
    only: Option<&[usize]>,
    freq: bool,
) -> Vec<WinSlant> {
    let n = b.prof[0].len();
    let dv_max = b.dv.iter().fold(0.0f64, |m, v| m.max(v.abs()));
    let all: Vec<usize> = (0..WINDOWS).collect();
    let one = |&w: &usize| -> Option<WinSlant> {
        // The window's centre part of at most WIN_MAX samples (long strips have plenty).
        let (a, z, i0, i1) = window_range(w, n);
        let uc = (a + z) as f64 * 0.5 * b.du;
        let px_per_u = {
            let (p, q) = (h.apply([uc - 0.01, 0.5]), h.apply([uc + 0.01, 0.5]));
            (q[0] - p[0]).hypot(q[1] - p[1]) / 0.02
        };
        // Largest shift in grid steps; the window must stay inside the grid.
        let steps_per_px = 1.0 / (px_per_u * b.du);
        let reach = (dv_max * range_px * steps_per_px).ceil() as usize + 2;
        if i0 < reach || i1 + reach >= n || i1 <= i0 + 16 {
            return None;
        }
        if b.prof
            .iter()
            .any(|p| p[i0 - reach..i1 + reach].iter().any(|v| !v.is_finite()))
        {
            return None;
        }
        let means: Vec<f64> = b
            .prof
            .iter()
            .map(|p| p[i0..i1].iter().sum::<f64>() / (i1 - i0) as f64)
            .collect();
        // The wide first search reads every other sample (0.5 px apart, still
        // over 4 per period below aliasing); the fine one reads them all.
        let span = (i0, i1, if only.is_none() { 2 } else { 1 });
        let inc = incoherent(b, &means, span).max(1e-300);
        let m = (range_px / step_px).round() as i64;
        let es: Vec<f64> = (-m..=m)
            .map(|k| energy(b, &means, span, k as f64 * step_px * steps_per_px) / inc)
            .collect();
        let (k, &emax) = es.iter().enumerate().max_by(|x, y| x.1.total_cmp(y.1))?;
        // The bands must line up clearly (more than twice the energy of no alignment)...
        if k == 0 || k + 1 == es.len() || emax < 2.0 {
            return None;
        }
        // ...and at one slant only (no rival peak half as far above incoherence).
        let sep = (1.0 / step_px).ceil() as usize;
        let rival = (1..es.len() - 1).any(|i| {
            i.abs_diff(k) > sep
                && es[i] >= es[i - 1]
                && es[i] >= es[i + 1]
                && es[i] - 1.0 >= 0.5 * (emax - 1.0)
        });
        let (e0, e1, e2) = (es[k - 1], es[k], es[k + 1]);
        let den = e0 - 2.0 * e1 + e2;
        if rival || den >= 0.0 {
            return None;
        }
        let sub = (0.5 * (e0 - e2) / den).clamp(-0.5, 0.5);
        let d_px = (k as f64 - m as f64 + sub) * step_px;
        let f = if freq {
            dominant_freq(b, &means, i0, i1, d_px * steps_per_px) * steps_per_px
        } else {
            0.0
        };
        Some(WinSlant {
            idx: w,
            u: uc,
            d_px,
            px_per_u,
            w: -den / (step_px * step_px),
            freq_cy_px: f,
        })
    };
    only.unwrap_or(&all).par_iter().filter_map(one).collect()
}
