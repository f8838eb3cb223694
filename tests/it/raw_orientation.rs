//! `--roi` on a raw whose EXIF orientation is not 1: coordinates are those of
//! the stored sensor frame (what the decoder returns, never turned), and the
//! summary says so, naming the orientation. A simulated Bayer shot written as
//! a DNG with orientation 6 (turn 90° clockwise to view) is measured with the
//! simulator's strip corners in the stored frame and must meet the noiseless
//! bar against the simulator's truth.

use sweepmtf::measure::measure_raw;
use sweepmtf::photo::raw::decode_raw;
use sweepmtf::simulate::dng::DngSettings;

#[allow(dead_code)] // only its `truth_at` is used here
use crate::raw_support;
use raw_support::{green_strip_options, rggb_shot, rms_vs_truth, write_dng};

#[test]
fn roi_is_in_the_stored_frame_and_the_orientation_is_named() {
    let (w, h) = (900usize, 600usize);
    let shot = rggb_shot(w, h);
    let settings = DngSettings {
        orientation: 6,
        ..DngSettings::default()
    };
    let dir = tempfile::tempdir().unwrap();
    let path = write_dng(dir.path(), "turned.dng", &shot.linear, (w, h), &settings);

    let frame = decode_raw(&path).unwrap();
    assert_eq!(frame.facts.orientation, Some(6));
    assert_eq!((frame.width, frame.height), (w, h), "stored, not turned");

    let m = measure_raw(&path, "turned.dng", None, &green_strip_options(&shot)).unwrap();
    assert!(
        m.warnings
            .iter()
            .any(|w| w.contains("orientation 6") && w.contains("stored sensor frame")),
        "{:?}",
        m.warnings
    );
    assert_eq!((m.image_width, m.image_height), (w, h));
    let (rms, n) = rms_vs_truth(&shot, &m, 0.01..=0.45);
    assert!(n > 20 && rms <= 0.005, "RMS {rms} over {n}");
}

#[test]
fn an_upright_raw_gets_no_orientation_warning() {
    let (w, h) = (600usize, 400usize);
    let shot = rggb_shot(w, h);
    let dir = tempfile::tempdir().unwrap();
    let path = write_dng(
        dir.path(),
        "upright.dng",
        &shot.linear,
        (w, h),
        &DngSettings::default(),
    );
    let m = measure_raw(&path, "upright.dng", None, &green_strip_options(&shot)).unwrap();
    assert!(
        !m.warnings.iter().any(|w| w.contains("orientation")),
        "{:?}",
        m.warnings
    );
}
