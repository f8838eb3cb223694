//! Response times of `sweepmtf gui` on the 24-megapixel JPEG of the speed
//! checks (`measure::synth::big_shot`: 6000×4000, a 5600×400 px log sweep,
//! q90): the photo named on the command line until its display rendition is
//! served, the same photo uploaded, a new MTF after a corner release (the
//! `/api/measure` round trip with the corners given, as the page sends them),
//! a model cut alone and with a 512² map; with chromium installed, also the
//! start until the page has drawn the photo. Medians of 7 runs. A documented run,
//! not a bar (the machine's load varies), so ignored by default:
//! `cargo build --release && SWEEPMTF_BIN=target/release/sweepmtf cargo test --test it gui_timing -- --ignored --nocapture`.

use crate::gui_browser::{Driver, find};
use crate::gui_support::{GuiProc, root};
use serde_json::json;
use std::time::Instant;
use sweepmtf::measure::synth::big_shot;

fn median(mut v: Vec<f64>) -> f64 {
    v.sort_by(f64::total_cmp);
    v[v.len() / 2]
}

fn ms(t: Instant) -> f64 {
    t.elapsed().as_secs_f64() * 1e3
}

#[test]
#[ignore]
fn gui_response_times_24mp() {
    const RUNS: usize = 7;
    let shot = big_shot();
    let jpeg = shot.encode(5);
    let dir = tempfile::tempdir().unwrap();
    let photo = dir.path().join("big.jpg");
    std::fs::write(&photo, &jpeg).unwrap();
    let out = dir.path().join("out");
    let args = [photo.to_str().unwrap(), "-o", out.to_str().unwrap()];

    // Opened from the command line: start → display rendition received.
    let mut opened = Vec::new();
    for _ in 0..RUNS {
        let t = Instant::now();
        let g = GuiProc::start(&root(), &args);
        let d = g.call("GET", "/api/display?id=0", b"");
        assert_eq!(d.status, 200);
        opened.push(ms(t));
    }
    // With chromium: start → the page in a (warm) browser has drawn the photo.
    let mut shown = Vec::new();
    if let (Some(chromium), Some(driver)) = (
        find(&["chromium", "chromium-browser", "google-chrome"]),
        find(&["chromedriver"]),
    ) {
        let profile = tempfile::tempdir().unwrap();
        let d = Driver::start(&driver, &chromium, profile.path());
        for _ in 0..RUNS {
            let t = Instant::now();
            let g = GuiProc::start(&root(), &args);
            d.s("POST", "/url", json!({"url": g.url}));
            d.wait("return document.body.dataset.photoShown === '0';", 30);
            shown.push(ms(t));
        }
    }
    let g = GuiProc::start(&root(), &args);
    // Uploaded from the page: POST → display rendition received.
    let mut uploaded = Vec::new();
    for _ in 0..RUNS {
        let t = Instant::now();
        let r = g.call("POST", "/api/upload?name=big.jpg", &jpeg);
        assert_eq!(r.status, 200, "{}", String::from_utf8_lossy(&r.body));
        let id = r.json()["id"].as_u64().unwrap();
        let d = g.call("GET", &format!("/api/display?id={id}"), b"");
        assert_eq!(d.status, 200);
        uploaded.push(ms(t));
    }
    // A corner released: the measurement with the corners as given.
    let mut measured = Vec::new();
    let mut server = Vec::new();
    for k in 0..RUNS {
        let mut roi = shot.quad;
        roi[2][0] += 0.25 * k as f64;
        let t = Instant::now();
        let r = g.post("/api/measure", &json!({"photo": 0, "roi": roi}));
        measured.push(ms(t));
        assert_eq!(r.status, 200, "{}", String::from_utf8_lossy(&r.body));
        server.push(r.json()["measure_ms"].as_f64().unwrap());
    }
    // The model view's request (diffraction, pixel aperture, sampling grid).
    let model = |fnum: f64, map: usize| {
        json!({
            "factors": [
                {"kind": "optics", "spec": format!("diffraction:lambda=550nm,fnum={fnum}")},
                {"kind": "aperture", "spec": "rect:A=4.3um,B=4.3um"},
                {"kind": "sampling", "spec": "rect:px=4.3um,py=4.3um"},
            ],
            "cut": "u", "f_max": 300, "points": 401, "map_size": map,
        })
    };
    let mut cut = Vec::new();
    let mut map = Vec::new();
    for k in 0..RUNS {
        let fnum = 4.0 + 0.5 * k as f64;
        let t = Instant::now();
        assert_eq!(g.post("/api/model", &model(fnum, 0)).status, 200);
        cut.push(ms(t));
        let t = Instant::now();
        assert_eq!(g.post("/api/model", &model(fnum, 512)).status, 200);
        map.push(ms(t));
    }
    if !shown.is_empty() {
        println!(
            "gui on a 24 MP JPEG: started → photo drawn in the page (warm headless chromium) {:.0} ms (median of {RUNS})",
            median(shown)
        );
    }
    println!(
        "gui on a 24 MP JPEG (6000×4000), medians of {RUNS}: opened from the command line → display served {:.0} ms; \
         uploaded → display served {:.0} ms; new MTF after a corner release {:.0} ms round trip ({:.0} ms measuring); \
         model cut {:.1} ms; cut + 512² map {:.0} ms",
        median(opened),
        median(uploaded),
        median(measured),
        median(server),
        median(cut),
        median(map)
    );
}
