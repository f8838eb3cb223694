//! Scoring one simulated shot against its renderer's exact truth, shared by
//! `examples/unseen.rs` and `examples/coarse_jpeg_study.rs`: strip corners
//! only, no target, default settings (refinement on), read from the file's
//! bytes as `sweepmtf measure` reads them.

use sweepmtf::measure::{MeasureOptions, measure_bytes, measure_decoded};
use sweepmtf::photo::decode::decode_bytes;

/// (RMS |MTF − truth| over 0.01–0.45 cy/px, MTF50 relative error, chart
/// modulation relative error; printed 0.8) of one shot.
pub type Score = (f64, f64, f64);

/// The first fall of `truth` through 0.5 (cy/px), by bisection on a 0.001 cy/px walk.
pub fn true_mtf50(truth: &dyn Fn(f64) -> f64) -> f64 {
    let mut lo = 0.0;
    while truth(lo + 0.001) >= 0.5 {
        lo += 0.001;
    }
    let mut hi = lo + 0.001;
    for _ in 0..50 {
        let mid = 0.5 * (lo + hi);
        if truth(mid) >= 0.5 {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    lo
}

/// Measures `bytes` with strip corners `roi` and default settings and scores
/// it against `truth` (MTF at cy/px). As the CLI reads a file (a JPEG's
/// luminance from its Y′ plane alone), or with `whole_rgb` from the whole
/// RGB decode, which under coloured light carries the chroma quantiser too.
pub fn score(
    bytes: &[u8],
    roi: [[f64; 2]; 4],
    truth: &dyn Fn(f64) -> f64,
    whole_rgb: bool,
) -> Result<Score, String> {
    let opts = MeasureOptions {
        roi: Some(roi),
        refine_roi: true,
        ..MeasureOptions::default()
    };
    let m = if whole_rgb {
        let dec = decode_bytes(bytes, "shot").map_err(|e| e.to_string())?;
        measure_decoded(&dec, "shot", None, &opts)
    } else {
        measure_bytes(bytes, "shot", None, &opts)
    }
    .map_err(|e| e.to_string())?;
    let c = &m.curves[0];
    let (mut se, mut n) = (0.0, 0);
    for p in c.points.iter().filter(|p| !p.aliased) {
        if (0.01..=0.45).contains(&p.freq_cy_px) {
            se += (p.mtf - truth(p.freq_cy_px)).powi(2);
            n += 1;
        }
    }
    let f50 = c.figures.mtf50_cy_px.ok_or("no MTF50")?;
    Ok((
        (se / n.max(1) as f64).sqrt(),
        f50 / true_mtf50(truth) - 1.0,
        c.chart_modulation / 0.8 - 1.0,
    ))
}
