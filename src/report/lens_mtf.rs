//! What `measure --lens-mtf` adds to the outputs: CSV columns
//! `sensor_mtf,lens_mtf,lens_mtf_err,lens_flag` at the end of each row
//! (`lens_mtf` and `lens_mtf_err` empty where `lens_flag` is `small_divisor`
//! or `aliased`), the `lens_mtf` object and per-curve lens MTF50 in the JSON
//! summary, and the lens curve for the plot.

use super::divided::{append_columns, cell, divided_figures};
use super::model_overlay::ModelCurve;
use crate::measure::Measurement;
use crate::measure::figures::Figures;
use crate::measure::lens_mtf::{LensCurve, LensFlag, MIN_DIVISOR, SensorPart};
use serde_json::{Value, json};

/// Appends `sensor_mtf,lens_mtf,lens_mtf_err,lens_flag` to a curves CSV (rows
/// in curve, then point order); unchanged when the row count does not match.
pub fn add_lens_columns(csv_bytes: &[u8], lcs: &[LensCurve]) -> Vec<u8> {
    let n = lcs.iter().map(|l| l.flag.len()).sum();
    let cells = lcs.iter().flat_map(|l| {
        (0..l.flag.len()).map(move |i| {
            [
                cell(l.sensor_mtf[i]),
                cell(l.lens_mtf[i]),
                cell(l.lens_mtf_err[i]),
                l.flag[i].as_str().to_string(),
            ]
        })
    });
    append_columns(
        csv_bytes,
        ["sensor_mtf", "lens_mtf", "lens_mtf_err", "lens_flag"],
        n,
        cells,
    )
}

/// The lens MTF's summary figures (MTF50 etc. of the given points; flagged points left out).
pub fn lens_figures(m: &Measurement, i: usize, l: &LensCurve) -> Figures {
    match m.curves.get(i) {
        Some(c) => divided_figures(c, &l.lens_mtf, &l.lens_mtf_err, |k| {
            l.flag[k] == LensFlag::Ok
        }),
        None => Figures::default(),
    }
}

/// Adds `lens_mtf` (the divisor, its floor) and per curve `lens_mtf50`, `lens_mtf10`
/// (cycles/pixel) and the count of flagged points to a JSON summary.
pub fn add_lens_json(v: &mut Value, m: &Measurement, sensor: &SensorPart, lcs: &[LensCurve]) {
    v["lens_mtf"] = json!({
        "sensor_part": sensor.describe(),
        "min_divisor": MIN_DIVISOR,
        "note": "lens MTF = measured MTF / sensor MTF along the sweep; not given (flagged) where the sensor MTF is below min_divisor or the point is aliased",
    });
    if let Some(Value::Array(curves)) = v.get_mut("curves") {
        for (i, (c, l)) in curves.iter_mut().zip(lcs).enumerate() {
            let g = lens_figures(m, i, l);
            c["lens_mtf50_cy_px"] = json!(g.mtf50_cy_px);
            c["lens_mtf10_cy_px"] = json!(g.mtf10_cy_px);
            c["lens_points_small_divisor"] = json!(
                l.flag
                    .iter()
                    .filter(|f| **f == LensFlag::SmallDivisor)
                    .count()
            );
        }
    }
}

/// The lens curves for the plot: one per measured curve, the given points only.
pub fn lens_plot_curves(m: &Measurement, lcs: &[LensCurve]) -> Vec<ModelCurve> {
    m.curves
        .iter()
        .zip(lcs)
        .map(|(c, l)| ModelCurve {
            label: if m.curves.len() > 1 {
                format!("lens MTF {}/{}", c.channel, c.sweep_id)
            } else {
                "lens MTF (MTF / sensor)".into()
            },
            points: l.given(c).collect(),
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn columns_go_at_the_end_and_flagged_values_stay_empty() {
        let text = b"freq_cy_px,mtf,aliased\n0.1,0.9,false\n0.45,0.1,false\n";
        let l = LensCurve {
            direction: [1.0, 0.0],
            sensor_mtf: vec![0.98, 0.15],
            lens_mtf: vec![0.9 / 0.98, f64::NAN],
            lens_mtf_err: vec![0.01, f64::NAN],
            flag: vec![LensFlag::Ok, LensFlag::SmallDivisor],
        };
        let out = String::from_utf8(add_lens_columns(text, &[l])).unwrap();
        assert_eq!(
            out,
            "freq_cy_px,mtf,aliased,sensor_mtf,lens_mtf,lens_mtf_err,lens_flag\n\
             0.1,0.9,false,0.980000,0.918367,0.010000,ok\n\
             0.45,0.1,false,0.150000,,,small_divisor\n"
        );
    }
}
