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
//!   product. No repeated multiplication: accurate for N up to 1e9 and
//!   ε down to 1e-12 (and ε = 1, a pure N-pixel shift).
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
        let xr = {
            let r = (xh - xh.round()) + (xl - xl.round());
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
                let phase = if c <= 0.5 {
                    n * (-c * sin2).atan2(1.0 - 2.0 * c * s2)
                } else {
                    // z = e^(−j2πx)·((1−d) + d·e^(j2πx)), d = 1 − c < 1/2.
                    let d = 1.0 - c;
                    let own = n * (d * sin2).atan2(1.0 - 2.0 * d * s2);
                    let turns = frac_prod(n, xh) + frac_prod(n, xl);
                    own - 2.0 * PI * (turns - turns.round())
                };
                Complex64::from_polar(mag, phase)
            }
        }
    }
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
