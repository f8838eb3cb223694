//! Renderer error against run time (the README's table): renders one
//! 1200×800 scene — sine patches at 0.05–0.6 cy/px and a black square with
//! axis-aligned edges on white, through a Gaussian PSF (σ = 0.5 px) and the
//! square pixel — for several oversampling factors, tile overlaps and FFT sizes,
//! and compares pixels with closed forms: the sines' analytic response
//! (mean·(1 + c·MTF·cos)) ≥ 10 px inside each patch, and the edge response
//! (step ⊗ box ⊗ Gaussian, via erf) within 4 px of the square's left edge,
//! worst over four sub-pixel positions of the chart; time: the fastest of the four.
//!
//! Run: `cargo bench --bench simulate` (release build; prints a Markdown table).

use std::f64::consts::PI;
use std::time::Instant;
use sweepmtf::model::System;
use sweepmtf::simulate::{self, Camera, RenderSettings, demo::GaussianPsf};
use sweepmtf::target::{Direction, GreyPatch, Rect, SinePatch, Target};

const PX_PER_MM: f64 = 4.0;
const SIGMA_PX: f64 = 0.5;
const FREQS: [f64; 4] = [0.05, 0.2, 0.45, 0.6];

/// erfc(x), Chebyshev fit (Numerical Recipes), relative error < 1.2e-7.
fn erfc(x: f64) -> f64 {
    let z = x.abs();
    let t = 1.0 / (1.0 + 0.5 * z);
    let r = t
        * (-z * z - 1.265_512_23
            + t * (1.000_023_68
                + t * (0.374_091_96
                    + t * (0.096_784_18
                        + t * (-0.186_288_06
                            + t * (0.278_868_07
                                + t * (-1.135_203_98
                                    + t * (1.488_515_87
                                        + t * (-0.822_152_23 + t * 0.170_872_77)))))))))
            .exp();
    if x >= 0.0 { r } else { 2.0 - r }
}

/// Standard normal CDF.
fn phi(x: f64) -> f64 {
    0.5 * erfc(-x / std::f64::consts::SQRT_2)
}

/// ∫_{−∞}^{t} Φ(s/σ) ds = t·Φ(t/σ) + σ·φ(t/σ).
fn g(t: f64) -> f64 {
    let z = t / SIGMA_PX;
    t * phi(z) + SIGMA_PX * (-0.5 * z * z).exp() / (2.0 * PI).sqrt()
}

/// Fraction of the box ⊗ Gaussian kernel centred `d` px right of an edge that lies left of it.
fn left_fraction(d: f64) -> f64 {
    // ∫_{−∞}^{0} (box⊗gauss)(x − d) dx = ∫_{−∞}^{−d} [Φ((t+½)/σ) − Φ((t−½)/σ)] dt.
    g(-d + 0.5) - g(-d - 0.5)
}

fn sinc(x: f64) -> f64 {
    if x == 0.0 {
        1.0
    } else {
        (PI * x).sin() / (PI * x)
    }
}

fn scene() -> Target {
    let patches = FREQS
        .iter()
        .enumerate()
        .map(|(i, &f)| SinePatch {
            id: format!("s{i}"),
            rect: Rect {
                x_mm: 10.0 + 57.0 * i as f64,
                y_mm: 10.0,
                width_mm: 50.0,
                height_mm: 50.0,
            },
            direction: Direction::X,
            freq_cy_mm: f * PX_PER_MM,
            mean: 0.5,
            contrast: 0.8,
        })
        .collect();
    Target {
        name: "error-scene".into(),
        width_mm: 240.0,
        height_mm: 160.0,
        background: 1.0,
        sweeps: vec![],
        patches,
        greys: vec![GreyPatch {
            id: "black".into(),
            rect: Rect {
                x_mm: 100.0,
                y_mm: 90.0,
                width_mm: 40.0,
                height_mm: 40.0,
            },
            reflectance: 0.03,
            density: None,
        }],
        fiducials: vec![],
    }
}

#[derive(Clone, Copy)]
struct Row {
    k: usize,
    margin: usize,
    fft: usize,
    seconds: f64,
    sine_err: f64,
    edge_err: f64,
}

fn run(target: &Target, system: &System, r: RenderSettings, offset: f64) -> Row {
    let cam = Camera {
        chart_px: Some(240.0 * PX_PER_MM),
        offset_px: [offset, 0.0], // edges off the pixel and fine grids
        exposure: 1.0,
        render: r,
        ..Camera::noiseless(1200, 800)
    };
    let t0 = Instant::now();
    let shot = simulate::render(target, system, &cam).expect("render");
    let seconds = t0.elapsed().as_secs_f64();
    let inv = shot.chart_to_image.inverse().unwrap();
    let (mut sine_err, mut edge_err) = (0.0f64, 0.0f64);
    for p in &target.patches {
        let f = p.freq_cy_mm / PX_PER_MM;
        let mtf = (-2.0 * PI * PI * SIGMA_PX * SIGMA_PX * f * f).exp() * sinc(f);
        let a = shot.chart_to_image.apply([p.rect.x_mm, p.rect.y_mm]);
        let b = shot.chart_to_image.apply([
            p.rect.x_mm + p.rect.width_mm,
            p.rect.y_mm + p.rect.height_mm,
        ]);
        for y in (a[1] + 10.0) as usize..(b[1] - 10.0) as usize {
            for x in (a[0] + 10.0) as usize..(b[0] - 10.0) as usize {
                let c = inv.apply([x as f64 + 0.5, y as f64 + 0.5]);
                let s = c[0] - p.rect.x_mm;
                let want = p.mean * (1.0 + p.contrast * mtf * (2.0 * PI * p.freq_cy_mm * s).cos());
                sine_err = sine_err.max((shot.signal[y * shot.width + x] as f64 - want).abs());
            }
        }
    }
    let gp = &target.greys[0];
    let e = shot.chart_to_image.apply([gp.rect.x_mm, gp.rect.y_mm]);
    let bottom = shot
        .chart_to_image
        .apply([gp.rect.x_mm, gp.rect.y_mm + gp.rect.height_mm])[1];
    for y in (e[1] + 10.0) as usize..(bottom - 10.0) as usize {
        for x in (e[0] - 4.0) as usize..(e[0] + 4.0) as usize {
            let d = x as f64 + 0.5 - e[0]; // > 0: inside the black square
            let want = gp.reflectance + (target.background - gp.reflectance) * left_fraction(d);
            let got = shot.signal[y * shot.width + x] as f64;
            edge_err = edge_err.max((got - want).abs());
        }
    }
    Row {
        k: r.oversample,
        margin: r.margin_px,
        fft: r.fft_size,
        seconds,
        sine_err,
        edge_err,
    }
}

fn main() {
    // `cargo bench` passes `--bench`; ignore arguments.
    let target = scene();
    let system = System {
        factors: vec![Box::new(GaussianPsf {
            sigma_mm: SIGMA_PX * 0.0043,
        })],
    };
    let settings = [
        (1, 8, 256, 1),
        (2, 8, 512, 1),
        (4, 16, 1024, 1),
        (8, 16, 1024, 1),
        (1, 8, 256, 8),
        (2, 4, 512, 8),
        (2, 8, 512, 8),
        (2, 16, 512, 4),
        (2, 16, 512, 8),
        (2, 16, 512, 16),
        (2, 16, 512, 32),
        (2, 32, 512, 8),
        (2, 16, 256, 8),
        (2, 16, 1024, 8),
        (4, 16, 1024, 8),
    ];
    println!("Renderer error against run time, 1200×800 px, Gaussian σ = 0.5 px × square pixel");
    println!(
        "(max |error| of linear signal, white = 1; {} threads)\n",
        rayon::current_num_threads()
    );
    println!(
        "| oversample | margin px | FFT size | edge sub-samples | time s | sine error | edge error |"
    );
    println!("|---:|---:|---:|---:|---:|---:|---:|");
    for (k, m, n, e) in settings {
        let r = RenderSettings {
            oversample: k,
            margin_px: m,
            fft_size: n,
            edge_subsamples: e,
        };
        if r.tile_px() < 8 {
            continue;
        }
        // Several sub-pixel edge positions; worst errors, fastest time.
        let rows: Vec<Row> = [0.3, 0.137, 0.41, 0.05]
            .iter()
            .map(|&o| run(&target, &system, r, o))
            .collect();
        let row = Row {
            seconds: rows.iter().map(|r| r.seconds).fold(f64::INFINITY, f64::min),
            sine_err: rows.iter().map(|r| r.sine_err).fold(0.0, f64::max),
            edge_err: rows.iter().map(|r| r.edge_err).fold(0.0, f64::max),
            ..rows[0]
        };
        println!(
            "| {} | {} | {} | {} | {:.3} | {:.1e} | {:.1e} |",
            row.k, row.margin, row.fft, r.edge_subsamples, row.seconds, row.sine_err, row.edge_err
        );
    }
}
