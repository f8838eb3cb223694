//! Camera raw path without demosaicing: a rendered sweep (Gaussian truth)
//! written as a 14-bit RGGB mosaic, measured on the green sites (both green
//! lattices binned together: a quincunx, whose band reaches 0.5 cy/px along
//! x) and on the red sites alone (a step-2 lattice, 0.25 cy/px). Each
//! lattice's own band flags aliasing; the error is taken over the same part
//! of the band as on grey images (up to 0.45 cy/px for the greens).

use sweepmtf::measure::synth::standard_cases;
use sweepmtf::measure::{MeasureOptions, measure_planes};
use sweepmtf::photo::raw::{BlackLevels, CfaPattern, RawChannel, RawFrame};

#[test]
fn bayer_sites_measure_the_truth_without_demosaicing() {
    let shot = standard_cases().remove(0); // noiseless, straight strip
    let lin = shot.render_linear();
    let (black, white) = (512.0, 16383.0);
    let data: Vec<u16> = lin
        .iter()
        .map(|&v| (black + v * (white - black)).round() as u16)
        .collect();
    let frame = RawFrame::from_mosaic_u16(
        shot.width,
        shot.height,
        CfaPattern::parse("RGGB").unwrap(),
        BlackLevels::uniform(black, 1),
        white,
        data,
    )
    .unwrap();
    let opts = MeasureOptions {
        roi: Some(shot.quad),
        ..MeasureOptions::default()
    };
    // Red sites are a quarter of the samples and reach their own Nyquist at
    // 0.25 cy/px; the two green lattices together reach 0.5 cy/px along x.
    for (ch, max_f, up_to, bar) in [
        (RawChannel::G, 0.5, 0.45, 0.005),
        (RawChannel::R, 0.25, 0.25, 0.01),
    ] {
        let groups = frame.channel_groups(ch);
        let m = measure_planes(
            &groups,
            (shot.width, shot.height),
            &shot.quad,
            None,
            &opts,
            0.9999,
        )
        .unwrap();
        let c = &m.curves[0];
        let mut se = 0.0;
        let mut n = 0;
        for p in &c.points {
            assert_eq!(
                p.aliased,
                p.freq_cy_px > max_f + 1e-9,
                "{ch:?} {}",
                p.freq_cy_px
            );
            if !p.aliased && (0.01..=up_to).contains(&p.freq_cy_px) {
                se += (p.mtf - shot.truth(p.freq_cy_px)).powi(2);
                n += 1;
            }
        }
        let rms = (se / n as f64).sqrt();
        eprintln!("{ch:?}: RMS {rms:.5} over {n} points up to {up_to} cy/px");
        assert!(n > 30 && rms < bar, "{ch:?}: RMS {rms} over {n}");
    }
}
