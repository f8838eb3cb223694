//! The sweep's phase law along the strip, φ(s) in cycles, and its fit.
//!
//! Two families, matching the printed sweeps: linear (φ = c0 + c1·s + c2·s²,
//! frequency c1 + 2·c2·s) and logarithmic (φ = c0 + c1·(e^{k·s} − 1)/k,
//! frequency c1·e^{k·s}). The first guess comes from the profile's zero
//! crossings (or from the target description); [`fit_law`] refines it from
//! phase samples measured by local sine fits.

#![allow(clippy::needless_range_loop, clippy::neg_cmp_op_on_partial_ord)]

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
