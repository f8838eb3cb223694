//! The simulator's files and geometry: photos decode (with the `image` crate)
//! to the code values the transfer curve predicts, the JSON names the strip's
//! corners in the right order, the truth follows the homography under
//! perspective (checked by finite differences of the chart phase), the Bayer
//! mosaic carries its gains, and noise has the spread the full well predicts.

use std::f64::consts::PI;
use sweepmtf::geometry::Homography;
use sweepmtf::model::System;
use sweepmtf::simulate::{self, BayerOrder, Camera, Encoding, demo::demo_target};
use sweepmtf::target::{SweepLaw, Target};

fn perfect() -> System {
    System::default()
}

#[test]
fn quick_shot_gives_roi_corners_round_the_strip_low_frequency_edge_first() {
    let t = demo_target(SweepLaw::Log);
    let shot = simulate::quick_shot(&t, &perfect(), 600, 400, 20.0).unwrap();
    let roi = shot.roi().unwrap();
    let sw = &t.sweeps[0];
    let h = shot.chart_to_image;
    let c1 = h.apply([sw.rect.x_mm, sw.rect.y_mm]);
    let c4 = h.apply([sw.rect.x_mm, sw.rect.y_mm + sw.rect.height_mm]);
    assert!((roi[0] - c1[0]).abs() < 1e-9 && (roi[1] - c1[1]).abs() < 1e-9);
    assert!((roi[6] - c4[0]).abs() < 1e-9 && (roi[7] - c4[1]).abs() < 1e-9);
    // Frequencies rise from corner 1/4 to corner 2/3 along the truth curve.
    let tr = shot.truth().unwrap();
    assert!(tr.rows.first().unwrap().freq_cy_px < tr.rows.last().unwrap().freq_cy_px);
    // Target corners: (0,0) maps to the first pair.
    let tl = h.apply([0.0, 0.0]);
    assert!((shot.target_corners[0] - tl[0]).abs() < 1e-9);
    // With no optics, the truth is the square pixel's sinc along the rotated direction.
    for r in tr.rows.iter().step_by(97) {
        let (s, c) = 20f64.to_radians().sin_cos();
        let (kx, ky) = (r.freq_cy_px * c, -r.freq_cy_px * s);
        let sinc = |x: f64| {
            if x == 0.0 {
                1.0
            } else {
                (PI * x).sin() / (PI * x)
            }
        };
        assert!((r.mtf - (sinc(kx) * sinc(ky)).abs()).abs() < 1e-9);
    }
}

#[test]
fn perspective_truth_frequency_matches_finite_differences_of_the_chart_phase() {
    let t = demo_target(SweepLaw::Linear);
    let cam = Camera {
        tilt_deg: 35.0,
        tilt_axis_deg: 70.0,
        rotate_deg: -12.0,
        ..Camera::noiseless(900, 600)
    };
    let shot = simulate::render(&t, &perfect(), &cam).unwrap();
    let inv: Homography = shot.chart_to_image.inverse().unwrap();
    let sw = &t.sweeps[0];
    let phase = |x: f64, y: f64| {
        let c = inv.apply([x, y]);
        sw.phase_cycles(sw.s_of(c[0], c[1]))
    };
    for r in shot.truth().unwrap().rows.iter().step_by(50) {
        let e = 1e-3;
        let gx = (phase(r.x_px + e, r.y_px) - phase(r.x_px - e, r.y_px)) / (2.0 * e);
        let gy = (phase(r.x_px, r.y_px + e) - phase(r.x_px, r.y_px - e)) / (2.0 * e);
        let f = gx.hypot(gy);
        assert!(
            (f - r.freq_cy_px).abs() < 1e-6 * (1.0 + f),
            "{f} vs {}",
            r.freq_cy_px
        );
        assert!((r.freq_cy_mm - r.freq_cy_px / 0.0043).abs() < 1e-9);
    }
}

#[test]
fn written_files_decode_to_the_predicted_codes() {
    let dir = tempfile::tempdir().unwrap();
    let t = demo_target(SweepLaw::Log);
    for (name, enc, bits) in [
        ("a.png", Encoding::Srgb, 8u8),
        ("b.png", Encoding::Gamma(2.2), 16),
        ("c.tif", Encoding::Linear, 16),
        ("d.tif", Encoding::Srgb, 8),
    ] {
        let cam = Camera {
            encoding: enc,
            bits,
            ..Camera::noiseless(300, 200)
        };
        let shot = simulate::render(&t, &perfect(), &cam).unwrap();
        let path = dir.path().join(name);
        simulate::write_shot(&shot, &path).unwrap();
        let img = image::open(&path).unwrap();
        let max = if bits == 8 { 255.0 } else { 65535.0 };
        let decoded = img.to_luma16();
        for (i, &v) in shot.linear.iter().enumerate().step_by(37) {
            // Independent transfer curves (IEC 61966-2-1 sRGB; power law).
            let v = v as f64;
            let code = match enc {
                Encoding::Srgb if v <= 0.003_130_8 => 12.92 * v,
                Encoding::Srgb => 1.055 * v.powf(1.0 / 2.4) - 0.055,
                Encoding::Gamma(g) => v.powf(1.0 / g),
                Encoding::Linear => v,
            };
            let want = (code * max).round();
            let got = decoded.as_raw()[i] as f64 / if bits == 8 { 257.0 } else { 1.0 };
            assert_eq!(got, want, "{name} pixel {i}");
        }
        let (_, csv, json) = simulate::output_paths(&path);
        let j: serde_json::Value = serde_json::from_slice(&std::fs::read(json).unwrap()).unwrap();
        assert_eq!(j["roi"].as_array().unwrap().len(), 8);
        assert_eq!(j["target_corners"].as_array().unwrap().len(), 8);
        assert_eq!(j["pixel_pitch_um"].as_f64().unwrap(), 4.3);
        let text = std::fs::read_to_string(csv).unwrap();
        assert!(
            text.starts_with("freq_cy_px,mtf,s_mm,freq_cy_mm"),
            "{text:.80}"
        );
    }
    // No temporary files left behind.
    let left: Vec<_> = std::fs::read_dir(dir.path())
        .unwrap()
        .filter_map(|e| e.ok())
        .filter(|e| e.file_name().to_string_lossy().starts_with('.'))
        .collect();
    assert!(left.is_empty());
}

#[test]
fn jpeg_at_quality_90_stays_close_to_the_srgb_codes() {
    let dir = tempfile::tempdir().unwrap();
    let t = demo_target(SweepLaw::Log);
    let cam = Camera {
        jpeg_quality: Some(90),
        ..Camera::noiseless(300, 200)
    };
    let cam = Camera {
        encoding: Encoding::Srgb,
        bits: 8,
        ..cam
    };
    let shot = simulate::render(&t, &perfect(), &cam).unwrap();
    let path = dir.path().join("s.jpg");
    simulate::write_shot(&shot, &path).unwrap();
    let img = image::open(&path).unwrap().to_luma8();
    let mut sum = 0.0;
    for (i, &v) in shot.linear.iter().enumerate() {
        let code = Encoding::Srgb.encode(v as f64) * 255.0;
        sum += (img.as_raw()[i] as f64 - code).powi(2);
    }
    let rms = (sum / shot.linear.len() as f64).sqrt();
    assert!(rms > 0.05 && rms < 4.0, "JPEG RMS code error {rms}");
    // A PNG name with a JPEG quality is refused before anything is written.
    assert!(simulate::write_shot(&shot, &dir.path().join("x.png")).is_err());
    assert!(!dir.path().join("x.png").exists());
}

#[test]
fn bayer_mosaic_applies_the_gains_per_site() {
    let dir = tempfile::tempdir().unwrap();
    let t = demo_target(SweepLaw::Log);
    let cam = Camera {
        bayer: Some(BayerOrder::Rggb),
        bayer_gains: [0.5, 1.0, 0.25],
        ..Camera::noiseless(200, 140)
    };
    let shot = simulate::render(&t, &perfect(), &cam).unwrap();
    // The surround (0.2 reflectance × exposure 0.8) in the top-left corner.
    let base = 0.2 * 0.8;
    let at = |x: usize, y: usize| shot.linear[y * shot.width + x] as f64;
    assert!((at(0, 0) - 0.5 * base).abs() < 1e-5);
    assert!((at(1, 0) - base).abs() < 1e-5 && (at(0, 1) - base).abs() < 1e-5);
    assert!((at(1, 1) - 0.25 * base).abs() < 1e-5);
    let path = dir.path().join("m.png");
    simulate::write_shot(&shot, &path).unwrap();
    let img = image::open(&path).unwrap();
    assert_eq!(img.color(), image::ColorType::L16);
    let tif = dir.path().join("m.tif");
    simulate::write_shot(&shot, &tif).unwrap();
    assert_eq!(image::open(&tif).unwrap().color(), image::ColorType::L16);
}

#[test]
fn photon_noise_spread_matches_the_full_well() {
    let t = Target {
        name: "flat".into(),
        width_mm: 100.0,
        height_mm: 100.0,
        background: 0.5,
        sweeps: vec![],
        patches: vec![],
        greys: vec![],
        fiducials: vec![],
    };
    let cam = Camera {
        full_well_e: Some(5000.0),
        read_noise_e: 10.0,
        exposure: 1.0,
        surround: 0.5,
        ..Camera::noiseless(200, 200)
    };
    let shot = simulate::render(&t, &perfect(), &cam).unwrap();
    let n = shot.linear.len() as f64;
    let mean = shot.linear.iter().map(|&v| v as f64).sum::<f64>() / n;
    let var = shot
        .linear
        .iter()
        .map(|&v| (v as f64 - mean).powi(2))
        .sum::<f64>()
        / n;
    // 2500 e⁻ mean: σ² = (2500 + 10²)/5000².
    let want = 2600.0 / 25e6;
    assert!((mean - 0.5).abs() < 5e-4, "{mean}");
    assert!((var / want - 1.0).abs() < 0.05, "{var} vs {want}");
}

#[test]
fn falloff_and_exposure_scale_the_flat_field() {
    let t = Target {
        name: "flat".into(),
        width_mm: 100.0,
        height_mm: 100.0,
        background: 0.5,
        sweeps: vec![],
        patches: vec![],
        greys: vec![],
        fiducials: vec![],
    };
    let cam = Camera {
        falloff: 0.3,
        exposure: 0.9,
        surround: 0.5,
        ..Camera::noiseless(120, 80)
    };
    let shot = simulate::render(&t, &perfect(), &cam).unwrap();
    let rc2 = 60.0f64 * 60.0 + 40.0 * 40.0;
    for (x, y) in [(0usize, 0usize), (59, 39), (119, 79), (30, 70)] {
        let (dx, dy) = (x as f64 + 0.5 - 60.0, y as f64 + 0.5 - 40.0);
        let want = 0.9 * 0.5 * (1.0 - 0.3 * (dx * dx + dy * dy) / rc2);
        let got = shot.linear[y * 120 + x] as f64;
        assert!((got - want).abs() < 1e-5, "({x},{y}): {got} vs {want}");
    }
}
