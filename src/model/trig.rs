//! Trigonometry of arguments given in half-turns (`sin(πx)`, `cos(πx)`) with
//! exact range reduction, so that `cos(π·d·u)` stays exact for huge `d·u`
//! (an even integer gives exactly 1) and no `π·x` product loses the phase.
//! Also the error-free product used to reduce `N·x` modulo 1.

/// Reduces `x` modulo 2 into [−1, 1] exactly (`%` on f64 is exact).
fn reduce2(x: f64) -> f64 {
    let mut r = x % 2.0;
    if r > 1.0 {
        r -= 2.0;
    } else if r < -1.0 {
        r += 2.0;
    }
    r
}

/// sin(πx) and cos(πx), with exact reduction of `x` modulo 2 (±inf counts
/// as an even integer, like every f64 beyond 2^54).
pub fn sincos_pi(x: f64) -> (f64, f64) {
    if x.is_nan() {
        return (f64::NAN, f64::NAN);
    }
    if x.is_infinite() {
        // Every f64 beyond 2^54 is an even integer; ±inf continues that.
        return (0.0, 1.0);
    }
    let r = reduce2(x);
    // sin(π(1−r)) = sin(πr), cos(π(1−r)) = −cos(πr): fold r into [−1/2, 1/2].
    let (r, cs) = if r > 0.5 {
        (1.0 - r, -1.0)
    } else if r < -0.5 {
        (-1.0 - r, -1.0)
    } else {
        (r, 1.0)
    };
    let a = r.abs();
    let sign = if r < 0.0 { -1.0 } else { 1.0 };
    let (s, c) = if a <= 0.25 {
        let (s, c) = (std::f64::consts::PI * a).sin_cos();
        (s, c)
    } else {
        // π(1/2 − a) with 1/2 − a exact for a in [1/4, 1/2].
        let (s, c) = (std::f64::consts::PI * (0.5 - a)).sin_cos();
        (c, s)
    };
    (sign * s, cs * c)
}

/// sin(πx) for finite `x`.
pub fn sin_pi(x: f64) -> f64 {
    sincos_pi(x).0
}

/// cos(πx) for finite `x`.
pub fn cos_pi(x: f64) -> f64 {
    sincos_pi(x).1
}

/// cos(π·a·b) for the exact product a·b (not its rounding): both parts of the
/// error-free product are reduced modulo 2 exactly before they are added.
pub fn cos_pi_prod(a: f64, b: f64) -> f64 {
    let (p, e) = two_prod(a, b);
    if !p.is_finite() {
        return cos_pi(p);
    }
    cos_pi(p % 2.0 + e % 2.0)
}

/// Error-free product: returns (p, e) with p = fl(a·b) and a·b = p + e exactly
/// (barring underflow).
pub fn two_prod(a: f64, b: f64) -> (f64, f64) {
    let p = a * b;
    let e = if p.is_finite() { a.mul_add(b, -p) } else { 0.0 };
    (p, e)
}

/// The fractional part of the exact product `n·x` minus the nearest integer,
/// in [−1/2, 1/2], computed without losing the small part of `n·x` (n ≤ 2^53).
pub fn frac_prod(n: f64, x: f64) -> f64 {
    const BIG: f64 = 9007199254740992.0;
    if x.is_nan() || n.is_nan() || x.abs() >= BIG || n.abs() >= BIG {
        // x (or n) is an integer (or ±inf, treated as one): so is n·x when n is.
        return 0.0;
    }
    let (p, e) = two_prod(n, x);
    let fp = p - p.round();
    let fe = e - e.round();
    let f = fp + fe;
    f - f.round()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn exact_at_special_points() {
        assert_eq!(sin_pi(1.0), 0.0);
        assert_eq!(cos_pi(0.5), 0.0);
        assert_eq!(cos_pi(1e300), 1.0);
        assert_eq!(sin_pi(0.5), 1.0);
        assert_eq!(cos_pi(1.0), -1.0);
        assert_eq!(cos_pi(3.0), -1.0);
        assert_eq!(sin_pi(-0.5), -1.0);
        assert_eq!(sin_pi(5e-324), std::f64::consts::PI * 5e-324);
    }

    #[test]
    fn agrees_with_std_for_moderate_arguments() {
        for i in -2000..2000 {
            let x = i as f64 * 0.01237;
            let (s, c) = sincos_pi(x);
            let (s0, c0) = (std::f64::consts::PI * x).sin_cos();
            assert!((s - s0).abs() < 1e-13 && (c - c0).abs() < 1e-13, "{x}");
        }
    }

    #[test]
    fn frac_prod_keeps_small_part() {
        // 1e9 · (0.1) where 0.1 is not exact: the exact product's fraction.
        let x = 0.1f64;
        let f = frac_prod(1e9, x);
        // 0.1 = 0.1000000000000000055511151231257827...; times 1e9 → fraction 5.55e-9.
        assert!((f - 5.551115123125783e-9).abs() < 1e-20, "{f}");
    }
}
