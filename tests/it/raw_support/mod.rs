//! Test helpers shared by the tests that write a simulated Bayer shot as a
//! DNG and measure it against the simulator's truth (needs `mod csv_support;`
//! beside it).

use std::path::{Path, PathBuf};
use sweepmtf::measure::{MeasureOptions, Measurement};
use sweepmtf::model::System;
use sweepmtf::photo::linearise::Channel;
use sweepmtf::simulate::dng::{DngSettings, encode_mosaic};
use sweepmtf::simulate::{self, BayerOrder, Camera, Shot};
use sweepmtf::target::SweepLaw;

/// A noiseless `w × h` RGGB shot of the demo log target.
pub fn rggb_shot(w: usize, h: usize) -> Shot {
    let camera = Camera {
        bayer: Some(BayerOrder::Rggb),
        ..Camera::noiseless(w, h)
    };
    let target = simulate::demo::demo_target(SweepLaw::Log);
    simulate::render(&target, &System::default(), &camera).unwrap()
}

/// Writes the linear RGGB mosaic `linear` (`w × h`, 4.3 µm pitch) as the DNG
/// `dir/name` with `settings`; returns its path.
pub fn write_dng(
    dir: &Path,
    name: &str,
    linear: &[f32],
    (w, h): (usize, usize),
    settings: &DngSettings,
) -> PathBuf {
    let bytes = encode_mosaic(linear, w, h, BayerOrder::Rggb, 4.3, settings).unwrap();
    let path = dir.join(name);
    std::fs::write(&path, bytes).unwrap();
    path
}

/// Options measuring the green sites of the shot's sweep strip (the
/// simulator's corners, in the stored frame).
pub fn green_strip_options(shot: &Shot) -> MeasureOptions {
    let r = shot.roi().unwrap();
    MeasureOptions {
        roi: Some([[r[0], r[1]], [r[2], r[3]], [r[4], r[5]], [r[6], r[7]]]),
        channel: Channel::G,
        ..MeasureOptions::default()
    }
}

/// RMS of MTF − truth over the first curve's unaliased points with frequency
/// in `band` (cy/px), and their count.
pub fn rms_vs_truth(
    shot: &Shot,
    m: &Measurement,
    band: std::ops::RangeInclusive<f64>,
) -> (f64, usize) {
    let truth: Vec<(f64, f64)> = shot
        .truth()
        .unwrap()
        .rows
        .iter()
        .map(|r| (r.freq_cy_px, r.mtf))
        .collect();
    let errs: Vec<f64> = m.curves[0]
        .points
        .iter()
        .filter(|p| !p.aliased && band.contains(&p.freq_cy_px))
        .map(|p| p.mtf - super::csv_support::truth_at(&truth, p.freq_cy_px))
        .collect();
    let rms = (errs.iter().map(|e| e * e).sum::<f64>() / errs.len().max(1) as f64).sqrt();
    (rms, errs.len())
}
