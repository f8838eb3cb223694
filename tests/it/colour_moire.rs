//! Issue 20, item 5: colour moiré, the R−B spread |MTF_R − MTF_B| along the
//! sweep, on shots from the camera simulator.
//!
//! Truth from the mosaic's physics, not from the measurement: without a
//! mosaic (a neutral RGB shot) the three channels are one image up to their
//! independent noise, so the spread is noise and nothing rises. On a Bayer
//! mosaic demosaicked bilinearly, red and blue are each sampled every second
//! pixel, one pixel apart: each passes the sweep's cosine at f with the same
//! gain cos²(πf) (no spread from that part) and adds its alias at ½ − f with
//! gain ±sin²(πf), opposite in sign for red and blue (the `simulate::demosaic`
//! unit test checks these closed forms on the simulator's own output). The
//! modulation estimator at f (a sine fit over a window of W = 4 cycles,
//! i.e. 4/f px) resolves frequencies about f/W apart, so the alias reaches
//! red's and blue's measured modulations — with opposite signs, hence the
//! spread — only once |f − (½ − f)| < f/W, i.e. f > ½/(2 + 1/W) = 0.222
//! cy/px, and fully at f = ¼ where alias and signal coincide (there the
//! spread swings between 0 and T(¼) with the sweep's phase against the
//! mosaic). So the onset must lie between ≈ 0.22 and 0.25 cy/px (asserted:
//! 0.2–0.3), and below 0.2 cy/px the spread stays near the noise.

use assert_cmd::Command;
use sweepmtf::measure::moire::{ColourMoire, ONSET_SPREAD};
use sweepmtf::measure::{MeasureOptions, Measurement, measure_decoded};
use sweepmtf::photo::decode::decode_bytes;
use sweepmtf::photo::linearise::Channel;
use sweepmtf::simulate::demo::demo_target_for;
use sweepmtf::simulate::{BayerOrder, Camera, Demosaic, Shot, encode::PhotoFormat, render};
use sweepmtf::target::SweepLaw;

use crate::system_support::aps_c_f4 as system;

/// 1000×600 frame, chart 840 px wide, shot noise (full well 20000 e⁻, read noise 4 e⁻).
fn camera() -> Camera {
    Camera {
        width_px: 1000,
        height_px: 600,
        chart_px: Some(840.0),
        full_well_e: Some(20000.0),
        read_noise_e: 4.0,
        seed: 5,
        ..Camera::default()
    }
}

fn neutral(c: Camera) -> Camera {
    Camera {
        light_colour: Some([1.0, 1.0, 1.0]),
        ..c
    }
}

fn mosaic(c: Camera) -> Camera {
    Camera {
        bayer: Some(BayerOrder::Rggb),
        demosaic: Some(Demosaic::Bilinear),
        ..c
    }
}

fn shoot(cam: &Camera, f_max: f64) -> (Shot, Vec<u8>) {
    let t = demo_target_for(cam, SweepLaw::Log, 0.01, f_max).unwrap();
    let shot = render(&t, &system(), cam).unwrap();
    let bytes = shot.encode(PhotoFormat::Png).unwrap();
    (shot, bytes)
}

fn measure(shot: &Shot, bytes: &[u8], channel: Channel) -> Measurement {
    let r = shot.roi().unwrap();
    let dec = decode_bytes(bytes, "moire").unwrap();
    let opts = MeasureOptions {
        roi: Some([[r[0], r[1]], [r[2], r[3]], [r[4], r[5]], [r[6], r[7]]]),
        channel,
        ..MeasureOptions::default()
    };
    measure_decoded(&dec, "moire", None, &opts).unwrap()
}

/// (largest spread, its σ, its frequency) over the points below `f` cy/px.
fn max_below(cm: &ColourMoire, f: f64) -> (f64, f64, f64) {
    cm.points
        .iter()
        .filter(|p| p.freq_cy_px < f)
        .map(|p| (p.spread, p.spread_err, p.freq_cy_px))
        .fold((0.0, 0.0, 0.0), |a, b| if b.0 > a.0 { b } else { a })
}

/// `--channel all` measures luma, r, g, b together.
fn channels(m: &Measurement) -> Vec<&str> {
    m.curves.iter().map(|c| c.channel.as_str()).collect()
}

#[test]
fn neutral_rgb_without_mosaic_has_no_spread_beyond_noise_and_no_onset() {
    // Noiseless: the three channels are the same image, so the spread is 0.
    let cam = Camera {
        full_well_e: None,
        read_noise_e: 0.0,
        ..neutral(camera())
    };
    let (shot, bytes) = shoot(&cam, 0.45);
    let m = measure(&shot, &bytes, Channel::All);
    assert_eq!(channels(&m), ["luma", "r", "g", "b"]);
    let cm = &m.colour_moire[0];
    eprintln!(
        "neutral noiseless: max {:?} at {:?}, onset {:?}, {} points",
        cm.max_spread,
        cm.max_at_cy_px,
        cm.onset_cy_px,
        cm.points.len()
    );
    assert!(cm.points.len() > 50);
    assert!(cm.max_spread.unwrap() < 1e-9, "{:?}", cm.max_spread);
    assert_eq!(cm.onset_cy_px, None);

    // With independent noise in each channel: the spread is noise, bounded
    // by 4.5 times its own σ everywhere, and nothing rises.
    let (shot, bytes) = shoot(&neutral(camera()), 0.45);
    let m = measure(&shot, &bytes, Channel::All);
    let cm = &m.colour_moire[0];
    let worst = cm
        .points
        .iter()
        .map(|p| p.spread / p.spread_err)
        .fold(0.0, f64::max);
    let (mx, sx, fx) = max_below(cm, 0.45);
    eprintln!(
        "neutral noisy: max {mx:.4} ± {sx:.4} at {fx:.3} cy/px, worst spread/σ {worst:.2}, smoothed max {:?}, onset {:?}",
        cm.max_spread, cm.onset_cy_px
    );
    assert_eq!(cm.onset_cy_px, None);
    assert!(worst < 4.5, "spread/σ {worst:.2}");
    assert!(cm.max_spread.unwrap() < ONSET_SPREAD, "{:?}", cm.max_spread);
}

#[test]
fn bilinear_demosaicked_mosaic_shows_moire_from_a_quarter_cycle_per_pixel() {
    let (shot, bytes) = shoot(&mosaic(camera()), 0.45);
    let m = measure(&shot, &bytes, Channel::All);
    assert_eq!(channels(&m), ["luma", "r", "g", "b"]);
    let cm = &m.colour_moire[0];
    let (lo, lo_err, lo_at) = max_below(cm, 0.2);
    let (lo18, _, lo18_at) = max_below(cm, 0.18);
    let onset = cm.onset_cy_px;
    eprintln!(
        "bilinear RGGB: max {:?} ± {:?} at {:?} cy/px, onset {onset:?}; below 0.2 cy/px max {lo:.4} ± {lo_err:.4} at {lo_at:.3}, below 0.18 max {lo18:.4} at {lo18_at:.3}",
        cm.max_spread, cm.max_spread_err, cm.max_at_cy_px
    );
    if std::env::var("MOIRE_DUMP").is_ok() {
        for p in &cm.points {
            eprintln!("{:.4} {:.4} {:.4}", p.freq_cy_px, p.spread, p.spread_err);
        }
    }
    let onset = onset.expect("an onset");
    assert!((0.2..=0.3).contains(&onset), "onset {onset}");
    // Below 0.18 cy/px the alias is ≥ 3 of the estimator's resolution widths
    // (f/W) away from the signal: no spread; up to 0.2 the window's leakage
    // begins but stays under the onset threshold.
    assert!(lo18 < 0.01, "below 0.18 cy/px the spread reaches {lo18:.4}");
    assert!(
        lo < ONSET_SPREAD,
        "below 0.2 cy/px the spread reaches {lo:.4}"
    );
    assert!(cm.max_spread.unwrap() > 0.15, "{:?}", cm.max_spread);
    let at = cm.max_at_cy_px.unwrap();
    assert!((0.2..=0.32).contains(&at), "max at {at}");
}

#[test]
fn a_sweep_that_stops_below_a_quarter_cycle_per_pixel_has_no_onset() {
    let (shot, bytes) = shoot(&mosaic(camera()), 0.2);
    let m = measure(&shot, &bytes, Channel::All);
    let cm = &m.colour_moire[0];
    eprintln!(
        "sweep to 0.2 cy/px: measured to {:?}, max {:?}, onset {:?}",
        cm.measured_to_cy_px, cm.max_spread, cm.onset_cy_px
    );
    assert!(cm.measured_to_cy_px.unwrap() < 0.25);
    assert_eq!(cm.onset_cy_px, None);
}

#[test]
fn a_grey_photo_with_channel_all_gives_a_note_and_no_block() {
    let cam = Camera {
        full_well_e: None,
        read_noise_e: 0.0,
        ..camera()
    };
    let (shot, bytes) = shoot(&cam, 0.45);
    let m = measure(&shot, &bytes, Channel::All);
    assert_eq!(channels(&m), ["grey"]);
    assert!(m.colour_moire.is_empty());
    assert!(
        m.notes
            .iter()
            .any(|n| n.contains("colour moiré not measured")),
        "{:?}",
        m.notes
    );
    let v = sweepmtf::report::json::summary(&m, None);
    assert!(v.get("colour_moire").is_none());
    // One channel asked for: no block, no note.
    let m = measure(&shot, &bytes, Channel::Luma);
    assert!(m.colour_moire.is_empty() && !m.notes.iter().any(|n| n.contains("moiré")));
}

/// The CLI end to end: `simulate --bayer RGGB --demosaic bilinear` writes an
/// RGB photo; `measure --channel all` writes the JSON block, the CSV column
/// on the red rows and the summary phrase. Bad combinations exit 2.
#[test]
fn cli_simulate_demosaic_and_measure_channel_all() {
    let dir = tempfile::tempdir().unwrap();
    let photo = dir.path().join("shot.png");
    Command::cargo_bin("sweepmtf")
        .unwrap()
        // The demo sweep (to 2.8 cy/mm) on a 1500 px chart ends near 0.45 cy/px.
        .args(["simulate", "--target", "demo:log", "--size", "1600x1100"])
        .args([
            "--chart-px",
            "1500",
            "--full-well",
            "20000",
            "--read-noise",
            "4",
        ])
        .args(["--bayer", "RGGB", "--demosaic", "bilinear", "-o"])
        .arg(&photo)
        .assert()
        .success();
    let settings: serde_json::Value =
        serde_json::from_slice(&std::fs::read(dir.path().join("shot.json")).unwrap()).unwrap();
    assert_eq!(settings["demosaic"], "bilinear");
    assert_eq!(settings["bits"], 8);
    let img = image::open(&photo).unwrap();
    assert_eq!(img.color(), image::ColorType::Rgb8);
    let roi = settings["roi"]
        .as_array()
        .unwrap()
        .iter()
        .map(|v| v.to_string())
        .collect::<Vec<_>>()
        .join(",");
    let out = dir.path().join("out");
    let run = Command::cargo_bin("sweepmtf")
        .unwrap()
        .arg("measure")
        .arg(&photo)
        .args(["--roi", &roi, "--channel", "all", "-o"])
        .arg(&out)
        .assert()
        .success();
    let line = String::from_utf8(run.get_output().stdout.clone()).unwrap();
    assert!(line.contains("colour moiré: R−B spread max"), "{line}");
    let v: serde_json::Value =
        serde_json::from_slice(&std::fs::read(out.join("shot.summary.json")).unwrap()).unwrap();
    let cm = &v["colour_moire"];
    assert!(
        cm["definition"]
            .as_str()
            .unwrap()
            .contains("|MTF_R - MTF_B|")
    );
    assert!(cm["max_spread"].as_f64().unwrap() > 0.0);
    assert!(cm["onset_cy_px"].is_number() || cm["onset_cy_px"].is_null());
    let csv = std::fs::read_to_string(out.join("shot.mtf.csv")).unwrap();
    let head: Vec<&str> = csv.lines().next().unwrap().split(',').collect();
    let col = head.iter().position(|h| *h == "rb_spread").unwrap();
    let ch = head.iter().position(|h| *h == "channel").unwrap();
    let (mut red_filled, mut other_filled) = (0, 0);
    for l in csv.lines().skip(1) {
        let cells: Vec<&str> = l.split(',').collect();
        match (cells[ch], cells[col].is_empty()) {
            ("r", false) => red_filled += 1,
            ("r", true) => {}
            (_, false) => other_filled += 1,
            _ => {}
        }
    }
    assert!(
        red_filled > 50 && other_filled == 0,
        "{red_filled} {other_filled}"
    );
    assert!(out.join("shot.mtf.png").exists());

    // --demosaic without --bayer, and a demosaicked DNG: usage errors, nothing written.
    for (args, what) in [
        (vec!["--demosaic", "bilinear"], "needs a mosaic"),
        (vec!["--bayer", "RGGB", "--demosaic", "ahd"], "not one of"),
    ] {
        let a = Command::cargo_bin("sweepmtf")
            .unwrap()
            .args(["simulate", "--target", "demo:log", "--size", "300x200"])
            .args(&args)
            .arg("-o")
            .arg(dir.path().join("bad.png"))
            .assert()
            .code(2);
        let err = String::from_utf8_lossy(&a.get_output().stderr).into_owned();
        assert!(err.contains(what), "{err}");
    }
    let a = Command::cargo_bin("sweepmtf")
        .unwrap()
        .args(["simulate", "--target", "demo:log", "--size", "300x200"])
        .args(["--bayer", "RGGB", "--demosaic", "bilinear", "-o"])
        .arg(dir.path().join("bad.dng"))
        .assert()
        .code(2);
    let err = String::from_utf8_lossy(&a.get_output().stderr).into_owned();
    assert!(err.contains("DNG holds the raw mosaic"), "{err}");
    assert!(!dir.path().join("bad.png").exists() && !dir.path().join("bad.dng").exists());
}

/// The demo sweep run far past Nyquist (to 0.93 cy/px on 900×600): red or
/// blue, aliased from ¼ cy/px, may not follow a sweep law of its own; it is
/// then measured along luma's (a note says so) instead of failing the whole
/// measurement, and the onset still lies where the physics puts it.
#[test]
fn channels_that_lose_their_own_law_are_measured_along_lumas() {
    // As `simulate --target demo:log --size 900x600 --full-well 20000
    // --read-noise 4 --bayer RGGB --demosaic bilinear` and `measure --channel
    // all` (which refines the corners): blue loses its own law.
    let cam = mosaic(Camera {
        width_px: 900,
        height_px: 600,
        chart_px: None,
        seed: 0,
        ..camera()
    });
    let t = sweepmtf::simulate::demo::demo_target(SweepLaw::Log);
    let shot = render(&t, &system(), &cam).unwrap();
    let bytes = shot.encode(PhotoFormat::Png).unwrap();
    let r = shot.roi().unwrap();
    let dec = decode_bytes(&bytes, "moire").unwrap();
    let opts = MeasureOptions {
        roi: Some([[r[0], r[1]], [r[2], r[3]], [r[4], r[5]], [r[6], r[7]]]),
        channel: Channel::All,
        refine_roi: true,
        ..MeasureOptions::default()
    };
    let m = measure_decoded(&dec, "moire", None, &opts).unwrap();
    // The same without the fallback: that channel fails on its own.
    let alone = measure_decoded(
        &dec,
        "moire",
        None,
        &MeasureOptions {
            channel: Channel::B,
            ..opts.clone()
        },
    );
    assert!(alone.is_err(), "blue alone measured");
    assert_eq!(channels(&m), ["luma", "r", "g", "b"]);
    let borrowed: Vec<&String> = m
        .notes
        .iter()
        .filter(|n| n.contains("measured along luma's sweep law"))
        .collect();
    let cm = &m.colour_moire[0];
    eprintln!(
        "demo sweep to 0.93 cy/px: max {:?} at {:?}, onset {:?}; {borrowed:?}",
        cm.max_spread, cm.max_at_cy_px, cm.onset_cy_px
    );
    assert_eq!(borrowed.len(), 1, "{:?}", m.notes);
    assert!(borrowed[0].contains("b/strip"), "{borrowed:?}");
    let onset = cm.onset_cy_px.expect("an onset");
    assert!((0.2..=0.3).contains(&onset), "onset {onset}");
}
