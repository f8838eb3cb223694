//! The luma MTF of a demosaicked photo whose strip runs along a pixel axis.
//!
//! Truth from the mosaic's physics, not from the measurement: a bilinear
//! demosaic of a white-balanced RGGB mosaic passes a cosine at image
//! frequency (u, v) with the mean gains T_G = (1 + (cos 2πu + cos 2πv)/2)/2
//! for green and T_RB = (1 + cos 2πu)(1 + cos 2πv)/4 for red and blue (the
//! `simulate::demosaic` unit test checks them on the simulator's output), and
//! adds aliases at (u + ½, v), (u, v + ½) and (u + ½, v + ½) that are locked
//! to the pixel grid. Each channel is linearised before the luma is formed, so the luma (Rec. 709
//! weights, as `measure` forms it) passes the presampling MTF times
//! 0.2126·T_RB + 0.7152·T_G + 0.0722·T_RB; the aliases are not MTF. Along a
//! pixel axis every bin of the profile holds pixels of one parity, the alias
//! reaches the profile at ½ − f cy/px, and a sine fit that does not model it
//! read up to +0.044 near 0.27 cy/px here (RMS 0.0102 / 0.0115 / 0.0025 /
//! 0.0013 turned 0° / 0.4° / 1.5° / 3°; 0.006–0.014 on the independent
//! camera's near-axis shots, `docs/studies/independent_shots.py … bayer`).

use std::f64::consts::PI;
use sweepmtf::measure::{MeasureOptions, measure_decoded};
use sweepmtf::photo::decode::decode_bytes;
use sweepmtf::simulate::demo::demo_target_for;
use sweepmtf::simulate::{BayerOrder, Camera, Demosaic, encode::PhotoFormat, mtf_at, render};
use sweepmtf::target::SweepLaw;

use crate::system_support::aps_c_f4 as system;

/// The bilinear demosaic's luma gain at frequency f along direction θ.
fn demosaic_gain(f: f64, theta: f64) -> f64 {
    let (u, v) = (f * theta.cos(), f * theta.sin());
    let g = 0.5 * (1.0 + 0.5 * ((2.0 * PI * u).cos() + (2.0 * PI * v).cos()));
    let rb = 0.25 * (1.0 + (2.0 * PI * u).cos()) * (1.0 + (2.0 * PI * v).cos());
    (0.2126 + 0.0722) * rb + 0.7152 * g
}

/// (RMS |MTF − truth| over 0.01–0.45 cy/px, worst point, its frequency) of
/// a bilinear-demosaicked RGGB shot turned by `deg`, luma, sRGB PNG (each
/// channel linearised before the luma is formed, so it is linear in them).
fn measure_turned(deg: f64) -> (f64, f64, f64) {
    let cam = Camera {
        width_px: 1000,
        height_px: 600,
        chart_px: Some(760.0),
        full_well_e: Some(20000.0),
        read_noise_e: 4.0,
        seed: 5,
        rotate_deg: deg,
        bayer: Some(BayerOrder::Rggb),
        demosaic: Some(Demosaic::Bilinear),
        ..Camera::default()
    };
    let t = demo_target_for(&cam, SweepLaw::Log, 0.01, 0.45).unwrap();
    let shot = render(&t, &system(), &cam).unwrap();
    let bytes = shot.encode(PhotoFormat::Png).unwrap();
    let r = shot.roi().unwrap();
    let dec = decode_bytes(&bytes, "demosaic").unwrap();
    let opts = MeasureOptions {
        roi: Some([[r[0], r[1]], [r[2], r[3]], [r[4], r[5]], [r[6], r[7]]]),
        ..MeasureOptions::default()
    };
    let m = measure_decoded(&dec, "demosaic", None, &opts).unwrap();
    let rows = &shot.truth().unwrap().rows;
    // The strip's direction in the image: from its low-frequency edge to the other.
    let theta = (r[3] + r[5] - r[1] - r[7]).atan2(r[2] + r[4] - r[0] - r[6]);
    let (mut se, mut n, mut worst) = (0.0, 0, (0.0f64, 0.0));
    for p in m.curves[0].points.iter().filter(|p| !p.aliased) {
        if (0.01..=0.45).contains(&p.freq_cy_px) {
            let d = p.mtf - mtf_at(rows, p.freq_cy_px) * demosaic_gain(p.freq_cy_px, theta);
            se += d * d;
            n += 1;
            if d.abs() > worst.0.abs() {
                worst = (d, p.freq_cy_px);
            }
        }
    }
    assert!(n > 50, "{n} points");
    ((se / n as f64).sqrt(), worst.0, worst.1)
}

#[test]
fn a_demosaicked_strip_along_a_pixel_axis_reads_its_luma_mtf_without_the_cfa_aliases() {
    for deg in [0.0, 0.4, 1.5, 3.0] {
        let (rms, worst, at) = measure_turned(deg);
        eprintln!("turned {deg}°: RMS {rms:.4}, worst {worst:+.4} at {at:.3} cy/px");
        assert!(
            rms < 0.006,
            "turned {deg}°: RMS {rms:.4}, worst {worst:+.4} at {at:.3} cy/px"
        );
    }
}
