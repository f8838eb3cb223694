//! Sensor noise with a deterministic, counter-based random generator: every
//! pixel seeds its own small xorshift generator from (seed, pixel index), so a
//! shot is the same whatever the thread count. Photon shot noise (Poisson in
//! electrons, from the full-well count), Gaussian read noise in electrons, and
//! a fixed pattern (photo-response non-uniformity: a per-pixel gain that depends
//! only on `fpn_seed`). Normal deviates by the Box–Muller transform.

use rayon::prelude::*;

/// SplitMix64 finaliser: a well-mixed 64-bit hash.
fn splitmix(mut z: u64) -> u64 {
    z = z.wrapping_add(0x9E37_79B9_7F4A_7C15);
    z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
    z ^ (z >> 31)
}

/// A small xorshift64* generator.
#[derive(Debug, Clone)]
pub struct Rng(u64);

impl Rng {
    /// A generator for stream `stream` of pixel `index` under `seed`.
    pub fn new(seed: u64, stream: u64, index: u64) -> Rng {
        let s =
            splitmix(seed ^ splitmix(stream.wrapping_mul(0xD1B5_4A32_D192_ED03) ^ splitmix(index)));
        Rng(if s == 0 { 0x2545_F491_4F6C_DD1D } else { s })
    }

    /// The next 64 random bits.
    pub fn next_u64(&mut self) -> u64 {
        let mut x = self.0;
        x ^= x >> 12;
        x ^= x << 25;
        x ^= x >> 27;
        self.0 = x;
        x.wrapping_mul(0x2545_F491_4F6C_DD1D)
    }

    /// A uniform deviate in (0, 1).
    pub fn uniform(&mut self) -> f64 {
        ((self.next_u64() >> 11) as f64 + 0.5) / (1u64 << 53) as f64
    }

    /// A standard normal deviate (Box–Muller, one of the pair).
    pub fn normal(&mut self) -> f64 {
        let (u1, u2) = (self.uniform(), self.uniform());
        (-2.0 * u1.ln()).sqrt() * (2.0 * std::f64::consts::PI * u2).cos()
    }

    /// A Poisson deviate of mean `lambda` (exact product method below 30, normal above).
    pub fn poisson(&mut self, lambda: f64) -> f64 {
        if lambda <= 0.0 {
            return 0.0;
        }
        if lambda < 30.0 {
            let l = (-lambda).exp();
            let mut k = 0u32;
            let mut p = self.uniform();
            while p > l {
                k += 1;
                p *= self.uniform();
            }
            k as f64
        } else {
            (lambda + lambda.sqrt() * self.normal()).max(0.0)
        }
    }
}

/// Noise settings in the units the sensor counts.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct NoiseModel {
    /// Electrons at clipping (signal 1.0); `None` = noiseless photon count.
    pub full_well_e: Option<f64>,
    /// Read noise, electrons RMS.
    pub read_noise_e: f64,
    /// Relative RMS gain spread of the fixed pattern.
    pub fpn: f64,
    /// Seed of the fixed pattern.
    pub fpn_seed: u64,
    /// Seed of the temporal noise.
    pub seed: u64,
}

/// Turns the noiseless signal (1.0 = clipping) into the recorded linear value:
/// fixed-pattern gain, shot noise, read noise, then clipping to [0, 1].
pub fn apply(model: &NoiseModel, signal: &[f32], width: usize) -> Vec<f32> {
    let mut out = apply_unclipped(model, signal, width);
    out.iter_mut().for_each(|v| *v = v.clamp(0.0, 1.0));
    out
}

/// [`apply`] without the clipping (for processing before it, e.g. sharpening).
pub fn apply_unclipped(model: &NoiseModel, signal: &[f32], width: usize) -> Vec<f32> {
    let mut out = vec![0f32; signal.len()];
    out.par_chunks_mut(width)
        .zip(signal.par_chunks(width))
        .enumerate()
        .for_each(|(row, (o, s))| {
            for (col, (o, &v)) in o.iter_mut().zip(s).enumerate() {
                let idx = (row * width + col) as u64;
                let mut v = v as f64;
                if model.fpn > 0.0 {
                    v *= 1.0 + model.fpn * Rng::new(model.fpn_seed, 2, idx).normal();
                }
                if let Some(fw) = model.full_well_e {
                    let mut rng = Rng::new(model.seed, 0, idx);
                    let mut e = rng.poisson(v.max(0.0) * fw);
                    if model.read_noise_e > 0.0 {
                        e += model.read_noise_e * rng.normal();
                    }
                    v = e / fw;
                }
                *o = v as f32;
            }
        });
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn deviates_have_the_right_moments() {
        let n = 200_000;
        let (mut s1, mut s2) = (0.0, 0.0);
        for i in 0..n {
            let z = Rng::new(7, 0, i).normal();
            s1 += z;
            s2 += z * z;
        }
        let mean = s1 / n as f64;
        let var = s2 / n as f64 - mean * mean;
        assert!(
            mean.abs() < 0.01 && (var - 1.0).abs() < 0.01,
            "{mean} {var}"
        );
        for lambda in [0.5, 4.0, 25.0, 400.0] {
            let (mut s1, mut s2) = (0.0, 0.0);
            let n = 100_000;
            for i in 0..n {
                let k = Rng::new(3, 1, i).poisson(lambda);
                s1 += k;
                s2 += k * k;
            }
            let mean = s1 / n as f64;
            let var = s2 / n as f64 - mean * mean;
            // Poisson: mean = variance = λ (tolerance ≈ 5 standard errors).
            assert!(
                (mean - lambda).abs() < 5.0 * (lambda / n as f64).sqrt() + 1e-9,
                "{lambda} {mean}"
            );
            assert!((var / lambda - 1.0).abs() < 0.03, "{lambda} {var}");
        }
    }

    #[test]
    fn shot_and_read_noise_have_the_expected_spread() {
        let model = NoiseModel {
            full_well_e: Some(10_000.0),
            read_noise_e: 20.0,
            fpn: 0.0,
            fpn_seed: 1,
            seed: 42,
        };
        let signal = vec![0.25f32; 100_000];
        let out = apply(&model, &signal, 1000);
        let mean = out.iter().map(|&v| v as f64).sum::<f64>() / out.len() as f64;
        let var = out.iter().map(|&v| (v as f64 - mean).powi(2)).sum::<f64>() / out.len() as f64;
        // σ² = (λ + r²)/FW² with λ = 2500 e⁻, r = 20 e⁻.
        let expect = (2500.0 + 400.0) / 1e8;
        assert!((mean - 0.25).abs() < 1e-4);
        assert!((var / expect - 1.0).abs() < 0.03, "{var} {expect}");
        // Same seed, same picture; fixed pattern independent of the temporal seed.
        assert_eq!(out, apply(&model, &signal, 1000));
        let fpn = |seed| {
            apply(
                &NoiseModel {
                    full_well_e: None,
                    read_noise_e: 0.0,
                    fpn: 0.01,
                    fpn_seed: 5,
                    seed,
                },
                &signal[..1000],
                100,
            )
        };
        assert_eq!(fpn(1), fpn(2));
    }
}
