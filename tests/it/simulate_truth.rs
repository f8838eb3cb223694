//! Truth bar of the simulator: noiseless constant-frequency sine patches at
//! 0.02–0.45 cy/px, at several rotations, show modulation = MTF × chart
//! modulation within 0.002. The modulation is measured by a least-squares sine
//! fit of the known frequency on interior pixels, and the MTF is computed here
//! from the closed forms (Gaussian × square pixel), not by the simulator.

use num_complex::Complex64;
use std::f64::consts::PI;
use sweepmtf::model::{Factor, System};
use sweepmtf::simulate::{self, Camera, demo::GaussianPsf};
use sweepmtf::target::{Direction, Rect, SinePatch, Target};

const PITCH_MM: f64 = 0.004;
const CHART_MM: f64 = 160.0;
const CHART_PX: f64 = 560.0;
const FREQS_CY_PX: [f64; 9] = [0.02, 0.05, 0.1, 0.15, 0.2, 0.25, 0.3, 0.38, 0.45];

/// A 160 mm square target with a 3×3 grid of 45 mm sine patches.
fn patch_target() -> Target {
    let s = CHART_PX / CHART_MM; // px per chart mm
    let patches = FREQS_CY_PX
        .iter()
        .enumerate()
        .map(|(i, &f)| SinePatch {
            id: format!("p{i}"),
            rect: Rect {
                x_mm: 5.0 + 52.5 * (i % 3) as f64,
                y_mm: 5.0 + 52.5 * (i / 3) as f64,
                width_mm: 45.0,
                height_mm: 45.0,
            },
            direction: if i % 2 == 0 {
                Direction::X
            } else {
                Direction::Y
            },
            freq_cy_mm: f * s,
            mean: 0.45,
            contrast: 0.5 + 0.05 * i as f64,
        })
        .collect();
    let t = Target {
        name: "patches".into(),
        width_mm: CHART_MM,
        height_mm: CHART_MM,
        background: 0.9,
        sweeps: vec![],
        patches,
        greys: vec![],
        fiducials: vec![],
    };
    t.validate().unwrap();
    t
}

/// Least-squares fit of a + b·cos(2πk·x) + c·sin(2πk·x); returns (a, b, c).
fn sine_fit(samples: &[([f64; 2], f64)], k: [f64; 2]) -> (f64, f64, f64) {
    let mut ata = [[0.0f64; 3]; 3];
    let mut atb = [0.0f64; 3];
    for &(p, v) in samples {
        let ph = 2.0 * PI * (k[0] * p[0] + k[1] * p[1]);
        let row = [1.0, ph.cos(), ph.sin()];
        for r in 0..3 {
            for c in 0..3 {
                ata[r][c] += row[r] * row[c];
            }
            atb[r] += row[r] * v;
        }
    }
    // Cramer's rule on the 3×3 normal equations.
    let det3 = |m: [[f64; 3]; 3]| {
        m[0][0] * (m[1][1] * m[2][2] - m[1][2] * m[2][1])
            - m[0][1] * (m[1][0] * m[2][2] - m[1][2] * m[2][0])
            + m[0][2] * (m[1][0] * m[2][1] - m[1][1] * m[2][0])
    };
    let d = det3(ata);
    let sol: Vec<f64> = (0..3)
        .map(|c| {
            let mut m = ata;
            for r in 0..3 {
                m[r][c] = atb[r];
            }
            det3(m) / d
        })
        .collect();
    (sol[0], sol[1], sol[2])
}

/// Interior pixels of patch `i` (at least `margin_px` from its edges): (centre, value).
fn interior(shot: &simulate::Shot, patch: &SinePatch, margin_px: f64) -> Vec<([f64; 2], f64)> {
    let inv = shot.chart_to_image.inverse().unwrap();
    let m = margin_px / (CHART_PX / CHART_MM);
    let r = patch.rect;
    let mut out = Vec::new();
    for y in 0..shot.height {
        for x in 0..shot.width {
            let p = [x as f64 + 0.5, y as f64 + 0.5];
            let c = inv.apply(p);
            if c[0] > r.x_mm + m
                && c[0] < r.x_mm + r.width_mm - m
                && c[1] > r.y_mm + m
                && c[1] < r.y_mm + r.height_mm - m
            {
                out.push((p, shot.signal[y * shot.width + x] as f64));
            }
        }
    }
    out
}

/// Image frequency vector (cy/px) of a patch under rotation `deg`, from first principles.
fn image_k(patch: &SinePatch, deg: f64) -> [f64; 2] {
    let f = patch.freq_cy_mm / (CHART_PX / CHART_MM);
    let (s, c) = deg.to_radians().sin_cos();
    // Chart +x → image (cos θ, −sin θ); chart +y → image (sin θ, cos θ) (counter-clockwise on screen).
    // A phase gradient rotates the same way as the chart axes under a similarity.
    match patch.direction {
        Direction::X => [f * c, -f * s],
        Direction::Y => [f * s, f * c],
    }
}

fn sinc(x: f64) -> f64 {
    if x == 0.0 {
        1.0
    } else {
        (PI * x).sin() / (PI * x)
    }
}

/// An anisotropic Gaussian: exp(−2π²(σx²u² + σy²v²)), in model axes (v up).
#[derive(Debug)]
struct EllipticGauss {
    sx_mm: f64,
    sy_mm: f64,
}

impl Factor for EllipticGauss {
    fn name(&self) -> String {
        "egauss".into()
    }
    fn otf(&self, u: f64, v: f64) -> Complex64 {
        Complex64::new(
            (-2.0 * PI * PI * (self.sx_mm.powi(2) * u * u + self.sy_mm.powi(2) * v * v)).exp(),
            0.0,
        )
    }
}

/// A PSF displaced by (dx, dy) mm in model axes (x right, y up): OTF = exp(−j2π(u·dx + v·dy)).
#[derive(Debug)]
struct Shift {
    dx_mm: f64,
    dy_mm: f64,
}

impl Factor for Shift {
    fn name(&self) -> String {
        "shift".into()
    }
    fn otf(&self, u: f64, v: f64) -> Complex64 {
        Complex64::from_polar(1.0, -2.0 * PI * (u * self.dx_mm + v * self.dy_mm))
    }
}

fn camera(deg: f64) -> Camera {
    Camera {
        rotate_deg: deg,
        chart_px: Some(CHART_PX),
        pixel_pitch_um: PITCH_MM * 1e3,
        exposure: 1.0,
        ..Camera::noiseless(800, 800)
    }
}

#[test]
fn sine_patches_show_mtf_times_chart_modulation_at_any_rotation() {
    let target = patch_target();
    let sigma_px = 0.45;
    let system = System {
        factors: vec![Box::new(GaussianPsf {
            sigma_mm: sigma_px * PITCH_MM,
        })],
    };
    let mut worst: f64 = 0.0;
    for deg in [0.0, 17.0, 45.0, 90.0, 133.0] {
        let shot = simulate::render(&target, &system, &camera(deg)).unwrap();
        for (p, truth) in target.patches.iter().zip(&shot.patches) {
            let k = image_k(p, deg);
            let (a, b, c) = sine_fit(&interior(&shot, p, 10.0), k);
            let measured = b.hypot(c) / a;
            let kk = k[0].hypot(k[1]);
            let mtf =
                (-2.0 * PI * PI * sigma_px * sigma_px * kk * kk).exp() * sinc(k[0]) * sinc(k[1]);
            let expect = mtf * p.contrast;
            let err = (measured - expect).abs();
            worst = worst.max(err);
            assert!(
                err < 0.002,
                "rotation {deg}°, patch {} at {kk:.3} cy/px: modulation {measured:.5}, expected {expect:.5}",
                p.id
            );
            // The shot's own truth agrees with the closed form.
            assert!((truth.freq_cy_px - kk).abs() < 1e-9 && (truth.mtf - mtf).abs() < 1e-9);
            // The mean level is the patch's mean reflectance (exposure 1, no fall-off).
            assert!((a - p.mean).abs() < 0.002, "mean {a} vs {}", p.mean);
        }
    }
    eprintln!("worst modulation error: {worst:.2e}");
}

#[test]
fn anisotropic_optics_follow_the_image_axes() {
    // σx ≠ σy: a sine varying along image x is blurred by σx, along image y by σy,
    // whatever the chart's rotation; catches transposed or mirrored OTF grids.
    let target = patch_target();
    let (sx, sy) = (0.7, 0.25); // px
    let system = System {
        factors: vec![Box::new(EllipticGauss {
            sx_mm: sx * PITCH_MM,
            sy_mm: sy * PITCH_MM,
        })],
    };
    for deg in [0.0, 30.0, 90.0] {
        let shot = simulate::render(&target, &system, &camera(deg)).unwrap();
        for p in target
            .patches
            .iter()
            .filter(|p| p.freq_cy_mm / (CHART_PX / CHART_MM) > 0.1)
        {
            let k = image_k(p, deg);
            let (a, b, c) = sine_fit(&interior(&shot, p, 10.0), k);
            let mtf = (-2.0 * PI * PI * (sx * sx * k[0] * k[0] + sy * sy * k[1] * k[1])).exp()
                * sinc(k[0])
                * sinc(k[1]);
            let err = (b.hypot(c) / a - mtf * p.contrast).abs();
            assert!(err < 0.002, "rotation {deg}°, patch {}: error {err}", p.id);
        }
    }
}

#[test]
fn a_displaced_psf_moves_the_image_the_right_way() {
    // PSF displaced by +dx (right) and +dy (up, model axes) must move the image
    // right by dx/pitch px and up (−y in the image) by dy/pitch px.
    let target = patch_target();
    let (dx_px, dy_px) = (0.3, 0.2);
    let plain = System { factors: vec![] };
    let shifted = System {
        factors: vec![Box::new(Shift {
            dx_mm: dx_px * PITCH_MM,
            dy_mm: dy_px * PITCH_MM,
        })],
    };
    let deg = 30.0;
    let a = simulate::render(&target, &plain, &camera(deg)).unwrap();
    let b = simulate::render(&target, &shifted, &camera(deg)).unwrap();
    for p in &target.patches[3..6] {
        let k = image_k(p, deg);
        let fa = sine_fit(&interior(&a, p, 10.0), k);
        let fb = sine_fit(&interior(&b, p, 10.0), k);
        // cos(2πk·x − φ): a shift d of the image changes φ by 2πk·d.
        let phase = |f: (f64, f64, f64)| f.2.atan2(f.1);
        let mut dphi = phase(fb) - phase(fa);
        dphi = (dphi + PI).rem_euclid(2.0 * PI) - PI;
        let expect = 2.0 * PI * (k[0] * dx_px + k[1] * (-dy_px));
        assert!(
            (dphi - expect).abs() < 1e-3,
            "patch {}: {dphi} vs {expect}",
            p.id
        );
    }
}

#[test]
fn a_model_system_with_its_own_aperture_is_not_blurred_twice() {
    // Diffraction (f/4, 550 nm) × a 4 µm square aperture × a sampling grid:
    // the aperture stands for the pixel (no second sinc), the sampling grid is
    // not applied. Expected MTF from the closed forms, computed here.
    use sweepmtf::model::spec::parse_factor;
    let system = System {
        factors: vec![
            parse_factor("optics", "diffraction:lambda=550nm,fnum=4").unwrap(),
            parse_factor("aperture", "rect:A=4um,B=4um").unwrap(),
            parse_factor("sampling", "rect:px=4um,py=4um").unwrap(),
        ],
    };
    let target = patch_target();
    let deg = 17.0;
    let shot = simulate::render(&target, &system, &camera(deg)).unwrap();
    assert_eq!(shot.factors_applied, ["diffraction", "aperture_rect"]);
    assert_eq!(shot.factors_skipped, ["sampling_rect"]);
    let cutoff = 1.0 / (550e-6 * 4.0); // cy/mm
    for p in &target.patches {
        let k = image_k(p, deg);
        let (a, b, c) = sine_fit(&interior(&shot, p, 10.0), k);
        let nu = k[0].hypot(k[1]) / PITCH_MM / cutoff;
        let diff = 2.0 / PI * (nu.acos() - nu * (1.0 - nu * nu).sqrt());
        let mtf = diff * sinc(k[0]) * sinc(k[1]);
        let err = (b.hypot(c) / a - mtf * p.contrast).abs();
        assert!(err < 0.002, "patch {}: error {err}", p.id);
    }
}
