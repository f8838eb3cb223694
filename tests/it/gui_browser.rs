//! `sweepmtf gui` end to end in a real browser: Debian's `chromium`, headless,
//! driven through WebDriver (`chromedriver`) with plain HTTP/JSON. Opens the
//! README sample, drags a corner, sees MTF50 change, saves, and checks the CSV
//! equals `sweepmtf measure` with the same corners; in the model view changes
//! the f-number and sees the cut change. Screenshots go to
//! target/gui-screenshots/. Without a browser the test prints "skipped" and
//! passes, unless SWEEPMTF_REQUIRE_BROWSER=1.

use crate::gui_support::{GuiProc, bin, http, root};
use serde_json::{Value, json};
use std::path::PathBuf;
use std::process::{Child, Command, Stdio};
use std::time::{Duration, Instant};

/// The first of `names` found on PATH.
pub fn find(names: &[&str]) -> Option<PathBuf> {
    let path = std::env::var_os("PATH")?;
    for dir in std::env::split_paths(&path) {
        for n in names {
            let p = dir.join(n);
            if p.is_file() {
                return Some(p);
            }
        }
    }
    None
}

/// A chromedriver child and one session in it.
pub struct Driver {
    child: Child,
    port: u16,
    session: String,
}

impl Driver {
    /// Starts chromedriver and a headless chromium session (profile in `profile`).
    pub fn start(chromedriver: &PathBuf, chromium: &PathBuf, profile: &std::path::Path) -> Driver {
        let port = std::net::TcpListener::bind("127.0.0.1:0")
            .unwrap()
            .local_addr()
            .unwrap()
            .port();
        let mut cmd = Command::new(chromedriver);
        cmd.arg(format!("--port={port}"))
            .stdout(Stdio::null())
            .stderr(Stdio::null());
        // Its own process group, so that the browser it starts is killed with it.
        #[cfg(unix)]
        std::os::unix::process::CommandExt::process_group(&mut cmd, 0);
        let child = cmd.spawn().expect("start chromedriver");
        let mut d = Driver {
            child,
            port,
            session: String::new(),
        };
        let t = Instant::now();
        while std::net::TcpStream::connect(("127.0.0.1", port)).is_err() {
            assert!(
                t.elapsed() < Duration::from_secs(20),
                "chromedriver did not start"
            );
            std::thread::sleep(Duration::from_millis(100));
        }
        let caps = json!({"capabilities": {"alwaysMatch": {
            "browserName": "chrome",
            "goog:chromeOptions": {
                "binary": chromium,
                "args": [
                    "--headless", "--no-sandbox", "--disable-gpu", "--disable-background-networking",
                    "--disable-component-update", "--no-first-run", "--disable-dev-shm-usage",
                    "--window-size=1500,1250",
                    format!("--user-data-dir={}", profile.display()),
                ],
            },
        }}});
        let v = d.cmd("POST", "/session", &caps);
        d.session = v["sessionId"].as_str().expect("session id").to_string();
        d
    }

    fn cmd(&self, method: &str, path: &str, body: &Value) -> Value {
        let host = format!("127.0.0.1:{}", self.port);
        let b = body.to_string();
        let r = http(
            self.port,
            method,
            path,
            &[
                ("Host", &host),
                ("Content-Type", "application/json; charset=utf-8"),
            ],
            if method == "GET" { b"" } else { b.as_bytes() },
        );
        let v: Value = serde_json::from_slice(&r.body).unwrap_or(Value::Null);
        assert_eq!(r.status, 200, "WebDriver {method} {path}: {v}");
        v["value"].clone()
    }

    /// A command on the session.
    pub fn s(&self, method: &str, path: &str, body: Value) -> Value {
        self.cmd(method, &format!("/session/{}{path}", self.session), &body)
    }

    pub fn js(&self, script: &str) -> Value {
        self.s(
            "POST",
            "/execute/sync",
            json!({"script": script, "args": []}),
        )
    }

    /// Waits until `script` returns a truthy value (up to `secs`), returns it.
    pub fn wait(&self, script: &str, secs: u64) -> Value {
        let t = Instant::now();
        loop {
            let v = self.js(script);
            if !(v.is_null() || v == json!(false) || v == json!("")) {
                return v;
            }
            assert!(
                t.elapsed() < Duration::from_secs(secs),
                "timed out waiting for: {script}"
            );
            std::thread::sleep(Duration::from_millis(20));
        }
    }

    pub fn element(&self, css: &str) -> String {
        let v = self.s(
            "POST",
            "/element",
            json!({"using": "css selector", "value": css}),
        );
        v.as_object()
            .and_then(|o| o.values().next())
            .and_then(|x| x.as_str())
            .unwrap_or_else(|| panic!("no element {css}"))
            .to_string()
    }

    /// A screenshot of the window, cut below the shown view's panes, as
    /// target/gui-screenshots/NAME.
    pub fn screenshot(&self, name: &str) -> PathBuf {
        let v = self.s("GET", "/screenshot", json!({}));
        let bytes = base64_decode(v.as_str().unwrap());
        let bottom = self
            .js("return Math.ceil(devicePixelRatio * (8 + Math.max(...[...document.querySelectorAll('.view:not(.hidden) .pane')].map(e => e.getBoundingClientRect().bottom))));")
            .as_f64()
            .unwrap_or(f64::INFINITY);
        let mut img = image::load_from_memory(&bytes).unwrap();
        if bottom < img.height() as f64 {
            img = img.crop_imm(0, 0, img.width(), bottom as u32);
        }
        let dir = root().join("target/gui-screenshots");
        std::fs::create_dir_all(&dir).unwrap();
        let p = dir.join(name);
        // Best compression, so that the pictures the README shows stay small.
        let png = image::codecs::png::PngEncoder::new_with_quality(
            std::fs::File::create(&p).unwrap(),
            image::codecs::png::CompressionType::Best,
            image::codecs::png::FilterType::Adaptive,
        );
        img.to_rgb8().write_with_encoder(png).unwrap();
        p
    }
}

impl Drop for Driver {
    fn drop(&mut self) {
        if !self.session.is_empty() {
            let host = format!("127.0.0.1:{}", self.port);
            let _ = http(
                self.port,
                "DELETE",
                &format!("/session/{}", self.session),
                &[("Host", &host)],
                b"",
            );
        }
        // The whole group: chromedriver and every browser process it started.
        #[cfg(unix)]
        let _ = Command::new("kill")
            .args(["-KILL", "--", &format!("-{}", self.child.id())])
            .stderr(Stdio::null())
            .status();
        let _ = self.child.kill();
        let _ = self.child.wait();
    }
}

/// Standard base64 (the WebDriver screenshot encoding).
pub(crate) fn base64_decode(s: &str) -> Vec<u8> {
    let val = |c: u8| match c {
        b'A'..=b'Z' => Some(c - b'A'),
        b'a'..=b'z' => Some(c - b'a' + 26),
        b'0'..=b'9' => Some(c - b'0' + 52),
        b'+' => Some(62),
        b'/' => Some(63),
        _ => None,
    };
    let mut out = Vec::new();
    let (mut acc, mut n) = (0u32, 0);
    for c in s.bytes().filter_map(val) {
        acc = (acc << 6) | c as u32;
        n += 6;
        if n >= 8 {
            n -= 8;
            out.push((acc >> n) as u8);
        }
    }
    out
}

fn mtf50(d: &Driver) -> f64 {
    let v = d.js("const r = document.getElementById('mtf50-0'); return r ? r.dataset.cyPx : null;");
    let f: f64 = v
        .as_str()
        .and_then(|s| s.parse().ok())
        .expect("MTF50 shown");
    // The table's cell shows it with its one-sigma uncertainty.
    let cell = d.js("return document.getElementById('mtf50-0').children[1].textContent;");
    let cell = cell.as_str().unwrap_or_default();
    assert!(
        cell.starts_with(&format!("{f:.4} ± ")),
        "MTF50 cell {cell:?} for {f}"
    );
    f
}

/// Chromium and chromedriver, or None (the test then reports itself
/// skipped) — a failure instead when SWEEPMTF_REQUIRE_BROWSER=1.
pub fn browser() -> Option<(PathBuf, PathBuf)> {
    let required = std::env::var("SWEEPMTF_REQUIRE_BROWSER").is_ok_and(|v| v == "1");
    let found = (
        find(&["chromium", "chromium-browser", "google-chrome"]),
        find(&["chromedriver"]),
    );
    let (Some(chromium), Some(driver)) = found else {
        assert!(
            !required,
            "SWEEPMTF_REQUIRE_BROWSER=1 but chromium/chromedriver are not installed"
        );
        println!("skipped: no chromium and chromedriver on PATH");
        return None;
    };
    Some((chromium, driver))
}

#[test]
fn browser_measures_drags_saves_and_models() {
    let Some((chromium, driver)) = browser() else {
        return;
    };
    let out = tempfile::tempdir().unwrap();
    let profile = tempfile::tempdir().unwrap();
    let g = GuiProc::start(
        &root(),
        &[
            "testdata/a4_log_shot.jpg",
            "--target",
            "targets/a4_log.toml",
            "-o",
            out.path().to_str().unwrap(),
        ],
    );
    let d = Driver::start(&driver, &chromium, profile.path());
    let t0 = Instant::now();
    d.s("POST", "/url", json!({"url": g.url}));
    d.wait("return document.body.dataset.photoShown === '0';", 30);
    let shown_ms = t0.elapsed().as_secs_f64() * 1e3;
    d.wait("return Number(document.body.dataset.measureCount) >= 1 && document.body.dataset.state === 'ready';", 60);
    let first_ms = t0.elapsed().as_secs_f64() * 1e3;
    let before = mtf50(&d);
    d.screenshot("measure_located.png");

    // Drag corner 3 by (−5, +3) CSS pixels (about −12, +8 image pixels) with the mouse.
    let corner = d.element("#corner-2");
    let actions = json!({"actions": [{
        "type": "pointer", "id": "mouse", "parameters": {"pointerType": "mouse"},
        "actions": [
            {"type": "pointerMove", "origin": {"element-6066-11e4-a52e-4f735466cecf": corner}, "x": 0, "y": 0, "duration": 0},
            {"type": "pointerDown", "button": 0},
            {"type": "pointerMove", "origin": "pointer", "x": -3, "y": 1, "duration": 100},
            {"type": "pointerMove", "origin": "pointer", "x": -2, "y": 2, "duration": 100},
            {"type": "pointerUp", "button": 0},
        ],
    }]});
    let count = d
        .js("return Number(document.body.dataset.measureCount);")
        .as_f64()
        .unwrap();
    d.s("POST", "/actions", actions);
    d.wait(&format!("return Number(document.body.dataset.measureCount) > {count} && document.body.dataset.state === 'ready';"), 60);
    let release_ms: f64 = d
        .js("return Number(document.body.dataset.lastMs);")
        .as_f64()
        .unwrap();
    let after = mtf50(&d);
    assert!(
        (after - before).abs() > 1e-4,
        "MTF50 did not change: {before} → {after}"
    );
    let errors = d.js("return [...document.querySelectorAll('#warnings li.error')].map(e => e.textContent).join('; ');");
    assert_eq!(errors, json!(""), "measurement error after the drag");
    d.screenshot("measure.png");

    // Hold corner 1 while dragging: the magnifier shows the photo's own
    // pixels (a full-resolution window from /api/crop) around it.
    let corner = d.element("#corner-0");
    let count = d
        .js("return Number(document.body.dataset.measureCount);")
        .as_f64()
        .unwrap();
    d.s("POST", "/actions", json!({"actions": [{
        "type": "pointer", "id": "mouse", "parameters": {"pointerType": "mouse"},
        "actions": [
            {"type": "pointerMove", "origin": {"element-6066-11e4-a52e-4f735466cecf": corner}, "x": 0, "y": 0, "duration": 0},
            {"type": "pointerDown", "button": 0},
            {"type": "pointerMove", "origin": "pointer", "x": 2, "y": 1, "duration": 100},
        ],
    }]}));
    d.wait("const m = document.getElementById('mag-full'); return Number(document.body.dataset.cropCount) >= 1 && m && (m.getAttribute('href') || '').startsWith('data:image/png') && !document.getElementById('magnifier').classList.contains('hidden');", 30);
    // Six screen pixels per image pixel: the window spans 30 image pixels.
    let span = d.js("return document.getElementById('magnifier').getAttribute('viewBox').split(' ').map(Number)[2];");
    assert_eq!(span.as_f64(), Some(30.0));
    d.screenshot("measure_magnifier.png");
    d.s(
        "POST",
        "/actions",
        json!({"actions": [{
            "type": "pointer", "id": "mouse", "parameters": {"pointerType": "mouse"},
            "actions": [{"type": "pointerUp", "button": 0}],
        }]}),
    );
    d.wait(&format!("return Number(document.body.dataset.measureCount) > {count} && document.body.dataset.state === 'ready';"), 60);

    // Save, then the same measurement from the command line.
    let el = d.element("#save");
    d.s("POST", &format!("/element/{el}/click"), json!({}));
    d.wait(
        "return document.getElementById('saved').dataset.count === '1';",
        60,
    );
    let command = d.js("return document.getElementById('command').textContent;");
    let command = command.as_str().unwrap().to_string();
    let args: Vec<&str> = command.split_whitespace().collect();
    let roi = args[args
        .iter()
        .position(|a| *a == "--roi")
        .expect("--roi in the command")
        + 1];
    assert!(command.contains("--no-refine-roi"), "{command}");
    let ref_dir = tempfile::tempdir().unwrap();
    let st = Command::new(bin())
        .current_dir(root())
        .args([
            "measure",
            "testdata/a4_log_shot.jpg",
            "--target",
            "targets/a4_log.toml",
            "--roi",
            roi,
            "--no-refine-roi",
            "-o",
        ])
        .arg(ref_dir.path())
        .output()
        .unwrap();
    assert!(
        st.status.success(),
        "{}",
        String::from_utf8_lossy(&st.stderr)
    );
    let a = std::fs::read(out.path().join("a4_log_shot.mtf.csv")).unwrap();
    let b = std::fs::read(ref_dir.path().join("a4_log_shot.mtf.csv")).unwrap();
    assert!(
        a == b,
        "the saved CSV differs from `sweepmtf measure {roi}`"
    );

    // Model view: change the f-number and see the cut change.
    let tab = d.element("#tab-model");
    d.s("POST", &format!("/element/{tab}/click"), json!({}));
    d.wait("return Number(document.body.dataset.modelCount) >= 1;", 30);
    let m50 = |d: &Driver| {
        d.js("return document.getElementById('cut-plot').dataset.mtf50;")
            .as_str()
            .unwrap()
            .parse::<f64>()
            .unwrap()
    };
    let f4 = m50(&d);
    let n = d
        .js("return Number(document.body.dataset.modelCount);")
        .as_f64()
        .unwrap();
    d.js("const r = document.getElementById('p-optics-fnum'); r.value = 11; r.dispatchEvent(new Event('input'));");
    d.wait(&format!("return Number(document.body.dataset.modelCount) > {n} && !document.getElementById('status').classList.contains('error');"), 30);
    // Let a queued redraw finish.
    std::thread::sleep(Duration::from_millis(300));
    let f11 = m50(&d);
    assert!(f11 < f4 * 0.8, "MTF50 at f/11 ({f11}) not below f/4 ({f4})");
    let model_ms = d
        .js("return Number(document.body.dataset.modelMs);")
        .as_f64()
        .unwrap();
    d.screenshot("model.png");
    println!(
        "gui timings (README sample, 2000×1400): photo shown {shown_ms:.0} ms after navigation, first MTF {first_ms:.0} ms, \
         new MTF after release {release_ms:.0} ms (round trip), model cut + 512² map {model_ms:.0} ms; MTF50 {before:.4} → {after:.4} cy/px"
    );
}
