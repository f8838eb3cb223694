//! Sine-patch measurement on the real MITRE sineMTF scan (≈501 ppi, turned by
//! 180°; corners located by hand, see testdata/real/README.md), with the
//! tone curve measured from its 14 density patches. No exact truth exists for
//! a real scanner; what is checked comes from outside the code: the image
//! frequency of each patch (chart cy/mm ÷ 19.72 px/mm from the hand-located
//! corners), the patches above Nyquist flagged, and an MTF that starts near 1
//! and falls with frequency.

use std::path::{Path, PathBuf};
use sweepmtf::measure::{MeasureOptions, measure_file};

/// The scan's folder: `../shared` beside the checkout (main, CI) or two levels up (a worktree).
fn dir() -> PathBuf {
    Path::new(concat!(env!("CARGO_MANIFEST_DIR"), "/testdata/real")).join("sine_target_scan")
}

/// The target frame's corners in the scan, from the three hand-located patch corners
/// (an affine fit: target (60,36)→(231,251), (9.95,36)→(1218,248), (60,11.4)→(230,736)).
fn roi() -> [[f64; 2]; 4] {
    let src = [[60.0, 36.0], [9.95, 36.0], [60.0, 11.4]];
    let dst = [[231.0, 251.0], [1218.0, 248.0], [230.0, 736.0]];
    // Solve x' = a·X + b·Y + c for each image axis (Cramer's rule).
    let det = |m: [[f64; 3]; 3]| {
        m[0][0] * (m[1][1] * m[2][2] - m[1][2] * m[2][1])
            - m[0][1] * (m[1][0] * m[2][2] - m[1][2] * m[2][0])
            + m[0][2] * (m[1][0] * m[2][1] - m[1][1] * m[2][0])
    };
    let a = [0, 1, 2].map(|i| [src[i][0], src[i][1], 1.0]);
    let d = det(a);
    let coef = |axis: usize| {
        [0, 1, 2].map(|k| {
            let mut m = a;
            for i in 0..3 {
                m[i][k] = dst[i][axis];
            }
            det(m) / d
        })
    };
    let (cx, cy) = (coef(0), coef(1));
    [[0.0, 0.0], [70.0, 0.0], [70.0, 47.5], [0.0, 47.5]]
        .map(|[x, y]| [cx[0] * x + cx[1] * y + cx[2], cy[0] * x + cy[1] * y + cy[2]])
}

#[test]
fn patches_of_the_real_scan() {
    let photo = dir().join("mitre_sinemtf_test.tif");
    let opts = MeasureOptions {
        roi: Some(roi()),
        target: Some(dir().join("mitre_sinemtf_tgt.txt")),
        tone_chart: true,
        ..MeasureOptions::default()
    };
    let m = measure_file(&photo, &opts).unwrap();
    assert!(m.curves.is_empty());
    assert_eq!(m.patches.len(), 15);
    let px_per_mm = 987.0 / 50.05; // hand-located corners 50.05 mm apart
    for p in &m.patches {
        let f = p.freq_chart_cy_mm / px_per_mm;
        assert!(
            (p.freq_cy_px / f - 1.0).abs() < 0.01,
            "{}: {} vs {f}",
            p.patch_id,
            p.freq_cy_px
        );
        assert_eq!(p.aliased, p.freq_cy_px > 0.5, "{}", p.patch_id);
    }
    let by = |id: &str| m.patches.iter().find(|p| p.patch_id == id).unwrap();
    // Low frequencies: the scanner barely attenuates (and the maker's modulation normalises).
    for id in ["1", "2", "3", "4", "5", "6"] {
        assert!((by(id).mtf - 1.0).abs() < 0.08, "{id}: {}", by(id).mtf);
    }
    // The MTF falls with frequency below Nyquist.
    assert!(
        by("8").mtf > by("10").mtf
            && by("10").mtf > by("12").mtf
            && by("12").mtf > by("13").mtf * 0.95
    );
    assert!(by("13").mtf < 0.8 && by("13").mtf > 0.2, "{}", by("13").mtf);
    // 14 density patches; near-equal densities (0.604–0.627) may pool into one level.
    assert!(m.tone.contains("grey levels"), "{}", m.tone);
}
