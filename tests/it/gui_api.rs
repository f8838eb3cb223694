//! `sweepmtf gui` without a browser: each endpoint's JSON in and out, errors
//! as JSON with the CLI's own messages and exit codes, and the security
//! checks (token, Host, Origin, upload size, where files are written).
//! The reference for every number is `sweepmtf measure` / `sweepmtf model`
//! run as a separate process, or a closed form written here.

use crate::gui_support::{GuiProc, Reply, bin, http, root};
use serde_json::{Value, json};
use std::process::Command;

const PHOTO: &str = "testdata/a4_log_shot.jpg";
const TARGET: &str = "targets/a4_log.toml";

fn start(out: &std::path::Path) -> GuiProc {
    GuiProc::start(
        &root(),
        &[PHOTO, "--target", TARGET, "-o", out.to_str().unwrap()],
    )
}

/// Runs `sweepmtf ARGS` in the repository root: (exit code, stderr without "sweepmtf: ").
fn cli(args: &[&str]) -> (i32, String) {
    let o = Command::new(bin())
        .current_dir(root())
        .args(args)
        .output()
        .unwrap();
    let err = String::from_utf8_lossy(&o.stderr);
    let line = err.lines().last().unwrap_or("").trim();
    (
        o.status.code().unwrap_or(-1),
        line.strip_prefix("sweepmtf: ").unwrap_or(line).to_string(),
    )
}

fn corners_arg(roi: &Value) -> String {
    roi.as_array()
        .unwrap()
        .iter()
        .flat_map(|p| {
            p.as_array()
                .unwrap()
                .iter()
                .map(|x| x.as_f64().unwrap().to_string())
        })
        .collect::<Vec<_>>()
        .join(",")
}

fn ok(r: &Reply) -> Value {
    assert_eq!(r.status, 200, "{}", String::from_utf8_lossy(&r.body));
    r.json()
}

#[test]
fn state_lists_the_photo_and_targets_and_display_is_a_small_jpeg() {
    let out = tempfile::tempdir().unwrap();
    let g = start(out.path());
    let s = ok(&g.call("GET", "/api/state", b""));
    let p = &s["photos"][0];
    assert_eq!(p["name"], PHOTO);
    assert_eq!(
        (p["width"].as_u64(), p["height"].as_u64()),
        (Some(2000), Some(1400))
    );
    assert_eq!(s["default_target"], 0);
    assert_eq!(s["targets"][0]["arg"], TARGET);
    let shipped: Vec<&str> = s["targets"]
        .as_array()
        .unwrap()
        .iter()
        .filter_map(|t| t["arg"].as_str())
        .collect();
    for t in [
        "targets/a4_linear.toml",
        "targets/a3_log.toml",
        "targets/a4_patches.toml",
    ] {
        assert!(shipped.contains(&t), "{t} not listed: {shipped:?}");
    }
    let d = g.call("GET", "/api/display?id=0", b"");
    assert_eq!(d.status, 200);
    assert_eq!(d.header("Content-Type"), Some("image/jpeg"));
    let img = image::load_from_memory(&d.body).unwrap();
    assert!(img.width() <= 1600 && img.height() <= 1600);
    assert_eq!(
        img.width() as f64 * p["display_scale"].as_f64().unwrap(),
        2000.0
    );
    // The page itself: one document, token filled in, nothing from elsewhere.
    let page = g.call("GET", &format!("/?token={}", g.token), b"");
    let html = String::from_utf8_lossy(&page.body);
    assert!(html.contains(&g.token) && !html.contains("__TOKEN__"));
    assert!(
        !html.contains("http://") && !html.contains("https://")
            || html.contains("http://www.w3.org/2000/svg")
    );
    assert!(!html.contains("src=\"http"), "external script");
}

#[test]
fn measure_and_save_equal_the_cli_with_the_same_corners() {
    let out = tempfile::tempdir().unwrap();
    let g = start(out.path());
    // Found automatically from the fiducials.
    let auto = ok(&g.post("/api/measure", &json!({"photo": 0, "target": 0})));
    assert_eq!(auto["roi"].as_array().unwrap().len(), 4);
    assert!(!auto["curves"].as_array().unwrap().is_empty());
    assert!(
        auto["notes"]
            .as_array()
            .unwrap()
            .iter()
            .any(|w| w.as_str().unwrap().contains("automatically"))
    );
    // A corner moved by hand (3 px right, 2 px up), used exactly as given.
    let mut roi = auto["roi"].clone();
    roi[2][0] = json!(roi[2][0].as_f64().unwrap() + 3.0);
    roi[2][1] = json!(roi[2][1].as_f64().unwrap() - 2.0);
    let req = json!({"photo": 0, "target": 0, "roi": roi, "out_dir": out.path()});
    let m = ok(&g.post("/api/measure", &req));
    let cmd = m["command"].as_str().unwrap();
    let corners = corners_arg(&roi);
    assert!(
        cmd.contains(&format!("--roi {corners} --no-refine-roi")),
        "{cmd}"
    );
    assert!(
        cmd.starts_with(&format!("sweepmtf measure {PHOTO} --target {TARGET}")),
        "{cmd}"
    );
    let saved = ok(&g.post("/api/save", &req));
    assert_eq!(saved["written"].as_array().unwrap().len(), 4);
    // The same measurement from the command line.
    let ref_dir = tempfile::tempdir().unwrap();
    let (code, err) = cli(&[
        "measure",
        PHOTO,
        "--target",
        TARGET,
        "--roi",
        &corners,
        "--no-refine-roi",
        "-o",
        ref_dir.path().to_str().unwrap(),
    ]);
    assert_eq!(code, 0, "{err}");
    for f in [
        "a4_log_shot.mtf.csv",
        "a4_log_shot.mtf.png",
        "a4_log_shot.roi.png",
    ] {
        let a = std::fs::read(out.path().join(f)).unwrap();
        let b = std::fs::read(ref_dir.path().join(f)).unwrap();
        assert!(a == b, "{f} differs from `sweepmtf measure`");
    }
    // The summary: equal except the timings.
    let read = |d: &std::path::Path| -> Value {
        let mut v: Value =
            serde_json::from_slice(&std::fs::read(d.join("a4_log_shot.summary.json")).unwrap())
                .unwrap();
        v.as_object_mut().unwrap().remove("timings_ms");
        v
    };
    assert_eq!(read(out.path()), read(ref_dir.path()));
    // The page's figures are the summary's.
    let summary = read(ref_dir.path());
    assert_eq!(m["summary"]["curves"], summary["curves"]);
    // The corner moved: MTF50 is not the automatic one's (the region changed).
    let f50 = |v: &Value| {
        v["summary"]["curves"][0]["mtf50"]["cy_px"]
            .as_f64()
            .unwrap()
    };
    assert_ne!(f50(&m), f50(&auto));
}

#[test]
fn errors_are_json_with_the_cli_message_and_code() {
    let out = tempfile::tempdir().unwrap();
    let g = start(out.path());
    // A region outside the image.
    let roi = json!([[10, 10], [5000, 10], [5000, 300], [10, 300]]);
    let r = g.post(
        "/api/measure",
        &json!({"photo": 0, "target": 0, "roi": roi}),
    );
    let e = r.json();
    let (code, msg) = cli(&[
        "measure",
        PHOTO,
        "--target",
        TARGET,
        "--roi",
        &corners_arg(&roi),
        "--no-refine-roi",
        "-o",
        out.path().to_str().unwrap(),
    ]);
    assert_ne!(code, 0);
    assert_eq!(e["error"], msg);
    assert_eq!(e["code"], code);
    assert_eq!(r.status, 422);
    // A bad option: the CLI's check and message.
    let r = g.post(
        "/api/measure",
        &json!({"photo": 0, "target": 0, "pixel_pitch": "4.3"}),
    );
    assert_eq!(r.status, 400);
    let (code, msg) = cli(&["measure", PHOTO, "--target", TARGET, "--pixel-pitch", "4.3"]);
    assert_eq!(r.json()["code"], code);
    assert_eq!(r.json()["error"], msg);
    let r = g.post("/api/measure", &json!({"photo": 0, "method": "median"}));
    assert_eq!(
        r.json()["error"],
        "--method: 'median': use extrema, fit or envelope"
    );
    // No such photo, unknown field, not JSON.
    assert_eq!(g.post("/api/measure", &json!({"photo": 7})).status, 404);
    assert_eq!(
        g.post("/api/measure", &json!({"photo": 0, "corners": 1}))
            .status,
        400
    );
    let r = g.call("POST", "/api/measure", b"{not json");
    assert_eq!(r.status, 400);
    assert!(
        r.json()["error"]
            .as_str()
            .unwrap()
            .starts_with("the request is not JSON")
    );
    // A model factor the CLI refuses: the same message.
    let r = g.post("/api/model", &json!({"factors": [{"kind": "optics", "spec": "diffraction:lambda=550,fnum=4"}], "f_max": 100}));
    let cut = out.path().join("cut.csv");
    let (code, msg) = cli(&[
        "model",
        "--optics",
        "diffraction:lambda=550,fnum=4",
        "--cut",
        "u",
        "--f-max",
        "100",
        "-o",
        cut.to_str().unwrap(),
    ]);
    assert_eq!(r.status, 400);
    assert_eq!(r.json()["error"], msg);
    assert_eq!(r.json()["code"], code);
}

#[test]
fn model_cut_and_map_match_the_closed_form() {
    let out = tempfile::tempdir().unwrap();
    let g = start(out.path());
    let req = json!({
        "factors": [{"kind": "optics", "spec": "diffraction:lambda=550nm,fnum=4"}],
        "cut": "u", "f_max": 500, "points": 101, "map_size": 64,
    });
    let r = ok(&g.post("/api/model", &req));
    let f = r["cut"]["freq_cy_mm"].as_array().unwrap();
    let m = r["cut"]["mtf"].as_array().unwrap();
    assert_eq!(f.len(), 101);
    // Diffraction-limited circular pupil: (2/π)(acos s − s√(1−s²)), s = f·λ·N.
    let uc = 1.0 / (550e-6 * 4.0);
    for (f, m) in f.iter().zip(m) {
        let s = (f.as_f64().unwrap() / uc).min(1.0);
        let truth = 2.0 / std::f64::consts::PI * (s.acos() - s * (1.0 - s * s).sqrt());
        assert!(
            (m.as_f64().unwrap() - truth).abs() < 1e-12,
            "f {f}: {m} vs {truth}"
        );
    }
    assert_eq!(r["cut"]["nyquist_cy_mm"], Value::Null);
    let map = &r["map"];
    assert_eq!(map["size"], 64);
    assert!(map["png_base64"].as_str().unwrap().len() > 100);
    // With a sampling grid the Nyquist frequency is 1/(2·pitch).
    let req = json!({
        "factors": [{"kind": "sampling", "spec": "rect:px=5um,py=5um"}],
        "cut": "v", "f_max": 200,
    });
    let r = ok(&g.post("/api/model", &req));
    assert!((r["cut"]["nyquist_cy_mm"].as_f64().unwrap() - 100.0).abs() < 1e-9);
}

#[test]
fn token_host_and_origin_are_checked() {
    let out = tempfile::tempdir().unwrap();
    let g = start(out.path());
    let host = g.host();
    let good = http(
        g.port,
        "GET",
        &format!("/api/state?token={}", g.token),
        &[("Host", &host)],
        b"",
    );
    assert_eq!(good.status, 200);
    let refused = |r: Reply, why: &str| {
        assert_eq!(r.status, 403, "{why}");
        assert!(
            r.json()["error"].as_str().unwrap().starts_with("refused"),
            "{why}"
        );
    };
    refused(
        http(g.port, "GET", "/api/state", &[("Host", &host)], b""),
        "no token",
    );
    refused(
        http(g.port, "GET", "/", &[("Host", &host)], b""),
        "page without token",
    );
    refused(
        http(
            g.port,
            "GET",
            "/api/state?token=0123456789abcdef0123456789abcdef",
            &[("Host", &host)],
            b"",
        ),
        "wrong token",
    );
    let tok = format!("/api/state?token={}", g.token);
    refused(
        http(
            g.port,
            "GET",
            &tok,
            &[("Host", &format!("evil.example:{}", g.port))],
            b"",
        ),
        "rebinding Host",
    );
    refused(
        http(
            g.port,
            "GET",
            &tok,
            &[("Host", &format!("localhost:{}", g.port))],
            b"",
        ),
        "other Host",
    );
    refused(http(g.port, "GET", &tok, &[], b""), "no Host");
    refused(
        http(
            g.port,
            "GET",
            &tok,
            &[("Host", &host), ("Origin", "http://evil.example")],
            b"",
        ),
        "cross-site Origin",
    );
    let same = http(
        g.port,
        "GET",
        &tok,
        &[("Host", &host), ("Origin", &format!("http://{host}"))],
        b"",
    );
    assert_eq!(same.status, 200);
    // A cross-site POST with the right token is still refused.
    refused(
        http(
            g.port,
            "POST",
            &format!("/api/save?token={}", g.token),
            &[("Host", &host), ("Origin", "null")],
            b"{}",
        ),
        "null Origin",
    );
    assert_eq!(g.token.len(), 32);
}

#[test]
fn uploads_are_bounded_and_saves_stay_in_the_output_folder() {
    let out = tempfile::tempdir().unwrap();
    let work = tempfile::tempdir().unwrap();
    let g = start(out.path());
    // Larger than the limit: refused from the declared length alone.
    let mut s = std::net::TcpStream::connect(("127.0.0.1", g.port)).unwrap();
    use std::io::{Read, Write};
    write!(
        s,
        "POST /api/upload?name=big.jpg HTTP/1.1\r\nHost: {}\r\nX-Sweepmtf-Token: {}\r\nContent-Length: {}\r\nConnection: close\r\n\r\n",
        g.host(),
        g.token,
        (400u64 << 20) + 1
    )
    .unwrap();
    let mut raw = String::new();
    let _ = s.read_to_string(&mut raw);
    assert!(raw.starts_with("HTTP/1.1 413"), "{raw}");
    // Not an image.
    let r = g.call("POST", "/api/upload?name=notes.txt", b"hello");
    assert_eq!(r.status, 422);
    assert!(r.json()["error"].as_str().unwrap().contains("notes.txt"));
    // A photo whose name tries to climb out of the output folder.
    let jpg = std::fs::read(root().join(PHOTO)).unwrap();
    let r = ok(&g.call("POST", "/api/upload?name=..%2F..%2Fescape.jpg", &jpg));
    assert_eq!(r["name"], "escape.jpg");
    let id = r["id"].as_u64().unwrap();
    let sub = work.path().join("a/b");
    let saved = ok(&g.post(
        "/api/save",
        &json!({"photo": id, "target": 0, "out_dir": sub}),
    ));
    assert_eq!(saved["written"].as_array().unwrap().len(), 4);
    assert!(sub.join("escape.mtf.csv").exists());
    // Nothing was written above the chosen folder.
    for d in [work.path().to_path_buf(), work.path().join("a")] {
        for e in std::fs::read_dir(&d).unwrap() {
            let p = e.unwrap().path();
            assert!(p.is_dir(), "unexpected file {}", p.display());
        }
    }
}
