//! Accuracy of the non-aperture model factors against references computed
//! here, independently of the code under test: tanh-sinh quadrature of the
//! pupil overlap (diffraction, defocus), a trapezoid Fourier integral of the
//! PSF (Gaussian), and the closed forms in double-double arithmetic (OLPF,
//! diffusion, CTE, the latter as a binary power of the complex base).
//! Bar: |ΔOTF| ≤ 1e-13 everywhere, including the stiff points.
//! Run with `--nocapture` to see the worst errors.

use crate::model_ref;

use model_ref::{Cdd, DD, tanh_sinh};
use num_complex::Complex64;
use proptest::prelude::*;
use std::f64::consts::PI;
use sweepmtf::model::Factor;
use sweepmtf::model::cte::{Cte, CteModel};
use sweepmtf::model::diffusion::Diffusion;
use sweepmtf::model::gaussian::Gaussian;
use sweepmtf::model::olpf::Olpf;
use sweepmtf::model::optics::{DefocusGeometric, DefocusWave, Diffraction};

const BAR: f64 = 1e-13;

/// Tracks the worst error and where it happened.
struct Worst {
    what: &'static str,
    err: f64,
    at: String,
}

impl Worst {
    fn new(what: &'static str) -> Self {
        Worst {
            what,
            err: 0.0,
            at: String::new(),
        }
    }
    fn check(&mut self, got: Complex64, want: Complex64, at: impl FnOnce() -> String) {
        let e = (got - want).norm();
        assert!(
            got.re.is_finite() && got.im.is_finite(),
            "non-finite at {}",
            at()
        );
        if e > self.err || e.is_nan() {
            self.err = e;
            self.at = at();
        }
    }
    fn report(&self) {
        eprintln!(
            "{}: worst |ΔOTF| = {:.3e} at {}",
            self.what, self.err, self.at
        );
        assert!(
            self.err <= BAR,
            "{}: {:.3e} at {}",
            self.what,
            self.err,
            self.at
        );
    }
}

fn re(x: f64) -> Complex64 {
    Complex64::new(x, 0.0)
}

/// A deterministic sequence in [0, 1).
fn lcg(n: usize, seed: u64) -> Vec<f64> {
    let mut s = seed;
    (0..n)
        .map(|_| {
            s = s
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            (s >> 11) as f64 / (1u64 << 53) as f64
        })
        .collect()
}

// ---------------------------------------------------------------- diffraction

/// Normalised overlap area of two unit disks whose centres are 2s apart,
/// s = 1 − t, by tanh-sinh quadrature over the chord half-widths: the
/// overlap is ∫ 2(√(1−y²) − s) dy over |y| ≤ Y = √(t(2−t)); with δ = Y − |y|
/// the width is δ(2Y−δ)/(√(s²+δ(2Y−δ)) + s), free of cancellation.
fn overlap_otf(t: f64) -> f64 {
    if t <= 0.0 {
        return 0.0;
    }
    let s = 1.0 - t;
    let y = (t * (2.0 - t)).sqrt();
    let area = tanh_sinh(0.0, y, 1e-15, |_, d, _| {
        let g = d * (2.0 * y - d);
        2.0 * g / ((s * s + g).sqrt() + s)
    });
    2.0 * area / PI
}

/// t = 1 − ρ/u_c in double-double for the exact (u, v), with u_c = 512.
fn t_exact(u: f64, v: f64) -> f64 {
    let rho2 = DD::prod(u, u) + DD::prod(v, v);
    let s = rho2.sqrt() * DD::new(1.0 / 512.0);
    (DD::ONE - s).to_f64()
}

#[test]
fn diffraction_matches_pupil_overlap_quadrature() {
    // λ = 2⁻¹¹ mm (488 nm), F# = 4: λ·F# = 2⁻⁹ exactly, cutoff 512 cycles/mm.
    let d = Diffraction::new(2f64.powi(-11), 4.0);
    assert_eq!(d.cutoff(), 512.0);
    let mut w = Worst::new("diffraction");
    let mut pts: Vec<(f64, f64)> = vec![(0.0, 0.0), (1e-300, 0.0), (0.0, 5e-324)];
    for k in 0..=100 {
        let s = k as f64 / 100.0;
        for ang in [0.0, 90.0, 45.0, 30.0, 1e-10, 89.999] {
            let a = f64::to_radians(ang);
            pts.push((512.0 * s * a.cos(), 512.0 * s * a.sin()));
        }
    }
    // v/u from 1e-1 down to 1e-15, u = ±v, at several radii.
    for s in [0.2, 0.6, 0.99] {
        for e in 1..=15 {
            let r = 10f64.powi(-e);
            let u = 512.0 * s / (1.0 + r * r).sqrt();
            pts.push((u, u * r));
            pts.push((-u, u * r));
        }
        let u = 512.0 * s / 2f64.sqrt();
        pts.push((u, u));
        pts.push((u, -u));
    }
    // Within 1e-12 (relative) of the cutoff, on and off axis, both sides.
    for e in [
        1e-9, 1e-10, 1e-11, 1e-12, 1e-13, 1e-14, 1e-15, 0.0, -1e-15, -1e-12,
    ] {
        let r = 512.0 * (1.0 - e);
        for ang in [0.0, 90.0, 45.0, 17.0, 63.0] {
            let a = f64::to_radians(ang);
            pts.push((r * a.cos(), r * a.sin()));
        }
    }
    // Random points out to 1.2× cutoff.
    let rnd = lcg(600, 7);
    for p in rnd.chunks(2) {
        let r = 512.0 * 1.2 * p[0];
        let a = 2.0 * PI * p[1];
        pts.push((r * a.cos(), r * a.sin()));
    }
    for &(u, v) in &pts {
        let want = overlap_otf(t_exact(u, v));
        w.check(d.otf(u, v), re(want), || format!("u={u:e}, v={v:e}"));
    }
    w.report();
}

#[test]
fn diffraction_keeps_relative_accuracy_at_the_cutoff() {
    let d = Diffraction::new(2f64.powi(-11), 4.0);
    let mut worst: f64 = 0.0;
    let mut at = String::new();
    for e in [1e-6, 1e-8, 1e-10, 1e-12, 1e-13, 1e-14] {
        for ang in [0.0, 90.0, 45.0, 17.0, 63.0, 1e-7] {
            let a = f64::to_radians(ang);
            let (u, v) = (512.0 * (1.0 - e) * a.cos(), 512.0 * (1.0 - e) * a.sin());
            let want = overlap_otf(t_exact(u, v));
            let got = d.otf(u, v).re;
            let rel = ((got - want) / want).abs();
            if rel > worst {
                worst = rel;
                at = format!("u={u:e}, v={v:e}");
            }
        }
    }
    eprintln!("diffraction: worst relative error near the cutoff {worst:.3e} at {at}");
    assert!(worst < 1e-13, "{worst} at {at}");
}

// ---------------------------------------------------------------- defocus

/// Defocused OTF as (4/π)∫₀^t cos(a(t−δ))·√(δ(2−δ)) dδ, a = 8πW020·s (x-form of
/// the sheared-pupil integral, with δ the distance to the pupil edge).
fn defocus_ref(t: f64, w020: f64) -> f64 {
    if t <= 0.0 {
        return 0.0;
    }
    let s = 1.0 - t;
    let a = 8.0 * PI * w020 * s;
    // Split the range so each piece holds at most ~1 oscillation.
    let pieces = ((a.abs() * t / PI).ceil() as usize).max(1);
    let mut sum = 0.0;
    for k in 0..pieces {
        let lo = t * k as f64 / pieces as f64;
        let hi = t * (k + 1) as f64 / pieces as f64;
        sum += tanh_sinh(lo, hi, 1e-15, |x, dlo, _| {
            let dd = if k == 0 { dlo } else { x };
            (a * (t - dd)).cos() * (dd * (2.0 - dd)).sqrt()
        });
    }
    4.0 / PI * sum
}

#[test]
fn defocus_matches_sheared_pupil_quadrature() {
    let mut w = Worst::new("defocus wave");
    for w020 in [0.1, 0.25, 0.5, 1.0, 3.0, -2.0, 10.0, 25.0] {
        let d = DefocusWave::new(2f64.powi(-11), 4.0, w020);
        let mut pts = vec![(0.0, 0.0)];
        for k in 0..=60 {
            let s = k as f64 / 60.0;
            pts.push((512.0 * s, 0.0));
            pts.push((512.0 * s * 0.6, 512.0 * s * 0.8));
        }
        for e in [1e-9, 1e-12, 1e-14] {
            pts.push((512.0 * (1.0 - e), 0.0));
        }
        for &(u, v) in &pts {
            let want = defocus_ref(t_exact(u, v), w020);
            w.check(d.otf(u, v), re(want), || {
                format!("W020={w020}, u={u}, v={v}")
            });
        }
    }
    w.report();
}

/// 2J₁(z)/z with J₁(z) = (1/π)∫₀^π cos(τ − z·sin τ) dτ by the trapezoid rule
/// (spectrally accurate for this periodic integrand); series for small z.
fn jinc_ref(z: f64) -> f64 {
    if z.abs() < 1e-3 {
        let q = z * z / 4.0;
        return 1.0 - q / 2.0 + q * q / 12.0 - q * q * q / 144.0;
    }
    let n = 64 + 2 * z.abs() as usize;
    let h = PI / n as f64;
    let mut sum = 0.0;
    for k in 0..=n {
        let t = k as f64 * h;
        let w = if k == 0 || k == n { 0.5 } else { 1.0 };
        sum += w * (t - z * t.sin()).cos();
    }
    2.0 * (sum * h / PI) / z
}

#[test]
fn geometric_defocus_matches_disk_transform() {
    let mut w = Worst::new("defocus geometric");
    for blur in [0.002, 0.0137, 0.05] {
        let d = DefocusGeometric { blur_mm: blur };
        for k in 0..400 {
            let rho = k as f64 * 25.0 / blur / 400.0;
            for (cu, cv) in [(1.0, 0.0), (0.0, 1.0), (0.6, 0.8)] {
                let (u, v) = (rho * cu, rho * cv);
                let z = PI * blur * DD::prod(u, u).add_prod(v, v).sqrt().to_f64();
                w.check(d.otf(u, v), re(jinc_ref(z)), || {
                    format!("blur={blur} ρ={rho}")
                });
            }
        }
    }
    w.report();
}

// ---------------------------------------------------------------- gaussian

/// 1-D OTF of a Gaussian PSF by the trapezoid rule on the Fourier integral.
fn gauss_1d(sigma: f64, u: f64) -> f64 {
    let h = sigma / 8.0;
    let n = 40 * 8;
    let mut sum = 0.0;
    for k in -n..=n {
        let x = k as f64 * h;
        sum += (-0.5 * (x / sigma).powi(2)).exp() * (2.0 * PI * u * x).cos();
    }
    sum * h / (sigma * (2.0 * PI).sqrt())
}

#[test]
fn gaussian_matches_fourier_integral() {
    let mut w = Worst::new("gaussian");
    for (sx, sy) in [(0.001, 0.001), (0.0025, 0.0007), (1e-5, 0.004)] {
        let g = Gaussian {
            sigma_x: sx,
            sigma_y: sy,
        };
        for i in -12..=12 {
            for j in -12..=12 {
                let u = i as f64 * 0.25 / sx;
                let v = j as f64 * 0.25 / sy;
                let want = gauss_1d(sx, u) * gauss_1d(sy, v);
                w.check(g.otf(u, v), re(want), || {
                    format!("σ=({sx},{sy}) u={u} v={v}")
                });
            }
        }
    }
    w.report();
}

// ---------------------------------------------------------------- olpf

#[test]
fn olpf_matches_spot_sum() {
    let mut w = Worst::new("olpf");
    for (dx, dy) in [
        (0.0043, 0.0),
        (0.0, 0.003),
        (0.005, 0.005),
        (0.0037, 0.0021),
    ] {
        let f = Olpf { dx, dy };
        let mut us = vec![0.0, 1e-300, 5e-324];
        for k in 0..200 {
            us.push(k as f64 * 0.37 / 0.004);
        }
        // Within 1e-9 of the zeros u = (k + 1/2)/d.
        for k in 0..25 {
            for e in [-1e-9, 0.0, 1e-9] {
                us.push((k as f64 + 0.5 + e) / dx.max(dy));
            }
        }
        for &u in &us {
            for &v in &[u, -u, 0.0, u * 1e-15, 0.5 * u] {
                // ½(e^{jπdu} + e^{−jπdu}) per plate, with the exact product d·u.
                let cx = DD::prod(dx, u).sincos_pi().1.to_f64();
                let cy = DD::prod(dy, v).sincos_pi().1.to_f64();
                w.check(f.otf(u, v), re(cx * cy), || {
                    format!("d=({dx},{dy}) u={u} v={v}")
                });
            }
        }
    }
    w.report();
}

// ---------------------------------------------------------------- diffusion

/// Seib's formula in double-double arithmetic.
fn diffusion_ref(alpha: f64, ld: f64, l0: f64, f: f64) -> f64 {
    let a = DD::new(alpha);
    let l0 = DD::new(l0);
    let k = DD::new(2.0) * DD::PI * DD::new(f) * l0;
    let l = l0 / (DD::ONE + k * k).sqrt();
    let e = (-(a * DD::new(ld))).exp();
    let num = DD::ONE - e / (DD::ONE + a * l);
    let den = DD::ONE - e / (DD::ONE + a * l0);
    (num / den).to_f64()
}

#[test]
fn diffusion_matches_double_double_formula() {
    let mut w = Worst::new("diffusion");
    // α in 1/mm: 1e-8 per µm = 1e-5 per mm, up to 1e4 per mm (10 per µm).
    for alpha in [1e-5, 1e-3, 0.639, 64.0, 639.0, 1e4] {
        for ld in [0.0, 1e-4, 0.002, 0.01] {
            for l0 in [0.001, 0.01, 0.1] {
                let d = Diffusion::new(alpha, ld, l0);
                for k in 0..60 {
                    let f = if k == 0 { 0.0 } else { 1.2f64.powi(k) * 0.05 };
                    for (u, v) in [(f, 0.0), (0.0, f), (f * 0.6, f * 0.8)] {
                        let fr = DD::prod(u, u) + DD::prod(v, v);
                        let want = diffusion_ref(alpha, ld, l0, fr.sqrt().to_f64());
                        w.check(d.otf(u, v), re(want), || {
                            format!("α={alpha}/mm L_D={ld} L0={l0} f={f}")
                        });
                    }
                }
            }
        }
    }
    w.report();
}

// ---------------------------------------------------------------- cte

/// ((1−c) + c·e^{−j2πx})^N in double-double, x = f·pitch exactly.
fn cte_exact_ref(n: u64, c: f64, f: f64, pitch: f64) -> Complex64 {
    let x2 = DD::prod(f, pitch) * DD::new(2.0);
    let (s, co) = x2.sincos_pi();
    let c = DD::new(c);
    let z = Cdd {
        re: (DD::ONE - c) + c * co,
        im: -(c * s),
    };
    let p = z.pow(n);
    Complex64::new(p.re.to_f64(), p.im.to_f64())
}

/// exp(−N·c·(1 − cos 2πx)) in double-double.
fn cte_exp_ref(n: f64, c: f64, f: f64, pitch: f64) -> f64 {
    let x2 = DD::prod(f, pitch) * DD::new(2.0);
    let (_, co) = x2.sincos_pi();
    (-(DD::new(n) * DD::new(c) * (DD::ONE - co))).exp().to_f64()
}

#[test]
fn cte_matches_binary_power_in_double_double() {
    let mut w = Worst::new("cte exact");
    let mut we = Worst::new("cte exp");
    let pitch = 0.0043;
    let cases: &[(u64, f64)] = &[
        (100_000_000, 1e-7),
        (1_000_000_000, 1e-12),
        (1_000_000_000, 1e-9),
        (1_000_000, 1e-5),
        (2000, 1e-3),
        (1000, 0.3),
        (1000, 0.5),
        (1000, 0.7),
        (1_000_000_000, 1.0 - 1e-12),
        (1_000_000_000, 1.0),
        (7, 0.9),
        (1_000_000_000, 0.5),
        (1_000_000_000, 0.3),
        (1_000_000_000, 0.7),
        (1_000_000_000, 1e-3),
        (100_000, 0.2),
    ];
    let rnd = lcg(80, 11);
    for &(n, c) in cases {
        let exact = Cte {
            n: n as f64,
            cti: c,
            pitch,
            model: CteModel::Exact,
            along_v: false,
        };
        let expm = Cte {
            model: CteModel::Exp,
            ..exact.clone()
        };
        let mut fs: Vec<f64> = vec![0.0, 5e-324, 1e-300, 0.5 / pitch, 1.0 / pitch, 0.25 / pitch];
        fs.extend(rnd.iter().map(|r| (r - 0.5) * 2.5 / pitch));
        // Near f = 0, where the magnitude is still large for big N·c.
        for e in 1..12 {
            fs.push(10f64.powi(-e) / pitch);
        }
        for &f in &fs {
            let want = cte_exact_ref(n, c, f, pitch);
            w.check(exact.otf(f, 0.0), want, || format!("N={n} cti={c} f={f}"));
            let want = cte_exp_ref(n as f64, c, f, pitch);
            we.check(expm.otf(f, 0.0), re(want), || {
                format!("N={n} cti={c} f={f}")
            });
        }
    }
    w.report();
    we.report();
}

// ---------------------------------------------------------------- properties

fn frequency() -> impl Strategy<Value = f64> {
    prop_oneof![
        -2000.0..2000.0f64,
        -1e6..1e6f64,
        Just(0.0),
        Just(1e300),
        Just(-1e300),
        Just(f64::MAX),
        Just(5e-324),
        Just(-2.2e-308),
        (1e-320..1e-300f64),
    ]
}

fn factors() -> impl Strategy<Value = Box<dyn Factor>> {
    prop_oneof![
        (1e-4..2e-3f64, 0.5..32.0f64)
            .prop_map(|(l, f)| Box::new(Diffraction::new(l, f)) as Box<dyn Factor>),
        (1e-4..2e-3f64, 0.5..32.0f64, -5.0..5.0f64)
            .prop_map(|(l, f, w)| Box::new(DefocusWave::new(l, f, w)) as Box<dyn Factor>),
        (1e-6..0.1f64, 1e-6..0.1f64).prop_map(|(a, b)| Box::new(Gaussian {
            sigma_x: a,
            sigma_y: b
        }) as Box<dyn Factor>),
        (0.0..0.1f64, 0.0..0.1f64)
            .prop_map(|(a, b)| Box::new(Olpf { dx: a, dy: b }) as Box<dyn Factor>),
        (1e-6..1e5f64, 0.0..0.1f64, 1e-5..1.0f64)
            .prop_map(|(a, d, l)| Box::new(Diffusion::new(a, d, l)) as Box<dyn Factor>),
        (
            0u64..2_000_000_000,
            0.0..=1.0f64,
            1e-5..0.1f64,
            any::<bool>(),
            any::<bool>()
        )
            .prop_map(|(n, c, p, exact, v)| Box::new(Cte {
                n: n as f64,
                cti: c,
                pitch: p,
                model: if exact {
                    CteModel::Exact
                } else {
                    CteModel::Exp
                },
                along_v: v,
            }) as Box<dyn Factor>),
    ]
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(3000))]

    #[test]
    fn otf_properties(f in factors(), u in frequency(), v in frequency()) {
        let o = f.otf(u, v);
        prop_assert!(o.re.is_finite() && o.im.is_finite(), "{f:?} ({u},{v}) → {o}");
        prop_assert!(o.norm() <= 1.0 + 2.0 * f64::EPSILON, "{f:?} ({u},{v}) → {o}");
        let m = f.otf(-u, -v);
        prop_assert!((m - o.conj()).norm() <= 1e-15, "{f:?} ({u},{v}): {o} vs {m}");
        let one = f.otf(0.0, 0.0);
        prop_assert!((one - Complex64::new(1.0, 0.0)).norm() <= 1e-15, "{f:?}: {one}");
    }
}
