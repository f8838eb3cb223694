//! Coarse JPEGs against the optics' truth, over the shots a camera makes:
//! the camera simulator's coloured-light RGB JPEG q75 4:2:0 with exposures
//! 0.5–0.9 of clipping and Gaussian lenses of σ = 0.45–0.7 px (drawn per
//! shot), at several turns to the 8×8 block grid, each measured from its
//! strip corners with default settings, from the file's bytes as `sweepmtf
//! measure` reads them (a JPEG's luminance from its Y′ plane alone; with
//! `STUDY_RGB=1` from the whole RGB decode instead, which under coloured
//! light carries the chroma quantiser too).
//!
//! Run: `cargo run --release --features examples --example coarse_jpeg_study
//! [-- N [SEED [TURNS [QUALITY]]]]`: N shots per turn (default 8, ≈ 30 s), seeds from
//! SEED (default 9000; the README's table pools 5000, 9000 and 13000),
//! TURNS a comma-separated list of degrees (default 0,0.7,1.1,1.5,2.2,3,5),
//! QUALITY the JPEG quality (default 75). Shots beyond a bar are listed on
//! stderr; with `STUDY_SAVE=DIR` the last shot's files and strip corners
//! are written to DIR (run one seed and one turn to keep a shot).
//! Prints one row per turn: shots, MTF50 errors beyond 1 %, RMS and largest
//! MTF50 error, mean MTF50 error, largest RMS |MTF − truth| over
//! 0.01–0.45 cy/px, largest chart-modulation error (and how many beyond
//! 0.5 %); then the same for the shots stored losslessly (PNG).

#[path = "common/scoring.rs"]
mod scoring;

use scoring::Score;
use sweepmtf::model::System;
use sweepmtf::simulate::demo::{GaussianPsf, demo_target_for};
use sweepmtf::simulate::{Camera, PhotoFormat, Shot, mtf_at, render};
use sweepmtf::target::SweepLaw;

/// `shot` stored as `format`, measured from its strip corners with defaults
/// as the CLI reads the file (with STUDY_RGB from the whole RGB decode), scored.
fn score(shot: &Shot, format: PhotoFormat) -> Result<Score, String> {
    let bytes = shot.encode(format).map_err(|e| e.to_string())?;
    if let Ok(dir) = std::env::var("STUDY_SAVE") {
        let r = shot.roi().unwrap_or_default();
        let _ = std::fs::write(format!("{dir}/shot.{format:?}"), &bytes);
        let _ = std::fs::write(format!("{dir}/roi.txt"), format!("{r:?}"));
    }
    let r = shot.roi().ok_or("no strip corners")?;
    let rows = &shot.truth().ok_or("no truth")?.rows;
    scoring::score(
        &bytes,
        [[r[0], r[1]], [r[2], r[3]], [r[4], r[5]], [r[6], r[7]]],
        &|f| mtf_at(rows, f),
        std::env::var_os("STUDY_RGB").is_some(),
    )
}

/// A number in [0, 1) drawn from `seed` and a salt (one multiply-shift hash).
fn draw(seed: u64, salt: u64) -> f64 {
    ((seed.wrapping_mul(salt) >> 7) % 1000) as f64 / 1000.0
}

/// One table row: turn, shots, failures, RMS / max / mean MTF50 error (%), worst RMS.
fn row(turn: f64, s: &[Score]) -> String {
    let n = s.len().max(1) as f64;
    let rms = (s.iter().map(|x| x.1 * x.1).sum::<f64>() / n).sqrt();
    let max = s.iter().map(|x| x.1.abs()).fold(0.0, f64::max);
    let mean = s.iter().map(|x| x.1).sum::<f64>() / n;
    let worst = s.iter().map(|x| x.0).fold(0.0, f64::max);
    let fails = s.iter().filter(|x| x.1.abs() > 0.01).count();
    let cm = s.iter().map(|x| x.2.abs()).fold(0.0, f64::max);
    let cm_fails = s.iter().filter(|x| x.2.abs() > 0.005).count();
    let cm_mean = s.iter().map(|x| x.2).sum::<f64>() / n;
    format!(
        "| {turn}° | {} | {fails} | {:.2} % | {:.2} % | {:+.2} % | {worst:.4} | {:.2} % ({cm_fails}), mean {:+.2} % |",
        s.len(),
        100.0 * rms,
        100.0 * max,
        100.0 * mean,
        100.0 * cm,
        100.0 * cm_mean
    )
}

fn main() {
    let arg = |i: usize| std::env::args().nth(i);
    let n: u64 = arg(1).and_then(|a| a.parse().ok()).unwrap_or(8);
    let base: u64 = arg(2).and_then(|a| a.parse().ok()).unwrap_or(9000);
    let turns: Vec<f64> = arg(3)
        .map(|v| v.split(',').filter_map(|x| x.parse().ok()).collect())
        .unwrap_or_else(|| vec![0.0, 0.7, 1.1, 1.5, 2.2, 3.0, 5.0]);
    let quality: u8 = arg(4).and_then(|a| a.parse().ok()).unwrap_or(75);
    let mut jpeg: Vec<Vec<Score>> = vec![Vec::new(); turns.len()];
    let mut png: Vec<Vec<Score>> = vec![Vec::new(); turns.len()];
    for k in 0..n {
        for (ti, &turn) in turns.iter().enumerate() {
            let seed = base + 37 * k + ti as u64;
            let cam = Camera {
                width_px: 1100,
                height_px: 700,
                chart_px: Some(900.0),
                rotate_deg: turn,
                full_well_e: Some(9000.0),
                read_noise_e: 4.0,
                seed,
                exposure: 0.5 + 0.4 * draw(seed, 0x9e37_79b9_7f4a_7c15),
                light_colour: Some([1.0, 0.82, 0.6]),
                jpeg_quality: Some(quality),
                ..Camera::default()
            };
            let sigma_px = 0.45 + 0.25 * draw(seed, 0xc2b2_ae3d_27d4_eb4f);
            let shot = demo_target_for(&cam, SweepLaw::Log, 0.006, 0.6)
                .map_err(|e| e.to_string())
                .and_then(|t| {
                    let system = System {
                        factors: vec![Box::new(GaussianPsf {
                            sigma_mm: sigma_px * cam.pitch_mm(),
                        })],
                    };
                    render(&t, &system, &cam).map_err(|e| e.to_string())
                });
            let shot = match shot {
                Ok(s) => s,
                Err(e) => {
                    eprintln!("seed {seed}: {e}");
                    continue;
                }
            };
            for (format, out) in [(PhotoFormat::Jpeg, &mut jpeg), (PhotoFormat::Png, &mut png)] {
                match score(&shot, format) {
                    Ok(s) => {
                        if s.1.abs() > 0.01 || s.0 > 0.012 || s.2.abs() > 0.005 {
                            eprintln!(
                                "seed {seed}, turned {turn}°, {format:?}: MTF50 {:+.2} %, RMS {:.4}, chart modulation {:+.2} %",
                                100.0 * s.1,
                                s.0,
                                100.0 * s.2
                            );
                        }
                        out[ti].push(s)
                    }
                    Err(e) => eprintln!("seed {seed}, turned {turn}°: {e}"),
                }
            }
        }
    }
    let jpeg_name = format!("RGB JPEG q{quality} 4:2:0");
    for (name, table) in [(jpeg_name.as_str(), &jpeg), ("the same shots as PNG", &png)] {
        println!("\n{name}\n");
        println!(
            "| turn | shots | MTF50 beyond 1 % | MTF50 RMS | largest | mean | worst RMS | chart modulation: largest error (beyond 0.5 %), mean |"
        );
        println!("|---|---|---|---|---|---|---|---|");
        for (turn, s) in turns.iter().zip(table.iter()) {
            println!("{}", row(*turn, s));
        }
    }
}
