//! The sweep's phase law along the strip, φ(s) in cycles, and its fits.
//!
//! Two families, matching the printed sweeps: linear (φ = c0 + c1·s + c2·s²,
//! frequency c1 + 2·c2·s) and logarithmic (φ = c0 + c1·(e^{k·s} − 1)/k,
//! frequency c1·e^{k·s}). The first guess comes from the profile's zero
//! crossings (or from the target description); [`fit_law`] refines it from
//! phase samples measured by local sine fits.

#![allow(clippy::needless_range_loop, clippy::neg_cmp_op_on_partial_ord)]

use serde::{Deserialize, Serialize};

mod fit;
pub use fit::{fit_law, fit_perspective};

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
    /// Foreshortening along the strip that its corners missed (1/unit): the
    /// law above holds in x = s/(1 + persp·s), the chart's own coordinate
    /// under a keystone the corners do not show (0: none; see [`fit_perspective`]).
    #[serde(default)]
    pub persp: f64,
}

impl PhaseLaw {
    /// The law's own coordinate x (strip units) at s: s/(1 + persp·s).
    fn x_of(&self, s: f64) -> f64 {
        if self.persp == 0.0 {
            s
        } else {
            s / (1.0 + self.persp * s)
        }
    }

    /// dx/ds at s (1 without foreshortening).
    fn dx_ds(&self, s: f64) -> f64 {
        if self.persp == 0.0 {
            1.0
        } else {
            (1.0 + self.persp * s).powi(-2)
        }
    }

    /// Phase (cycles) at s.
    pub fn phase(&self, s: f64) -> f64 {
        let s = self.x_of(s);
        match self.kind {
            LawKind::Linear => self.c0 + self.c1 * s + self.c2 * s * s,
            LawKind::Log => self.c0 + self.c1 * expm1_over(self.c2, s),
        }
    }

    /// Phase (cycles) and frequency (cycles per strip unit) at s, sharing one exponential.
    pub fn phase_freq(&self, s: f64) -> (f64, f64) {
        let d = self.dx_ds(s);
        let s = self.x_of(s);
        match self.kind {
            LawKind::Linear => (
                self.c0 + self.c1 * s + self.c2 * s * s,
                (self.c1 + 2.0 * self.c2 * s) * d,
            ),
            LawKind::Log => {
                let em1 = (self.c2 * s).exp_m1();
                let phase = if (self.c2 * s).abs() < 1e-12 {
                    self.c0 + self.c1 * s
                } else {
                    self.c0 + self.c1 * em1 / self.c2
                };
                (phase, self.c1 * (1.0 + em1) * d)
            }
        }
    }

    /// Frequency (cycles per strip unit) at s.
    pub fn freq(&self, s: f64) -> f64 {
        let d = self.dx_ds(s);
        let s = self.x_of(s);
        d * match self.kind {
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
        // Back from the law's own coordinate: s = x/(1 − persp·x).
        let s = if self.persp == 0.0 {
            s
        } else {
            s / (1.0 - self.persp * s)
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

#[cfg(test)]
mod tests {
    use super::*;

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
        // The last entries are foreshortened (persp·1600 = ±0.25, the fit's limit, and small).
        let laws = [
            (LawKind::Linear, 0.3, 0.01, 2e-5, 0.0),
            (LawKind::Linear, -2.0, 0.02, 1e-14, 0.0),
            (LawKind::Linear, 0.0, 0.5, 0.0, 0.0),
            (LawKind::Linear, 0.1, 0.4, -5e-5, 0.0), // falling chirp, monotone on [0, 1600]
            (LawKind::Log, -0.1, 0.01, 0.0025, 0.0),
            (LawKind::Log, 0.2, 0.05, 1e-13, 0.0),
            (LawKind::Log, 0.0, 1e-3, 0.009, 0.0),
            (LawKind::Linear, 0.3, 0.01, 2e-5, 0.25 / 1600.0),
            (LawKind::Linear, 0.3, 0.01, 2e-5, -0.25 / 1600.0),
            (LawKind::Log, -0.1, 0.01, 0.0025, 1e-3 / 1600.0),
            (LawKind::Log, 0.0, 1e-3, 0.009, -0.25 / 1600.0),
        ];
        for (kind, c0, c1, c2, persp) in laws {
            let l = PhaseLaw {
                kind,
                c0,
                c1,
                c2,
                persp,
            };
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
