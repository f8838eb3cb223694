//! The page's batch view: a `sweepmtf batch` output folder's table and
//! pictures (`/api/batch`, `/api/batch/file`), against the folder's own files
//! as `batch` wrote them; only its pictures are served; and in a real browser
//! (when one is installed) the table shown and a row's plot opened.

use crate::gui_browser::{Driver, browser};
use crate::gui_support::{GuiProc, Reply, bin, root};
use serde_json::Value;
use std::path::Path;

fn ok(r: &Reply) -> Value {
    assert_eq!(r.status, 200, "{}", String::from_utf8_lossy(&r.body));
    r.json()
}

/// A batch run over the README sample, a copy of it and a file that is not a photo.
fn batch_folder(dir: &Path) -> std::path::PathBuf {
    let shots = dir.join("shots_in");
    std::fs::create_dir_all(&shots).unwrap();
    std::fs::copy(root().join("testdata/a4_log_shot.jpg"), shots.join("a.jpg")).unwrap();
    std::fs::copy(root().join("testdata/a4_log_shot.jpg"), shots.join("b.jpg")).unwrap();
    std::fs::write(shots.join("c.jpg"), b"not a photo").unwrap();
    let out = dir.join("out");
    let st = std::process::Command::new(bin())
        .arg("batch")
        .arg(&shots)
        .arg("-o")
        .arg(&out)
        .arg("--target")
        .arg(root().join("targets/a4_log.toml"))
        .arg("-q")
        .status()
        .unwrap();
    assert_eq!(st.code(), Some(7), "one shot fails: exit 7");
    out
}

#[test]
fn batch_folder_table_and_pictures_are_the_folders_own() {
    let dir = tempfile::tempdir().unwrap();
    let out = batch_folder(dir.path());
    let g = GuiProc::start(&root(), &["--batch", out.to_str().unwrap()]);
    let s = ok(&g.call("GET", "/api/state", b""));
    assert_eq!(s["batch_dir"].as_str(), out.to_str());
    let q = |p: &str| format!("/api/batch?dir={}{p}", out.display());
    let t = ok(&g.call("GET", &q(""), b""));
    // The table is summary.csv as batch wrote it.
    let csv = crate::csv_support::read_csv(&out.join("summary.csv"));
    let cols: Vec<&str> = t["columns"]
        .as_array()
        .unwrap()
        .iter()
        .map(|c| c.as_str().unwrap())
        .collect();
    let rows = t["rows"].as_array().unwrap();
    assert_eq!(rows.len(), csv.len());
    assert_eq!(rows.len(), 3);
    for (row, want) in rows.iter().zip(&csv) {
        for (k, c) in cols.iter().enumerate() {
            assert_eq!(row[k].as_str().unwrap(), want[*c], "column {c}");
        }
    }
    assert!(
        t["pictures"]
            .as_array()
            .unwrap()
            .iter()
            .any(|p| p == "curves.png")
    );
    // Pictures: byte for byte the folder's files.
    let file = |name: &str| {
        g.call(
            "GET",
            &format!("/api/batch/file?dir={}&name={name}", out.display()),
            b"",
        )
    };
    for name in ["curves.png", "shots/a.mtf.png", "shots/b.roi.png"] {
        let r = file(name);
        assert_eq!(r.status, 200, "{name}");
        assert_eq!(r.body, std::fs::read(out.join(name)).unwrap(), "{name}");
        assert_eq!(r.header("Content-Type"), Some("image/png"));
    }
    // Nothing else is served, whatever is asked.
    for name in [
        "summary.csv",
        "shots/a.mtf.csv",
        "shots/a.done.json",
        "shots/../../etc/passwd",
        "/etc/passwd",
        "shots/zz.mtf.png",
    ] {
        assert_eq!(file(name).status, 404, "{name}");
    }
    // Not a batch folder, not a folder, no folder.
    let r = g.call(
        "GET",
        &format!("/api/batch?dir={}", dir.path().join("shots_in").display()),
        b"",
    );
    assert_eq!((r.status, r.json()["code"].as_u64()), (422, Some(3)));
    assert!(
        r.json()["error"]
            .as_str()
            .unwrap()
            .contains("not a sweepmtf batch output folder")
    );
    let r = g.call("GET", "/api/batch?dir=/no/such/folder", b"");
    assert_eq!(r.status, 422);
    assert_eq!(g.call("GET", "/api/batch", b"").status, 400);
}

#[test]
fn browser_batch_view_shows_the_table_and_a_shots_plot() {
    let Some((chromium, driver)) = browser() else {
        return;
    };
    let dir = tempfile::tempdir().unwrap();
    let out = batch_folder(dir.path());
    let profile = tempfile::tempdir().unwrap();
    let g = GuiProc::start(&root(), &["--batch", out.to_str().unwrap()]);
    let d = Driver::start(&driver, &chromium, profile.path());
    d.s("POST", "/url", serde_json::json!({"url": g.url}));
    d.wait("return document.body.dataset.batchRows === '3';", 30);
    // Sort by MTF50 (the failed shot last), then open the first row's plot.
    let th = d.element("#batch-table th:nth-child(3)");
    d.s(
        "POST",
        &format!("/element/{th}/click"),
        serde_json::json!({}),
    );
    let first = d.js("return document.querySelector('#batch-table tbody tr').dataset.stem;");
    let last =
        d.js("return [...document.querySelectorAll('#batch-table tbody tr')].pop().dataset.stem;");
    assert_eq!(last.as_str(), Some("c"), "the failed shot sorts last");
    let row = d.element("#batch-table tbody tr");
    d.s(
        "POST",
        &format!("/element/{row}/click"),
        serde_json::json!({}),
    );
    d.wait(
        &format!("return document.body.dataset.shotShown === {first};"),
        30,
    );
    let shown = d.js("return document.getElementById('shot-mtf').naturalWidth;");
    assert!(shown.as_f64().unwrap() > 100.0, "the plot did not load");
    // (WebDriver scrolled the clicked cells into view; show the table from its start.)
    d.js("document.getElementById('batch-table-wrap').scrollLeft = 0;");
    d.screenshot("batch.png");
}
