//! `--roi` on a raw whose EXIF orientation is not 1: coordinates are those of
//! the stored sensor frame (what the decoder returns, never turned), and the
//! summary says so, naming the orientation. A simulated Bayer shot written as
//! a DNG with orientation 6 (turn 90° clockwise to view) is measured with the
//! simulator's strip corners in the stored frame and must meet the noiseless
//! bar against the simulator's truth.

use sweepmtf::measure::{MeasureOptions, measure_raw};
use sweepmtf::model::System;
use sweepmtf::photo::linearise::Channel;
use sweepmtf::photo::raw::decode_raw;
use sweepmtf::simulate::dng::{DngSettings, encode_mosaic};
use sweepmtf::simulate::{self, BayerOrder, Camera};
use sweepmtf::target::SweepLaw;

#[test]
fn roi_is_in_the_stored_frame_and_the_orientation_is_named() {
    let (w, h) = (900usize, 600usize);
    let camera = Camera {
        bayer: Some(BayerOrder::Rggb),
        ..Camera::noiseless(w, h)
    };
    let target = simulate::demo::demo_target(SweepLaw::Log);
    let shot = simulate::render(&target, &System::default(), &camera).unwrap();
    let settings = DngSettings {
        orientation: 6,
        ..DngSettings::default()
    };
    let bytes = encode_mosaic(&shot.linear, w, h, BayerOrder::Rggb, 4.3, &settings).unwrap();
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("turned.dng");
    std::fs::write(&path, bytes).unwrap();

    let frame = decode_raw(&path).unwrap();
    assert_eq!(frame.facts.orientation, Some(6));
    assert_eq!((frame.width, frame.height), (w, h), "stored, not turned");

    let r = shot.roi().unwrap();
    let opts = MeasureOptions {
        roi: Some([[r[0], r[1]], [r[2], r[3]], [r[4], r[5]], [r[6], r[7]]]),
        channel: Channel::G,
        ..MeasureOptions::default()
    };
    let m = measure_raw(&path, "turned.dng", None, &opts).unwrap();
    assert!(
        m.warnings
            .iter()
            .any(|w| w.contains("orientation 6") && w.contains("stored sensor frame")),
        "{:?}",
        m.warnings
    );
    assert_eq!((m.image_width, m.image_height), (w, h));
    let truth = shot.truth().unwrap();
    let truth_at = |f: f64| {
        let rows = &truth.rows;
        let i = rows
            .partition_point(|p| p.freq_cy_px < f)
            .clamp(1, rows.len() - 1);
        let (a, b) = (&rows[i - 1], &rows[i]);
        a.mtf + (b.mtf - a.mtf) * (f - a.freq_cy_px) / (b.freq_cy_px - a.freq_cy_px)
    };
    let errs: Vec<f64> = m.curves[0]
        .points
        .iter()
        .filter(|p| !p.aliased && (0.01..=0.45).contains(&p.freq_cy_px))
        .map(|p| p.mtf - truth_at(p.freq_cy_px))
        .collect();
    let rms = (errs.iter().map(|e| e * e).sum::<f64>() / errs.len() as f64).sqrt();
    assert!(
        errs.len() > 20 && rms <= 0.005,
        "RMS {rms} over {}",
        errs.len()
    );
}

#[test]
fn an_upright_raw_gets_no_orientation_warning() {
    let (w, h) = (600usize, 400usize);
    let camera = Camera {
        bayer: Some(BayerOrder::Rggb),
        ..Camera::noiseless(w, h)
    };
    let target = simulate::demo::demo_target(SweepLaw::Log);
    let shot = simulate::render(&target, &System::default(), &camera).unwrap();
    let bytes = encode_mosaic(
        &shot.linear,
        w,
        h,
        BayerOrder::Rggb,
        4.3,
        &DngSettings::default(),
    )
    .unwrap();
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("upright.dng");
    std::fs::write(&path, bytes).unwrap();
    let r = shot.roi().unwrap();
    let opts = MeasureOptions {
        roi: Some([[r[0], r[1]], [r[2], r[3]], [r[4], r[5]], [r[6], r[7]]]),
        channel: Channel::G,
        ..MeasureOptions::default()
    };
    let m = measure_raw(&path, "upright.dng", None, &opts).unwrap();
    assert!(
        !m.warnings.iter().any(|w| w.contains("orientation")),
        "{:?}",
        m.warnings
    );
}
