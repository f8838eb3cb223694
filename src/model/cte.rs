//! Charge transfer inefficiency (`--cte n=..,cti=..,pitch=..[,model=exp|exact][,axis=u|v]`).
//!
//! After N transfers with inefficiency ε = cti = 1 − CTE along a register of
//! pitch p, a charge packet becomes a binomial distribution over N pixels.
//! With x = f·p (f = u or v, the transfer axis):
//! - `exact`: OTF = ((1−ε) + ε·e^(−j2πx))^N, complex (the trailing charge
//!   shifts the image). Evaluated in polar form: |z|² = 1 − 4ε(1−ε)sin²(πx),
//!   so ln|z^N| = (N/2)·log1p(−4ε(1−ε)sin²(πx)) and
//!   arg z^N = N·atan2(−ε sin 2πx, 1 − 2ε sin²(πx)); for ε > 1/2 the factor
//!   e^(−j2πx) is pulled out and N·x is reduced modulo 1 with an error-free
//!   product; where N·arg z is large (small x, |OTF| still large) arg z is
//!   formed in double-double. No repeated multiplication: accurate for N up
//!   to 1e9 and ε down to 1e-12 (and ε = 1, a pure N-pixel shift).
//! - `exp` (published, the default): exp(−N·ε·(1 − cos 2πx)), evaluated as
//!   exp(−2Nε·sin²(πx)). It is the magnitude of the exact form to first
//!   order in ε.
//!
//! `cte=` may be given instead of `cti=` (ε = 1 − CTE; prefer `cti=` for
//! very small ε, since 1 − CTE loses digits). N is a whole number ≥ 0.

use super::params::Params;
use super::trig::{frac_prod, sin_pi, two_prod};
use super::{Factor, ModelError};
use num_complex::Complex64;
use std::f64::consts::PI;

/// Which CTE formula.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum CteModel {
    /// exp(−Nε(1 − cos 2πfp)), real.
    Exp,
    /// ((1−ε) + ε·e^(−j2πfp))^N, complex.
    Exact,
}

/// Charge-transfer factor along one axis.
#[derive(Debug, Clone)]
pub struct Cte {
    /// Number of transfers N.
    pub n: f64,
    /// Inefficiency ε = 1 − CTE per transfer, in [0, 1].
    pub cti: f64,
    /// Transfer pitch, mm.
    pub pitch: f64,
    /// Formula.
    pub model: CteModel,
    /// Transfer along v (y) instead of u (x).
    pub along_v: bool,
}

impl Cte {
    /// OTF at x = f·pitch (cycles per pitch).
    pub fn otf_x(&self, x: f64) -> Complex64 {
        self.otf_x2(x, 0.0)
    }

    /// OTF at x = xh + xl cycles per pitch, xl a tiny correction (|xl| ≤ ulp(xh)),
    /// as from an error-free product f·pitch.
    fn otf_x2(&self, xh: f64, xl: f64) -> Complex64 {
        let (n, c) = (self.n, self.cti);
        if n == 0.0 || c == 0.0 {
            return Complex64::new(1.0, 0.0);
        }
        // An overflowed f·pitch is treated like every f64 beyond 2^53: an integer.
        let (xh, xl) = if xh.is_finite() { (xh, xl) } else { (0.0, 0.0) };
        // Everything but the N-turn shift is periodic in x with period 1:
        // reduce x = xh + xl modulo 1 (each part exactly) into [−1/2, 1/2].
        let (xa, xb) = (xh - xh.round(), xl - xl.round());
        let xr = {
            let r = xa + xb;
            r - r.round()
        };
        let s = sin_pi(xr);
        let s2 = s * s;
        match self.model {
            CteModel::Exp => Complex64::new((-2.0 * n * c * s2).exp(), 0.0),
            CteModel::Exact => {
                let mag = (0.5 * n * (-4.0 * c * (1.0 - c) * s2).ln_1p()).exp();
                if mag == 0.0 {
                    return Complex64::new(0.0, 0.0);
                }
                let sin2 = sin_pi(2.0 * xr);
                let (a, b) = if c <= 0.5 {
                    n_arg(n, c, (xa, xb), xr, s2, sin2)
                } else {
                    // z = e^(−j2πx)·((1−d) + d·e^(j2πx)), d = 1 − c < 1/2; the
                    // second factor is the conjugate of the d-form at x.
                    let (a, b) = n_arg(n, 1.0 - c, (xa, xb), xr, s2, sin2);
                    let turns = frac_prod(n, xh) + frac_prod(n, xl);
                    (-a, -b - 2.0 * PI * (turns - turns.round()))
                };
                Complex64::from_polar(mag, a) * Complex64::from_polar(1.0, b)
            }
        }
    }
}

/// The low part of π as a double-double (π = PI + PI_LO).
const PI_LO: f64 = 1.2246467991473532e-16;

/// Error-free sum: (s, e) with s + e = a + b exactly.
fn two_sum(a: f64, b: f64) -> (f64, f64) {
    let s = a + b;
    let bb = s - a;
    (s, (a - (s - bb)) + (b - bb))
}

/// N·arg((1−c) + c·e^(−j2πx)) for c ≤ 1/2 and x ≡ xab.0 + xab.1 (mod 1), whose
/// rounded reduction to [−1/2, 1/2] is `xr`, given s2 = sin²(πx) and
/// sin2 = sin(2πx), as a pair (a, b) whose sum is the phase.
///
/// A large phase (up to ~1e5 rad while |OTF| is still far from 0, for N = 1e9)
/// needs arg to ~1e-19 relative: there (|x| < 0.01) arg = atan(q), q = Im/Re,
/// is formed in double-double (sin 2πx by its Taylor series, π split in two)
/// and N·q is split exactly, so the phase stays accurate to ~1e-14 rad.
fn n_arg(n: f64, c: f64, xab: (f64, f64), xr: f64, s2: f64, sin2: f64) -> (f64, f64) {
    let plain = n * (-c * sin2).atan2(1.0 - 2.0 * c * s2);
    if plain.abs() <= 1.0 || xr.abs() >= 0.01 {
        return (plain, 0.0);
    }
    // y = 2πx in double-double, from both parts of x (|x| < 0.01 here, so
    // xab.0 + xab.1 is x itself, not x ± 1).
    let (p1, e1) = two_prod(2.0 * PI, xab.0);
    let (p2, e2) = two_prod(2.0 * PI, xab.1);
    let (y_hi, e3) = two_sum(p1, p2);
    let y_lo = e1 + e2 + e3 + 2.0 * PI_LO * xr;
    // sin y = y + y·k, k = −y²/6 + y⁴/120 − …, |y| < 0.063.
    let y2 = y_hi * y_hi;
    let k = y2
        * (-1.0 / 6.0
            + y2 * (1.0 / 120.0 + y2 * (-1.0 / 5040.0 + y2 * (1.0 / 362880.0 - y2 / 39916800.0))));
    let (s_hi, e) = two_sum(y_hi, y_hi * k);
    let s_lo = e + y_lo * (1.0 + k);
    // Im = −c·sin y; Re = 1 − δ, δ = 2c·sin²(πx) (small; f64 suffices).
    let (im_hi, e) = two_prod(-c, s_hi);
    let im_lo = e - c * s_lo;
    let delta = 2.0 * c * s2;
    // q = Im/Re = Im·(1 + δ/(1−δ)).
    let (q_hi, e) = two_sum(im_hi, im_hi * (delta / (1.0 - delta)));
    let q_lo = e + im_lo / (1.0 - delta);
    // atan q = q − corr, corr = q³/3 − q⁵/5 + … (|q| < 0.07: 11 terms).
    let q2 = q_hi * q_hi;
    let mut corr = 0.0;
    let mut term = q_hi * q2;
    for k in 1..=11 {
        let sign = if k % 2 == 1 { 1.0 } else { -1.0 };
        corr += sign * term / (2 * k + 1) as f64;
        term *= q2;
    }
    let (a, e) = two_prod(n, q_hi);
    (a, e + n * q_lo - n * corr)
}

impl Factor for Cte {
    fn name(&self) -> String {
        "cte".into()
    }
    fn otf(&self, u: f64, v: f64) -> Complex64 {
        let f = if self.along_v { v } else { u };
        let (xh, xl) = two_prod(f, self.pitch);
        self.otf_x2(xh, xl)
    }
}

/// Parses a `--cte` spec.
pub fn parse(spec: &str) -> Result<Box<dyn Factor>, ModelError> {
    let p = Params::parse("cte", spec)?;
    let n = p.number("n")?;
    if !(n >= 0.0 && n.fract() == 0.0 && n <= 1e15) {
        return Err(p.error(format!(
            "n must be a whole number of transfers between 0 and 1e15, got {n}"
        )));
    }
    let cti = match (p.has("cti"), p.has("cte")) {
        (true, false) => p.number("cti")?,
        (false, true) => {
            let e = p.number("cte")?;
            if !(0.0..=1.0).contains(&e) {
                return Err(p.error(format!("cte must be in [0, 1], got {e}")));
            }
            1.0 - e
        }
        _ => return Err(p.error("give exactly one of cti=<0..1> or cte=<0..1>")),
    };
    if !(0.0..=1.0).contains(&cti) {
        return Err(p.error(format!("cti must be in [0, 1], got {cti}")));
    }
    let pitch = p.positive_length("pitch")?;
    let model = match p.choice_opt("model", &["exp", "exact"])?.as_deref() {
        Some("exact") => CteModel::Exact,
        _ => CteModel::Exp,
    };
    let along_v = p.choice_opt("axis", &["u", "v"])?.as_deref() == Some("v");
    p.finish(&["n", "cti", "cte", "pitch", "model", "axis"])?;
    Ok(Box::new(Cte {
        n,
        cti,
        pitch,
        model,
        along_v,
    }))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn cte(n: f64, cti: f64, model: CteModel) -> Cte {
        Cte {
            n,
            cti,
            pitch: 0.005,
            model,
            along_v: false,
        }
    }

    #[test]
    fn small_n_matches_direct_power() {
        for &c in &[0.0, 0.1, 0.3, 0.5, 0.7, 0.9, 1.0] {
            for n in 0..8 {
                let f = cte(n as f64, c, CteModel::Exact);
                for k in 0..40 {
                    let x = k as f64 * 0.0371 - 0.6;
                    let z = Complex64::new(1.0 - c, 0.0) + Complex64::from_polar(c, -2.0 * PI * x);
                    let direct = z.powi(n);
                    let got = f.otf_x(x);
                    assert!(
                        (got - direct).norm() < 1e-14,
                        "c={c} n={n} x={x}: {got} {direct}"
                    );
                }
            }
        }
    }

    #[test]
    fn full_inefficiency_is_a_pure_shift() {
        let f = cte(1e9, 1.0, CteModel::Exact);
        // z = e^(−j2πx): z^N = e^(−j2πNx), with N·x reduced exactly modulo 1.
        let o = f.otf_x(0.25);
        assert!((o - Complex64::new(1.0, 0.0)).norm() < 1e-15, "{o}");
        // x = 0.1 (binary 0.1000000000000000055…): N·x has fraction 5.55e-9.
        let o = f.otf_x(0.1);
        let want = Complex64::from_polar(1.0, -2.0 * PI * 5.551115123125783e-9);
        assert!((o - want).norm() < 1e-15, "{o} {want}");
    }
}
