//! The model at sine patches on the MTF plot (`measure --model` on a
//! patch-only target): every patch with a finite model value gets a ring at
//! (its frequency, its CSV `mtf_model`), grey when aliased, placed through the
//! axis mapping read off the measured dots; the summary line's median
//! measured/model equals the median worked out from the CSV; a model whose
//! cutoff lies inside the patch range draws no NaN and leaves exactly the
//! patches out that the closed-form diffraction MTF puts below 0.05.

use assert_cmd::Command;
use std::path::{Path, PathBuf};

use crate::patch_shot;
use patch_shot::{SYSTEM, TARGET, shot};

fn cmd() -> Command {
    Command::cargo_bin("sweepmtf").unwrap()
}

/// Runs `measure` with `model` and `--plot svg`; returns stdout.
fn measure(photo: &Path, roi: &str, model: &str, plot: &str, out: &Path) -> String {
    let a = cmd()
        .arg("measure")
        .arg(photo)
        .args(["--target", TARGET, "--roi", roi, "--no-refine-roi"])
        .args([
            "--pixel-pitch",
            "4.3um",
            "--model",
            model,
            "--plot",
            plot,
            "-o",
        ])
        .arg(out)
        .assert()
        .success();
    String::from_utf8_lossy(&a.get_output().stdout).into_owned()
}

/// One CSV row per patch: (freq_cy_px, mtf, mtf_model, aliased).
fn rows(csv_path: &Path) -> Vec<(f64, f64, f64, bool)> {
    let mut r = csv::Reader::from_path(csv_path).unwrap();
    let head = r.headers().unwrap().clone();
    let col = |n: &str| head.iter().position(|h| h == n).unwrap();
    let (f, m, mm, al) = (
        col("freq_cy_px"),
        col("mtf"),
        col("mtf_model"),
        col("aliased"),
    );
    let all: Vec<(f64, f64, f64, bool)> = r
        .records()
        .map(|rec| {
            let rec = rec.unwrap();
            (
                rec[f].parse().unwrap(),
                rec[m].parse().unwrap(),
                rec[mm].parse().unwrap(),
                &rec[al] == "true",
            )
        })
        .collect();
    all
}

/// The rows the plot shows: its axis ends at 1 cy/px when patches lie beyond (checked here).
fn shown(rows: &[(f64, f64, f64, bool)]) -> Vec<(f64, f64, f64, bool)> {
    assert!(
        rows.iter().any(|r| r.0 > 1.0),
        "a patch lies beyond the axis"
    );
    rows.iter().copied().filter(|r| r.0 <= 1.0).collect()
}

/// An SVG circle: centre, radius, fill, stroke.
struct Circle {
    cx: f64,
    cy: f64,
    r: f64,
    fill: String,
    stroke: String,
}

fn circles(svg: &str) -> Vec<Circle> {
    let attr = |el: &str, name: &str| -> String {
        let key = format!(" {name}=\"");
        let i = el.find(&key).unwrap() + key.len();
        el[i..].split('"').next().unwrap().to_string()
    };
    svg.split("<circle")
        .skip(1)
        .map(|el| {
            let el = &el[..el.find("/>").unwrap()];
            Circle {
                cx: attr(el, "cx").parse().unwrap(),
                cy: attr(el, "cy").parse().unwrap(),
                r: attr(el, "r").parse().unwrap(),
                fill: attr(el, "fill"),
                stroke: attr(el, "stroke"),
            }
        })
        .collect()
}

/// Least-squares line px = a + b·v.
fn fit(pairs: &[(f64, f64)]) -> (f64, f64) {
    let n = pairs.len() as f64;
    let (sv, sp) = pairs
        .iter()
        .fold((0.0, 0.0), |(a, b), &(v, p)| (a + v, b + p));
    let (mv, mp) = (sv / n, sp / n);
    let (cov, var) = pairs.iter().fold((0.0, 0.0), |(c, w), &(v, p)| {
        (c + (v - mv) * (p - mp), w + (v - mv) * (v - mv))
    });
    let b = cov / var;
    (mp - b * mv, b)
}

/// Median of measured/model over the non-aliased patches with model ≥ 0.05, from the CSV.
fn median_ratio(rows: &[(f64, f64, f64, bool)]) -> (f64, usize) {
    let mut r: Vec<f64> = rows
        .iter()
        .filter(|r| !r.3 && r.2 >= 0.05)
        .map(|r| r.1 / r.2)
        .collect();
    r.sort_by(f64::total_cmp);
    let k = r.len();
    let med = if k % 2 == 1 {
        r[k / 2]
    } else {
        0.5 * (r[k / 2 - 1] + r[k / 2])
    };
    (med, k)
}

/// The number after `key` in `line`.
fn number_after(line: &str, key: &str) -> f64 {
    let i = line.find(key).unwrap_or_else(|| panic!("{key} in {line}")) + key.len();
    line[i..]
        .split(|c: char| !(c.is_ascii_digit() || c == '.'))
        .next()
        .unwrap()
        .parse()
        .unwrap()
}

/// Checks every ring against its patch's (freq, mtf_model) through the axis
/// mapping of the measured dots; returns the ring y of MTF 0.
fn check_rings(svg: &str, rows: &[(f64, f64, f64, bool)]) -> f64 {
    let rows = &shown(rows)[..];
    let cs = circles(svg);
    // Patch dots (r 4, filled orange or aliased grey) come first, in CSV order.
    let dots: Vec<&Circle> = cs
        .iter()
        .filter(|c| c.r == 4.0 && c.stroke == "none")
        .take(rows.len())
        .collect();
    assert_eq!(dots.len(), rows.len());
    for (d, r) in dots.iter().zip(rows) {
        let want = if r.3 { "#A0A0A0" } else { "#E67814" };
        assert_eq!(d.fill, want, "dot at {}", r.0);
    }
    let (ax, bx) = fit(&dots
        .iter()
        .zip(rows)
        .map(|(d, r)| (r.0, d.cx))
        .collect::<Vec<_>>());
    let (ay, by) = fit(&dots
        .iter()
        .zip(rows)
        .map(|(d, r)| (r.1, d.cy))
        .collect::<Vec<_>>());
    assert!(bx > 0.0 && by < 0.0, "{bx} {by}");
    // Rings (hollow), one per patch plus the legend's, which comes last.
    let rings: Vec<&Circle> = cs.iter().filter(|c| c.fill == "none").collect();
    assert_eq!(rings.len(), rows.len() + 1, "one ring per patch + legend");
    for (g, r) in rings.iter().zip(rows) {
        let (x, y) = (ax + bx * r.0, ay + by * r.2);
        assert!(
            (g.cx - x).abs() <= 1.5 && (g.cy - y).abs() <= 1.5,
            "ring ({}, {}) vs model ({x:.1}, {y:.1}) at {} cy/px",
            g.cx,
            g.cy,
            r.0
        );
        let want = if r.3 { "#A0A0A0" } else { "#000000" };
        assert_eq!(g.stroke, want, "ring at {}", r.0);
    }
    assert!(svg.contains("model at patches"));
    assert!(!svg.contains("NaN") && !svg.contains("inf"));
    ay
}

#[test]
fn patch_only_plot_rings_sit_at_the_model_and_the_summary_gives_the_median() {
    let dir = tempfile::tempdir().unwrap();
    let (photo, roi) = shot(dir.path());
    let out = dir.path().join("out");

    // PNG: produced, the plot's size.
    measure(&photo, &roi, SYSTEM, "png", &out);
    let png = std::fs::File::open(out.join("shot.mtf.png")).unwrap();
    let info = png::Decoder::new(std::io::BufReader::new(png))
        .read_info()
        .unwrap();
    assert_eq!((info.info().width, info.info().height), (1000, 620));

    // SVG: rings checked against the CSV.
    let line = measure(&photo, &roi, SYSTEM, "svg", &out);
    let rows = rows(&out.join("shot.mtf.csv"));
    assert!(rows.len() >= 20, "{}", rows.len());
    assert!(rows.iter().any(|r| r.3), "some patches are aliased");
    let svg = std::fs::read_to_string(out.join("shot.mtf.svg")).unwrap();
    check_rings(&svg, &rows);
    assert!(svg.contains("model: APS-C"), "the model curve's legend");

    // The summary: median and counts from the CSV's own columns.
    let (med, n) = median_ratio(&rows);
    let got = number_after(&line, "patches measured/model median ");
    assert!((got - med).abs() <= 1.5e-3, "{got} vs {med}: {line}");
    assert_eq!(
        number_after(&line, &format!("median {got:.3} over ")),
        n as f64
    );
    assert!(
        line.contains(&format!("({} left out)", rows.len() - n)),
        "{line}"
    );
    assert!(line.contains("furthest "), "{line}");
    assert_eq!(line.trim().lines().count(), 1, "{line}");
}

/// Diffraction alone at f/26 (cutoff 1/(λN) = 69.9 cy/mm = 0.301 cy/px at
/// 4.3 µm): one patch has model 0.004, the ones above have model 0. No NaN is drawn, rings at model 0 sit on
/// the MTF-0 line, and the patches left out are the aliased ones plus those
/// where (2/π)(acos s − s√(1−s²)), s = (f/p)·λ·N, is below 0.05.
#[test]
fn model_beyond_cutoff_draws_rings_at_zero_and_leaves_those_patches_out() {
    let dir = tempfile::tempdir().unwrap();
    let (photo, roi) = shot(dir.path());
    let sys = dir.path().join("f26.toml");
    std::fs::write(
        &sys,
        "name = \"diffraction f/26\"\n[[factor]]\nkind = \"optics\"\n\
         spec = \"diffraction:lambda=550nm,fnum=26\"\n",
    )
    .unwrap();
    let out = dir.path().join("out");
    let line = measure(&photo, &roi, sys.to_str().unwrap(), "svg", &out);
    let rows = rows(&out.join("shot.mtf.csv"));
    let diff = |f: f64| {
        let s = f / 0.0043 * 550e-6 * 26.0;
        if s >= 1.0 {
            0.0
        } else {
            2.0 / std::f64::consts::PI * (s.acos() - s * (1.0 - s * s).sqrt())
        }
    };
    let zeros = rows.iter().filter(|r| diff(r.0) == 0.0).count();
    assert!(zeros >= 5, "{zeros} patches beyond the cutoff");
    let left_out = rows.iter().filter(|r| r.3 || diff(r.0) < 0.05).count();
    // No closed-form value sits near the floor, so the count does not hinge on rounding.
    assert!(rows.iter().all(|r| (diff(r.0) - 0.05).abs() > 0.01));
    let svg = std::fs::read_to_string(out.join("shot.mtf.svg")).unwrap();
    let y0 = check_rings(&svg, &rows);
    let rings: Vec<Circle> = circles(&svg)
        .into_iter()
        .filter(|c| c.fill == "none")
        .collect();
    for (g, r) in rings.iter().zip(&shown(&rows)) {
        if diff(r.0) == 0.0 {
            assert!(
                (g.cy - y0).abs() <= 1.5,
                "ring at {} cy/px: {} vs {y0}",
                r.0,
                g.cy
            );
        }
    }
    let s: serde_json::Value =
        serde_json::from_slice(&std::fs::read(out.join("shot.summary.json")).unwrap()).unwrap();
    let c = &s["model"]["patches_measured_over_model"];
    assert_eq!(c["patches_left_out"].as_u64(), Some(left_out as u64), "{c}");
    assert_eq!(
        c["patches_used"].as_u64(),
        Some((rows.len() - left_out) as u64),
        "{c}"
    );
    assert!(c["median"].as_f64().unwrap().is_finite());
    assert!(line.contains(&format!("({left_out} left out)")), "{line}");
}

/// The real sineMTF scan's folder: `../shared` beside the checkout or two levels up (a worktree).
fn scan_dir() -> PathBuf {
    Path::new(concat!(env!("CARGO_MANIFEST_DIR"), "/testdata/real")).join("sine_target_scan")
}

/// The real sineMTF scan (patch-only, 50.7 µm at ≈501 ppi) with a scanner
/// model (50.7 µm square pixel × Gaussian σ 20 µm): the plot's rings sit at the
/// CSV's model values, which match the closed form sinc(p·u)·exp(−2π²σ²u²)
/// (u = f/p; the scan's skew is under 1°, so the v-factor differs from 1 by
/// < 1e-4); patches 14 and 15 (above the 9.9 cy/mm Nyquist) are the 2 left out.
#[test]
fn real_scan_with_a_scanner_model() {
    let photo = scan_dir().join("mitre_sinemtf_test.tif");
    let dir = tempfile::tempdir().unwrap();
    let sys = dir.path().join("scanner.toml");
    std::fs::write(
        &sys,
        "name = \"scanner\"\n[[factor]]\nkind = \"aperture\"\nspec = \"rect:A=50.7um,B=50.7um\"\n\
         [[factor]]\nkind = \"gaussian\"\nspec = \"sigma=20um\"\n",
    )
    .unwrap();
    let out = dir.path().join("out");
    let a = cmd()
        .arg("measure")
        .arg(&photo)
        .arg("--target")
        .arg(scan_dir().join("mitre_sinemtf_tgt.txt"))
        .args([
            "--tone",
            "chart",
            "--pixel-pitch",
            "50.7um",
            "--plot",
            "svg",
        ])
        .args([
            "--roi",
            "1412.75,957.16,32.33,961.36,34.26,24.87,1414.68,20.68",
            "--model",
        ])
        .arg(&sys)
        .arg("-o")
        .arg(&out)
        .assert()
        .success();
    let line = String::from_utf8_lossy(&a.get_output().stdout).into_owned();
    let rows = rows(&out.join("mitre_sinemtf_test.mtf.csv"));
    assert_eq!(rows.len(), 15);
    let pi = std::f64::consts::PI;
    let (p, sigma) = (0.0507, 0.020);
    for r in &rows {
        let u = r.0 / p;
        let x = pi * p * u;
        let want = (x.sin() / x).abs() * (-2.0 * pi * pi * sigma * sigma * u * u).exp();
        assert!(
            (r.2 - want).abs() < 2e-4,
            "{} cy/px: {} vs {want}",
            r.0,
            r.2
        );
    }
    assert_eq!(
        rows.iter().map(|r| r.3).collect::<Vec<_>>(),
        [vec![false; 13], vec![true; 2]].concat()
    );
    // All 15 patches lie inside the axis here, so every patch has its ring.
    let svg = std::fs::read_to_string(out.join("mitre_sinemtf_test.mtf.svg")).unwrap();
    let cs = circles(&svg);
    let rings: Vec<&Circle> = cs.iter().filter(|c| c.fill == "none").collect();
    assert_eq!(rings.len(), 16, "15 patches + legend");
    assert_eq!(
        rings.iter().filter(|c| c.stroke == "#A0A0A0").count(),
        2,
        "the two aliased patches"
    );
    let (med, n) = median_ratio(&rows);
    assert_eq!(n, 13);
    let got = number_after(&line, "patches measured/model median ");
    assert!((got - med).abs() <= 1.5e-3, "{got} vs {med}: {line}");
    assert!(line.contains("(2 left out)"), "{line}");
}

/// A target with a sweep (sines along x) and sine patches along x and along y.
fn mixed_target() -> String {
    let mut s = String::from(
        "name = \"sweep and patches\"\nwidth_mm = 240.0\nheight_mm = 160.0\nbackground = 1.0\n\
         greys = []\nfiducials = []\n\n[[sweeps]]\nid = \"main\"\nx_mm = 10.0\ny_mm = 15.0\n\
         width_mm = 220.0\nheight_mm = 30.0\ndirection = \"x\"\nlaw = \"log\"\n\
         f_min_cy_mm = 0.1\nf_max_cy_mm = 2.5\nmean = 0.5\ncontrast = 0.8\n\n",
    );
    for (y, d) in [(60.0, "x"), (105.0, "y")] {
        for (i, f) in [0.3, 0.6, 1.0, 1.6].iter().enumerate() {
            s.push_str(&format!(
                "[[patches]]\nid = \"{d}{i}\"\nx_mm = {}\ny_mm = {y}\nwidth_mm = 50.0\n\
                 height_mm = 35.0\ndirection = \"{d}\"\nfreq_cy_mm = {f}\nmean = 0.5\n\
                 contrast = 0.8\n\n",
                10.0 + 56.0 * i as f64
            ));
        }
    }
    s
}

/// Sweep and patches on one plot, turned 10°: the sweep's dashed model curve
/// stays; the y patches get a second curve only when the model differs along
/// their sines (the L-shaped phone pixel is anisotropic; a square pixel behind
/// diffraction is the same along 10° and 100°); every patch has its ring, and
/// the line gives both the MTF50 ratio and the patch median.
#[test]
fn sweep_and_patches_on_one_plot() {
    let dir = tempfile::tempdir().unwrap();
    let target = dir.path().join("mixed.toml");
    std::fs::write(&target, mixed_target()).unwrap();
    for (sys, pitch, second_curve) in [
        ("phone_cmos_f2", "1.4um", true),
        ("aps_c_f4", "4.3um", false),
    ] {
        let system = format!("{}/targets/systems/{sys}.toml", env!("CARGO_MANIFEST_DIR"));
        let photo = dir.path().join(format!("{sys}.png"));
        cmd()
            .args(["simulate", "--target"])
            .arg(&target)
            .args([
                "--system", &system, "--size", "1200x800", "--rotate", "10", "-o",
            ])
            .arg(&photo)
            .assert()
            .success();
        let meta: serde_json::Value =
            serde_json::from_slice(&std::fs::read(dir.path().join(format!("{sys}.json"))).unwrap())
                .unwrap();
        let roi: Vec<String> = meta["target_corners"]
            .as_array()
            .unwrap()
            .iter()
            .map(|v| format!("{}", v.as_f64().unwrap()))
            .collect();
        let out = dir.path().join(format!("out_{sys}"));
        let a = cmd()
            .arg("measure")
            .arg(&photo)
            .arg("--target")
            .arg(&target)
            .args([
                "--roi",
                &roi.join(","),
                "--no-refine-roi",
                "--pixel-pitch",
                pitch,
            ])
            .args(["--model", &system, "--plot", "svg", "-o"])
            .arg(&out)
            .assert()
            .success();
        let line = String::from_utf8_lossy(&a.get_output().stdout).into_owned();
        assert!(line.contains(", measured/model "), "{line}");
        assert!(line.contains("patches measured/model median "), "{line}");
        let svg = std::fs::read_to_string(out.join(format!("{sys}.mtf.svg"))).unwrap();
        let rings = circles(&svg)
            .into_iter()
            .filter(|c| c.fill == "none")
            .count();
        assert_eq!(rings, 8 + 1, "{sys}: 8 patches + legend");
        assert!(svg.contains("model: "), "{sys}");
        assert_eq!(
            svg.contains("model along patches at 100°"),
            second_curve,
            "{sys}"
        );
        assert!(!svg.contains("NaN"), "{sys}");
    }
}
