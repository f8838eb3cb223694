//! Ends-clicked rows of the accuracy example (session 35): the real
//! simulator's strip on white paper (a log and a linear sweep, 0.01–0.45
//! cy/px, ≈ 830 × 80 px), its high-frequency end given 0, 4, 12, 22, 40
//! and 75 px beyond the print (corners 2 and 3 moved along the strip), or its low end
//! 3, 20 and 45 px (corners 1 and 4), measured with
//! the CLI's defaults, with the printed ends looked for (the default) and
//! without (`--keep-ends`, as before session 35). Session 37: the same
//! strip on a grey background at the sweep's mean (no step in level beyond
//! its ends), its high end 40 and 75 px beyond. Truth: the simulator's
//! analytic MTF and printed contrast.

use std::time::Instant;
use sweepmtf::measure::{MeasureOptions, measure_decoded};
use sweepmtf::photo::decode::decode_bytes;
use sweepmtf::simulate::demo::demo_target_for;
use sweepmtf::simulate::{Camera, encode::PhotoFormat, mtf_at, render};
use sweepmtf::target::SweepLaw;

/// Prints the table.
pub fn table() {
    println!();
    println!(
        "| sweep | high / low end beyond (px) | ends | RMS error | worst point | MTF50 error % | chart modulation error % | ends found inside, low / high (px) | time ms |"
    );
    println!("|---|---|---|---|---|---|---|---|---|");
    let cam = Camera {
        width_px: 1200,
        height_px: 800,
        chart_px: Some(1000.0),
        full_well_e: Some(20000.0),
        read_noise_e: 3.0,
        seed: 7,
        rotate_deg: 2.5,
        ..Camera::default()
    };
    let path =
        std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("targets/systems/aps_c_f4.toml");
    let system = sweepmtf::model::System::from_file(&path).expect("aps_c_f4.toml");
    let paper: &[(f64, f64)] = &[
        (0.0, 0.0),
        (4.0, 0.0),
        (12.0, 0.0),
        (22.0, 0.0),
        (40.0, 0.0),
        (75.0, 0.0),
        (0.0, 3.0),
        (0.0, 20.0),
        (0.0, 45.0),
    ];
    let grey: &[(f64, f64)] = &[(0.0, 0.0), (40.0, 0.0), (75.0, 0.0)];
    for (law, on_grey) in [
        (SweepLaw::Log, false),
        (SweepLaw::Linear, false),
        (SweepLaw::Log, true),
        (SweepLaw::Linear, true),
    ] {
        let mut t = demo_target_for(&cam, law, 0.01, 0.45).expect("target");
        if on_grey {
            t.background = t.sweeps[0].mean;
        }
        let name = if on_grey {
            format!("{law:?} on grey")
        } else {
            format!("{law:?}")
        };
        let contrast = t.sweeps[0].contrast;
        let shot = render(&t, &system, &cam).expect("render");
        let bytes = shot.encode(PhotoFormat::Png).expect("encode");
        let truth = shot.truth().expect("truth");
        let rows = &truth.rows;
        let w = rows
            .windows(2)
            .find(|w| w[0].mtf >= 0.5 && w[1].mtf < 0.5)
            .expect("MTF50 inside the truth");
        let f50 = w[0].freq_cy_px
            + (w[0].mtf - 0.5) / (w[0].mtf - w[1].mtf) * (w[1].freq_cy_px - w[0].freq_cy_px);
        let r = shot.roi().expect("roi");
        let c: Vec<[f64; 2]> = (0..4).map(|i| [r[2 * i], r[2 * i + 1]]).collect();
        let len = (c[1][0] - c[0][0]).hypot(c[1][1] - c[0][1]);
        let along = [(c[1][0] - c[0][0]) / len, (c[1][1] - c[0][1]) / len];
        for &(beyond, low) in if on_grey { grey } else { paper } {
            let mut quad = [c[0], c[1], c[2], c[3]];
            for k in 0..2 {
                quad[1][k] += beyond * along[k];
                quad[2][k] += beyond * along[k];
                quad[0][k] -= low * along[k];
                quad[3][k] -= low * along[k];
            }
            for find in [false, true] {
                let opts = MeasureOptions {
                    roi: Some(quad),
                    refine_roi: true,
                    find_print_ends: find,
                    ..MeasureOptions::default()
                };
                let label = if find { "found" } else { "kept" };
                let t0 = Instant::now();
                let res = decode_bytes(&bytes, "ends.png")
                    .map_err(|e| e.to_string())
                    .and_then(|d| {
                        measure_decoded(&d, "ends.png", None, &opts).map_err(|e| e.to_string())
                    });
                let ms = t0.elapsed().as_secs_f64() * 1e3;
                let m = match res {
                    Ok(m) => m,
                    Err(e) => {
                        println!("| {name} | {beyond} / {low} | {label} | failed: {e} | | | | | |");
                        continue;
                    }
                };
                let cv = &m.curves[0];
                let (mut se, mut n, mut worst) = (0.0, 0usize, 0.0f64);
                for p in cv
                    .points
                    .iter()
                    .filter(|p| !p.aliased && (0.01..=0.45).contains(&p.freq_cy_px))
                {
                    let e = p.mtf - mtf_at(rows, p.freq_cy_px);
                    se += e * e;
                    n += 1;
                    worst = worst.max(e.abs());
                }
                let e50 = cv
                    .figures
                    .mtf50_cy_px
                    .map(|m| format!("{:+.2}", 100.0 * (m / f50 - 1.0)))
                    .unwrap_or_else(|| "none".into());
                let found = cv
                    .print_ends_inside_px
                    .map(|e| e.map_or_else(|| "none".into(), |d| format!("{d:.1}")))
                    .join(" / ");
                println!(
                    "| {name} | {beyond} / {low} | {label} | {:.4} | {worst:.4} | {e50} | {:+.2} | {found} | {ms:.1} |",
                    (se / n.max(1) as f64).sqrt(),
                    100.0 * (cv.chart_modulation / contrast - 1.0),
                );
            }
        }
    }
}
