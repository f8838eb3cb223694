//! Analytic-signal envelope: the profile on a uniform grid (the finest whole
//! multiple of the bin width that leaves almost no cell empty), minus its
//! one-period moving mean, is turned into the analytic signal by FFT (negative
//! frequencies removed); its magnitude, averaged over a window of cycles and
//! divided by the local mean, is the modulation.

#![allow(clippy::needless_range_loop, clippy::neg_cmp_op_on_partial_ord)]

use super::{Estimator, ModPoint, bin_attenuation};
use crate::measure::law::PhaseLaw;
use crate::measure::law_guess::{moving_mean_frac, uniform_dense};
use crate::measure::profile::Profile;
use num_complex::Complex64;
use realfft::RealFftPlanner;
use rustfft::FftPlanner;

/// The analytic-signal envelope estimator.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Envelope {
    /// Averaging window of the envelope, in cycles.
    pub window_cycles: f64,
}

/// Magnitude of the analytic signal of `v` (zero-padded to a fast length).
pub fn analytic_magnitude(v: &[f64]) -> Vec<f64> {
    let n = v.len();
    let m = n.next_power_of_two().max(2);
    let mut input = vec![0.0f64; m];
    input[..n].copy_from_slice(v);
    let r2c = RealFftPlanner::<f64>::new().plan_fft_forward(m);
    let mut spec = r2c.make_output_vec();
    if r2c.process(&mut input, &mut spec).is_err() {
        return vec![0.0; n];
    }
    let mut full = vec![Complex64::new(0.0, 0.0); m];
    full[0] = spec[0];
    for k in 1..m / 2 {
        full[k] = spec[k] * 2.0;
    }
    full[m / 2] = spec[m / 2];
    FftPlanner::<f64>::new()
        .plan_fft_inverse(m)
        .process(&mut full);
    full[..n].iter().map(|z| z.norm() / m as f64).collect()
}

impl Estimator for Envelope {
    fn name(&self) -> &'static str {
        "envelope"
    }

    fn estimate(&self, prof: &Profile, law: &PhaseLaw, grid: &[f64]) -> Vec<ModPoint> {
        let (s0, ds, v, avg_var) = uniform_dense(prof);
        let n = v.len();
        if n < 16 {
            return Vec::new();
        }
        let pos = |i: usize| s0 + i as f64 * ds;
        // One local period, in samples, at every sample.
        let half: Vec<f64> = (0..n)
            .map(|i| (0.5 / law.freq(pos(i)).max(1e-300) / ds).min(n as f64))
            .collect();
        let mean = moving_mean_frac(&v, |i| half[i]);
        let d: Vec<f64> = v.iter().zip(&mean).map(|(a, b)| a - b).collect();
        let env = analytic_magnitude(&d);
        let (p_lo, p_hi) = (law.phase(pos(0)), law.phase(pos(n - 1)));
        grid.iter()
            .filter_map(|&s| {
                let p = law.phase(s);
                let hw = 0.5 * self.window_cycles;
                // Keep one cycle away from the ends (FFT edge effects).
                if p - hw < p_lo + 1.0 || p + hw > p_hi - 1.0 {
                    return None;
                }
                let a = law.s_at_phase(p - hw, pos(0), pos(n - 1));
                let b = law.s_at_phase(p + hw, pos(0), pos(n - 1));
                let ia = (((a - s0) / ds).ceil().max(0.0)) as usize;
                let ib = (((b - s0) / ds).floor() as usize).min(n - 1);
                if ib <= ia + 2 {
                    return None;
                }
                let cnt = (ib - ia + 1) as f64;
                // The envelope relative to the local mean sample by sample, so that
                // uneven light (gradient, vignetting) cancels within the window.
                if mean[ia..=ib].iter().any(|&m| m <= 0.0) {
                    return None;
                }
                let rel = || env[ia..=ib].iter().zip(&mean[ia..=ib]).map(|(e, m)| e / m);
                let e: f64 = rel().sum::<f64>() / cnt;
                let e2: f64 = rel().map(|x| x * x).sum::<f64>() / cnt;
                let mu = 1.0;
                let att = bin_attenuation(law.freq(s), avg_var);
                // Independent envelope samples in the window ≈ its cycles.
                let sd = (e2 - e * e).max(0.0).sqrt() / self.window_cycles.max(1.0).sqrt();
                Some(ModPoint {
                    s,
                    modulation: e / mu / att,
                    err: sd / mu / att,
                })
            })
            .collect()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::measure::estimate::tests_support::chirp;

    #[test]
    fn analytic_magnitude_of_a_pure_tone_is_flat() {
        let v: Vec<f64> = (0..1024)
            .map(|i| 0.7 * (2.0 * std::f64::consts::PI * 37.0 * i as f64 / 1024.0).cos())
            .collect();
        let e = analytic_magnitude(&v);
        assert!(e.iter().all(|x| (x - 0.7).abs() < 1e-9));
    }

    #[test]
    fn noiseless_chirp_gives_the_known_modulation() {
        let (prof, law, truth) = chirp(0.0, 1);
        let grid: Vec<f64> = (2..39).map(|i| i as f64 * 100.0).collect();
        let pts = Envelope { window_cycles: 4.0 }.estimate(&prof, &law, &grid);
        assert!(pts.len() > 30);
        for p in &pts {
            assert!(
                (p.modulation - truth(p.s)).abs() < 0.01,
                "{} {} {}",
                p.s,
                p.modulation,
                truth(p.s)
            );
        }
    }
}
