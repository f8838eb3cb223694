//! Batch demo and throughput fixture: simulated shots of the demo sweep chart
//! through a toy lens at several f-numbers (blur falls as the lens stops down,
//! then diffraction-like blur rises), encoded as JPEG with camera EXIF (make,
//! model, lens, f-number, focal length, ISO, exposure), plus `rois.csv` (each
//! shot's strip corners) and `truth.csv` (each shot's true MTF50 from the
//! simulator's truth curve).
//!
//! ```sh
//! cargo run --release --features examples --example batch_demo -- demo_shots [WIDTHxHEIGHT] [COPIES]
//! sweepmtf batch demo_shots -o demo_out --roi-file demo_shots/rois.csv
//! ```

#[path = "../tests/it/batch_stub/exif_jpeg.rs"]
mod exif_jpeg;

use std::fmt::Write as _;
use std::path::PathBuf;
use sweepmtf::model::System;
use sweepmtf::simulate::demo::{GaussianPsf, demo_target};
use sweepmtf::simulate::{self, Camera, PhotoFormat};
use sweepmtf::target::SweepLaw;

/// f-numbers of the series (as marked; the EXIF stores these).
const STOPS: [(f64, u32, u32); 8] = [
    (2.0, 20, 10),
    (2.8, 28, 10),
    (4.0, 40, 10),
    (5.6, 56, 10),
    (8.0, 80, 10),
    (11.0, 110, 10),
    (16.0, 160, 10),
    (22.0, 220, 10),
];

/// Blur σ (pixels) of the toy lens at f-number `n`: aberrations ∝ 1/N,
/// diffraction-like growth ∝ N, added in quadrature; sharpest near f/5.6.
fn sigma_px(n: f64) -> f64 {
    let aberr = 4.0 / n;
    let diff = n / 11.0;
    (0.35f64.powi(2) + aberr * aberr + diff * diff).sqrt()
}

/// First frequency where a curve falls through `level` (linear interpolation).
fn crossing(rows: &[(f64, f64)], level: f64) -> Option<f64> {
    rows.windows(2).find_map(|w| {
        let ((f0, m0), (f1, m1)) = (w[0], w[1]);
        (m0 >= level && m1 < level).then(|| f0 + (f1 - f0) * (m0 - level) / (m0 - m1))
    })
}

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let args: Vec<String> = std::env::args().collect();
    let dir = PathBuf::from(args.get(1).map(String::as_str).unwrap_or("demo_shots"));
    let (w, h) = match args.get(2) {
        Some(s) => {
            let (a, b) = s.split_once('x').ok_or("size as WIDTHxHEIGHT")?;
            (a.parse()?, b.parse()?)
        }
        None => (1500, 1000),
    };
    let copies: usize = args.get(3).map(|s| s.parse()).transpose()?.unwrap_or(1);
    std::fs::create_dir_all(&dir)?;
    let target = demo_target(SweepLaw::Log);
    let mut rois = String::from("file,x1,y1,x2,y2,x3,y3,x4,y4\n");
    let mut truth = String::from("file,f_number,sigma_px,mtf50_true_cy_px\n");
    for (k, &(n, num, den)) in STOPS.iter().enumerate() {
        let camera0 = Camera {
            width_px: w,
            height_px: h,
            full_well_e: Some(20000.0),
            read_noise_e: 4.0,
            jpeg_quality: Some(92),
            ..Camera::default()
        };
        let sigma = sigma_px(n);
        let system = System {
            factors: vec![Box::new(GaussianPsf {
                sigma_mm: sigma * camera0.pitch_mm(),
            })],
        };
        for c in 0..copies {
            let camera = Camera {
                seed: (k * 1000 + c) as u64,
                ..camera0.clone()
            };
            let shot = simulate::render(&target, &system, &camera)?;
            let jpeg = shot.encode(PhotoFormat::Jpeg)?;
            let facts = exif_jpeg::Facts {
                make: "SimCam".into(),
                model: "SimCam One".into(),
                lens: "Toy 50mm f/2".into(),
                f_number: (num, den),
                focal_length: (50, 1),
                exposure_time: (1, 125),
                iso: 100,
                pitch_um_and_size: Some((camera.pixel_pitch_um, w as u32, h as u32)),
            };
            let name = if copies == 1 {
                format!("f{}.jpg", sweepmtf::batch::plots::fmt_fnumber(n))
            } else {
                format!("f{}_{c:02}.jpg", sweepmtf::batch::plots::fmt_fnumber(n))
            };
            std::fs::write(dir.join(&name), exif_jpeg::with_exif(&jpeg, &facts))?;
            let r = shot.roi().ok_or("the demo target has a sweep")?;
            writeln!(
                rois,
                "{name},{}",
                r.iter()
                    .map(|v| v.to_string())
                    .collect::<Vec<_>>()
                    .join(",")
            )?;
            let t = shot.truth().ok_or("truth")?;
            let pts: Vec<(f64, f64)> = t.rows.iter().map(|r| (r.freq_cy_px, r.mtf)).collect();
            let m50 = crossing(&pts, 0.5)
                .map(|f| f.to_string())
                .unwrap_or_default();
            writeln!(truth, "{name},{n},{sigma},{m50}")?;
            eprintln!("{name}: sigma {sigma:.3} px, true MTF50 {m50} cy/px");
        }
    }
    std::fs::write(dir.join("rois.csv"), rois)?;
    std::fs::write(dir.join("truth.csv"), truth)?;
    Ok(())
}
