//! Issue 15's nuisances rendered by the full camera simulator (optics ×
//! square pixel, photon and read noise, sRGB 8-bit), not by the reference
//! renderer the estimators were tuned on: unsharp-mask sharpening after the
//! noise, an illumination gradient with fall-off, and a coloured light written
//! as an RGB JPEG q75 with 4:2:0 chroma. Measured with strip corners only and
//! the default settings, against the simulator's truth (its OTF times the
//! sharpening's exact discrete transfer): RMS |MTF − truth| over 0.01–0.45
//! cy/px, MTF50 within 1 %, chart modulation within 0.5 % of the printed 0.8.
//! Also the CLI: the files it writes, and the settings it refuses.

use assert_cmd::Command;
use sweepmtf::measure::{MeasureOptions, measure_bytes};
use sweepmtf::model::System;
use sweepmtf::simulate::demo::{GaussianPsf, demo_target_for};
use sweepmtf::simulate::{
    Camera, LightGradient, PhotoFormat, RenderSettings, Sharpen, Shot, render,
};
use sweepmtf::target::SweepLaw;

/// A 1100×700 frame, chart 900 px wide, Gaussian lens σ = 0.55 px, SNR ≈ 60.
fn camera() -> Camera {
    Camera {
        width_px: 1100,
        height_px: 700,
        chart_px: Some(900.0),
        rotate_deg: 1.5,
        full_well_e: Some(9000.0),
        read_noise_e: 4.0,
        seed: 23,
        ..Camera::default()
    }
}

fn shoot(cam: &Camera) -> Shot {
    let t = demo_target_for(cam, SweepLaw::Log, 0.006, 0.6).unwrap();
    let system = System {
        factors: vec![Box::new(GaussianPsf {
            sigma_mm: 0.55 * cam.pitch_mm(),
        })],
    };
    render(&t, &system, cam).unwrap()
}

/// The truth at `f` cy/px, interpolated in the simulator's truth rows.
fn truth_at(shot: &Shot, f: f64) -> f64 {
    sweepmtf::simulate::mtf_at(&shot.truth().unwrap().rows, f)
}

/// (RMS, MTF50 relative error, chart modulation and its claimed σ, measured
/// peak, warnings) of the shot encoded as `format`.
fn score(name: &str, shot: &Shot, format: PhotoFormat) -> (f64, f64, (f64, f64), f64, Vec<String>) {
    let bytes = shot.encode(format).unwrap();
    let r = shot.roi().unwrap();
    let opts = MeasureOptions {
        roi: Some([[r[0], r[1]], [r[2], r[3]], [r[4], r[5]], [r[6], r[7]]]),
        ..MeasureOptions::default()
    };
    // As `measure` reads the file (for a JPEG: the luma plane Y′ alone).
    let m = measure_bytes(&bytes, name, None, &opts).unwrap_or_else(|e| panic!("{name}: {e}"));
    let c = &m.curves[0];
    let (mut se, mut n) = (0.0, 0);
    for p in c.points.iter().filter(|p| !p.aliased) {
        if (0.01..=0.45).contains(&p.freq_cy_px) {
            se += (p.mtf - truth_at(shot, p.freq_cy_px)).powi(2);
            n += 1;
        }
    }
    assert!(n > 60, "{name}: {n} points");
    // The true MTF50: the first fall through 0.5 in the truth rows (past any peak).
    let rows = &shot.truth().unwrap().rows;
    let k = rows
        .windows(2)
        .position(|w| w[0].mtf >= 0.5 && w[1].mtf < 0.5)
        .expect("truth falls through 0.5");
    let (a, b) = (&rows[k], &rows[k + 1]);
    let f50 = a.freq_cy_px + (0.5 - a.mtf) * (b.freq_cy_px - a.freq_cy_px) / (b.mtf - a.mtf);
    let got = c.figures.mtf50_cy_px.expect("MTF50 measured");
    let peak = c.points.iter().map(|p| p.mtf).fold(0.0, f64::max);
    (
        (se / n as f64).sqrt(),
        got / f50 - 1.0,
        (c.chart_modulation, c.chart_modulation_err),
        peak,
        m.warnings.clone(),
    )
}

fn check(name: &str, shot: &Shot, format: PhotoFormat, bar: f64) -> f64 {
    let (rms, e50, (cm, _), peak, _) = score(name, shot, format);
    eprintln!("{name}: RMS {rms:.4}, MTF50 {e50:+.4}, chart {cm:.4}, peak {peak:.3}");
    assert!(rms <= bar, "{name}: RMS {rms:.4} > {bar}");
    assert!(e50.abs() <= 0.01, "{name}: MTF50 off by {e50:+.4}");
    assert!(
        (cm / 0.8 - 1.0).abs() <= 0.005,
        "{name}: chart modulation {cm:.4} (printed 0.8)"
    );
    peak
}

#[test]
fn sharpened_after_the_noise_keeps_its_peak_within_0_01() {
    let cam = Camera {
        sharpen: Some(Sharpen {
            amount: 0.9,
            radius_px: 1.3,
        }),
        ..camera()
    };
    let shot = shoot(&cam);
    let true_peak = shot
        .truth()
        .unwrap()
        .rows
        .iter()
        .map(|r| r.mtf)
        .fold(0.0, f64::max);
    assert!(
        (1.08..1.25).contains(&true_peak),
        "the case should peak near 1.15, truth peaks at {true_peak:.3}"
    );
    let peak = check("sharpened", &shot, PhotoFormat::Png, 0.01);
    // Never clipped at 1 nor normalised to the peak.
    assert!(
        (peak / true_peak - 1.0).abs() < 0.03,
        "{peak} vs {true_peak}"
    );
}

#[test]
fn light_gradient_with_falloff_within_0_008() {
    for (ratio, toward) in [(3.0, 0.0), (2.5, 160.0)] {
        let cam = Camera {
            light_gradient: Some(LightGradient {
                ratio,
                toward_deg: toward,
            }),
            falloff: 0.5,
            exposure: 0.9,
            ..camera()
        };
        check(
            &format!("gradient {ratio}:1 towards {toward}°"),
            &shoot(&cam),
            PhotoFormat::Png,
            0.008,
        );
    }
}

#[test]
fn coloured_light_rgb_jpeg_q75_420_within_0_012() {
    let cam = Camera {
        light_colour: Some([1.0, 0.82, 0.6]),
        jpeg_quality: Some(75),
        ..camera()
    };
    let shot = shoot(&cam);
    // The same shot losslessly: the measurement itself holds every bar.
    check("colour PNG", &shot, PhotoFormat::Png, 0.002);
    // As JPEG q75 the file's own MTF moves: block quantisation ripples the
    // curve (smoothed by a twiced local quadratic over σ ≤ 0.06 cy/px, as the
    // summary's warning says), and what is left moves MTF50 by up to ±1 %
    // turned 0.1–5° (`examples/coarse_jpeg_study.rs`, `examples/unseen.rs`).
    // Square to the grid (0°) the error is not averaged along the bars
    // (RMS 0.013 unsmoothed, MTF50 up to ±2.5 % on other seeds): the summary
    // says so and asks for a turn.
    let square = shoot(&Camera {
        rotate_deg: 0.0,
        ..cam.clone()
    });
    for (turn, shot) in [(cam.rotate_deg, &shot), (0.0, &square)] {
        let name = format!("colour 4:2:0 q75 turned {turn}°");
        let (rms, e50, (cm, _), _, warnings) = score(&name, shot, PhotoFormat::Jpeg);
        eprintln!("{name}: RMS {rms:.4}, MTF50 {e50:+.4}, chart {cm:.4}");
        let square = warnings
            .iter()
            .any(|w| w.contains("square to the JPEG's 8×8 blocks"));
        assert_eq!(square, turn == 0.0, "{name}: {warnings:?}");
        assert!(rms <= 0.012, "{name}: RMS {rms:.4}");
        assert!(e50.abs() <= 0.01, "{name}: MTF50 off by {e50:+.4}");
        assert!(
            (cm / 0.8 - 1.0).abs() <= 0.005,
            "{name}: chart modulation {cm:.4}"
        );
    }
}

/// Every real lens stops down to a finite aperture, so its diffraction gives
/// the MTF a falling linear start, 1 − (4/π)·f/f_c. Without a target the chart
/// modulation is extrapolated to 0 cy/px; assuming an even start (as before)
/// put it 1.9 % low at f/5.6 and 3.6 % low at f/11 on 4.3 µm pixels, and every
/// MTF as much high. Diffraction × pixel × a little Gaussian blur, PNG and the
/// colour JPEG, f/2.8–f/16: the linear start is found and every bar holds.
#[test]
fn diffraction_limited_lenses_start_linearly_and_hold_the_bars() {
    use sweepmtf::model::optics::Diffraction;
    for (fnum, jpeg) in [(2.8, false), (5.6, false), (11.0, true), (16.0, false)] {
        // Tiles wide enough to carry diffraction's far tail: the paper's
        // light reaches well into the strip (the leak the measurement takes
        // out), which 16-px tile margins would cut and wrap.
        let cam = Camera {
            light_colour: jpeg.then_some([1.0, 0.82, 0.6]),
            jpeg_quality: jpeg.then_some(90),
            seed: 31 + fnum as u64,
            render: RenderSettings {
                fft_size: 1024,
                margin_px: 160,
                ..RenderSettings::default()
            },
            ..camera()
        };
        let t = demo_target_for(&cam, SweepLaw::Log, 0.006, 0.6).unwrap();
        let system = System {
            factors: vec![
                Box::new(Diffraction::new(0.55e-3, fnum)),
                Box::new(GaussianPsf {
                    sigma_mm: 0.3 * cam.pitch_mm(),
                }),
            ],
        };
        let shot = render(&t, &system, &cam).unwrap();
        let format = if jpeg {
            PhotoFormat::Jpeg
        } else {
            PhotoFormat::Png
        };
        let bar = if jpeg { 0.012 } else { 0.004 };
        if fnum < 16.0 {
            check(&format!("diffraction f/{fnum}"), &shot, format, bar);
            continue;
        }
        // f/16 on 4.3 µm pixels (cut-off 0.49 cy/px): the extrapolation to 0
        // is read over a steep fall; its claimed uncertainty must hold it.
        let (rms, e50, (cm, cm_err), _, _) = score("diffraction f/16", &shot, format);
        eprintln!("diffraction f/16: RMS {rms:.4}, MTF50 {e50:+.4}, chart {cm:.4} ± {cm_err:.4}");
        assert!(rms <= bar && e50.abs() <= 0.01, "{rms} {e50}");
        assert!(
            (cm - 0.8).abs() <= 2.0 * cm_err,
            "chart modulation {cm:.4} ± {cm_err:.4}"
        );
    }
}

/// Start of the SOF0 segment's component table: (id, sampling byte) per component.
fn sof_components(jpeg: &[u8]) -> Vec<(u8, u8)> {
    let mut i = 2;
    while i + 4 <= jpeg.len() {
        assert_eq!(jpeg[i], 0xFF, "marker expected at {i}");
        let marker = jpeg[i + 1];
        let len = u16::from_be_bytes([jpeg[i + 2], jpeg[i + 3]]) as usize;
        if marker == 0xC0 {
            let n = jpeg[i + 9] as usize;
            return (0..n)
                .map(|k| (jpeg[i + 10 + 3 * k], jpeg[i + 11 + 3 * k]))
                .collect();
        }
        i += 2 + len;
    }
    panic!("no SOF0");
}

#[test]
fn cli_writes_an_rgb_jpeg_with_the_chroma_asked_and_refuses_nonsense() {
    let dir = tempfile::tempdir().unwrap();
    let run = |extra: &[&str], out: &str| {
        Command::cargo_bin("sweepmtf")
            .unwrap()
            .args([
                "simulate", "--target", "demo:log", "--size", "400x300", "-q",
            ])
            .args(extra)
            .arg("-o")
            .arg(dir.path().join(out))
            .output()
            .unwrap()
    };
    for (chroma, y_sampling) in [("420", 0x22u8), ("444", 0x11)] {
        let name = format!("c{chroma}.jpg");
        let o = run(
            &[
                "--light-colour",
                "1,0.8,0.5",
                "--chroma",
                chroma,
                "--sharpen",
                "amount=0.5,radius=1",
                "--light-gradient",
                "2,45",
                "--jpeg",
                "80",
            ],
            &name,
        );
        assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
        let bytes = std::fs::read(dir.path().join(&name)).unwrap();
        let comps = sof_components(&bytes);
        assert_eq!(comps.len(), 3, "{comps:?}");
        assert_eq!(comps[0].1, y_sampling, "{chroma}: {comps:?}");
        assert!(comps[1..].iter().all(|c| c.1 == 0x11), "{comps:?}");
        let json: serde_json::Value = serde_json::from_slice(
            &std::fs::read(dir.path().join(format!("c{chroma}.json"))).unwrap(),
        )
        .unwrap();
        assert_eq!(json["camera"]["sharpen"]["amount"], 0.5);
        assert_eq!(json["camera"]["light_gradient"]["ratio"], 2.0);
    }
    // A colour PNG is RGB, 8 bits.
    let o = run(&["--light-colour", "0.9,1,0.7"], "c.png");
    assert!(o.status.success());
    let img = image::open(dir.path().join("c.png")).unwrap();
    assert_eq!(img.color(), image::ColorType::Rgb8);
    for (bad, out) in [
        (&["--chroma", "420"][..], "a.jpg"),
        (&["--sharpen", "amount=9,radius=1"][..], "b.png"),
        (&["--sharpen", "amount=1"][..], "b2.png"),
        (&["--light-gradient", "0.5"][..], "g.png"),
        (&["--light-colour", "1,1"][..], "d.png"),
        (&["--light-colour", "1,1,1.5"][..], "e.png"),
        (
            &["--bayer", "RGGB", "--sharpen", "amount=1,radius=1"][..],
            "f.png",
        ),
    ] {
        let o = run(bad, out);
        assert_eq!(o.status.code(), Some(2), "{bad:?}");
        let err = String::from_utf8_lossy(&o.stderr);
        assert_eq!(err.trim().lines().count(), 1, "{bad:?}: {err}");
        assert!(!dir.path().join(out).exists(), "{bad:?} left {out}");
    }
}
