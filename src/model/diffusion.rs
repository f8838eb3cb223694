//! Lateral diffusion of photo-generated carriers in a CCD/CMOS substrate
//! (Seib 1974, as given by Holst 1998 and Boreman 2001):
//!
//! MTF(f) = [1 − e^(−αL_D)/(1+αL(f))] / [1 − e^(−αL_D)/(1+αL₀)],
//! L(f) = L₀/√(1+(2πfL₀)²), f = √(u²+v²) (radial, cycles/mm),
//!
//! with α the absorption coefficient, L_D the depletion width and L₀ the
//! diffusion length. Each bracket is rewritten as (αL − expm1(−αL_D))/(1+αL),
//! a sum of two non-negative terms, so nothing cancels when αL_D is tiny.
//! L_D = 0 (no depletion region) is allowed.
//!
//! `lambda=` instead of `alpha=` looks α up in the table of intrinsic silicon
//! at 300 K (Green & Keevers 1995 as tabulated by PVEducation, 250–1100 nm
//! every 10 nm), interpolated linearly in λ and in log α.

use super::params::Params;
use super::{Factor, ModelError};
use num_complex::Complex64;
use std::f64::consts::PI;

/// First wavelength of [`SILICON_ALPHA_PER_CM`], nm.
pub const TABLE_START_NM: f64 = 250.0;
/// Wavelength step of [`SILICON_ALPHA_PER_CM`], nm.
pub const TABLE_STEP_NM: f64 = 10.0;
/// Absorption coefficient of intrinsic silicon at 300 K, 1/cm, from 250 nm in 10 nm steps.
pub const SILICON_ALPHA_PER_CM: [f64; 86] = [
    1.84e6, 1.97e6, 2.18e6, 2.36e6, 2.24e6, 1.73e6, 1.44e6, 1.28e6, 1.17e6,
    1.09e6, // 250–340
    1.04e6, 1.02e6, 6.97e5, 2.93e5, 1.50e5, 9.52e4, 6.74e4, 5.00e4, 3.92e4,
    3.11e4, // 350–440
    2.55e4, 2.10e4, 1.72e4, 1.48e4, 1.27e4, 1.11e4, 9.70e3, 8.80e3, 7.85e3,
    7.05e3, // 450–540
    6.39e3, 5.78e3, 5.32e3, 4.88e3, 4.49e3, 4.14e3, 3.81e3, 3.52e3, 3.27e3,
    3.04e3, // 550–640
    2.81e3, 2.58e3, 2.38e3, 2.21e3, 2.05e3, 1.90e3, 1.77e3, 1.66e3, 1.54e3,
    1.42e3, // 650–740
    1.30e3, 1.19e3, 1.10e3, 1.01e3, 9.28e2, 8.50e2, 7.75e2, 7.07e2, 6.38e2,
    5.76e2, // 750–840
    5.35e2, 4.81e2, 4.32e2, 3.83e2, 3.39e2, 3.06e2, 2.70e2, 2.39e2, 2.10e2,
    1.83e2, // 850–940
    1.57e2, 1.34e2, 1.14e2, 9.59e1, 7.92e1, 6.40e1, 5.11e1, 3.99e1, 3.02e1,
    2.26e1, // 950–1040
    1.63e1, 1.11e1, 8.00, 6.20, 4.70, 3.50, // 1050–1100
];

/// Absorption coefficient of silicon at `lambda_mm` (mm), 1/mm, or None outside the table.
pub fn silicon_alpha_per_mm(lambda_mm: f64) -> Option<f64> {
    let nm = lambda_mm * 1e6;
    let last = TABLE_START_NM + TABLE_STEP_NM * (SILICON_ALPHA_PER_CM.len() - 1) as f64;
    if !(nm >= TABLE_START_NM && nm <= last) {
        return None;
    }
    let pos = (nm - TABLE_START_NM) / TABLE_STEP_NM;
    let i = (pos.floor() as usize).min(SILICON_ALPHA_PER_CM.len() - 2);
    let f = pos - i as f64;
    let (a0, a1) = (
        SILICON_ALPHA_PER_CM[i].ln(),
        SILICON_ALPHA_PER_CM[i + 1].ln(),
    );
    Some((a0 + f * (a1 - a0)).exp() / 10.0)
}

/// Seib's diffusion MTF.
#[derive(Debug, Clone)]
pub struct Diffusion {
    /// Absorption coefficient α, 1/mm.
    pub alpha: f64,
    /// Depletion width L_D, mm.
    pub depletion: f64,
    /// Diffusion length L₀, mm.
    pub length: f64,
    /// −expm1(−α·L_D), ≥ 0.
    em: f64,
    /// The bracket at f = 0.
    norm: f64,
}

impl Diffusion {
    /// Diffusion MTF for α (1/mm), depletion width and diffusion length (mm).
    pub fn new(alpha: f64, depletion: f64, length: f64) -> Self {
        let em = -(-alpha * depletion).exp_m1();
        let al0 = alpha * length;
        let norm = (al0 + em) / (1.0 + al0);
        Diffusion {
            alpha,
            depletion,
            length,
            em,
            norm,
        }
    }

    /// MTF at radial frequency `f` (cycles/mm, ≥ 0).
    pub fn mtf_radial(&self, f: f64) -> f64 {
        let l = self.length / (1.0f64).hypot(2.0 * PI * f * self.length);
        let al = self.alpha * l;
        let num = (al + self.em) / (1.0 + al);
        num / self.norm
    }
}

impl Factor for Diffusion {
    fn name(&self) -> String {
        "diffusion".into()
    }
    fn otf(&self, u: f64, v: f64) -> Complex64 {
        Complex64::new(self.mtf_radial(u.hypot(v)), 0.0)
    }
}

/// Parses a `--diffusion` spec: `alpha=..|lambda=..,depletion=..,length=..`.
pub fn parse(spec: &str) -> Result<Box<dyn Factor>, ModelError> {
    let p = Params::parse("diffusion", spec)?;
    let alpha = match (p.has("alpha"), p.has("lambda")) {
        (true, false) => {
            let a = p.absorption_opt("alpha")?.unwrap_or(0.0);
            if a.is_nan() || a <= 0.0 {
                return Err(p.error(format!(
                    "alpha must be a positive absorption coefficient (e.g. 0.05/um), got {a} /mm"
                )));
            }
            a
        }
        (false, true) => {
            let l = p.positive_length("lambda")?;
            silicon_alpha_per_mm(l).ok_or_else(|| {
                p.error(format!(
                    "lambda={} nm is outside the silicon table (250–1100 nm); give alpha=.. instead",
                    l * 1e6
                ))
            })?
        }
        _ => {
            return Err(p.error(
                "give exactly one of alpha=<absorption, e.g. 0.05/um> or lambda=<wavelength>",
            ));
        }
    };
    let depletion = p
        .length_opt("depletion")?
        .ok_or_else(|| p.error("missing depletion=<length> (e.g. depletion=2um)"))?;
    if depletion.is_nan() || depletion < 0.0 {
        return Err(p.error(format!(
            "depletion must be a length ≥ 0, got {depletion} mm"
        )));
    }
    let length = p.positive_length("length")?;
    p.finish(&["alpha", "lambda", "depletion", "length"])?;
    Ok(Box::new(Diffusion::new(alpha, depletion, length)))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn table_lookup_hits_nodes_and_interpolates_in_log() {
        assert!((silicon_alpha_per_mm(550e-6).unwrap() - 639.0).abs() < 1e-9);
        let mid = silicon_alpha_per_mm(555e-6).unwrap();
        assert!((mid - (639.0f64 * 578.0).sqrt()).abs() < 1e-9, "{mid}");
        assert!(silicon_alpha_per_mm(1100e-6).is_some());
        assert!(silicon_alpha_per_mm(1101e-6).is_none());
        assert!(silicon_alpha_per_mm(249e-6).is_none());
    }

    #[test]
    fn table_agrees_with_an_independent_measurement() {
        // Schinke et al., AIP Advances 5 (2015) 067168, 295 K: extinction k at
        // λ; α = 4πk/λ. Their stated uncertainty is about 11 % near 600 nm.
        for (nm, k) in [
            (450.0, 9.5362e-2),
            (550.0, 2.8038e-2),
            (600.0, 1.8521e-2),
            (700.0, 1.0623e-2),
            (750.0, 7.6156e-3),
        ] {
            let lambda_mm = nm * 1e-6;
            let want = 4.0 * PI * k / lambda_mm;
            let got = silicon_alpha_per_mm(lambda_mm).unwrap();
            assert!(
                (got / want - 1.0).abs() < 0.08,
                "{nm} nm: {got} vs {want} /mm"
            );
        }
    }

    #[test]
    fn unity_at_zero_and_decreasing() {
        let d = Diffusion::new(50.0, 0.002, 0.01);
        assert_eq!(d.mtf_radial(0.0), 1.0);
        let mut last = 1.0;
        for k in 1..100 {
            let m = d.mtf_radial(k as f64 * 10.0);
            assert!(m < last && m > 0.0);
            last = m;
        }
        assert!(d.mtf_radial(1e300) > 0.0);
    }
}
