//! Error against run time: every method and the main settings (bin width,
//! window length, margin) over a fixed set of simulated shots with known truth.
//!
//! Run: `cargo run --release --features examples --example accuracy [-- --quick]`; `-- --write DIR`
//! instead writes every case as a photo and prints its `--roi`.
//! Prints one table row per (case, method, setting): RMS |MTF − truth| over
//! 0.01–0.45 cy/px, the largest local-frequency error (%), and the time of one
//! measurement (decode + measure) in milliseconds. A second table measures the
//! nuisance shots of issue 15 (uneven light, keystone, sharpening, RGB JPEG
//! 4:2:0; `synth::nuisance_cases(0)`) with the CLI's defaults (refinement on),
//! adding the MTF50 error and the chart modulation found (printed 0.800).
//! Then the distortion rows (`-- --distortion-only` alone) and the same
//! nuisance shots on paper with their high end clicked beyond the print
//! (`-- --ends-only` alone).

#[path = "accuracy/distortion.rs"]
mod distortion;
#[path = "accuracy/ends.rs"]
mod ends;

use std::time::Instant;
use sweepmtf::measure::synth::{SynthShot, nuisance_cases, standard_cases};
use sweepmtf::measure::{MeasureOptions, Method, measure_bytes};

/// Accuracy figures of one run.
struct Score {
    rms: f64,
    freq_err_pct: f64,
    ms: f64,
    n: usize,
}

fn score(shot: &SynthShot, bytes: &[u8], opts: &MeasureOptions) -> Result<Score, String> {
    let t0 = Instant::now();
    let m = measure_bytes(bytes, &shot.name, None, opts).map_err(|e| e.to_string())?;
    let ms = t0.elapsed().as_secs_f64() * 1e3;
    let c = &m.curves[0];
    let d = |a: [f64; 2], b: [f64; 2]| (a[0] - b[0]).hypot(a[1] - b[1]);
    let q = shot.quad;
    let len_mine = 0.5 * (d(q[0], q[1]) + d(q[3], q[2]));
    let ratio = shot.length / len_mine;
    let mut se = 0.0;
    let mut n = 0;
    let mut ferr: f64 = 0.0;
    for p in c.points.iter().filter(|p| !p.aliased) {
        let f_true = shot.freq_px_at(p.s * ratio);
        ferr = ferr.max((p.freq_cy_px / f_true - 1.0).abs());
        if (0.01..=0.45).contains(&p.freq_cy_px) {
            se += (p.mtf - shot.truth(p.freq_cy_px)).powi(2);
            n += 1;
        }
    }
    if n == 0 {
        return Err("no points in 0.01–0.45 cy/px".into());
    }
    Ok(Score {
        rms: (se / n as f64).sqrt(),
        freq_err_pct: 100.0 * ferr,
        ms,
        n,
    })
}

fn main() {
    let args: Vec<String> = std::env::args().collect();
    let quick = args.iter().any(|a| a == "--quick");
    if args.iter().any(|a| a == "--distortion-only") {
        distortion::table();
        return;
    }
    if args.iter().any(|a| a == "--ends-only") {
        ends::table();
        return;
    }
    let cases = standard_cases();
    if let Some(i) = args.iter().position(|a| a == "--write-big") {
        // A 24-megapixel JPEG (6000×4000, quality 90) for the speed and memory check.
        let path = args.get(i + 1).map(String::as_str).unwrap_or("big.jpg");
        let shot = sweepmtf::measure::synth::big_shot();
        std::fs::write(path, shot.encode(5)).expect("write");
        let roi: Vec<String> = shot
            .quad
            .iter()
            .flatten()
            .map(|v| format!("{v:.2}"))
            .collect();
        println!("{path} --roi {}", roi.join(","));
        return;
    }
    if let Some(i) = args.iter().position(|a| a == "--write") {
        // Write every case as a file plus its region, for trying the CLI.
        let dir = std::path::PathBuf::from(args.get(i + 1).map(String::as_str).unwrap_or("."));
        std::fs::create_dir_all(&dir).expect("output folder");
        for shot in &cases {
            let ext = if shot.jpeg_quality.is_some() {
                "jpg"
            } else {
                "png"
            };
            let path = dir.join(format!("{}.{ext}", shot.name));
            std::fs::write(&path, shot.encode(42)).expect("write");
            let roi: Vec<String> = shot
                .quad
                .iter()
                .flatten()
                .map(|v| format!("{v:.2}"))
                .collect();
            println!("{} --roi {}", path.display(), roi.join(","));
        }
        return;
    }
    let mut settings: Vec<(String, MeasureOptions)> = Vec::new();
    for method in Method::ALL {
        settings.push((
            "default".into(),
            MeasureOptions {
                method,
                ..MeasureOptions::default()
            },
        ));
        if quick {
            continue;
        }
        for bin in [0.1, 0.5, 1.0] {
            settings.push((
                format!("bin {bin} px"),
                MeasureOptions {
                    method,
                    bin_px: bin,
                    ..MeasureOptions::default()
                },
            ));
        }
        if method != Method::Extrema {
            for w in [2.0, 8.0] {
                settings.push((
                    format!("window {w} cy"),
                    MeasureOptions {
                        method,
                        window_cycles: w,
                        ..MeasureOptions::default()
                    },
                ));
            }
        }
        for margin in [0.05, 0.3] {
            settings.push((
                format!("margin {margin}"),
                MeasureOptions {
                    method,
                    margin,
                    ..MeasureOptions::default()
                },
            ));
        }
    }
    println!("| case | method | setting | RMS error | max freq error % | points | time ms |");
    println!("|---|---|---|---|---|---|---|");
    for shot in &cases {
        let bytes = shot.encode(42);
        for (label, o) in &settings {
            let opts = MeasureOptions {
                roi: Some(shot.quad),
                ..o.clone()
            };
            match score(shot, &bytes, &opts) {
                Ok(s) => println!(
                    "| {} | {} | {} | {:.4} | {:.3} | {} | {:.1} |",
                    shot.name,
                    opts.method.name(),
                    label,
                    s.rms,
                    s.freq_err_pct,
                    s.n,
                    s.ms
                ),
                Err(e) => println!(
                    "| {} | {} | {} | failed: {} | | | |",
                    shot.name,
                    opts.method.name(),
                    label,
                    e
                ),
            }
        }
    }
    println!();
    println!(
        "| nuisance case | method | RMS error | MTF50 error % | chart modulation (0.800) | time ms |"
    );
    println!("|---|---|---|---|---|---|");
    for shot in nuisance_cases(0) {
        let bytes = shot.encode(42);
        for method in Method::ALL {
            let opts = MeasureOptions {
                roi: Some(shot.quad),
                refine_roi: true,
                method,
                ..MeasureOptions::default()
            };
            let t0 = Instant::now();
            let res = measure_bytes(&bytes, &shot.name, None, &opts).map_err(|e| e.to_string());
            let ms = t0.elapsed().as_secs_f64() * 1e3;
            match res {
                Ok(m) => {
                    let c = &m.curves[0];
                    let (mut se, mut n) = (0.0, 0);
                    for p in c.points.iter().filter(|p| !p.aliased) {
                        if (0.01..=0.45).contains(&p.freq_cy_px) {
                            se += (p.mtf - shot.truth(p.freq_cy_px)).powi(2);
                            n += 1;
                        }
                    }
                    let mut f = 0.0;
                    while shot.truth(f) >= 0.5 && f < 0.5 {
                        f += 1e-5;
                    }
                    let e50 = c
                        .figures
                        .mtf50_cy_px
                        .map(|m| format!("{:+.2}", 100.0 * (m / f - 1.0)))
                        .unwrap_or_else(|| "none".into());
                    println!(
                        "| {} | {} | {:.4} | {} | {:.4} ± {:.4} | {:.1} |",
                        shot.name,
                        method.name(),
                        (se / n.max(1) as f64).sqrt(),
                        e50,
                        c.chart_modulation,
                        c.chart_modulation_err,
                        ms
                    );
                }
                Err(e) => println!("| {} | {} | failed: {e} | | | |", shot.name, method.name()),
            }
        }
    }
    distortion::table();
    ends::table();
}
