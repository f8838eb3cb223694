//! Issue 15's bars on shots no test and no tuning ever saw: many fresh
//! geometries and noise seeds of each nuisance, measured as a new user would
//! (strip corners only, no target, default settings), scored against the
//! renderers' exact truth. Each shot is measured from its bytes as
//! `sweepmtf measure` measures a file (`measure_bytes`: a JPEG luminance
//! measurement decodes the Y′ plane alone).
//!
//! Run: `cargo run --release --features examples --example unseen [-- N [-v]]`
//! (N shots of each kind, default 20: ≈ 2.5 min; `-v` lists the JPEG shots).
//! Prints one row per kind: shots, failures of the bars, worst RMS
//! |MTF − truth| over 0.01–0.45 cy/px, the range of the MTF50 error and of
//! the chart modulation's error (printed 0.800).
//!
//! Kinds: the reference renderer's nuisance shots (`synth::nuisance_cases`,
//! variants from 100 on; the tests use 7 and 12, the report 0); the camera
//! simulator's strip photographed through radial distortion (−4…+4 % at the
//! frame corner, a, b, c mixed, near a random frame edge, turned ±2°); and
//! the camera simulator's coloured-light RGB JPEG q75 4:2:0 at turns of
//! 0–5° to the block grid; and everything at once (radial distortion ±3 %,
//! a perspective tilt up to 15°, 50 % fall-off and a 2:1 light gradient,
//! unsharp-mask sharpening, coloured light, RGB JPEG q85 or q75 4:2:0,
//! turned ±1.5°, near a random long edge).

#[path = "common/scoring.rs"]
mod scoring;

use scoring::{Score, score};
use sweepmtf::distortion::{Lens, Ptlens};
use sweepmtf::measure::synth::nuisance_cases;
use sweepmtf::model::System;
use sweepmtf::simulate::demo::{GaussianPsf, demo_target_for, strip_card};
use sweepmtf::simulate::{Camera, LightGradient, PhotoFormat, Sharpen, Shot, mtf_at, render};
use sweepmtf::target::{SweepLaw, Target};

/// Results of one kind, with its RMS bar.
struct Kind {
    name: String,
    bar: f64,
    scores: Vec<Score>,
    errors: Vec<String>,
}

impl Kind {
    fn new(name: &str, bar: f64) -> Kind {
        Kind {
            name: name.into(),
            bar,
            scores: Vec::new(),
            errors: Vec::new(),
        }
    }

    /// Keeps one shot's result; with a `label`, lists its score on stderr.
    fn record(&mut self, result: Result<Score, String>, label: Option<String>) {
        match result {
            Ok(s) => {
                if let Some(l) = label {
                    eprintln!("{l}: RMS {:.4} MTF50 {:+.2} %", s.0, 100.0 * s.1);
                }
                self.scores.push(s)
            }
            Err(e) => self.errors.push(e),
        }
    }

    fn fails(&self, s: &Score) -> bool {
        !(s.0 <= self.bar && s.1.abs() <= 0.01 && s.2.abs() <= 0.005)
    }

    fn row(&self) -> String {
        let range = |k: fn(&Score) -> f64| {
            let lo = self.scores.iter().map(k).fold(f64::INFINITY, f64::min);
            let hi = self.scores.iter().map(k).fold(f64::NEG_INFINITY, f64::max);
            format!("{:+.2}…{:+.2} %", 100.0 * lo, 100.0 * hi)
        };
        let worst = self.scores.iter().map(|s| s.0).fold(0.0, f64::max);
        let fails = self.scores.iter().filter(|s| self.fails(s)).count() + self.errors.len();
        format!(
            "| {} | {} | {} | {:.4} (≤ {}) | {} | {} |",
            self.name,
            self.scores.len() + self.errors.len(),
            fails,
            worst,
            self.bar,
            range(|s| s.1),
            range(|s| s.2)
        )
    }
}

/// A deterministic uniform generator on [0, 1).
struct Lcg(u64);

impl Lcg {
    fn next(&mut self) -> f64 {
        self.0 = self
            .0
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        (self.0 >> 11) as f64 / (1u64 << 53) as f64
    }
}

fn roi_of(shot: &Shot) -> [[f64; 2]; 4] {
    let r = shot.roi().expect("a strip shot has corners");
    [[r[0], r[1]], [r[2], r[3]], [r[4], r[5]], [r[6], r[7]]]
}

/// The strip near a random frame edge through random radial distortion.
fn distorted(k: u64, u: &mut Lcg) -> Result<Score, String> {
    let portrait = u.next() < 0.3;
    let (w, h) = if portrait {
        (
            900 + (200.0 * u.next()) as usize,
            1300 + (200.0 * u.next()) as usize,
        )
    } else {
        (
            1200 + (300.0 * u.next()) as usize,
            800 + (200.0 * u.next()) as usize,
        )
    };
    let side = (u.next() * 4.0) as usize; // bottom, top, left, right
    let across = if side < 2 { w } else { h } as f64;
    let chart_px = 0.9 * across;
    let half = 0.5 * (if side < 2 { h } else { w }) as f64;
    let edge = half - 0.5 * 40.0 / 260.0 * chart_px - (20.0 + 60.0 * u.next());
    let (offset, turn) = match side {
        0 => ([0.0, edge], 0.0),
        1 => ([0.0, -edge], 0.0),
        2 => ([-edge, 0.0], 90.0),
        _ => ([edge, 0.0], -90.0),
    };
    let pct = -4.0 + 8.0 * u.next();
    let mix = [
        0.4 * (u.next() - 0.5),
        0.8 + 0.4 * u.next(),
        0.2 * (u.next() - 0.5),
    ];
    let rc2 = ((w * w + h * h) as f64) / ((w.min(h) * w.min(h)) as f64);
    let b = pct / 100.0 / (rc2 - 1.0);
    let model = Ptlens {
        a: mix[0] * b,
        b: mix[1] * b,
        c: mix[2] * b,
    };
    Lens::new(model, w, h).check()?;
    let cam = Camera {
        width_px: w,
        height_px: h,
        chart_px: Some(chart_px),
        offset_px: offset,
        rotate_deg: turn + 4.0 * (u.next() - 0.5),
        distortion: Some(model),
        full_well_e: Some(20_000.0),
        read_noise_e: 3.0,
        seed: 500 + k,
        ..Camera::default()
    };
    strip_card_score(&cam, 0.5 + 0.2 * u.next(), PhotoFormat::Png)
}

/// Every nuisance at once, stored as RGB JPEG at `quality`: the strip near
/// the top or bottom edge through radial distortion (−3…+3 % at the corner),
/// a perspective tilt of 0–15° about the vertical axis, 50 % fall-off and a
/// 2:1 light gradient in a random direction, unsharp-mask sharpening,
/// coloured light, 4:2:0 chroma, turned ±1.5°.
fn everything(k: u64, u: &mut Lcg, quality: u8) -> Result<Score, String> {
    let (w, h) = (1400usize, 950usize);
    let chart_px = 0.9 * w as f64;
    let edge = 0.5 * h as f64 - 0.5 * 40.0 / 260.0 * chart_px - (20.0 + 60.0 * u.next());
    let offset = if u.next() < 0.5 {
        [0.0, edge]
    } else {
        [0.0, -edge]
    };
    let rc2 = ((w * w + h * h) as f64) / ((h * h) as f64);
    let b = (-3.0 + 6.0 * u.next()) / 100.0 / (rc2 - 1.0);
    let cam = Camera {
        width_px: w,
        height_px: h,
        chart_px: Some(chart_px),
        offset_px: offset,
        rotate_deg: 3.0 * (u.next() - 0.5),
        tilt_deg: 15.0 * u.next(),
        tilt_axis_deg: 90.0,
        distortion: Some(Ptlens { a: 0.0, b, c: 0.0 }),
        falloff: 0.5,
        light_gradient: Some(LightGradient {
            ratio: 2.0,
            toward_deg: 360.0 * u.next(),
        }),
        sharpen: Some(Sharpen {
            amount: 0.4,
            radius_px: 1.5,
        }),
        light_colour: Some([1.0, 0.85, 0.65]),
        jpeg_quality: Some(quality),
        full_well_e: Some(20_000.0),
        read_noise_e: 3.0,
        seed: 900 + k,
        ..Camera::default()
    };
    strip_card_score(&cam, 0.5 + 0.2 * u.next(), PhotoFormat::Jpeg)
}

/// The strip card (0.006–0.6 cycles per mm of a 260 mm chart, `cam.chart_px`
/// wide) shot with `cam` through a Gaussian lens of `sigma_px`, stored as
/// `format` and scored.
fn strip_card_score(cam: &Camera, sigma_px: f64, format: PhotoFormat) -> Result<Score, String> {
    let px_per_mm = cam.chart_px.ok_or("no chart size")? / 260.0;
    let t = strip_card(0.006 * px_per_mm, 0.6 * px_per_mm);
    score_shot(&shoot(&t, cam, sigma_px)?, format)
}

/// `shot` stored as `format`, measured from its strip corners and scored against its truth.
fn score_shot(shot: &Shot, format: PhotoFormat) -> Result<Score, String> {
    let bytes = shot.encode(format).map_err(|e| e.to_string())?;
    let rows = &shot.truth().ok_or("no truth")?.rows;
    score(&bytes, roi_of(shot), &|f| mtf_at(rows, f), false)
}

/// Renders target `t` with camera `cam` through a Gaussian lens of `sigma_px`.
fn shoot(t: &Target, cam: &Camera, sigma_px: f64) -> Result<Shot, String> {
    let system = System {
        factors: vec![Box::new(GaussianPsf {
            sigma_mm: sigma_px * cam.pitch_mm(),
        })],
    };
    render(t, &system, cam).map_err(|e| e.to_string())
}

/// The camera simulator's coloured-light RGB JPEG q75 4:2:0, turned `turn_deg`.
fn jpeg_q75(turn_deg: f64, seed: u64) -> Result<Score, String> {
    let cam = Camera {
        width_px: 1100,
        height_px: 700,
        chart_px: Some(900.0),
        rotate_deg: turn_deg,
        full_well_e: Some(9000.0),
        read_noise_e: 4.0,
        seed,
        light_colour: Some([1.0, 0.82, 0.6]),
        jpeg_quality: Some(75),
        ..Camera::default()
    };
    let t = demo_target_for(&cam, SweepLaw::Log, 0.006, 0.6).map_err(|e| e.to_string())?;
    let shot = shoot(&t, &cam, 0.55)?;
    score_shot(&shot, PhotoFormat::Jpeg)
}

fn main() {
    let n: u64 = std::env::args()
        .nth(1)
        .and_then(|a| a.parse().ok())
        .unwrap_or(20);
    let verbose = std::env::args().any(|a| a == "-v");
    let bars = [
        ("light3_vignette50", 0.008),
        ("keystone1.5_linear", 0.006),
        ("usm_peak1.15", 0.01),
        ("rgb_jpeg75_420", 0.012),
    ];
    let mut kinds: Vec<Kind> = bars.iter().map(|(k, b)| Kind::new(k, *b)).collect();
    for v in 100..100 + n {
        for shot in nuisance_cases(v) {
            let Some(kind) = kinds.iter_mut().find(|k| k.name == shot.name) else {
                continue;
            };
            kind.record(
                score(&shot.encode(1000 + v), shot.quad, &|f| shot.truth(f), false),
                None,
            );
        }
    }
    let mut dist = Kind::new("camera: radial distortion −4…+4 %, near an edge", 0.006);
    let mut u = Lcg(0x0005_eed0_fd15);
    for k in 0..n {
        // A draw whose chart does not fit the frame is drawn again.
        let mut tries = 0;
        loop {
            tries += 1;
            match distorted(k, &mut u) {
                Err(e) if e.contains("does not fit") && tries < 10 => continue,
                Ok(s) => dist.scores.push(s),
                Err(e) => dist.errors.push(e),
            }
            break;
        }
    }
    kinds.push(dist);
    let turns = [0.0, 0.7, 1.5, 3.0, 5.0];
    let mut jpeg = Kind::new("camera: RGB JPEG q75 4:2:0, turned 0–5°", 0.012);
    for k in 0..n {
        let turn = turns[k as usize % turns.len()];
        jpeg.record(
            jpeg_q75(turn, 700 + k),
            verbose.then(|| format!("q75 turned {turn}°")),
        );
    }
    kinds.push(jpeg);
    for quality in [85, 75] {
        let mut all = Kind::new(
            &format!(
                "camera: everything at once (distortion ±3 %, tilt ≤ 15°, light, USM, RGB JPEG q{quality})"
            ),
            0.012,
        );
        let mut u = Lcg(0xc0b0 + quality as u64);
        for k in 0..n {
            let label = verbose.then(|| format!("everything q{quality} {k}"));
            all.record(everything(k, &mut u, quality), label);
        }
        kinds.push(all);
    }
    println!(
        "| kind | shots | failing a bar | worst RMS (bar) | MTF50 error | chart modulation error |"
    );
    println!("|---|---|---|---|---|---|");
    for k in &kinds {
        println!("{}", k.row());
        for e in &k.errors {
            println!("  error: {e}");
        }
    }
}
