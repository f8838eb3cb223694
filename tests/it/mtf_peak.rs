//! Issue 20, item 1: MTF50P/20P/10P and the peak on sharpened shots of the
//! reference renderer (`sweepmtf::measure::synth`, unsharp mask in linear
//! light). The truth is the renderer's analytic MTF, evaluated densely here
//! and its crossings found by bisection: MTFnn where it first falls to nn %,
//! MTFnnP where, above its peak, it first falls to nn % of the peak.

use assert_cmd::Command;
use sweepmtf::measure::figures::Figures;
use sweepmtf::measure::synth::{Nuisances, SynthShot, nuisance_cases};
use sweepmtf::measure::{MeasureOptions, measure_decoded};
use sweepmtf::photo::decode::decode_bytes;

/// The truth's figures (frequencies in cy/px).
struct TruthFigures {
    peak: f64,
    f_peak: f64,
    mtf50: Option<f64>,
    mtf50p: Option<f64>,
    mtf20p: Option<f64>,
    mtf10p: Option<f64>,
}

/// First frequency at or above `from` where `t` falls below `level`, by a 1e-4 cy/px scan up to 0.5 then bisection.
fn fall(t: &dyn Fn(f64) -> f64, from: f64, level: f64) -> Option<f64> {
    let step = 1e-4;
    let mut lo = from;
    while lo + step <= 0.5 {
        let hi = lo + step;
        if t(lo) >= level && t(hi) < level {
            let (mut a, mut b) = (lo, hi);
            for _ in 0..60 {
                let m = 0.5 * (a + b);
                if t(m) >= level {
                    a = m;
                } else {
                    b = m;
                }
            }
            return Some(0.5 * (a + b));
        }
        lo = hi;
    }
    None
}

fn truth_figures(shot: &SynthShot) -> TruthFigures {
    let t = |f: f64| shot.truth(f);
    // The peak on a 1e-5 grid from 0 (golden-section refinement is not needed at this step).
    let (mut peak, mut f_peak) = (t(0.0), 0.0);
    for i in 1..=50_000 {
        let f = i as f64 * 1e-5;
        if t(f) > peak {
            peak = t(f);
            f_peak = f;
        }
    }
    TruthFigures {
        peak,
        f_peak,
        mtf50: fall(&t, 0.0, 0.5),
        mtf50p: fall(&t, f_peak, 0.5 * peak),
        mtf20p: fall(&t, f_peak, 0.2 * peak),
        mtf10p: fall(&t, f_peak, 0.1 * peak),
    }
}

fn measure(shot: &SynthShot, seed: u64) -> Figures {
    let dec = decode_bytes(&shot.encode(seed), &shot.name).unwrap();
    let opts = MeasureOptions {
        roi: Some(shot.quad),
        refine_roi: true,
        ..MeasureOptions::default()
    };
    let m = measure_decoded(&dec, &shot.name, None, &opts)
        .unwrap_or_else(|e| panic!("{}: {e}", shot.name));
    m.curves[0].figures
}

fn rel(a: Option<f64>, b: Option<f64>) -> f64 {
    a.unwrap() / b.unwrap() - 1.0
}

/// The sharpened shots: issue 15's USM case (peak ≈ 1.15, SNR 50) in two
/// geometry variants, a noiseless one, and a stronger, narrower mask (amount
/// 1.6, radius 1 px: peak ≈ 1.14 further out, at 0.14 cy/px).
fn sharpened() -> Vec<(SynthShot, u64)> {
    let mut out = Vec::new();
    for v in [7u64, 12] {
        let s = nuisance_cases(v)
            .into_iter()
            .find(|s| s.name == "usm_peak1.15")
            .unwrap();
        out.push((
            SynthShot {
                name: format!("usm1.0r1.5_v{v}"),
                ..s.clone()
            },
            100 + v,
        ));
        if v == 7 {
            out.push((
                SynthShot {
                    name: "usm1.0r1.5_noiseless".into(),
                    noise: None,
                    ..s.clone()
                },
                1,
            ));
            out.push((
                SynthShot {
                    name: "usm1.6r1.0".into(),
                    sigma_px: 0.85,
                    nuisance: Nuisances {
                        usm: Some((1.6, 1.0)),
                        ..Nuisances::default()
                    },
                    ..s
                },
                5,
            ));
        }
    }
    out
}

#[test]
fn mtf50_and_mtf50p_on_sharpened_shots_within_half_a_percent_of_the_truth() {
    for (shot, seed) in sharpened() {
        let t = truth_figures(&shot);
        assert!(t.peak > 1.1, "{}: truth peak {}", shot.name, t.peak);
        let g = measure(&shot, seed);
        assert!(g.sharpening_peak, "{}: {g:?}", shot.name);
        let (e50, e50p) = (rel(g.mtf50_cy_px, t.mtf50), rel(g.mtf50p_cy_px, t.mtf50p));
        let e20p = rel(g.mtf20p_cy_px, t.mtf20p);
        let e10p = g.mtf10p_cy_px.zip(t.mtf10p).map(|(a, b)| a / b - 1.0);
        let pk = g.peak_mtf.unwrap() - t.peak;
        eprintln!(
            "{}: truth peak {:.4} at {:.4}, MTF50 {:.4}, MTF50P {:.4} | measured peak {:+.4} at {:.4}, \
             MTF50 {e50:+.4}, MTF50P {e50p:+.4}, MTF20P {e20p:+.4}, MTF10P {e10p:?}",
            shot.name,
            t.peak,
            t.f_peak,
            t.mtf50.unwrap(),
            t.mtf50p.unwrap(),
            pk,
            g.peak_cy_px.unwrap(),
        );
        assert!(e50.abs() <= 0.005, "{}: MTF50 off by {e50:+.4}", shot.name);
        assert!(
            e50p.abs() <= 0.005,
            "{}: MTF50P off by {e50p:+.4}",
            shot.name
        );
        assert!(
            e20p.abs() <= 0.01,
            "{}: MTF20P off by {e20p:+.4}",
            shot.name
        );
        assert!(pk.abs() <= 0.01, "{}: peak off by {pk:+.4}", shot.name);
        assert_eq!(e10p.is_some(), t.mtf10p.is_some(), "{}", shot.name);
        assert!(
            e10p.unwrap_or(0.0).abs() <= 0.01,
            "{}: MTF10P {e10p:?}",
            shot.name
        );
        // MTF50P lies below MTF50 with a peak above 1.
        assert!(g.mtf50p_cy_px < g.mtf50_cy_px);
    }
}

/// Without sharpening the truth's peak is its value at 0 (1): MTF50P is MTF50, in the truth and measured.
#[test]
fn unsharpened_shot_gives_mtf50p_equal_to_mtf50() {
    let s = nuisance_cases(7)
        .into_iter()
        .find(|s| s.name == "usm_peak1.15")
        .map(|s| SynthShot {
            name: "plain".into(),
            nuisance: Nuisances::default(),
            ..s
        })
        .unwrap();
    let t = truth_figures(&s);
    assert_eq!((t.peak, t.f_peak), (1.0, 0.0));
    assert_eq!(t.mtf50, t.mtf50p);
    let g = measure(&s, 9);
    assert!(!g.sharpening_peak, "{g:?}");
    assert_eq!((g.peak_mtf, g.peak_cy_px), (Some(1.0), Some(0.0)));
    assert_eq!(g.mtf50p_cy_px, g.mtf50_cy_px);
    assert_eq!(g.mtf20p_cy_px, g.mtf20_cy_px);
    assert_eq!(g.mtf10p_cy_px, g.mtf10_cy_px);
    let e = rel(g.mtf50p_cy_px, t.mtf50p);
    assert!(e.abs() <= 0.005, "MTF50P off by {e:+.4}");
}

/// The CLI's JSON summary and summary line carry the new figures;
/// a figure the curve never reaches is JSON null, not a number.
#[test]
fn cli_summary_names_mtf50p_and_the_peak() {
    let (shot, seed) = sharpened().remove(2);
    let dir = tempfile::tempdir().unwrap();
    let photo = dir.path().join("usm.png");
    std::fs::write(&photo, shot.encode(seed)).unwrap();
    let roi = shot
        .quad
        .iter()
        .flatten()
        .map(|v| v.to_string())
        .collect::<Vec<_>>()
        .join(",");
    let out = Command::cargo_bin("sweepmtf")
        .unwrap()
        .arg("measure")
        .arg(&photo)
        .args(["--roi", &roi, "-o"])
        .arg(dir.path())
        .assert()
        .success();
    let line = String::from_utf8_lossy(&out.get_output().stdout).into_owned();
    assert!(
        line.contains("MTF50P ") && line.contains("peak 1."),
        "{line}"
    );
    let v: serde_json::Value =
        serde_json::from_slice(&std::fs::read(dir.path().join("usm.summary.json")).unwrap())
            .unwrap();
    let c = &v["curves"][0];
    let t = truth_figures(&shot);
    let f50p = c["mtf50p"]["cy_px"].as_f64().unwrap();
    assert!((f50p / t.mtf50p.unwrap() - 1.0).abs() <= 0.005, "{f50p}");
    assert_eq!(c["peak"]["sharpening"], serde_json::Value::Bool(true));
    assert!((c["peak"]["mtf"].as_f64().unwrap() - t.peak).abs() < 0.01);
    for k in ["mtf50", "mtf20", "mtf10", "mtf20p", "mtf10p"] {
        assert!(c.get(k).is_some(), "{k} missing");
    }
    // MTF10P: null exactly when the truth does not fall to 10 % of its peak inside the measured band.
    assert!(c["mtf10p"].is_null() || c["mtf10p"]["cy_px"].as_f64().unwrap() > f50p);
    assert!(dir.path().join("usm.mtf.png").exists());
}
