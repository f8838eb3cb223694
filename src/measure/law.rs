//! The sweep's phase law along the strip, φ(s) in cycles, and its fit.
//!
//! Two families, matching the printed sweeps: linear (φ = c0 + c1·s + c2·s²,
//! frequency c1 + 2·c2·s) and logarithmic (φ = c0 + c1·(e^{k·s} − 1)/k,
//! frequency c1·e^{k·s}). The first guess comes from the profile's zero
//! crossings (or from the target description); [`fit_law`] refines it from
//! phase samples measured by local sine fits.

#![allow(clippy::needless_range_loop, clippy::neg_cmp_op_on_partial_ord)]

use super::profile::Profile;
use serde::{Deserialize, Serialize};

/// The family of a sweep's frequency law.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum LawKind {
    /// Frequency rises linearly with distance.
    Linear,
    /// Frequency rises exponentially with distance (log sweep).
    Log,
}

/// A phase law φ(s) (cycles) along a strip (s in strip units).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct PhaseLaw {
    /// Family.
    pub kind: LawKind,
    /// Phase at s = 0 (cycles).
    pub c0: f64,
    /// Frequency at s = 0 (cycles per strip unit).
    pub c1: f64,
    /// Linear: half the frequency slope (cycles per unit²); log: the rate k (1/unit).
    pub c2: f64,
}

impl PhaseLaw {
    /// Phase (cycles) at s.
    pub fn phase(&self, s: f64) -> f64 {
        match self.kind {
            LawKind::Linear => self.c0 + self.c1 * s + self.c2 * s * s,
            LawKind::Log => self.c0 + self.c1 * expm1_over(self.c2, s),
        }
    }

    /// Phase (cycles) and frequency (cycles per strip unit) at s, sharing one exponential.
    pub fn phase_freq(&self, s: f64) -> (f64, f64) {
        match self.kind {
            LawKind::Linear => (self.phase(s), self.freq(s)),
            LawKind::Log => {
                let em1 = (self.c2 * s).exp_m1();
                let phase = if (self.c2 * s).abs() < 1e-12 {
                    self.c0 + self.c1 * s
                } else {
                    self.c0 + self.c1 * em1 / self.c2
                };
                (phase, self.c1 * (1.0 + em1))
            }
        }
    }

    /// Frequency (cycles per strip unit) at s.
    pub fn freq(&self, s: f64) -> f64 {
        match self.kind {
            LawKind::Linear => self.c1 + 2.0 * self.c2 * s,
            LawKind::Log => self.c1 * (self.c2 * s).exp(),
        }
    }

    /// The s (within [lo, hi]) where the phase equals `phi`: the law's closed
    /// inverse polished by Newton steps, or bisection where that fails (the
    /// law is monotone on [lo, hi]).
    pub fn s_at_phase(&self, phi: f64, lo: f64, hi: f64) -> f64 {
        if let Some(s) = self.invert(phi)
            && s >= lo
            && s <= hi
        {
            let mut s = s;
            for _ in 0..2 {
                let f = self.freq(s);
                if !(f.is_finite() && f > 0.0) {
                    break;
                }
                s = (s - (self.phase(s) - phi) / f).clamp(lo, hi);
            }
            return s;
        }
        let (mut a, mut b) = (lo, hi);
        for _ in 0..80 {
            let m = 0.5 * (a + b);
            if self.phase(m) < phi {
                a = m;
            } else {
                b = m;
            }
        }
        0.5 * (a + b)
    }

    /// Closed inverse of the phase (None where it has no real solution).
    fn invert(&self, phi: f64) -> Option<f64> {
        let d = phi - self.c0;
        let s = match self.kind {
            // c2·s² + c1·s − d = 0, in the form without cancellation.
            LawKind::Linear => {
                let disc = self.c1 * self.c1 + 4.0 * self.c2 * d;
                if disc < 0.0 {
                    return None;
                }
                let q = self.c1 + disc.sqrt().copysign(self.c1);
                if q == 0.0 {
                    return None;
                }
                2.0 * d / q
            }
            // c1·(e^{k s} − 1)/k = d  ⇒  s = ln(1 + k d / c1)/k.
            LawKind::Log => {
                let x = self.c2 * d / self.c1;
                if (self.c2 * d).abs() < 1e-300 || x.abs() < 1e-12 {
                    d / self.c1
                } else {
                    x.ln_1p() / self.c2
                }
            }
        };
        s.is_finite().then_some(s)
    }
}

/// (e^{k·s} − 1)/k, stable as k → 0.
fn expm1_over(k: f64, s: f64) -> f64 {
    if (k * s).abs() < 1e-12 {
        s
    } else {
        (k * s).exp_m1() / k
    }
}

/// Weighted least-squares fit of a law of the given family to (s, phase, weight) samples; returns it and its weighted RMS residual (cycles).
pub fn fit_law(pts: &[(f64, f64, f64)], kind: LawKind) -> Option<(PhaseLaw, f64)> {
    if pts.len() < 4 {
        return None;
    }
    match kind {
        LawKind::Linear => {
            let (c, rms) = lsq(pts, |s| [1.0, s, s * s])?;
            Some((
                PhaseLaw {
                    kind,
                    c0: c[0],
                    c1: c[1],
                    c2: c[2],
                },
                rms,
            ))
        }
        LawKind::Log => {
            // Rate k by golden-section search, c0 and c1 by linear least squares.
            let (lin, _) = fit_law(pts, LawKind::Linear)?;
            let smin = pts.iter().map(|p| p.0).fold(f64::INFINITY, f64::min);
            let smax = pts.iter().map(|p| p.0).fold(f64::NEG_INFINITY, f64::max);
            let span = (smax - smin).max(1e-300);
            let (f0, f1) = (lin.freq(smin), lin.freq(smax));
            let k_guess = if f0 > 0.0 && f1 > 0.0 {
                (f1 / f0).ln() / span
            } else {
                1.0 / span
            };
            let cost = |k: f64| lsq2(pts, k).map(|(_, r)| r).unwrap_or(f64::INFINITY);
            let (mut a, mut b) = (
                -0.5 / span,
                (3.0 * k_guess.abs()).max(1.0 / span) + 10.0 / span,
            );
            let g = 0.5 * (5f64.sqrt() - 1.0);
            let mut x1 = b - g * (b - a);
            let mut x2 = a + g * (b - a);
            let (mut f1c, mut f2c) = (cost(x1), cost(x2));
            // 40 steps shrink the bracket by 4e-9: phase errors ≲ 1e-4 cycles over
            // a thousand-cycle sweep; a parabola through the last three points polishes k.
            for _ in 0..40 {
                if f1c < f2c {
                    b = x2;
                    x2 = x1;
                    f2c = f1c;
                    x1 = b - g * (b - a);
                    f1c = cost(x1);
                } else {
                    a = x1;
                    x1 = x2;
                    f1c = f2c;
                    x2 = a + g * (b - a);
                    f2c = cost(x2);
                }
            }
            let mid = 0.5 * (a + b);
            let k = parabola_min([(x1, f1c), (mid, cost(mid)), (x2, f2c)])
                .filter(|k| *k > a && *k < b && cost(*k) <= f1c.min(f2c))
                .unwrap_or(mid);
            let (c, rms) = lsq2(pts, k)?;
            Some((
                PhaseLaw {
                    kind,
                    c0: c[0],
                    c1: c[1],
                    c2: k,
                },
                rms,
            ))
        }
    }
}

/// The abscissa of the vertex of the parabola through three points (None when they are collinear).
fn parabola_min(p: [(f64, f64); 3]) -> Option<f64> {
    let [(x0, y0), (x1, y1), (x2, y2)] = p;
    let num = (x1 - x0).powi(2) * (y1 - y2) - (x1 - x2).powi(2) * (y1 - y0);
    let den = (x1 - x0) * (y1 - y2) - (x1 - x2) * (y1 - y0);
    (den.abs() > 0.0 && den.is_finite()).then(|| x1 - 0.5 * num / den)
}

fn lsq2(pts: &[(f64, f64, f64)], k: f64) -> Option<([f64; 2], f64)> {
    let (c, r) = lsq(pts, |s| [1.0, expm1_over(k, s), 0.0])?;
    Some(([c[0], c[1]], r))
}

/// Weighted least squares with up to three basis functions (a zero third column is dropped).
fn lsq(pts: &[(f64, f64, f64)], basis: impl Fn(f64) -> [f64; 3]) -> Option<([f64; 3], f64)> {
    // Each point's basis values once (they may cost an exponential each).
    let xs: Vec<[f64; 3]> = pts.iter().map(|p| basis(p.0)).collect();
    let third = xs.iter().any(|x| x[2] != 0.0);
    let n = if third { 3 } else { 2 };
    let mut a = [[0.0; 3]; 3];
    let mut r = [0.0; 3];
    let mut wsum = 0.0;
    for (&(_, y, w), x) in pts.iter().zip(&xs) {
        for i in 0..n {
            r[i] += w * x[i] * y;
            for j in 0..n {
                a[i][j] += w * x[i] * x[j];
            }
        }
        wsum += w;
    }
    let c = solve(&mut a, &mut r, n)?;
    let rss: f64 = pts
        .iter()
        .zip(&xs)
        .map(|(&(_, y, w), x)| {
            let p: f64 = (0..n).map(|i| c[i] * x[i]).sum();
            w * (y - p) * (y - p)
        })
        .sum();
    Some((c, (rss / wsum.max(1e-300)).sqrt()))
}

/// Solves a small symmetric system in place (Gaussian elimination with pivoting); `n` ≤ 3.
fn solve(a: &mut [[f64; 3]; 3], r: &mut [f64; 3], n: usize) -> Option<[f64; 3]> {
    // Scale columns for conditioning.
    let scale: Vec<f64> = (0..n).map(|i| a[i][i].abs().sqrt().max(1e-300)).collect();
    for i in 0..n {
        r[i] /= scale[i];
        for j in 0..n {
            a[i][j] /= scale[i] * scale[j];
        }
    }
    for col in 0..n {
        let piv = (col..n).max_by(|&i, &j| a[i][col].abs().total_cmp(&a[j][col].abs()))?;
        if a[piv][col].abs() < 1e-13 {
            return None;
        }
        a.swap(col, piv);
        r.swap(col, piv);
        for row in 0..n {
            if row != col {
                let f = a[row][col] / a[col][col];
                for j in 0..n {
                    a[row][j] -= f * a[col][j];
                }
                r[row] -= f * r[col];
            }
        }
    }
    let mut c = [0.0; 3];
    for i in 0..n {
        c[i] = r[i] / a[i][i] / scale[i];
    }
    Some(c)
}

/// The profile resampled onto its uniform bin grid (empty bins filled linearly): (s of bin 0 centre, step, values).
pub fn uniform(prof: &Profile) -> (f64, f64, Vec<f64>) {
    let bin = prof.bin;
    let n = ((prof.length / bin).ceil() as usize).max(1);
    let mut v = vec![f64::NAN; n];
    for k in 0..prof.s.len() {
        let b = ((prof.s[k] / bin) as usize).min(n - 1);
        v[b] = prof.y[k];
    }
    fill_gaps(&mut v);
    (0.5 * bin, bin, v)
}

/// Like [`uniform`], but on the finest grid (a whole multiple of the bin width, at most 8)
/// on which at most 5 % of the cells are empty, so that little needs filling in.
/// Each cell is the count-weighted mean of the bins that fall in it. Also returns the
/// mean variance of sample positions within a cell (strip units²).
pub fn uniform_dense(prof: &Profile) -> (f64, f64, Vec<f64>, f64) {
    let mut best = None;
    for k in 1..=8usize {
        let step = prof.bin * k as f64;
        let n = ((prof.length / step).ceil() as usize).max(1);
        let mut sum = vec![0.0f64; n];
        let mut cnt = vec![0.0f64; n];
        let mut ss = vec![0.0f64; n];
        let mut ss2 = vec![0.0f64; n];
        for i in 0..prof.s.len() {
            let b = ((prof.s[i] / step) as usize).min(n - 1);
            let c = prof.count[i];
            sum[b] += prof.y[i] * c;
            cnt[b] += c;
            ss[b] += prof.s[i] * c;
            ss2[b] += (prof.s[i] * prof.s[i] + prof.var_s[i]) * c;
        }
        let (mut vsum, mut vn) = (0.0f64, 0.0f64);
        for b in 0..n {
            if cnt[b] > 0.0 {
                let m = ss[b] / cnt[b];
                vsum += (ss2[b] / cnt[b] - m * m).max(0.0);
                vn += 1.0;
            }
        }
        let avg_var = vsum / vn.max(1.0);
        // Only the span between the first and last filled cells matters.
        let first = cnt.iter().position(|&c| c > 0.0).unwrap_or(0);
        let last = cnt.iter().rposition(|&c| c > 0.0).unwrap_or(0);
        let empty = cnt[first..=last].iter().filter(|&&c| c == 0.0).count();
        let mut v: Vec<f64> = (0..n)
            .map(|b| {
                if cnt[b] > 0.0 {
                    sum[b] / cnt[b]
                } else {
                    f64::NAN
                }
            })
            .collect();
        let ok = (empty as f64) <= 0.05 * (last + 1 - first) as f64;
        if ok || k == 8 {
            fill_gaps(&mut v);
            best = Some((0.5 * step, step, v, avg_var));
            break;
        }
    }
    best.unwrap_or_else(|| {
        let (a, b, v) = uniform(prof);
        (a, b, v, 0.0)
    })
}

fn fill_gaps(v: &mut [f64]) {
    let known: Vec<usize> = (0..v.len()).filter(|&i| v[i].is_finite()).collect();
    if known.is_empty() {
        v.iter_mut().for_each(|x| *x = 0.0);
        return;
    }
    let (first, last) = (known[0], *known.last().unwrap_or(&0));
    let (vf, vl) = (v[first], v[last]);
    v[..first].iter_mut().for_each(|x| *x = vf);
    v[last + 1..].iter_mut().for_each(|x| *x = vl);
    for w in known.windows(2) {
        let (a, b) = (w[0], w[1]);
        for i in a + 1..b {
            v[i] = v[a] + (v[b] - v[a]) * (i - a) as f64 / (b - a) as f64;
        }
    }
}

/// Moving average with a per-sample window half-width (in samples), by cumulative sums.
pub fn moving_mean(v: &[f64], half: impl Fn(usize) -> usize) -> Vec<f64> {
    let mut cum = Vec::with_capacity(v.len() + 1);
    cum.push(0.0);
    let mut acc = 0.0;
    for &x in v {
        acc += x;
        cum.push(acc);
    }
    (0..v.len())
        .map(|i| {
            let h = half(i);
            let a = i.saturating_sub(h);
            let b = (i + h + 1).min(v.len());
            (cum[b] - cum[a]) / (b - a) as f64
        })
        .collect()
}

/// Moving average over ±`half(i)` samples (fractional), treating samples as unit cells; by cumulative sums.
pub fn moving_mean_frac(v: &[f64], half: impl Fn(usize) -> f64) -> Vec<f64> {
    let n = v.len();
    let mut cum = Vec::with_capacity(n + 1);
    cum.push(0.0);
    let mut acc = 0.0;
    for &x in v {
        acc += x;
        cum.push(acc);
    }
    // Integral of the piecewise-constant signal from cell edge 0 to x.
    let integral = |x: f64| -> f64 {
        let x = x.clamp(0.0, n as f64);
        let k = (x.floor() as usize).min(n - 1);
        cum[k] + (x - k as f64) * v[k]
    };
    (0..n)
        .map(|i| {
            let h = half(i).max(0.5);
            let c = i as f64 + 0.5;
            let (a, b) = ((c - h).max(0.0), (c + h).min(n as f64));
            (integral(b) - integral(a)) / (b - a)
        })
        .collect()
}

/// Zero crossings of `d` with hysteresis `h[i]`: (position in samples, rising?).
fn crossings(d: &[f64], h: &[f64]) -> Vec<(f64, bool)> {
    let mut out = Vec::new();
    let mut state = 0i8;
    let mut last_zero = 0.0;
    for i in 0..d.len() {
        if i > 0 && (d[i - 1] < 0.0) != (d[i] < 0.0) {
            let t = d[i - 1] / (d[i - 1] - d[i]);
            last_zero = (i - 1) as f64 + t;
        }
        if d[i] > h[i] && state != 1 {
            if state == -1 {
                out.push((last_zero, true));
            }
            state = 1;
        } else if d[i] < -h[i] && state != -1 {
            if state == 1 {
                out.push((last_zero, false));
            }
            state = -1;
        }
    }
    out
}

/// (s, phase in cycles, weight) samples of a phase law.
pub type PhasePoints = Vec<(f64, f64, f64)>;

/// The profile's zero crossings as (s, phase) points over the well-resolved
/// low-frequency part (stops where the half-periods become irregular, the
/// oscillation fades, or `max_cy_px` is reached). `s_per_px` gives strip
/// units per pixel at s.
fn crossing_points(
    prof: &Profile,
    s_per_px: impl Fn(f64) -> f64,
    max_cy_px: f64,
) -> Option<PhasePoints> {
    let (s0, ds, v) = uniform(prof);
    let n = v.len();
    if n < 16 {
        return None;
    }
    // Pass 1: wide moving mean; pass 2: one local period.
    let mut trend = moving_mean(&v, |_| n / 16);
    let mut cross = Vec::new();
    for pass in 0..2 {
        let d: Vec<f64> = v.iter().zip(&trend).map(|(a, b)| a - b).collect();
        let sq: Vec<f64> = d.iter().map(|x| x * x).collect();
        let half_env = if pass == 0 {
            vec![n / 16; n]
        } else {
            local_half_period(&cross, n)
        };
        let rms = moving_mean(&sq, |i| half_env[i].max(2));
        let noise = noise_sigma(&v);
        let h: Vec<f64> = rms
            .iter()
            .map(|r| (0.35 * r.sqrt()).max(2.5 * noise))
            .collect();
        cross = crossings(&d, &h);
        if cross.len() < 4 {
            return None;
        }
        let hp = local_half_period(&cross, n);
        trend = moving_mean(&v, |i| hp[i]);
    }
    // Accept crossings while the half-periods shrink smoothly.
    let mut pts = Vec::new();
    let first_phase = if cross[0].1 { -0.25 } else { 0.25 };
    for (k, &(pos, _)) in cross.iter().enumerate() {
        let s = s0 + pos * ds;
        if k >= 2 {
            let p1 = cross[k].0 - cross[k - 1].0;
            let p0 = cross[k - 1].0 - cross[k - 2].0;
            if !(p1 > 0.45 * p0 && p1 < 1.8 * p0) {
                break;
            }
            // Frequency in cycles/pixel from the half-period.
            let f_px = s_per_px(s) / (2.0 * p1 * ds);
            if f_px > max_cy_px {
                break;
            }
        }
        pts.push((s, first_phase + 0.5 * k as f64, 1.0));
    }
    if pts.len() < 8 {
        return None;
    }
    Some(pts)
}

/// A first phase law from the profile's zero crossings: the best-fitting
/// family (or `kind`) over the regularly spaced crossings, with those
/// crossings as (s, phase, weight) points.
pub fn initial_law(
    prof: &Profile,
    kind: Option<LawKind>,
    s_per_px: impl Fn(f64) -> f64,
    max_cy_px: f64,
) -> Option<(PhaseLaw, PhasePoints)> {
    let kinds: &[LawKind] = match &kind {
        Some(k) => std::slice::from_ref(k),
        None => &[LawKind::Linear, LawKind::Log],
    };
    let (laws, pts) = initial_laws(prof, kinds, s_per_px, max_cy_px)?;
    let best = laws.into_iter().min_by(|a, b| a.1.total_cmp(&b.1))?;
    Some((best.0, pts))
}

/// First phase laws of each family in `kinds` (with their RMS residuals,
/// cycles) from one search for the profile's zero crossings.
pub fn initial_laws(
    prof: &Profile,
    kinds: &[LawKind],
    s_per_px: impl Fn(f64) -> f64,
    max_cy_px: f64,
) -> Option<(Vec<(PhaseLaw, f64)>, PhasePoints)> {
    let pts = crossing_points(prof, s_per_px, max_cy_px)?;
    let laws: Vec<_> = kinds.iter().filter_map(|&k| fit_law(&pts, k)).collect();
    (!laws.is_empty()).then_some((laws, pts))
}

/// Half a local period (in samples) at every sample, from crossings (which are half a period apart).
fn local_half_period(cross: &[(f64, bool)], n: usize) -> Vec<usize> {
    let mut out = vec![n / 16; n];
    if cross.len() < 2 {
        return out;
    }
    let mut k = 0;
    for (i, o) in out.iter_mut().enumerate() {
        let x = i as f64;
        while k + 2 < cross.len() && cross[k + 1].0 < x {
            k += 1;
        }
        let hp = cross[k + 1].0 - cross[k].0;
        *o = (hp.round() as usize).max(1);
    }
    out
}

/// Robust noise estimate of a uniformly sampled profile (from second differences).
pub fn noise_sigma(v: &[f64]) -> f64 {
    if v.len() < 3 {
        return 0.0;
    }
    let mut d: Vec<f64> = v
        .windows(3)
        .map(|w| (w[0] - 2.0 * w[1] + w[2]).abs())
        .collect();
    let mid = d.len() / 2;
    d.select_nth_unstable_by(mid, |a, b| a.total_cmp(b));
    d[mid] * 1.4826 / 6f64.sqrt()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn fits_recover_both_families() {
        let lin = PhaseLaw {
            kind: LawKind::Linear,
            c0: 0.3,
            c1: 0.01,
            c2: 2e-5,
        };
        let log = PhaseLaw {
            kind: LawKind::Log,
            c0: -0.1,
            c1: 0.01,
            c2: 0.0025,
        };
        for law in [lin, log] {
            let pts: Vec<_> = (0..200)
                .map(|i| {
                    let s = i as f64 * 8.0;
                    (s, law.phase(s), 1.0)
                })
                .collect();
            let (fit, rms) = fit_law(&pts, law.kind).unwrap();
            assert!(rms < 1e-6, "{rms}");
            for s in [0.0, 500.0, 1500.0] {
                assert!((fit.freq(s) / law.freq(s) - 1.0).abs() < 1e-6);
            }
            let s = law.s_at_phase(law.phase(777.0), 0.0, 1600.0);
            assert!((s - 777.0).abs() < 1e-6);
        }
    }

    #[test]
    fn finds_a_chirp_from_crossings() {
        let law = PhaseLaw {
            kind: LawKind::Linear,
            c0: 0.1,
            c1: 0.01,
            c2: 0.4 / 4000.0 / 2.0,
        };
        let n = 4000 * 4;
        let prof = Profile {
            s: (0..n).map(|i| (i as f64 + 0.5) * 0.25).collect(),
            y: (0..n)
                .map(|i| {
                    let s = (i as f64 + 0.5) * 0.25;
                    0.4 + 0.00002 * s + 0.2 * (2.0 * std::f64::consts::PI * law.phase(s)).cos()
                })
                .collect(),
            count: vec![1.0; n],
            var_s: vec![0.0; n],
            bin: 0.25,
            length: 4000.0,
            ..Profile::default()
        };
        let (fit, pts) = initial_law(&prof, None, |_| 1.0, 0.3).unwrap();
        assert!(pts.len() > 100);
        assert_eq!(fit.kind, LawKind::Linear);
        for s in [100.0, 1000.0, 2000.0] {
            assert!((fit.freq(s) / law.freq(s) - 1.0).abs() < 0.01, "{s}");
        }
    }

    #[test]
    fn phase_inverse_matches_bisection_on_stiff_laws() {
        // Truth by brute bisection on the phase itself (the law is monotone).
        let bisect = |l: &PhaseLaw, phi: f64, lo: f64, hi: f64| {
            let (mut a, mut b) = (lo, hi);
            for _ in 0..200 {
                let m = 0.5 * (a + b);
                if l.phase(m) < phi { a = m } else { b = m }
            }
            0.5 * (a + b)
        };
        let laws = [
            (LawKind::Linear, 0.3, 0.01, 2e-5),
            (LawKind::Linear, -2.0, 0.02, 1e-14),
            (LawKind::Linear, 0.0, 0.5, 0.0),
            (LawKind::Linear, 0.1, 0.4, -5e-5), // falling chirp, monotone on [0, 1600]
            (LawKind::Log, -0.1, 0.01, 0.0025),
            (LawKind::Log, 0.2, 0.05, 1e-13),
            (LawKind::Log, 0.0, 1e-3, 0.009),
        ];
        for (kind, c0, c1, c2) in laws {
            let l = PhaseLaw { kind, c0, c1, c2 };
            for s in [0.0, 1e-9, 3.7, 777.0, 1599.0, 1600.0] {
                let phi = l.phase(s);
                let got = l.s_at_phase(phi, 0.0, 1600.0);
                let want = bisect(&l, phi, 0.0, 1600.0);
                let tol = 1e-9 * (1.0 + s);
                assert!((got - want).abs() <= tol, "{l:?} s={s}: {got} vs {want}");
            }
            for s in [0.0, 1e-9, 3.7, 777.0, 1600.0] {
                let (ph, f) = l.phase_freq(s);
                assert!(
                    (ph - l.phase(s)).abs() <= 1e-12 * (1.0 + ph.abs()),
                    "{l:?} {s}"
                );
                assert!((f - l.freq(s)).abs() <= 1e-12 * f.abs(), "{l:?} {s}");
            }
            // Outside the range: clamps like bisection does.
            let got = l.s_at_phase(l.phase(0.0) - 5.0, 0.0, 1600.0);
            assert!(got.abs() < 1e-9, "{l:?}: {got}");
        }
    }
}
