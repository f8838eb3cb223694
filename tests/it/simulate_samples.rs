//! The shipped sample photos in testdata/: each decodes (with the `image`
//! crate) to the size and format its JSON states, its truth CSV has the
//! promised columns, and its region lies inside the frame. With
//! `SWEEPMTF_PREVIEW=DIR` set, 8-bit PNG previews (and a 4× crop of the
//! sweep's high-frequency end) are written there so a person can look at them.

use std::path::{Path, PathBuf};

fn testdata() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("testdata")
}

const SAMPLES: &[&str] = &[
    "sweep_log_srgb_q90.jpg",
    "sweep_linear_srgb.png",
    "sweep_log_rot12_tilt25.png",
    "sweep_log_bayer_rggb.tif",
];

#[test]
fn samples_decode_and_match_their_settings() {
    for name in SAMPLES {
        let path = testdata().join(name);
        let stem = name.rsplit_once('.').unwrap().0;
        let img = image::open(&path).unwrap_or_else(|e| panic!("{name}: {e}"));
        let j: serde_json::Value = serde_json::from_slice(
            &std::fs::read(testdata().join(format!("{stem}.json"))).unwrap(),
        )
        .unwrap();
        assert_eq!(
            img.width() as u64,
            j["width_px"].as_u64().unwrap(),
            "{name}"
        );
        assert_eq!(
            img.height() as u64,
            j["height_px"].as_u64().unwrap(),
            "{name}"
        );
        let bits = j["bits"].as_u64().unwrap();
        let want = if bits == 16 {
            image::ColorType::L16
        } else {
            image::ColorType::L8
        };
        assert_eq!(img.color(), want, "{name}");
        let roi: Vec<f64> = j["roi"]
            .as_array()
            .unwrap()
            .iter()
            .map(|v| v.as_f64().unwrap())
            .collect();
        assert_eq!(roi.len(), 8);
        for c in roi.chunks(2) {
            assert!(
                c[0] > 0.0 && c[0] < img.width() as f64 && c[1] > 0.0 && c[1] < img.height() as f64
            );
        }
        let csv = std::fs::read_to_string(testdata().join(format!("{stem}.truth.csv"))).unwrap();
        assert!(csv.starts_with("freq_cy_px,mtf,s_mm,freq_cy_mm"), "{name}");
        assert!(csv.lines().count() > 100);

        if let Ok(dir) = std::env::var("SWEEPMTF_PREVIEW") {
            std::fs::create_dir_all(&dir).unwrap();
            let l16 = img.to_luma16();
            // Linear 16-bit data is shown through the sRGB curve.
            let linear = bits == 16;
            let to8 = |v: u16| -> u8 {
                let x = v as f64 / 65535.0;
                let c = if linear {
                    if x <= 0.003_130_8 {
                        12.92 * x
                    } else {
                        1.055 * x.powf(1.0 / 2.4) - 0.055
                    }
                } else {
                    x
                };
                (c * 255.0).round() as u8
            };
            let prev = image::GrayImage::from_fn(img.width(), img.height(), |x, y| {
                image::Luma([to8(l16.get_pixel(x, y)[0])])
            });
            prev.save(Path::new(&dir).join(format!("{stem}.png")))
                .unwrap();
            // 4× crop around the strip's high-frequency edge (corners 2 and 3).
            let (cx, cy) = ((roi[2] + roi[4]) / 2.0, (roi[3] + roi[5]) / 2.0);
            let (w, h) = (120u32, 80u32);
            let x0 = (cx as u32).saturating_sub(w - 10);
            let y0 = (cy as u32).saturating_sub(h / 2);
            let crop = image::GrayImage::from_fn(4 * w, 4 * h, |x, y| {
                let (sx, sy) = (
                    (x0 + x / 4).min(img.width() - 1),
                    (y0 + y / 4).min(img.height() - 1),
                );
                *prev.get_pixel(sx, sy)
            });
            crop.save(Path::new(&dir).join(format!("{stem}.crop.png")))
                .unwrap();
        }
    }
}
