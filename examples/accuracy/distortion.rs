//! Distortion rows of the accuracy example (issue 15): the real simulator
//! (`simulate::render`) with radial lens distortion in the PTLens form, a strip
//! across the frame near an edge, measured from its photo corners with
//! default settings — the distortion estimated from the strip's edges, and
//! given (`--distortion`). Truth: the simulator's OTF at the distorted local
//! frequency.

use std::time::Instant;
use sweepmtf::distortion::Ptlens;
use sweepmtf::measure::{MeasureOptions, measure_decoded};
use sweepmtf::model::System;
use sweepmtf::photo::decode::decode_bytes;
use sweepmtf::simulate::demo::{GaussianPsf, strip_card};
use sweepmtf::simulate::{Camera, encode::PhotoFormat, render};

/// One row: (RMS |MTF − truth| over 0.01–0.45 cy/px, MTF50 error %, chart modulation, b used, ms).
fn row(
    distortion: Option<Ptlens>,
    given: bool,
    estimate: bool,
    offset_y: f64,
    seed: u64,
) -> Result<(f64, f64, f64, f64, f64), String> {
    let (w, h) = (1200usize, 800usize);
    let chart_px = 1100.0;
    let ppm = chart_px / 260.0;
    let target = strip_card(0.006 * ppm, 0.6 * ppm);
    let camera = Camera {
        width_px: w,
        height_px: h,
        chart_px: Some(chart_px),
        offset_px: [0.0, offset_y],
        distortion,
        full_well_e: Some(20_000.0),
        read_noise_e: 3.0,
        seed,
        ..Camera::default()
    };
    let system = System {
        factors: vec![Box::new(GaussianPsf {
            sigma_mm: 0.55 * camera.pitch_mm(),
        })],
    };
    let shot = render(&target, &system, &camera).map_err(|e| e.to_string())?;
    let bytes = shot.encode(PhotoFormat::Png).map_err(|e| e.to_string())?;
    let r = shot.roi().ok_or("no roi")?;
    let opts = MeasureOptions {
        roi: Some([[r[0], r[1]], [r[2], r[3]], [r[4], r[5]], [r[6], r[7]]]),
        distortion: if given { distortion } else { None },
        estimate_distortion: estimate,
        ..MeasureOptions::default()
    };
    let t0 = Instant::now();
    let dec = decode_bytes(&bytes, "shot.png").map_err(|e| e.to_string())?;
    let m = measure_decoded(&dec, "shot.png", None, &opts).map_err(|e| e.to_string())?;
    let ms = t0.elapsed().as_secs_f64() * 1e3;
    let rows = &shot.truth().ok_or("no truth")?.rows;
    let truth = |f: f64| sweepmtf::simulate::mtf_at(rows, f);
    let c = &m.curves[0];
    let (mut se, mut n) = (0.0, 0);
    for p in c.points.iter().filter(|p| !p.aliased) {
        if (0.01..=0.45).contains(&p.freq_cy_px) {
            se += (p.mtf - truth(p.freq_cy_px)).powi(2);
            n += 1;
        }
    }
    let i = rows.iter().position(|r| r.mtf < 0.5).ok_or("no MTF50")?;
    let (a, b) = (&rows[i - 1], &rows[i]);
    let f50 = a.freq_cy_px + (b.freq_cy_px - a.freq_cy_px) * (a.mtf - 0.5) / (a.mtf - b.mtf);
    let m50 = c.figures.mtf50_cy_px.unwrap_or(f64::NAN);
    let b_used = m.distortion.and_then(|d| d.used()).map_or(0.0, |d| d.b);
    Ok((
        (se / n.max(1) as f64).sqrt(),
        100.0 * (m50 / f50 - 1.0),
        c.chart_modulation,
        b_used,
        ms,
    ))
}

/// Prints the distortion table.
pub fn table() {
    let b = |pct: f64| pct / 100.0 / 2.25; // 1200×800: r_corner² − 1 = 2.25
    println!();
    println!(
        "| distortion case (strip near the frame edge, 1200×800) | RMS error | MTF50 error % | chart modulation | b used | time ms |"
    );
    println!("|---|---|---|---|---|---|");
    let cases: [(&str, f64, bool, f64); 7] = [
        ("none", 0.0, false, 300.0),
        ("none, near the top edge", 0.0, false, -300.0),
        ("barrel −3 % at the corner, estimated", -3.0, false, 300.0),
        ("barrel −3 %, given", -3.0, true, 300.0),
        ("pincushion +4 %, estimated", 4.0, false, -300.0),
        ("pincushion +4 %, given", 4.0, true, -300.0),
        (
            "pincushion +4 %, ignored (--no-estimate-distortion)",
            4.0,
            false,
            -300.0,
        ),
    ];
    for (k, (name, pct, given, oy)) in cases.iter().enumerate() {
        let model = (*pct != 0.0).then(|| Ptlens {
            a: 0.0,
            b: b(*pct),
            c: 0.0,
        });
        let res = row(model, *given, !name.contains("ignored"), *oy, 70 + k as u64);
        match res {
            Ok((rms, e50, cm, bu, ms)) => {
                println!("| {name} | {rms:.4} | {e50:+.2} | {cm:.4} | {bu:.5} | {ms:.1} |")
            }
            Err(e) => println!("| {name} | failed: {e} | | | | |"),
        }
    }
}
