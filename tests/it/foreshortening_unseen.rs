//! A keystone the strip's corners miss is read from the sweep's own phase.
//!
//! The corners set the foreshortening along a strip through the ratio of its
//! end heights, so on a long, narrow strip a fraction of a pixel across it
//! reads as a keystone: 0.2 px at each far corner of a 37 px strip says the
//! far end is 1.1 % farther away than it is. A phase law in the corners'
//! coordinate then misses the bars by up to a tenth of a cycle at the ends,
//! and the modulations there fall (the independent study's `varied` seed 4
//! #4, 649 × 36 px: corners refined to within 0.14 px were refused, "the
//! modulation is lost in noise"; a corner moved 0.2 px by hand read the
//! chart modulation −1.8 % and MTF50 +1.5 %). The law now carries the
//! foreshortening its phase shows (`PhaseLaw::persp`, x = s/(1 + persp·s)).
//!
//! Truth: the simulator's analytic MTF and printed contrast, and the
//! foreshortening the moved corners imply (a far end r times as tall as
//! the near one reads persp·length = 1/r − 1).

use sweepmtf::measure::{MeasureOptions, measure_decoded};
use sweepmtf::photo::decode::decode_bytes;
use sweepmtf::simulate::demo::demo_target_for;
use sweepmtf::simulate::{Camera, encode::PhotoFormat, mtf_at, render};
use sweepmtf::target::SweepLaw;

use crate::system_support::aps_c_f4 as system;

/// The frequency (cy/px) where the truth's rows fall through 0.5.
fn true_mtf50(rows: &[sweepmtf::simulate::truth::TruthRow]) -> f64 {
    let w = rows
        .windows(2)
        .find(|w| w[0].mtf >= 0.5 && w[1].mtf < 0.5)
        .unwrap();
    let t = (w[0].mtf - 0.5) / (w[0].mtf - w[1].mtf);
    w[0].freq_cy_px + t * (w[1].freq_cy_px - w[0].freq_cy_px)
}

#[test]
fn a_keystone_the_corners_miss_is_read_from_the_phase() {
    let cam = Camera {
        width_px: 1200,
        height_px: 800,
        chart_px: Some(1000.0),
        full_well_e: Some(60000.0),
        read_noise_e: 2.0,
        bits: 16,
        seed: 11,
        rotate_deg: 2.0,
        ..Camera::default()
    };
    let mut t = demo_target_for(&cam, SweepLaw::Linear, 0.01, 0.5).unwrap();
    // A long, narrow strip: 200 × 9 mm, ≈ 830 × 37 px.
    let r = &mut t.sweeps[0].rect;
    r.y_mm += 0.5 * (r.height_mm - 9.0);
    r.height_mm = 9.0;
    let contrast = t.sweeps[0].contrast;
    let shot = render(&t, &system(), &cam).unwrap();
    let bytes = shot.encode(PhotoFormat::Png).unwrap();
    let dec = decode_bytes(&bytes, "keystone_unseen").unwrap();
    let truth = shot.truth().unwrap();
    let f50 = true_mtf50(&truth.rows);
    let exact = shot.roi().unwrap();
    let c: Vec<[f64; 2]> = (0..4).map(|i| [exact[2 * i], exact[2 * i + 1]]).collect();
    let height = (c[3][0] - c[0][0]).hypot(c[3][1] - c[0][1]);
    // Corners 2 and 3 (the high-frequency end) moved `d` px towards each
    // other (inwards) or apart, across the strip.
    for d in [0.0, 0.2, -0.2, 0.4] {
        let mut given = [c[0], c[1], c[2], c[3]];
        let across = [(c[2][0] - c[1][0]) / height, (c[2][1] - c[1][1]) / height];
        for k in 0..2 {
            given[1][k] += d * across[k];
            given[2][k] -= d * across[k];
        }
        let opts = MeasureOptions {
            roi: Some(given),
            refine_roi: false,
            ..MeasureOptions::default()
        };
        let m = measure_decoded(&dec, "keystone_unseen", None, &opts).unwrap();
        let cv = &m.curves[0];
        let (mut se, mut n) = (0.0, 0usize);
        for p in cv
            .points
            .iter()
            .filter(|p| !p.aliased && (0.01..=0.45).contains(&p.freq_cy_px))
        {
            se += (p.mtf - mtf_at(&truth.rows, p.freq_cy_px)).powi(2);
            n += 1;
        }
        let rms = (se / n as f64).sqrt();
        let e50 = cv.figures.mtf50_cy_px.unwrap() / f50 - 1.0;
        let cm = cv.chart_modulation / contrast - 1.0;
        let r = (height - 2.0 * d) / height;
        let want = 1.0 / r - 1.0;
        let got = cv.law.persp * cv.strip_length;
        eprintln!(
            "d {d:+.1} px: RMS {rms:.4} MTF50 {:+.2} % chart mod. {:+.2} % foreshortening {got:+.5} (corners imply {want:+.5})",
            100.0 * e50,
            100.0 * cm
        );
        assert!(rms <= 0.004, "d {d}: RMS {rms}");
        assert!(e50.abs() <= 0.01, "d {d}: MTF50 {e50}");
        assert!(cm.abs() <= 0.005, "d {d}: chart modulation {cm}");
        assert!((got - want).abs() <= 0.0005, "d {d}: {got} against {want}");
    }
}
