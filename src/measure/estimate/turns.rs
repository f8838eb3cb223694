//! sin 2πt and cos 2πt together, for the phase tables of the local fits.
//!
//! `PhaseTable::new` evaluates them at every bin of a strip for every law
//! it tries (≈ 240 000 times on a 24 MP target): libm's `sincos` was ≈ 2 %
//! of a measurement's CPU. Here the turn is reduced to a quadrant exactly
//! and the rest is fdlibm's two kernel polynomials on [−π/4, π/4] (error
//! ≈ 1e-16; the unit test holds it to 1e-15 against `f64::sin_cos` of the
//! rounded angle, whose own rounding is up to 4.4e-16 at 2π).

// The coefficients are quoted to the digits fdlibm prints them with.
#![allow(clippy::excessive_precision)]

use std::f64::consts::TAU;

// fdlibm's __kernel_sin and __kernel_cos coefficients.
const S1: f64 = -1.666_666_666_666_663_243_48e-1;
const S2: f64 = 8.333_333_333_322_489_461_24e-3;
const S3: f64 = -1.984_126_982_985_794_931_34e-4;
const S4: f64 = 2.755_731_370_707_006_767_89e-6;
const S5: f64 = -2.505_076_025_340_686_341_95e-8;
const S6: f64 = 1.589_690_995_211_550_102_21e-10;
const C1: f64 = 4.166_666_666_666_660_190_37e-2;
const C2: f64 = -1.388_888_888_887_410_957_49e-3;
const C3: f64 = 2.480_158_728_947_672_941_78e-5;
const C4: f64 = -2.755_731_435_139_066_330_35e-7;
const C5: f64 = 2.087_572_321_298_174_827_90e-9;
const C6: f64 = -1.135_964_755_778_819_482_65e-11;

/// (sin 2πt, cos 2πt) for a phase `t` in turns (any value; the exact
/// reduction below 4.5e15 turns, libm's beyond).
#[inline]
pub fn sin_cos_turns(t: f64) -> (f64, f64) {
    if !(t.abs() < 4.5e15) {
        let (s, c) = (TAU * (t - t.floor())).sin_cos();
        return (s, c);
    }
    // The fraction, by integer conversion (baseline x86-64 has no rounding
    // instruction: `floor` and `round` are calls): exact below 2⁵².
    let whole = t as i64 as f64;
    let t = t - if whole > t { whole - 1.0 } else { whole };
    // Quadrant q (0–4; either neighbour at a tie) and the rest u = t − q/4,
    // exact (|u| ≤ 1/8: both terms within a factor of two of each other,
    // or q = 0).
    let q = (4.0 * t + 0.5) as i64 as f64;
    let u = t - 0.25 * q;
    let x = TAU * u;
    let z = x * x;
    let s = x + x * z * (S1 + z * (S2 + z * (S3 + z * (S4 + z * (S5 + z * S6)))));
    let r = z * (C1 + z * (C2 + z * (C3 + z * (C4 + z * (C5 + z * C6)))));
    // fdlibm's form: 1 − (z/2 − z·r), with the large-|x| split of z/2.
    let hz = 0.5 * z;
    let w = 1.0 - hz;
    let c = w + (((1.0 - w) - hz) + z * r);
    match q as u8 & 3 {
        0 => (s, c),
        1 => (c, -s),
        2 => (-s, -c),
        _ => (-c, s),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn agrees_with_libm_over_every_quadrant() {
        let mut worst = 0.0f64;
        let mut st = 99u64;
        for k in 0..400_000 {
            st = st
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            // Uniform turns, the quadrant boundaries and their neighbours,
            // and whole-number phases as the tables give them.
            let t = match k % 4 {
                0 => (st >> 11) as f64 / (1u64 << 53) as f64,
                1 => (k / 4 % 9) as f64 * 0.125 + ((st >> 40) as f64 - 8e6) * 1e-22,
                2 => (st >> 11) as f64 / (1u64 << 53) as f64 * 3000.0,
                _ => -((st >> 11) as f64 / (1u64 << 53) as f64),
            };
            let (s, c) = sin_cos_turns(t);
            let (ws, wc) = (TAU * (t - t.floor())).sin_cos();
            worst = worst.max((s - ws).abs()).max((c - wc).abs());
            assert!((s * s + c * c - 1.0).abs() < 1e-15, "{t}");
        }
        assert!(worst < 1e-15, "{worst:e}");
        // Huge and non-finite phases go to libm.
        for t in [1e16, -3e17, f64::MAX] {
            assert_eq!(sin_cos_turns(t), (TAU * (t - t.floor())).sin_cos());
        }
        assert!(sin_cos_turns(f64::NAN).0.is_nan());
    }
}
