//! A single strip's end lines from its printed bars. With the strip's long
//! edges fitted, each corner can only slide along its long edge; what matters
//! for the measurement is that the homography's iso-u lines (the bins average
//! across the strip along them) run along the printed bars. In the strip's
//! current frame (u along, v across, the unit square) every bar is a straight
//! line through one point (the image of the bars' vanishing point), so a bar
//! crossing the centre line at `u0` is `u = u0 + (v − ½)·s(u0)` with a slant
//! `s` that is exactly linear in `u0`.
//!
//! The slant is measured from the image: lines of constant v (about a pixel
//! apart, at most 32, sheared along the current slant estimate) are sampled
//! every 0.25 px along the strip and grouped into 12 bands; in 24 windows along
//! the strip the residual slant that makes the bands' sum most energetic (the
//! bars line up) is found. Only windows below aliasing count (from the
//! low-frequency end while the frequency rises, ≤ 0.42 cy/px): beyond, the bars
//! alias into patterns of other directions. A robust weighted line through the
//! windows' slants updates `s`; two passes, a wide coarse search and a fine
//! one. The end lines are then the bars through the current ends' centre
//! points, so the strip's extent (already kept inside the user's lines) is
//! unchanged and only the slant is corrected.

use super::sample::Gray;
use crate::geometry::{Homography, Point};
use rayon::prelude::*;

/// The slant correction found for a strip's ends.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct EndsFit {
    /// New corners (image px): the long edges' lines, ends along the bars.
    pub corners: [Point; 4],
    /// Slant of the bars at the low-u and high-u end: shift along the strip (image px)
    /// from the v = 0 edge to the v = 1 edge, relative to the given ends.
    pub slant_px: [f64; 2],
    /// Windows agreeing with the fitted slant line in the last pass.
    pub windows: usize,
    /// Weighted RMS of those windows' slants about the line (px).
    pub rms_px: f64,
}

/// Sample step along the strip (image px).
const STEP_PX: f64 = 0.25;
/// Across-strip range sampled (v), inside the long edges.
const V_RANGE: (f64, f64) = (0.15, 0.85);
/// Bands the sampled lines are grouped into.
const BANDS: usize = 12;
/// Windows along the strip (half-overlapping).
const WINDOWS: usize = 24;
/// Most samples of a window searched (its centre part; 120 px).
const WIN_MAX: usize = 480;

/// Slant model: `s(u0) = a + b·u0` (u per unit v).
#[derive(Debug, Clone, Copy)]
struct Slant {
    a: f64,
    b: f64,
}

impl Slant {
    fn at(&self, u0: f64) -> f64 {
        self.a + self.b * u0
    }
}

/// The lines of constant v, sampled along the bars of slant `s`, averaged into bands.
struct Bands {
    /// Band profiles on the u0 grid (NaN where outside the image).
    prof: Vec<Vec<f64>>,
    /// Mean v of each band, minus ½.
    dv: Vec<f64>,
    /// Grid step in u.
    du: f64,
}

/// Window `w` of a grid of `n` samples: its range (a, z) and the centre part
/// (i0, i1) of at most [`WIN_MAX`] samples that is searched.
fn window_range(w: usize, n: usize) -> (usize, usize, usize, usize) {
    let len = 2 * n / (WINDOWS + 1);
    let start = w * len / 2;
    let (a, z) = (start, (start + len).min(n));
    let cut = (z - a).saturating_sub(WIN_MAX) / 2;
    (a, z, a + cut, z - cut)
}

/// Which grid samples the search of `windows` reads, shifts of up to
/// ±`range_px` across the strip included (a bound: |v − ½| ≤ ½).
fn needed(h: &Homography, n: usize, windows: &[usize], range_px: f64) -> Vec<bool> {
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
fn sample_bands(
    g: &Gray<'_>,
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
                        *q = g.to_grid(h.apply([u0 + (v - 0.5) * s.at(u0), v]));
                    }
                    for ((acc, &keep), &q) in accs.iter_mut().zip(keeps).zip(&grid) {
                        *acc = if keep {
                            *acc + g.bilinear(q).unwrap_or(f64::NAN)
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
struct WinSlant {
    /// Window index.
    idx: usize,
    /// Window centre (u0).
    u: f64,
    /// Residual slant (px across the whole strip height).
    d_px: f64,
    /// Image px per unit u at the window.
    px_per_u: f64,
    /// Curvature of the energy at its peak, relative to incoherence (weight).
    w: f64,
    /// Dominant frequency of the aligned bands (cycles/px along the strip).
    freq_cy_px: f64,
}

/// Energy of the bands' sum over grid indices `i0..i1` (every `stride`-th) with
/// each band shifted by `dv·d` (d in grid steps), each band's window mean removed.
fn energy(b: &Bands, means: &[f64], (i0, i1, stride): (usize, usize, usize), d: f64) -> f64 {
    aligned_sums(b, means, &band_shifts(b, d), (i0, i1, stride))
        .iter()
        .map(|v| v * v)
        .sum()
}

/// The bands' sums at grid indices `i0..i1` (every `stride`-th), each band
/// shifted by `shifts` (linear interpolation) and its window mean removed;
/// accumulated a band at a time over all indices (contiguous reads the
/// compiler vectorises).
fn aligned_sums(
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
fn band_shifts(b: &Bands, d: f64) -> Vec<(usize, f64)> {
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
fn incoherent(b: &Bands, means: &[f64], (i0, i1, stride): (usize, usize, usize)) -> f64 {
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
fn dominant_freq(b: &Bands, means: &[f64], i0: usize, i1: usize, d: f64) -> f64 {
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
fn window_slants(
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

/// The windows of the sweep below `F_MAX` cycles/px, walking from its low-frequency
/// end while the frequency keeps rising (beyond, the bars alias into patterns of
/// other directions).
fn below_aliasing(ws: Vec<WinSlant>) -> Vec<WinSlant> {
    let walk = |ordered: &mut dyn Iterator<Item = &WinSlant>| -> Vec<WinSlant> {
        let mut out: Vec<WinSlant> = Vec::new();
        let mut top = 0.0f64;
        for w in ordered {
            if w.freq_cy_px > F_MAX || w.freq_cy_px < 0.7 * top {
                break;
            }
            top = top.max(w.freq_cy_px);
            out.push(*w);
        }
        out
    };
    // From whichever end gives the longer rising run (the user's corners may start at
    // either end).
    let up = walk(&mut ws.iter());
    let down = walk(&mut ws.iter().rev());
    if down.len() > up.len() { down } else { up }
}

/// Highest local frequency (cycles/px along the strip) a window may have.
const F_MAX: f64 = 0.42;

/// A robust line through the windows' slants.
struct LineFit {
    /// The slant correction.
    line: Slant,
    /// Windows kept.
    inliers: usize,
    /// Their weighted RMS about the line (px).
    rms_px: f64,
    /// Standard error of the line at u = 0 and u = 1 (u per unit v), from the scatter.
    sigma_u: [f64; 2],
}

/// Robust weighted line `d_u = a + b·u` through the windows' slants (in u per unit v).
fn fit_line(ws: &[WinSlant]) -> Option<LineFit> {
    let mut keep = vec![true; ws.len()];
    let mut line = Slant { a: 0.0, b: 0.0 };
    for _ in 0..4 {
        let (mut s0, mut s1, mut s2, mut t0, mut t1) = (0.0, 0.0, 0.0, 0.0, 0.0);
        for (w, _) in ws.iter().zip(&keep).filter(|x| *x.1) {
            // A slant's weight in u units: the energy's curvature (per px²) scaled.
            let y = w.d_px / w.px_per_u;
            let wt = w.w * w.px_per_u * w.px_per_u;
            s0 += wt;
            s1 += wt * w.u;
            s2 += wt * w.u * w.u;
            t0 += wt * y;
            t1 += wt * w.u * y;
        }
        let det = s0 * s2 - s1 * s1;
        if s0 <= 0.0 || det.abs() <= 1e-12 * s0 * s0 {
            return None;
        }
        line = Slant {
            a: (t0 * s2 - t1 * s1) / det,
            b: (s0 * t1 - s1 * t0) / det,
        };
        // Residuals in px; a robust scale from the median of their sizes.
        let res: Vec<f64> = ws
            .iter()
            .map(|w| (w.d_px - line.at(w.u) * w.px_per_u).abs())
            .collect();
        let mut r: Vec<f64> = res
            .iter()
            .zip(&keep)
            .filter(|x| *x.1)
            .map(|x| *x.0)
            .collect();
        r.sort_by(f64::total_cmp);
        let scale = (1.4826 * r[r.len() / 2]).max(0.05);
        let next: Vec<bool> = res.iter().map(|r| *r <= 3.0 * scale).collect();
        if next == keep {
            break;
        }
        keep = next;
        if keep.iter().filter(|k| **k).count() < 3 {
            return None;
        }
    }
    let (mut se, mut sw, mut n) = (0.0, 0.0, 0);
    let (mut s0, mut s1, mut s2, mut su) = (0.0, 0.0, 0.0, 0.0);
    for (w, _) in ws.iter().zip(&keep).filter(|x| *x.1) {
        let r = w.d_px - line.at(w.u) * w.px_per_u;
        se += w.w * r * r;
        sw += w.w;
        n += 1;
        let wt = w.w * w.px_per_u * w.px_per_u;
        let ru = r / w.px_per_u;
        s0 += wt;
        s1 += wt * w.u;
        s2 += wt * w.u * w.u;
        su += wt * ru * ru;
    }
    // Residual variance per unit weight (at least that of a 0.05 px scatter).
    let det = s0 * s2 - s1 * s1;
    let dof = (n as f64 - 2.0).max(1.0);
    let var0 = su.max(0.05f64.powi(2) * sw) / dof;
    let sd = |u: f64| {
        (var0 * (s2 - 2.0 * u * s1 + u * u * s0) / det)
            .max(0.0)
            .sqrt()
    };
    Some(LineFit {
        line,
        inliers: n,
        rms_px: (se / sw.max(1e-300)).sqrt(),
        sigma_u: [sd(0.0), sd(1.0)],
    })
}

/// Finds the bars' slant in the strip `h` (unit square → image, long edges fitted,
/// ends already inside the strip) and returns the corners whose end lines run
/// along the bars through the current ends' centre points. `max_slant_px` bounds
/// the correction at each end. `Err` says why the bars were not clearly seen.
pub fn align_ends(g: &Gray<'_>, h: &Homography, max_slant_px: f64) -> Result<EndsFit, String> {
    let dist = |p: Point, q: Point| (p[0] - q[0]).hypot(p[1] - q[1]);
    let len_px = dist(h.apply([0.0, 0.5]), h.apply([1.0, 0.5]));
    let wid_px = 0.5 * (dist(h.apply([0.0, 0.0]), h.apply([0.0, 1.0])))
        + 0.5 * dist(h.apply([1.0, 0.0]), h.apply([1.0, 1.0]));
    if !(len_px.is_finite() && wid_px.is_finite()) || len_px < 64.0 || wid_px < 8.0 {
        return Err(format!(
            "the strip ({len_px:.0} × {wid_px:.0} px) is too small to see its bars' direction"
        ));
    }
    let n = ((len_px / STEP_PX).ceil() as usize + 1).min(60_000);
    // About one line per pixel across the strip (at most 32: enough samples on a
    // wide strip, and the cost stays bounded).
    let lines = (((V_RANGE.1 - V_RANGE.0) * wid_px).round() as usize).clamp(BANDS, 32);
    let px_per_u = |u: f64| {
        let (p, q) = (h.apply([u - 0.01, 0.5]), h.apply([u + 0.01, 0.5]));
        dist(p, q) / 0.02
    };
    let mut s = Slant { a: 0.0, b: 0.0 };
    let passes = [(max_slant_px, 0.5), (1.5, 0.25)];
    let mut last = (0, f64::NAN);
    // The windows below aliasing, chosen in the first pass.
    let mut chosen: Option<Vec<usize>> = None;
    for &(range, step) in &passes {
        let all: Vec<usize> = (0..WINDOWS).collect();
        let keep = needed(h, n, chosen.as_deref().unwrap_or(&all), range);
        let bands = sample_bands(g, h, n, lines, s, &keep);
        let ws = match &chosen {
            None => {
                let ws = below_aliasing(window_slants(&bands, h, range, step, None, true));
                chosen = Some(ws.iter().map(|w| w.idx).collect());
                ws
            }
            Some(only) => window_slants(&bands, h, range, step, Some(only), false),
        };
        if ws.len() < 4 {
            return Err(format!(
                "the bars' direction is not clearly seen ({} of {WINDOWS} windows along the strip)",
                ws.len()
            ));
        }
        let Some(fit) = fit_line(&ws) else {
            return Err("the bars' direction is not clearly seen (windows disagree)".into());
        };
        let span = {
            let us: Vec<f64> = ws.iter().map(|w| w.u).collect();
            us.iter().cloned().fold(f64::NEG_INFINITY, f64::max)
                - us.iter().cloned().fold(f64::INFINITY, f64::min)
        };
        // Seen over enough of the strip that the slant carries to both ends: a
        // third of it, or a tenth when the line's scatter predicts the ends to
        // 0.25 px.
        let sigma_px = [
            fit.sigma_u[0] * px_per_u(0.0),
            fit.sigma_u[1] * px_per_u(1.0),
        ];
        let carries = span >= 0.3 || (span >= 0.1 && sigma_px.iter().all(|v| *v <= 0.25));
        if fit.inliers < 4 || !carries {
            return Err(format!(
                "the bars' direction is seen over too little of the strip ({} windows over {:.0} %; \
                 ends predicted to ±{:.2} / ±{:.2} px)",
                fit.inliers,
                100.0 * span,
                sigma_px[0],
                sigma_px[1]
            ));
        }
        s = Slant {
            a: s.a + fit.line.a,
            b: s.b + fit.line.b,
        };
        last = (fit.inliers, fit.rms_px);
    }
    let slant_px = [s.at(0.0) * px_per_u(0.0), s.at(1.0) * px_per_u(1.0)];
    if slant_px
        .iter()
        .any(|v| !v.is_finite() || v.abs() > max_slant_px)
    {
        return Err(format!(
            "the bars' direction found ({:.1} / {:.1} px across the strip) is beyond the corners' range",
            slant_px[0], slant_px[1]
        ));
    }
    if last.1 > 0.3 {
        return Err(format!(
            "the bars' direction is unclear (windows scatter {:.2} px about the fit)",
            last.1
        ));
    }
    let corners = [
        h.apply([-0.5 * s.at(0.0), 0.0]),
        h.apply([1.0 - 0.5 * s.at(1.0), 0.0]),
        h.apply([1.0 + 0.5 * s.at(1.0), 1.0]),
        h.apply([0.5 * s.at(0.0), 1.0]),
    ];
    Ok(EndsFit {
        corners,
        slant_px,
        windows: last.0,
        rms_px: last.1,
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::photo::Plane;

    /// A log sweep strip (0.02 → 0.6 cycles/px along 600 px, so its last part aliases)
    /// rendered under perspective on white, 4×4 supersampled, and the strip's true
    /// homography (unit square → image).
    fn render(contrast: f64) -> (Plane, Homography) {
        let (w, h) = (720usize, 260usize);
        let truth = Homography::from_quads(
            &[[0.0, 0.0], [1.0, 0.0], [1.0, 1.0], [0.0, 1.0]],
            &[[52.3, 61.7], [668.1, 40.2], [655.4, 201.9], [60.8, 181.1]],
        )
        .unwrap();
        let inv = truth.inverse().unwrap();
        let (f0, f1, len) = (0.02f64, 0.6f64, 600.0);
        let r = f1 / f0;
        let phase = |u: f64| len * f0 * (r.powf(u) - 1.0) / r.ln();
        let mut data = vec![0f32; w * h];
        for y in 0..h {
            for x in 0..w {
                let mut acc = 0.0;
                for sy in 0..4 {
                    for sx in 0..4 {
                        let p = [
                            x as f64 + (sx as f64 + 0.5) / 4.0,
                            y as f64 + (sy as f64 + 0.5) / 4.0,
                        ];
                        let q = inv.apply(p);
                        acc += if (0.0..=1.0).contains(&q[0]) && (0.0..=1.0).contains(&q[1]) {
                            0.5 + 0.5 * contrast * (std::f64::consts::TAU * phase(q[0])).cos()
                        } else {
                            1.0
                        };
                    }
                }
                data[y * w + x] = (acc / 16.0) as f32;
            }
        }
        (Plane::full(w, h, data), truth)
    }

    /// Corners on the true long edges at the given u (top, bottom) for each end.
    fn on_edges(truth: &Homography, u: [[f64; 2]; 2]) -> Homography {
        let c = [
            truth.apply([u[0][0], 0.0]),
            truth.apply([u[1][0], 0.0]),
            truth.apply([u[1][1], 1.0]),
            truth.apply([u[0][1], 1.0]),
        ];
        Homography::from_quads(&[[0.0, 0.0], [1.0, 0.0], [1.0, 1.0], [0.0, 1.0]], &c).unwrap()
    }

    #[test]
    fn slanted_ends_are_turned_along_the_bars() {
        let (plane, truth) = render(0.8);
        let g = Gray::of_plane(&plane);
        // Ends slanted by about ±6 px (0.01 of the length) the opposite ways.
        let given = on_edges(&truth, [[0.02, 0.03], [0.985, 0.975]]);
        let fit = align_ends(&g, &given, 20.0).unwrap();
        let inv = truth.inverse().unwrap();
        let q = fit.corners.map(|p| inv.apply(p));
        // Each new end is one bar: the same u (true frame) at both long edges.
        let px = 600.0;
        assert!(((q[3][0] - q[0][0]) * px).abs() < 0.15, "{q:?}");
        assert!(((q[2][0] - q[1][0]) * px).abs() < 0.3, "{q:?}");
        // On the long edges, and pivoted about the given ends' centres.
        for (k, v) in [(0, 0.0), (1, 0.0), (2, 1.0), (3, 1.0)] {
            assert!((q[k][1] - v).abs() < 1e-9, "{q:?}");
        }
        assert!((0.5 * (q[0][0] + q[3][0]) - 0.025).abs() < 0.002, "{q:?}");
        assert!((0.5 * (q[1][0] + q[2][0]) - 0.98).abs() < 0.002, "{q:?}");
    }

    #[test]
    fn corners_given_from_the_high_frequency_end_work_too() {
        let (plane, truth) = render(0.8);
        let g = Gray::of_plane(&plane);
        // The same strip with the corners' order turned by two (u and v reversed).
        let c = [
            truth.apply([0.975, 1.0]),
            truth.apply([0.03, 1.0]),
            truth.apply([0.02, 0.0]),
            truth.apply([0.985, 0.0]),
        ];
        let given =
            Homography::from_quads(&[[0.0, 0.0], [1.0, 0.0], [1.0, 1.0], [0.0, 1.0]], &c).unwrap();
        let fit = align_ends(&g, &given, 20.0).unwrap();
        let q = fit.corners.map(|p| truth.inverse().unwrap().apply(p));
        // Corners 0/3 are now the high-frequency end, 1/2 the low one.
        assert!(((q[3][0] - q[0][0]) * 600.0).abs() < 0.3, "{q:?}");
        assert!(((q[2][0] - q[1][0]) * 600.0).abs() < 0.15, "{q:?}");
    }

    #[test]
    fn low_contrast_strip_still_gives_the_bars() {
        let (plane, truth) = render(0.1);
        let g = Gray::of_plane(&plane);
        let given = on_edges(&truth, [[0.03, 0.02], [0.97, 0.98]]);
        let fit = align_ends(&g, &given, 20.0).unwrap();
        let q = fit.corners.map(|p| truth.inverse().unwrap().apply(p));
        assert!(((q[3][0] - q[0][0]) * 600.0).abs() < 0.15, "{q:?}");
    }

    #[test]
    fn a_strip_without_bars_is_refused() {
        let (w, h) = (400usize, 120usize);
        let plane = Plane::full(w, h, vec![0.5; w * h]);
        let g = Gray::of_plane(&plane);
        let given = Homography::from_quads(
            &[[0.0, 0.0], [1.0, 0.0], [1.0, 1.0], [0.0, 1.0]],
            &[[20.0, 20.0], [380.0, 22.0], [378.0, 100.0], [22.0, 98.0]],
        )
        .unwrap();
        let e = align_ends(&g, &given, 20.0).unwrap_err();
        assert!(e.contains("not clearly seen"), "{e}");
    }
}
