//! TEMPORARY stub of helper model-ap's special functions (replaced on merge).

/// sinc(x) = sin(πx)/(πx), 1 at 0.
pub fn sinc(x: f64) -> f64 {
    if x == 0.0 {
        1.0
    } else {
        super::trig::sin_pi(x) / (std::f64::consts::PI * x)
    }
}

/// jinc(x) = 2J₁(πx)/(πx), 1 at 0 (stub: trapezoid on the Bessel integral).
pub fn jinc(x: f64) -> f64 {
    let z = std::f64::consts::PI * x.abs();
    if z < 1e-8 {
        return 1.0;
    }
    if !z.is_finite() || z > 1e6 {
        return 0.0;
    }
    let n = 2000 + (z as usize) * 8;
    let h = std::f64::consts::PI / n as f64;
    let mut s = 0.0;
    for k in 0..=n {
        let t = k as f64 * h;
        let w = if k == 0 || k == n { 0.5 } else { 1.0 };
        s += w * (t - z * t.sin()).cos();
    }
    2.0 * (s * h / std::f64::consts::PI) / z
}
