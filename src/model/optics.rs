//! Optics: the diffraction-limited circular pupil (Fliegel eq. 44 with cutoff
//! u_c = 1/(λ·F#)) and defocus.
//!
//! With s = ρ/u_c, ρ = √(u²+v²), eq. 44 reads OTF = (2/π)[acos s − s√(1−s²)].
//! Writing β = acos s and x = 2β it is OTF = (x − sin x)/π, which is evaluated
//! without cancellation: β = 2·asin(√(t/2)) from t = 1 − s (near the cutoff
//! computed as (1 − s²)/(1 + s) with u², v² and (λ·F#)² in double-double, so
//! t keeps its relative accuracy within 1e-12 of the cutoff, on and off axis), and x − sin x by its Taylor series for small x. Any
//! s ≥ 1, however it rounds, gives exactly 0: never NaN.
//!
//! Defocus (`--defocus`) comes in two forms:
//! - `wave:lambda=..,fnum=..,w020=<waves>` or `dz=<length>`: the exact (scalar,
//!   paraxial) OTF of a circular pupil with defocus wavefront W(r) = W020·r²
//!   (Hopkins 1955). With the pupil radius 1 and the two sheared pupils
//!   centred at ±s, the phase difference across the overlap is 4·W020·s·x
//!   waves, so OTF(s) = (4/π)∫₀^β cos(8πW020·s·(cos θ − s)) sin²θ dθ, which
//!   reduces to eq. 44 for W020 = 0. It includes diffraction: use it instead
//!   of `--optics diffraction`, not together with it. `dz` is the image-side
//!   focus shift: W020 = dz/(8·F#²) (as a length), in waves divided by λ.
//!   The integral is done by composite 20-point Gauss–Legendre with panels
//!   short enough that the phase turns by at most 8 rad in each.
//! - `geometric:blur=<diameter>` or `geometric:dz=..,fnum=..` (blur = |dz|/F#):
//!   the geometric-optics blur disk, a uniform disk of that diameter,
//!   OTF = 2J₁(πdρ)/(πdρ). It excludes diffraction and multiplies with
//!   `--optics diffraction`; it is a good approximation only when the blur is
//!   several times the Airy disk.

use super::params::Params;
use super::spec::split_shape;
use super::trig::two_prod;
use super::{Factor, ModelError};
use num_complex::Complex64;
use std::f64::consts::PI;
use std::sync::OnceLock;

/// Diffraction-limited incoherent OTF of a circular pupil.
#[derive(Debug, Clone)]
pub struct Diffraction {
    /// Wavelength, mm.
    pub lambda_mm: f64,
    /// Working f-number.
    pub fnum: f64,
    /// λ·F# split exactly into a high and a low part (mm).
    w: (f64, f64),
}

impl Diffraction {
    /// A pupil at wavelength `lambda_mm` (mm) and f-number `fnum`.
    pub fn new(lambda_mm: f64, fnum: f64) -> Self {
        Diffraction {
            lambda_mm,
            fnum,
            w: two_prod(lambda_mm, fnum),
        }
    }

    /// Cutoff frequency 1/(λ·F#), cycles/mm.
    pub fn cutoff(&self) -> f64 {
        1.0 / (self.lambda_mm * self.fnum)
    }
}

/// Error-free sum: (s, e) with s = fl(a + b) and a + b = s + e exactly.
fn two_sum(a: f64, b: f64) -> (f64, f64) {
    let s = a + b;
    let bb = s - a;
    (s, (a - (s - bb)) + (b - bb))
}

/// t = 1 − ρ·w with ρ = √(u²+v²) and w = w.0 + w.1 (an exact product λ·F#).
///
/// Near the cutoff (ρw close to 1) it is computed as (1 − ρ²w²)/(1 + ρw) with
/// u², v² and w² carried in double-double, so that t keeps its relative
/// accuracy on and off axis (no rounding of √(u²+v²) enters); elsewhere
/// 1 − ρ·w directly.
fn one_minus(u: f64, v: f64, w: (f64, f64)) -> f64 {
    let rho = u.hypot(v);
    let s = rho * w.0;
    if !(0.5..=2.0).contains(&s) {
        return rho.mul_add(-w.0, 1.0) - rho * w.1;
    }
    // ρ² = u² + v² as hi + lo.
    let (uh, ul) = two_prod(u, u);
    let (vh, vl) = two_prod(v, v);
    let (r_hi, e) = two_sum(uh, vh);
    let r_lo = e + ul + vl;
    // w² = w0² + 2·w0·w1 as hi + lo.
    let (w_hi, e) = two_prod(w.0, w.0);
    let w_lo = e + 2.0 * w.0 * w.1;
    // ρ²w² − 1 with the big parts exact.
    let (p_hi, p_e) = two_prod(r_hi, w_hi);
    let small = p_e + r_hi * w_lo + r_lo * w_hi;
    let one_minus_s2 = (1.0 - p_hi) - small;
    one_minus_s2 / (1.0 + rho.mul_add(w.0, rho * w.1))
}

/// x − sin x for x in [0, π], without cancellation at small x.
fn x_minus_sin(x: f64) -> f64 {
    if x < 1.0 {
        // Σ_{k≥1} (−1)^{k+1} x^{2k+1}/(2k+1)!
        let x2 = x * x;
        let mut term = x * x2 / 6.0;
        let mut sum = 0.0;
        let mut k = 1.0;
        let mut terms = [0.0; 12];
        for t in terms.iter_mut() {
            *t = term;
            term *= -x2 / ((2.0 * k + 2.0) * (2.0 * k + 3.0));
            k += 1.0;
        }
        for t in terms.iter().rev() {
            sum += t;
        }
        sum
    } else {
        x - x.sin()
    }
}

/// β = acos(s) from t = 1 − s (0 < t ≤ 1), stable for t → 0.
fn acos_from_t(t: f64) -> f64 {
    if t < 0.5 {
        2.0 * (0.5 * t).sqrt().asin()
    } else {
        (1.0 - t).acos()
    }
}

/// Eq. 44 as a function of t = 1 − ρ/u_c: 0 for t ≤ 0, 1 for t ≥ 1.
pub fn diffraction_otf_t(t: f64) -> f64 {
    if t.is_nan() || t <= 0.0 {
        return 0.0;
    }
    if t >= 1.0 {
        return 1.0;
    }
    x_minus_sin(2.0 * acos_from_t(t)) / PI
}

impl Factor for Diffraction {
    fn name(&self) -> String {
        "diffraction".into()
    }
    fn otf(&self, u: f64, v: f64) -> Complex64 {
        Complex64::new(diffraction_otf_t(one_minus(u, v, self.w)), 0.0)
    }
}

/// Parses an `--optics` spec: `diffraction:lambda=..,fnum=..`.
pub fn parse(spec: &str) -> Result<Box<dyn Factor>, ModelError> {
    let (_, rest) = split_shape("optics", spec, &["diffraction"])?;
    let p = Params::parse("optics diffraction", rest)?;
    let lambda = p.positive_length("lambda")?;
    let fnum = positive_number(&p, "fnum")?;
    p.finish(&["lambda", "fnum"])?;
    Ok(Box::new(Diffraction::new(lambda, fnum)))
}

/// A required number > 0 (e.g. an f-number).
pub(crate) fn positive_number(p: &Params, key: &str) -> Result<f64, ModelError> {
    let v = p.number(key)?;
    if v > 0.0 {
        Ok(v)
    } else {
        Err(p.error(format!("{key} must be > 0, got {v}")))
    }
}

/// Gauss–Legendre nodes and weights on [−1, 1], 20 points.
fn gauss_legendre_20() -> &'static ([f64; 20], [f64; 20]) {
    static GL: OnceLock<([f64; 20], [f64; 20])> = OnceLock::new();
    GL.get_or_init(|| {
        const N: usize = 20;
        let mut x = [0.0; N];
        let mut w = [0.0; N];
        for i in 0..N {
            let mut z = (PI * (i as f64 + 0.75) / (N as f64 + 0.5)).cos();
            let mut dp = 0.0;
            for _ in 0..100 {
                let (mut p0, mut p1) = (1.0, z);
                for k in 2..=N {
                    let kf = k as f64;
                    let p2 = ((2.0 * kf - 1.0) * z * p1 - (kf - 1.0) * p0) / kf;
                    p0 = p1;
                    p1 = p2;
                }
                dp = N as f64 * (z * p1 - p0) / (z * z - 1.0);
                let dz = p1 / dp;
                z -= dz;
                if dz.abs() < 1e-16 {
                    break;
                }
            }
            x[i] = z;
            w[i] = 2.0 / ((1.0 - z * z) * dp * dp);
        }
        (x, w)
    })
}

/// Phase turn (radians) covered by one 20-point Gauss–Legendre panel of the defocus integral.
const PANEL_PHASE: f64 = 8.0;

/// Defocused diffraction-limited circular pupil (exact, Hopkins).
#[derive(Debug, Clone)]
pub struct DefocusWave {
    /// Wavelength, mm.
    pub lambda_mm: f64,
    /// Working f-number.
    pub fnum: f64,
    /// Defocus coefficient W020, waves.
    pub w020_waves: f64,
    w: (f64, f64),
}

impl DefocusWave {
    /// A defocused pupil: wavelength (mm), f-number, W020 (waves).
    pub fn new(lambda_mm: f64, fnum: f64, w020_waves: f64) -> Self {
        DefocusWave {
            lambda_mm,
            fnum,
            w020_waves,
            w: two_prod(lambda_mm, fnum),
        }
    }

    /// OTF as a function of t = 1 − ρ/u_c.
    fn otf_t(&self, t: f64) -> f64 {
        if t.is_nan() || t <= 0.0 {
            return 0.0;
        }
        if t >= 1.0 {
            return 1.0;
        }
        let s = 1.0 - t;
        let beta = acos_from_t(t);
        let a = 8.0 * PI * self.w020_waves * s;
        if a == 0.0 {
            return diffraction_otf_t(t);
        }
        let (xs, ws) = gauss_legendre_20();
        // The phase a·(cos θ − s) turns by at most |a|·sin β·β over [0, β];
        // one 20-point panel per PANEL_PHASE radians of it.
        let phase_span = a.abs() * beta.sin() * beta;
        let panels = (phase_span / PANEL_PHASE).ceil().clamp(1.0, 1e6) as usize;
        let h = beta / panels as f64;
        let mut total = 0.0;
        for k in 0..panels {
            let mid = (k as f64 + 0.5) * h;
            let mut sum = 0.0;
            for (x, w) in xs.iter().zip(ws) {
                let (sh, ch) = (0.5 * (mid + 0.5 * h * x)).sin_cos();
                // sin θ = 2 sin(θ/2) cos(θ/2); cos θ − s = t − 2 sin²(θ/2).
                let st = 2.0 * sh * ch;
                let d = t - 2.0 * sh * sh;
                sum += w * (a * d).cos() * st * st;
            }
            total += 0.5 * h * sum;
        }
        4.0 / PI * total
    }
}

impl Factor for DefocusWave {
    fn name(&self) -> String {
        "defocus".into()
    }
    fn otf(&self, u: f64, v: f64) -> Complex64 {
        Complex64::new(self.otf_t(one_minus(u, v, self.w)), 0.0)
    }
}

/// Geometric-optics defocus: a uniform blur disk of diameter `blur_mm`.
#[derive(Debug, Clone)]
pub struct DefocusGeometric {
    /// Blur-disk diameter, mm.
    pub blur_mm: f64,
}

impl Factor for DefocusGeometric {
    fn name(&self) -> String {
        "defocus".into()
    }
    fn otf(&self, u: f64, v: f64) -> Complex64 {
        let rho = u.hypot(v);
        Complex64::new(super::special::jinc(PI * self.blur_mm * rho), 0.0)
    }
}

/// Largest |W020| accepted for `defocus wave`, waves (beyond it use `geometric`).
pub const MAX_W020_WAVES: f64 = 100.0;

/// Parses a `--defocus` spec (`wave:…` or `geometric:…`).
pub fn parse_defocus(spec: &str) -> Result<Box<dyn Factor>, ModelError> {
    let (shape, rest) = split_shape("defocus", spec, &["wave", "geometric"])?;
    if shape == "wave" {
        let p = Params::parse("defocus wave", rest)?;
        let lambda = p.positive_length("lambda")?;
        let fnum = positive_number(&p, "fnum")?;
        let w020 = match (p.has("w020"), p.has("dz")) {
            (true, false) => p.number("w020")?,
            (false, true) => {
                let dz = p.length_opt("dz")?.unwrap_or(0.0);
                dz / (8.0 * fnum * fnum) / lambda
            }
            _ => {
                return Err(p.error(
                    "give exactly one of w020=<waves> or dz=<focus shift length>".to_string(),
                ));
            }
        };
        if w020.is_nan() || w020.abs() > MAX_W020_WAVES {
            return Err(p.error(format!(
                "|W020| must be at most {MAX_W020_WAVES} waves (got {w020}); use defocus geometric:blur=.. for larger defocus"
            )));
        }
        p.finish(&["lambda", "fnum", "w020", "dz"])?;
        Ok(Box::new(DefocusWave::new(lambda, fnum, w020)))
    } else {
        let p = Params::parse("defocus geometric", rest)?;
        let blur = match (p.has("blur"), p.has("dz")) {
            (true, false) => p.positive_length("blur")?,
            (false, true) => {
                let dz = p.length_opt("dz")?.unwrap_or(0.0).abs();
                let fnum = positive_number(&p, "fnum")?;
                if dz.is_nan() || dz <= 0.0 {
                    return Err(p.error("dz must be a non-zero length"));
                }
                dz / fnum
            }
            _ => {
                return Err(
                    p.error("give exactly one of blur=<diameter> or dz=<focus shift>,fnum=<F#>")
                );
            }
        };
        p.finish(&["blur", "dz", "fnum"])?;
        Ok(Box::new(DefocusGeometric { blur_mm: blur }))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn eq44_at_ordinary_points() {
        let d = Diffraction::new(550e-6, 4.0);
        for s in [0.0, 0.1, 0.3, 0.5, 0.7, 0.9, 0.99] {
            let direct = 2.0 / PI * (f64::acos(s) - s * (1.0 - s * s).sqrt());
            let got = d.otf(s * d.cutoff(), 0.0).re;
            assert!((got - direct).abs() < 2e-15, "s={s}: {got} vs {direct}");
        }
    }

    #[test]
    fn zero_at_and_past_cutoff_never_nan() {
        let d = Diffraction::new(550e-6, 4.0);
        let c = d.cutoff();
        for u in [c, c * (1.0 + 1e-16), c * 2.0, 1e300, f64::MAX] {
            let o = d.otf(u, u * 0.3).re;
            assert!(o == 0.0, "{u}: {o}");
        }
        assert_eq!(d.otf(0.0, 0.0).re, 1.0);
        assert_eq!(d.otf(5e-324, -5e-324).re, 1.0);
    }

    #[test]
    fn defocus_specs_convert_focus_shift() {
        // dz = 10 µm at f/2.8, 550 nm: W020 = dz/(8·F#²) = 0.1594 µm = 0.28989 waves.
        let f = parse_defocus("wave:lambda=550nm,fnum=2.8,dz=10um").unwrap();
        let g = DefocusWave::new(550e-6, 2.8, 0.01 / (8.0 * 2.8 * 2.8) / 550e-6);
        for u in [10.0, 100.0, 300.0] {
            assert!((f.otf(u, 0.0) - g.otf(u, 0.0)).norm() < 1e-15);
        }
        // Geometric: blur = dz/F# = 20 µm at dz = 80 µm, f/4.
        let f = parse_defocus("geometric:dz=80um,fnum=4").unwrap();
        let g = DefocusGeometric { blur_mm: 0.02 };
        assert!((f.otf(50.0, 20.0) - g.otf(50.0, 20.0)).norm() < 1e-15);
        assert!(parse_defocus("wave:lambda=550nm,fnum=4,w020=101").is_err());
        assert!(parse_defocus("wave:lambda=550nm,fnum=4,w020=1,dz=1um").is_err());
        assert!(parse_defocus("geometric:blur=1um,dz=1um,fnum=2").is_err());
    }

    #[test]
    fn defocus_zero_is_diffraction() {
        let d = Diffraction::new(500e-6, 2.8);
        let f = DefocusWave::new(500e-6, 2.8, 0.0);
        let g = DefocusWave::new(500e-6, 2.8, 1e-30);
        for k in 0..50 {
            let u = k as f64 * 15.0;
            assert_eq!(f.otf(u, 0.0), d.otf(u, 0.0));
            assert!((g.otf(u, 0.0) - d.otf(u, 0.0)).norm() < 1e-15);
        }
    }
}
