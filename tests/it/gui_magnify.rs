//! The page's full-resolution magnifier (`/api/crop`), its chart picker for
//! frames holding several charts (`/api/charts`), and raws opened from the
//! page (`/api/upload` of a `.dng`). References: the photo decoded by the
//! image crate, the charts `measure` finds on its own (its per-chart
//! outputs), and `sweepmtf measure` of the same raw file from disk.

use crate::gui_support::{GuiProc, Reply, root};
use serde_json::{Value, json};
use std::path::Path;

fn ok(r: &Reply) -> Value {
    assert_eq!(r.status, 200, "{}", String::from_utf8_lossy(&r.body));
    r.json()
}

/// The crop's picture, decoded.
fn crop_image(v: &Value) -> image::RgbImage {
    let url = v["png"].as_str().unwrap();
    let b64 = url
        .strip_prefix("data:image/png;base64,")
        .expect("a PNG data URL");
    image::load_from_memory(&crate::gui_browser::base64_decode(b64))
        .unwrap()
        .to_rgb8()
}

#[test]
fn crop_is_the_photos_own_pixels_around_the_point() {
    let out = tempfile::tempdir().unwrap();
    let g = GuiProc::start(
        &root(),
        &[
            "testdata/a4_log_shot.jpg",
            "-o",
            out.path().to_str().unwrap(),
        ],
    );
    let v = ok(&g.call("GET", "/api/crop?id=0&x=1000.3&y=700.8", b""));
    // Pixel (1000, 700) (covering [1000, 1001) × [700, 701)) is the window's centre.
    assert_eq!(
        [&v["x"], &v["y"], &v["width"], &v["height"]].map(|x| x.as_f64().unwrap()),
        [968.0, 668.0, 64.0, 64.0]
    );
    let crop = crop_image(&v);
    assert_eq!(crop.dimensions(), (64, 64));
    let whole = image::open(root().join("testdata/a4_log_shot.jpg"))
        .unwrap()
        .to_rgb8();
    let mut worst = 0i32;
    for (x, y, p) in crop.enumerate_pixels() {
        let q = whole.get_pixel(968 + x, 668 + y);
        for c in 0..3 {
            worst = worst.max((p[c] as i32 - q[c] as i32).abs());
        }
    }
    // Another JPEG decoder (the image crate's) may round differently by one code.
    assert!(worst <= 1, "crop differs from the photo by {worst} codes");
    // At the photo's corner the window is pushed inside; it never leaves the photo.
    let v = ok(&g.call("GET", "/api/crop?id=0&x=-40&y=99999", b""));
    assert_eq!(
        [&v["x"], &v["y"]].map(|x| x.as_f64().unwrap()),
        [0.0, 1400.0 - 64.0]
    );
    // Bad requests: JSON errors, not a crash.
    for (q, status) in [
        ("/api/crop?id=0&x=5", 400),
        ("/api/crop?id=0&x=nan&y=3", 400),
        ("/api/crop?id=9&x=5&y=5", 404),
    ] {
        let r = g.call("GET", q, b"");
        assert_eq!(r.status, status, "{q}");
        assert!(r.json()["error"].is_string(), "{q}");
    }
}

#[test]
fn every_chart_of_a_frame_is_listed_and_each_measured_as_measure_does() {
    let dir = tempfile::tempdir().unwrap();
    let (photo, _) = crate::locate_each_chart::two_charts(dir.path());
    let target = root().join("targets/a4_log.toml");
    let out = dir.path().join("out");
    let g = GuiProc::start(
        &root(),
        &[
            photo.to_str().unwrap(),
            "--target",
            target.to_str().unwrap(),
            "-o",
            out.to_str().unwrap(),
        ],
    );
    let c = ok(&g.call("GET", "/api/charts?id=0&target=0", b""));
    let charts = c["charts"].as_array().unwrap();
    assert_eq!(charts.len(), 2, "{c}");
    // Left to right, each inside its own half of the frame (700 px wide each).
    for (i, ch) in charts.iter().enumerate() {
        for p in ch["corners_px"].as_array().unwrap() {
            let x = p[0].as_f64().unwrap();
            assert!(
                (700.0 * i as f64..700.0 * (i + 1) as f64).contains(&x),
                "chart {i}: {p}"
            );
        }
    }
    // Measuring chart 1 on the page gives what `measure --chart-index 1` writes.
    let m = ok(&g.post(
        "/api/measure",
        &json!({"photo": 0, "target": 0, "chart_index": 1}),
    ));
    assert!(m["command"].as_str().unwrap().contains("--chart-index 1"));
    let cli_out = dir.path().join("cli");
    let st = std::process::Command::new(crate::gui_support::bin())
        .arg("measure")
        .arg(&photo)
        .arg("--target")
        .arg(&target)
        .args(["--chart-index", "1", "--json", "-o"])
        .arg(&cli_out)
        .status()
        .unwrap();
    assert!(st.success());
    let s: Value =
        serde_json::from_slice(&std::fs::read(cli_out.join("two.summary.json")).unwrap()).unwrap();
    let roi = |v: &Value| -> Vec<f64> {
        v.as_array()
            .unwrap()
            .iter()
            .flat_map(|p| p.as_array().unwrap().iter().map(|x| x.as_f64().unwrap()))
            .collect()
    };
    let (a, b) = (roi(&m["roi"]), roi(&s["roi_px"]));
    assert_eq!(a.len(), 8);
    for (x, y) in a.iter().zip(&b) {
        assert!((x - y).abs() < 1e-9, "page {a:?} vs measure {b:?}");
    }
    // A target not in the frame: the location error, as JSON with exit code 4.
    let one = GuiProc::start(
        &root(),
        &[
            "testdata/a4_log_shot.jpg",
            "--target",
            "targets/a3_linear.toml",
        ],
    );
    let r = one.call("GET", "/api/charts?id=0&target=0", b"");
    assert_eq!(
        (r.status, r.json()["code"].as_u64()),
        (422, Some(4)),
        "{}",
        r.json()
    );
    assert_eq!(one.call("GET", "/api/charts?id=0", b"").status, 400);
}

#[test]
fn a_raw_uploaded_from_the_page_measures_as_the_file_does() {
    let dir = tempfile::tempdir().unwrap();
    let dng = dir.path().join("shot.dng");
    let target = root().join("targets/a4_log.toml");
    let st = std::process::Command::new(crate::gui_support::bin())
        .args(["simulate", "--target"])
        .arg(&target)
        .args(["--size", "1200x800", "--bayer", "RGGB", "-o"])
        .arg(&dng)
        .status()
        .unwrap();
    assert!(st.success());
    let out = dir.path().join("out");
    let g = GuiProc::start(
        &root(),
        &[
            "--target",
            target.to_str().unwrap(),
            "-o",
            out.to_str().unwrap(),
        ],
    );
    let bytes = std::fs::read(&dng).unwrap();
    let up = ok(&g.call("POST", "/api/upload?name=shot.dng", &bytes));
    assert_eq!(
        (up["raw"].as_bool(), up["width"].as_u64()),
        (Some(true), Some(1200))
    );
    let id = up["id"].as_u64().unwrap();
    let saved = ok(&g.post(
        "/api/save",
        &json!({"photo": id, "target": 0, "channel": "g"}),
    ));
    assert_eq!(saved["written"].as_array().unwrap().len(), 4);
    let cli_out = dir.path().join("cli");
    let st = std::process::Command::new(crate::gui_support::bin())
        .arg("measure")
        .arg(&dng)
        .arg("--target")
        .arg(&target)
        .args(["--channel", "g", "-o"])
        .arg(&cli_out)
        .status()
        .unwrap();
    assert!(st.success());
    assert_eq!(
        std::fs::read(out.join("shot.mtf.csv")).unwrap(),
        std::fs::read(cli_out.join("shot.mtf.csv")).unwrap(),
        "the page's CSV differs from measure's"
    );
    // The magnifier reads the raw's green lattice: 2-pixel squares.
    let v = ok(&g.call("GET", &format!("/api/crop?id={id}&x=600&y=400"), b""));
    assert_eq!(crop_image(&v).dimensions(), (32, 32));
    assert_eq!(v["width"].as_f64(), Some(64.0));
    // A damaged raw: one line naming the upload, not the temporary file.
    let r = g.call(
        "POST",
        "/api/upload?name=broken.dng",
        &bytes[..bytes.len() / 3],
    );
    assert_eq!(r.status, 422);
    let e = r.json()["error"].as_str().unwrap().to_string();
    assert!(
        e.contains("broken.dng") && !e.contains("sweepmtf-gui-"),
        "{e}"
    );
    assert!(
        Path::new(&std::env::temp_dir())
            .read_dir()
            .unwrap()
            .all(|f| {
                !f.unwrap()
                    .file_name()
                    .to_string_lossy()
                    .starts_with("sweepmtf-gui-")
            }),
        "a temporary upload was left behind"
    );
}

#[test]
fn browser_lists_two_charts_and_measures_the_one_picked() {
    use crate::gui_browser::{Driver, browser};
    let Some((chromium, driver)) = browser() else {
        return;
    };
    let dir = tempfile::tempdir().unwrap();
    let (photo, _) = crate::locate_each_chart::two_charts(dir.path());
    let target = root().join("targets/a4_log.toml");
    let g = GuiProc::start(
        &root(),
        &[
            photo.to_str().unwrap(),
            "--target",
            target.to_str().unwrap(),
        ],
    );
    let profile = tempfile::tempdir().unwrap();
    let d = Driver::start(&driver, &chromium, profile.path());
    d.s("POST", "/url", json!({"url": g.url}));
    d.wait("return document.body.dataset.charts === '2' && document.body.dataset.state === 'ready' && Number(document.body.dataset.measureCount) >= 1;", 60);
    // Two dashed outlines; the first chart measured; pick the second.
    assert_eq!(
        d.js("return document.querySelectorAll('#overlay .other-chart').length;"),
        json!(2)
    );
    let left = d
        .js("return Math.max(...M.corners.map((c) => c[0]));")
        .as_f64()
        .unwrap();
    assert!(left < 700.0, "chart 1 is the left one: {left}");
    d.js("const s = document.getElementById('chart'); s.value = '1'; s.dispatchEvent(new Event('change'));");
    d.wait("return Number(document.body.dataset.measureCount) >= 2 && document.body.dataset.state === 'ready';", 60);
    let right = d
        .js("return Math.min(...M.corners.map((c) => c[0]));")
        .as_f64()
        .unwrap();
    assert!(right >= 700.0, "chart 2 is the right one: {right}");
    let cmd = d.js("return document.getElementById('command').textContent;");
    assert!(cmd.as_str().unwrap().contains("--chart-index 1"), "{cmd}");
    d.screenshot("measure_two_charts.png");
}
