//! The JSON summary of a measurement: MTF50/30/20/10 and MTF50P/20P/10P (nn %
//! of the peak, searched from the peak upward) in every known unit, the peak
//! (value, frequency, whether it is a sharpening peak), MTF at Nyquist,
//! method, chart modulation and its source, warnings, timings; with red and
//! blue curves, the colour moiré block (`colour_moire`).

use super::csv::lw_ph;
use crate::measure::Measurement;
use serde_json::{Value, json};

/// Wall-clock timings measured by the caller (the library never reads the clock).
#[derive(Debug, Clone, Copy, Default)]
pub struct Timings {
    /// Reading, decoding and measuring the photo (ms).
    pub measure_ms: f64,
    /// Whole run including output (ms).
    pub total_ms: f64,
}

fn freq(f: Option<f64>, m: &Measurement) -> Value {
    match f {
        None => Value::Null,
        Some(f) => {
            let mut o = json!({ "cy_px": f, "lw_ph": lw_ph(f, m.image_height) });
            if let Some(p) = m.pixel_pitch_mm {
                o["cy_mm"] = json!(f / p);
            }
            o
        }
    }
}

/// A frequency object given its one-sigma uncertainty beside it, in the same units (`err_cy_px`, `err_lw_ph`, `err_cy_mm`).
fn with_err(mut o: Value, err: Option<f64>, m: &Measurement) -> Value {
    if let (Value::Object(map), Value::Object(e)) = (&mut o, freq(err, m)) {
        for (k, v) in e {
            map.insert(format!("err_{k}"), v);
        }
    }
    o
}

/// The summary as a JSON value.
pub fn summary(m: &Measurement, t: Option<Timings>) -> Value {
    let curves: Vec<Value> = m
        .curves
        .iter()
        .map(|c| {
            json!({
                "channel": c.channel,
                "sweep": c.sweep_id,
                "mtf50": with_err(freq(c.figures.mtf50_cy_px, m), c.figures.mtf50_err_cy_px, m),
                "mtf30": freq(c.figures.mtf30_cy_px, m),
                "mtf20": freq(c.figures.mtf20_cy_px, m),
                "mtf10": freq(c.figures.mtf10_cy_px, m),
                "mtf50p": freq(c.figures.mtf50p_cy_px, m),
                "mtf20p": freq(c.figures.mtf20p_cy_px, m),
                "mtf10p": freq(c.figures.mtf10p_cy_px, m),
                "peak": {
                    "mtf": c.figures.peak_mtf,
                    "freq": freq(c.figures.peak_cy_px, m),
                    "sharpening": c.figures.sharpening_peak,
                },
                "mtf_at_nyquist": c.figures.mtf_nyquist,
                "chart_modulation": c.chart_modulation,
                "chart_modulation_err": c.chart_modulation_err,
                "chart_modulation_source": c.chart_modulation_source,
                "aliasing_from_cy_px": c.aliasing_from_cy_px,
                "rounded_away_from_cy_px": c.rounded_away_from_cy_px,
                "clipped_fraction": c.clipped_fraction,
                "points": c.points.len(),
                "points_aliased": c.points.iter().filter(|p| p.aliased).count(),
                "points_jpeg_limited": c.points.iter().filter(|p| p.jpeg_limited).count(),
                "print_ends_inside_px": c.print_ends_inside_px,
                "tone_correction": c.tone_fix.as_ref().map(|f| json!({
                    "used": f.used,
                    "base": f.base.name(),
                    "passes": f.passes.len(),
                    "significance": f.significance,
                    "mtf_change_at_half": -f.effect,
                    "max_shift_255": f.max_shift_255,
                    "code_range": [f.code_range.0, f.code_range.1],
                    "windows": f.windows,
                    "light_ratio": f.light_ratio,
                    "code_sharpening_seen": f.sharpening_seen,
                    "black_level": f.black.as_ref().map(black_level_json),
                    "unseen_black_relative": crate::measure::tone_unseen::scale(f),
                })),
                "sweep_law": {
                    "kind": c.law.kind,
                    "strip_unit": c.strip_unit,
                    "phase_c0_cycles": c.law.c0,
                    "freq_start_cy_per_unit": c.law.c1,
                    "c2": c.law.c2,
                    "foreshortening_per_unit": c.law.persp,
                },
            })
        })
        .collect();
    let patches: Vec<Value> = m
        .patches
        .iter()
        .map(|p| serde_json::to_value(p).unwrap_or(Value::Null))
        .collect();
    let mut v = json!({
        "source": m.source,
        "image_width_px": m.image_width,
        "image_height_px": m.image_height,
        "bits_per_sample": m.bits,
        "method": m.method.name(),
        "tone": m.tone,
        "green_gain": m.green_gain,
        "pixel_pitch_um": m.pixel_pitch_mm.map(|p| p * 1e3),
        "roi_px": m.roi,
        "distortion": m.distortion.map(|d| json!({
            "model": d.model.to_string(),
            "a": d.model.a,
            "b": d.model.b,
            "c": d.model.c,
            "corner_percent": d.corner_percent,
            "source": d.source,
            "used": d.used().is_some(),
            "b_sigma": d.b_sigma,
            "a_sigma": d.a_sigma,
            "c_sigma": d.c_sigma,
            "significance": d.significance,
            "edge_rms_px": d.edge_rms_px,
            "straight_rms_px": d.straight_rms_px,
            "edge_coverage": d.edge_coverage,
            "edge_points": d.edge_points,
            "bow_px": d.bow_px,
            "why_not": d.why_not,
        })),
        "curves": curves,
        "patches": patches,
        "warnings": m.warnings,
        "notes": m.notes,
    });
    if let Some(cm) = colour_moire(m) {
        v["colour_moire"] = cm;
    }
    if let Some(t) = t {
        v["timings_ms"] = json!({
            "decode_and_measure": t.measure_ms,
            "total": t.total_ms,
        });
    }
    v
}

/// The `colour_moire` block: the definition, the thresholds, the first
/// sweep's figures at the top and every sweep's in `sweeps`; None when no
/// sweep was measured in both red and blue.
fn colour_moire(m: &Measurement) -> Option<Value> {
    use crate::measure::moire::{DEFINITION, ONSET_RUN, ONSET_SIGMAS, ONSET_SPREAD};
    let first = m.colour_moire.first()?;
    let one = |c: &crate::measure::moire::ColourMoire| {
        json!({
            "sweep": c.sweep_id,
            "max_spread": c.max_spread,
            "max_spread_err": c.max_spread_err,
            "max_at_cy_px": c.max_at_cy_px,
            "onset_cy_px": c.onset_cy_px,
            "measured_to_cy_px": c.measured_to_cy_px,
            "points": c.points.len(),
        })
    };
    let mut v = one(first);
    v["definition"] = json!(DEFINITION);
    v["onset_spread"] = json!(ONSET_SPREAD);
    v["onset_sigmas"] = json!(ONSET_SIGMAS);
    v["onset_run_points"] = json!(ONSET_RUN);
    v["sweeps"] = Value::Array(m.colour_moire.iter().map(one).collect());
    Some(v)
}

/// The summary as pretty-printed JSON bytes.
pub fn summary_json(m: &Measurement, t: Option<Timings>) -> Vec<u8> {
    let mut s = serde_json::to_string_pretty(&summary(m, t)).unwrap_or_default();
    s.push('\n');
    s.into_bytes()
}

/// A tone correction's black level from the paper, as the summary JSON gives it.
fn black_level_json(b: &crate::measure::tone_black::BlackLevel) -> serde_json::Value {
    json!({
        "used": b.used,
        "offset": b.offset,
        "offset_err": b.sigma,
        "offset_band_spread": b.band_spread,
        "relative_to_mean": b.relative,
        "strip_mean": b.mean,
        "significant": b.significant,
        "chart_modulation_rel_err": b.claims().then(|| b.modulation_rel_err()),
        "stretches": b.stretches,
        "bands": b.bands,
        "light_spread": b.light_spread,
        "residual": b.residual,
        "why_not": b.why_not,
    })
}
