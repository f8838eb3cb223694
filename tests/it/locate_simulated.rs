//! Locating the shipped charts (`targets/*.toml`, written by `chart`) in shots
//! from the project's simulator (`sweepmtf::simulate`: optics, perspective,
//! illumination fall-off, photon and read noise, sRGB 8-bit JPEG q90), against
//! the simulator's own target corners.

use sweepmtf::locate;
use sweepmtf::model::{System, gaussian};
use sweepmtf::photo::Plane;
use sweepmtf::simulate::{self, Camera, PhotoFormat};
use sweepmtf::target::Target;

fn target(name: &str) -> Target {
    let p = std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("targets")
        .join(name);
    Target::load(&p).unwrap()
}

/// Encodes the shot as JPEG q90 and decodes it back to linear luminance.
fn as_jpeg(shot: &simulate::Shot) -> Plane {
    let bytes = shot.encode(PhotoFormat::Jpeg).unwrap();
    let img = image::load_from_memory(&bytes).unwrap().to_luma8();
    let lin = |c: u8| {
        let c = c as f64 / 255.0;
        if c <= 0.04045 {
            c / 12.92
        } else {
            ((c + 0.055) / 1.055).powf(2.4)
        }
    };
    let data = img.pixels().map(|p| lin(p[0]) as f32).collect();
    Plane::full(img.width() as usize, img.height() as usize, data)
}

#[test]
fn shipped_charts_are_found_in_simulated_jpeg_shots() {
    let cases = [
        ("a4_log.toml", 0.0, 0.0, 90.0, 900.0),
        ("a4_log.toml", 27.0, 35.0, 90.0, 560.0),
        ("a4_linear.toml", -140.0, 40.0, 30.0, 500.0),
        ("a4_patches.toml", 200.0, 25.0, 0.0, 640.0),
        ("a3_log.toml", 75.0, 45.0, 60.0, 420.0),
    ];
    let mut errs = vec![];
    for (i, &(name, rot, tilt, axis, chart_px)) in cases.iter().enumerate() {
        let t = target(name);
        let system = System {
            factors: vec![gaussian::parse("sigma=4um").unwrap()],
        };
        let camera = Camera {
            width_px: 1200,
            height_px: 800,
            chart_px: Some(chart_px),
            rotate_deg: rot,
            tilt_deg: tilt,
            tilt_axis_deg: axis,
            falloff: 0.3,
            exposure: 0.8,
            full_well_e: Some(20000.0),
            read_noise_e: 5.0,
            seed: i as u64,
            jpeg_quality: Some(90),
            ..Camera::default()
        };
        let shot = simulate::render(&t, &system, &camera).unwrap();
        let plane = as_jpeg(&shot);
        let s = locate::search(&plane, &t).unwrap();
        let dir = std::path::Path::new(env!("CARGO_TARGET_TMPDIR")).join("locate");
        std::fs::create_dir_all(&dir).unwrap();
        locate::debug_image(&plane, &s.candidates, &s.charts)
            .save(dir.join(format!("sim{i}.roi.png")))
            .unwrap();
        if s.charts.is_empty() {
            for c in &s.candidates {
                eprintln!("{c:?}");
            }
        }
        let found = locate::find_chart(&plane, &t, None)
            .unwrap_or_else(|e| panic!("{name} rot {rot} tilt {tilt}: {e}"));
        assert_eq!(found.hidden, None, "{name}: {:?}", found.warnings);
        for k in 0..4 {
            let (x, y) = (shot.target_corners[2 * k], shot.target_corners[2 * k + 1]);
            let e = (found.corners_px[k][0] - x).hypot(found.corners_px[k][1] - y);
            errs.push(e);
        }
        let e = &errs[errs.len() - 4..];
        eprintln!("{name} rot {rot} tilt {tilt} chart {chart_px} px: corner errors {e:.3?}");
    }
    let rms = (errs.iter().map(|e| e * e).sum::<f64>() / errs.len() as f64).sqrt();
    let max = errs.iter().cloned().fold(0.0, f64::max);
    eprintln!("simulated JPEG shots: corner error RMS {rms:.3} px, max {max:.3} px");
    assert!(rms <= 0.5 && max <= 1.0, "RMS {rms}, max {max}");
}
