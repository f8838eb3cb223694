//! Modulation estimators behind one [`Estimator`] trait, one file each:
//! [`extrema`] (the paper's local maxima/minima per half period), [`fit`]
//! (windowed least-squares sine fit along the phase law; the default) and
//! [`envelope`] (analytic signal via FFT).
//!
//! Every estimator returns modulation M = amplitude / local mean at positions
//! along the strip, with an uncertainty from the residual noise, and corrects
//! the (known, tiny) attenuation of averaging within sub-pixel bins.

use super::law::PhaseLaw;
use super::profile::Profile;
use serde::{Deserialize, Serialize};

pub mod cfa;
pub mod envelope;
pub mod extrema;
pub mod fit;
pub mod turns;

/// One modulation sample along the strip.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ModPoint {
    /// Position along the strip (strip units).
    pub s: f64,
    /// Modulation (amplitude / local mean), not yet divided by the chart's modulation.
    pub modulation: f64,
    /// One-sigma uncertainty of `modulation`.
    pub err: f64,
}

/// Estimates modulation along a binned profile, given the sweep's phase law.
pub trait Estimator: Sync {
    /// Short name (`extrema`, `fit`, `envelope`).
    fn name(&self) -> &'static str;
    /// Modulation samples; `grid` suggests output positions (estimators with their own natural positions may ignore it).
    fn estimate(&self, prof: &Profile, law: &PhaseLaw, grid: &[f64]) -> Vec<ModPoint>;
    /// [`Estimator::estimate`] given `law` already tabulated over the bins
    /// (estimators that use the table skip building their own).
    fn estimate_tabulated(
        &self,
        prof: &Profile,
        law: &PhaseLaw,
        _table: &fit::PhaseTable,
        grid: &[f64],
    ) -> Vec<ModPoint> {
        self.estimate(prof, law, grid)
    }
}

/// The modulation estimator to use.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize, Default)]
#[serde(rename_all = "lowercase")]
pub enum Method {
    /// Local extrema per half period (the paper's method).
    Extrema,
    /// Windowed least-squares sine fit (default).
    #[default]
    Fit,
    /// Analytic-signal envelope via FFT.
    Envelope,
}

impl Method {
    /// All methods.
    pub const ALL: [Method; 3] = [Method::Extrema, Method::Fit, Method::Envelope];

    /// Parses `extrema|fit|envelope`.
    pub fn parse(s: &str) -> Option<Method> {
        Some(match s {
            "extrema" => Method::Extrema,
            "fit" => Method::Fit,
            "envelope" => Method::Envelope,
            _ => return None,
        })
    }

    /// The name used on the command line and in files.
    pub fn name(self) -> &'static str {
        match self {
            Method::Extrema => "extrema",
            Method::Fit => "fit",
            Method::Envelope => "envelope",
        }
    }

    /// The estimator, with a window of `window_cycles` cycles where it has one.
    pub fn estimator(self, window_cycles: f64) -> Box<dyn Estimator> {
        match self {
            Method::Extrema => Box::new(extrema::Extrema),
            Method::Fit => Box::new(fit::SineFit { window_cycles }),
            Method::Envelope => Box::new(envelope::Envelope { window_cycles }),
        }
    }
}

/// Attenuation of a sine of `f` cycles/unit by averaging samples spread with variance `var_s` (Gaussian approximation).
pub fn bin_attenuation(f: f64, var_s: f64) -> f64 {
    (-2.0 * std::f64::consts::PI.powi(2) * f * f * var_s).exp()
}

#[cfg(test)]
pub(crate) mod tests_support {
    //! Synthetic 1-D chirps with known modulation for estimator tests.
    use super::super::law::{LawKind, PhaseLaw};
    use super::super::profile::Profile;

    /// A deterministic standard-normal generator (LCG + Box–Muller).
    pub fn lcg_normal(state: &mut u64) -> f64 {
        let mut u = || {
            *state = state
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            ((*state >> 11) as f64 + 0.5) / (1u64 << 53) as f64
        };
        let (a, b) = (u(), u());
        (-2.0 * a.ln()).sqrt() * (2.0 * std::f64::consts::PI * b).cos()
    }

    /// A linear chirp 0.01→0.3 cycles/unit over 4000 units, bins of 0.25, mean
    /// 0.5 with a 20 % gradient, modulation 0.6·(1 − 0.8·s/L), additive noise of
    /// `noise` per bin. Returns the profile, the true law and the true modulation.
    pub fn chirp(noise: f64, seed: u64) -> (Profile, PhaseLaw, impl Fn(f64) -> f64) {
        let l = 4000.0;
        let law = PhaseLaw {
            kind: LawKind::Linear,
            c0: 0.2,
            c1: 0.01,
            c2: 0.29 / l / 2.0,
            persp: 0.0,
        };
        let truth = move |s: f64| 0.6 * (1.0 - 0.8 * s / l);
        let n = (l / 0.25) as usize;
        let mut st = seed;
        let s: Vec<f64> = (0..n).map(|i| (i as f64 + 0.5) * 0.25).collect();
        let y = s
            .iter()
            .map(|&s| {
                let mean = 0.5 * (1.0 + 0.2 * s / l);
                mean * (1.0 + truth(s) * (2.0 * std::f64::consts::PI * law.phase(s)).cos())
                    + noise * lcg_normal(&mut st)
            })
            .collect();
        let prof = Profile {
            s,
            y,
            count: vec![1.0; n],
            var_s: vec![0.0; n],
            bin: 0.25,
            length: l,
            ..Profile::default()
        };
        (prof, law, truth)
    }

    /// A noise-free profile over `length` units in bins of 0.25 (one sample
    /// each) under the linear law starting at `f0` cycles/unit and rising
    /// `rate` per unit; `value(law, s)` gives each bin's value.
    pub fn linear_profile(
        f0: f64,
        rate: f64,
        length: f64,
        value: impl Fn(&PhaseLaw, f64) -> f64,
    ) -> (Profile, PhaseLaw) {
        let law = PhaseLaw {
            kind: LawKind::Linear,
            c0: 0.0,
            c1: f0,
            c2: rate / 2.0,
            persp: 0.0,
        };
        let n = (length / 0.25) as usize;
        let s: Vec<f64> = (0..n).map(|i| (i as f64 + 0.5) * 0.25).collect();
        let y = s.iter().map(|&s| value(&law, s)).collect();
        let prof = Profile {
            s,
            y,
            count: vec![1.0; n],
            var_s: vec![0.0; n],
            bin: 0.25,
            length,
            ..Profile::default()
        };
        (prof, law)
    }
}
