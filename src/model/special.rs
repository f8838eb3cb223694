//! Special functions of the model, each with a stable path at its singular
//! points: `sinpi`/`cospi` with exact argument reduction, the normalised
//! `sinc(x) = sin(πx)/(πx)`, the Bessel function `J₁` and `jinc(z) = 2J₁(z)/z`.
//!
//! Every function returns a finite value for every finite argument (huge
//! arguments included) and is accurate to a few units of 1e-16 absolute.

mod j1_taylor;

use std::f64::consts::{FRAC_1_SQRT_2, PI};

/// Above this magnitude every f64 is an integer, so sin(πx) = 0.
const INTEGER_ONLY: f64 = 4_503_599_627_370_496.0; // 2^52

/// Splits x into n + r with n an integer (as f64) and |r| ≤ 1/2, exactly.
fn reduce(x: f64) -> (f64, f64) {
    let n = x.round();
    (n, x - n)
}

/// Whether the integer-valued `n` is odd.
fn is_odd(n: f64) -> bool {
    n % 2.0 != 0.0
}

/// sin(πr) for |r| ≤ 1/2, to full relative accuracy.
fn sinpi_reduced(r: f64) -> f64 {
    let a = r.abs();
    let s = if a <= 0.25 {
        (PI * a).sin()
    } else {
        (PI * (0.5 - a)).cos()
    };
    s.copysign(r)
}

/// cos(πr) for |r| ≤ 1/2, to full relative accuracy (also near r = ±1/2).
fn cospi_reduced(r: f64) -> f64 {
    let a = r.abs();
    if a <= 0.25 {
        (PI * a).cos()
    } else {
        (PI * (0.5 - a)).sin()
    }
}

/// sin(πx) with exact argument reduction; 0 for |x| ≥ 2⁵² (and for ±∞, the limit used).
pub fn sinpi(x: f64) -> f64 {
    if x.abs() >= INTEGER_ONLY {
        return 0.0;
    }
    let (n, r) = reduce(x);
    let s = sinpi_reduced(r);
    if is_odd(n) { -s } else { s }
}

/// cos(πx) with exact argument reduction; 1 for ±∞ (the value used for overflowed phases).
pub fn cospi(x: f64) -> f64 {
    if x.is_infinite() {
        return 1.0;
    }
    let (n, r) = reduce(x);
    let c = cospi_reduced(r);
    if is_odd(n) { -c } else { c }
}

/// (sin(πx), cos(πx)) with one exact argument reduction and one `sin_cos`;
/// (0, ±1) for |x| ≥ 2⁵² and (0, 1) for ±∞, as [`sinpi`] and [`cospi`].
pub fn sincospi(x: f64) -> (f64, f64) {
    if x.abs() >= INTEGER_ONLY {
        return (0.0, cospi(x));
    }
    let (n, r) = reduce(x);
    let a = r.abs();
    let (s, c) = if a <= 0.25 {
        (PI * a).sin_cos()
    } else {
        let (c, s) = (PI * (0.5 - a)).sin_cos();
        (s, c)
    };
    let s = s.copysign(r);
    if is_odd(n) { (-s, -c) } else { (s, c) }
}

/// sinc(x) given s = sin(πx) already computed (see [`sinc`]).
pub fn sinc_from_sinpi(x: f64, s: f64) -> f64 {
    let a = x.abs();
    if a < 1e-4 {
        let y2 = (PI * a) * (PI * a);
        return 1.0 - y2 / 6.0 * (1.0 - y2 / 20.0);
    }
    s.abs().copysign(s * x) / (PI * a)
}

/// The normalised sinc, sin(πx)/(πx), with sinc(0) = 1 and a Taylor path for |x| < 1e-4.
pub fn sinc(x: f64) -> f64 {
    let a = x.abs();
    if a < 1e-4 {
        let y2 = (PI * a) * (PI * a);
        return 1.0 - y2 / 6.0 * (1.0 - y2 / 20.0);
    }
    // π·a may overflow to +∞ for a > 5.7e307; the quotient is then 0, the limit.
    sinpi(a) / (PI * a)
}

/// Below this argument J₁ and jinc use their power series.
const SERIES_MAX: f64 = 2.0;
/// At and above this argument J₁ and jinc use Hankel's asymptotic expansion.
const HANKEL_MIN: f64 = 25.0;

/// Power series of 2J₁(z)/z = Σ (−z²/4)ᵏ / (k!(k+1)!), for |z| ≤ 2.
fn jinc_series(z: f64) -> f64 {
    let w = -0.25 * z * z;
    let mut term = 1.0;
    let mut sum = 1.0;
    for k in 1..40 {
        let kf = k as f64;
        term *= w / (kf * (kf + 1.0));
        sum += term;
        if term.abs() < 1e-18 * sum.abs() {
            break;
        }
    }
    sum
}

/// J₁(x) for 2 < x < 25 by its Taylor series about the nearest zero j₁,ₖ
/// (coefficients from mpmath, see `j1_taylor`); x − j₁,ₖ is formed in
/// double-double, so the relative error stays a few ulp even next to a zero.
fn j1_near_zero(x: f64) -> f64 {
    let k = j1_taylor::MIDS.iter().take_while(|&&m| x > m).count();
    let (hi, lo) = j1_taylor::ZEROS[k];
    let d = (x - hi) - lo;
    j1_taylor::TAYLOR[k]
        .iter()
        .rev()
        .fold(0.0, |acc, &c| acc * d + c)
}

/// Number of terms of Hankel's expansion kept at most (x ≥ 25 needs about 24).
const HANKEL_TERMS: usize = 48;

/// Ratios aₖ(1)/aₖ₋₁(1)·x = (4 − (2k−1)²)/(8k), k = 1…, of Hankel's expansion for ν = 1.
const HANKEL_RATIO: [f64; HANKEL_TERMS] = {
    let mut r = [0.0; HANKEL_TERMS];
    let mut k = 1;
    while k <= HANKEL_TERMS {
        let odd = (2 * k - 1) as f64;
        r[k - 1] = (4.0 - odd * odd) / (8.0 * k as f64);
        k += 1;
    }
    r
};

/// J₁(x) for x ≥ 25 by Hankel's expansion (DLMF 10.17.3), terms summed until below 1e-18.
fn j1_hankel(x: f64) -> f64 {
    if !x.is_finite() {
        return 0.0;
    }
    let inv_x = 1.0 / x;
    let mut p = 1.0;
    let mut q = 0.0;
    let mut term: f64 = 1.0;
    for (k, ratio) in HANKEL_RATIO.iter().enumerate() {
        let next = term * ratio * inv_x;
        if next.abs() > term.abs() {
            break; // the asymptotic series starts to diverge
        }
        term = next;
        // sign pattern: P = a0 − a2 + a4 …, Q = a1 − a3 + …
        match (k + 1) % 4 {
            0 => p += term,
            1 => q += term,
            2 => p -= term,
            _ => q -= term,
        }
        if term.abs() < 1e-18 {
            break;
        }
    }
    let (s, c) = x.sin_cos();
    let cos_chi = (s - c) * FRAC_1_SQRT_2; // cos(x − 3π/4)
    let sin_chi = -(s + c) * FRAC_1_SQRT_2; // sin(x − 3π/4)
    (2.0 / (PI * x)).sqrt() * (p * cos_chi - q * sin_chi)
}

/// The Bessel function of the first kind of order one, J₁(x); odd in x.
///
/// Against mpmath: relative error ≤ 4e-16 for |x| < 25 (series to 2, Taylor about the
/// zeros to 25), absolute error ≤ 1e-16 beyond (Hankel's expansion).
pub fn bessel_j1(x: f64) -> f64 {
    let a = x.abs();
    let r = if a <= SERIES_MAX {
        0.5 * a * jinc_series(a)
    } else if a < HANKEL_MIN {
        j1_near_zero(a)
    } else {
        j1_hankel(a)
    };
    if x < 0.0 { -r } else { r }
}

/// jinc(z) = 2J₁(z)/z with jinc(0) = 1 (the circular aperture's OTF at z = πDρ); even in z.
pub fn jinc(z: f64) -> f64 {
    let a = z.abs();
    if a <= SERIES_MAX {
        jinc_series(a)
    } else if a < HANKEL_MIN {
        2.0 * j1_near_zero(a) / a
    } else {
        2.0 * j1_hankel(a) / a
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Reference J₁ from the periodic integral J₁(x) = (1/π)∫₀^π sinτ·sin(x sinτ) dτ
    /// by the trapezoidal rule (spectrally convergent), independent of the code above.
    fn j1_ref(x: f64) -> f64 {
        let n = (x.abs() as usize) + 80;
        let mut sum = 0.0;
        let mut comp = 0.0;
        for k in 0..n {
            let t = PI * (k as f64) / (n as f64);
            let f = t.sin() * (x * t.sin()).sin();
            let y = f - comp;
            let s = sum + y;
            comp = (s - sum) - y;
            sum = s;
        }
        sum / n as f64
    }

    #[test]
    fn sinpi_cospi_exact_at_integers_and_halves() {
        for k in -10..=10 {
            let x = k as f64;
            assert_eq!(sinpi(x), 0.0);
            assert_eq!(cospi(x).abs(), 1.0);
            assert_eq!(cospi(x + 0.5), 0.0);
        }
        assert_eq!(sinpi(1e300), 0.0);
        assert_eq!(cospi(1e300), 1.0);
        assert!((sinpi(1.0 / 6.0) - 0.5).abs() < 1e-16);
        assert!((cospi(1.0 / 3.0) - 0.5).abs() < 1e-16);
        assert!((sinpi(2.5) - 1.0).abs() == 0.0);
        assert!((sinpi(-3.5) - 1.0).abs() == 0.0);
        for x in [
            -7.3, -2.5, -0.7, -0.26, -0.25, -1e-9, 0.0, 0.1, 0.3, 0.5, 1.75, 3.0, 1e17,
        ] {
            assert_eq!(sincospi(x), (sinpi(x), cospi(x)), "{x}");
            assert_eq!(sinc_from_sinpi(x, sinpi(x)), sinc(x), "{x}");
        }
    }

    #[test]
    fn sinc_small_and_large() {
        assert_eq!(sinc(0.0), 1.0);
        assert_eq!(sinc(5e-324), 1.0);
        assert_eq!(sinc(f64::MAX), 0.0);
        assert_eq!(sinc(3.0), 0.0);
        let x: f64 = 1e-4 * (1.0 + 1e-12);
        let direct = (PI * x).sin() / (PI * x);
        assert!((sinc(x) - direct).abs() < 1e-16);
        assert!((sinc(0.5) - 2.0 / PI).abs() < 1e-16);
    }

    #[test]
    fn j1_known_values_and_reference() {
        // DLMF / A&S table values
        assert!((bessel_j1(1.0) - 0.440_050_585_744_933_5).abs() < 6e-17);
        assert!((bessel_j1(10.0) - 0.043_472_746_168_861_44).abs() < 1.5e-16);
        // at the f64 nearest the first zero, J₁ = 1.17e-16 (mpmath)
        assert!(bessel_j1(3.831_705_970_207_512).abs() < 3e-16);
        let mut worst: f64 = 0.0;
        let mut x = 0.0;
        while x < 120.0 {
            // the reference's own rounding grows like x·1e-17
            let d = (bessel_j1(x) - j1_ref(x)).abs() / (1.0 + x / 20.0);
            worst = worst.max(d);
            x += 0.0731;
        }
        eprintln!("worst |ΔJ1| = {worst:e}");
        assert!(worst < 5e-16, "worst |ΔJ1| = {worst:e}");
    }

    #[test]
    fn jinc_limits() {
        assert_eq!(jinc(0.0), 1.0);
        assert_eq!(jinc(1e-300), 1.0);
        assert!(jinc(1e300).abs() < 1e-300);
        assert!(jinc(f64::MAX).is_finite());
        assert_eq!(bessel_j1(-2.0), -bessel_j1(2.0));
        assert_eq!(bessel_j1(0.0), 0.0);
    }
}
