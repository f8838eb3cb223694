//! What `measure --chart-mtf` adds to the outputs: CSV columns
//! `chart_mtf,camera_mtf,camera_mtf_err,chart_flag` at the end of each row
//! (`camera_mtf` and `camera_mtf_err` empty where `chart_flag` is not `ok`),
//! the `chart_mtf` object and per-curve camera MTF50/MTF50P/MTF10 in the JSON
//! summary, and the camera curve for the plot.
//!
//! The summary's own `mtf50` etc. stay the figures of the measured curve (the
//! `mtf` column: camera and print together); the compensated figures are the
//! `camera_*` fields beside them, so that one field keeps one meaning whatever
//! flags a run was given.

use super::divided::{append_columns, cell, divided_figures};
use super::model_overlay::ModelCurve;
use crate::measure::Measurement;
use crate::measure::chart_mtf::{ChartCurve, ChartFlag, ChartMtf, MIN_CHART_MTF};
use crate::measure::figures::Figures;
use serde_json::{Value, json};

/// Appends `chart_mtf,camera_mtf,camera_mtf_err,chart_flag` to a curves CSV
/// (rows in curve, then point order); unchanged when the row count does not match.
pub fn add_chart_columns(csv_bytes: &[u8], ccs: &[ChartCurve]) -> Vec<u8> {
    let n = ccs.iter().map(|l| l.flag.len()).sum();
    let cells = ccs.iter().flat_map(|l| {
        (0..l.flag.len()).map(move |i| {
            [
                cell(l.chart_mtf[i]),
                cell(l.camera_mtf[i]),
                cell(l.camera_mtf_err[i]),
                l.flag[i].as_str().to_string(),
            ]
        })
    });
    append_columns(
        csv_bytes,
        ["chart_mtf", "camera_mtf", "camera_mtf_err", "chart_flag"],
        n,
        cells,
    )
}

/// The camera MTF's summary figures (MTF50 etc. of the given points; flagged points left out).
pub fn camera_figures(m: &Measurement, i: usize, l: &ChartCurve) -> Figures {
    match m.curves.get(i) {
        Some(c) => divided_figures(c, &l.camera_mtf, &l.camera_mtf_err, |k| {
            l.flag[k] == ChartFlag::Ok
        }),
        None => Figures::default(),
    }
}

/// Adds `chart_mtf` (the source, the floor) and per curve `camera_mtf50_cy_px`,
/// `camera_mtf50p_cy_px`, `camera_mtf10_cy_px` (cycles/pixel; null where the
/// compensated curve does not reach the level before its flagged points) and
/// the counts of flagged points to a JSON summary.
pub fn add_chart_json(v: &mut Value, m: &Measurement, chart: &ChartMtf, ccs: &[ChartCurve]) {
    v["chart_mtf"] = json!({
        "source": chart.describe(),
        "floor": MIN_CHART_MTF,
        "note": "camera MTF = measured MTF / the print's MTF at each point's chart frequency (cy/mm of print); not given (flagged) where the print's MTF is below floor, outside the chart file's range, or the point is aliased; mtf50 etc. above are the measured curve's, camera_mtf50 etc. the compensated curve's",
    });
    if let Some(Value::Array(curves)) = v.get_mut("curves") {
        for (i, (c, l)) in curves.iter_mut().zip(ccs).enumerate() {
            let g = camera_figures(m, i, l);
            c["camera_mtf50_cy_px"] = json!(g.mtf50_cy_px);
            c["camera_mtf50p_cy_px"] = json!(g.mtf50p_cy_px);
            c["camera_mtf10_cy_px"] = json!(g.mtf10_cy_px);
            c["chart_points_below_floor"] = json!(l.count(ChartFlag::BelowFloor));
            c["chart_points_outside_file"] = json!(l.count(ChartFlag::OutsideFile));
            // Where compensation stops: the lowest frequency refused for the print.
            let stop = compensated_to(m, i, l);
            c["chart_compensated_to_cy_px"] = json!(stop);
        }
    }
}

/// The highest frequency (cy/px) below the first point refused for the print (below the floor or outside the file), if any is refused.
fn compensated_to(m: &Measurement, i: usize, l: &ChartCurve) -> Option<f64> {
    let c = m.curves.get(i)?;
    let k = l
        .flag
        .iter()
        .position(|f| matches!(f, ChartFlag::BelowFloor | ChartFlag::OutsideFile))?;
    Some(if k == 0 {
        0.0
    } else {
        c.points[k - 1].freq_cy_px
    })
}

/// The camera curves for the plot: one per measured curve, the given points only.
pub fn chart_plot_curves(m: &Measurement, ccs: &[ChartCurve]) -> Vec<ModelCurve> {
    m.curves
        .iter()
        .zip(ccs)
        .map(|(c, l)| ModelCurve {
            label: if m.curves.len() > 1 {
                format!("camera MTF {}/{}", c.channel, c.sweep_id)
            } else {
                "camera MTF (MTF / print)".into()
            },
            points: l.given(c).collect(),
        })
        .collect()
}

/// The print's MTF along the first curve, against image frequency (cy/px), for the plot.
pub fn print_plot_curve(m: &Measurement, ccs: &[ChartCurve]) -> Option<ModelCurve> {
    let (c, l) = m.curves.iter().zip(ccs).next()?;
    Some(ModelCurve {
        label: "print MTF".into(),
        points: c
            .points
            .iter()
            .zip(&l.chart_mtf)
            .filter(|(p, d)| d.is_finite() && !p.aliased)
            .map(|(p, d)| (p.freq_cy_px, *d))
            .collect(),
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn columns_go_at_the_end_and_flagged_values_stay_empty() {
        let text = b"freq_cy_px,mtf,aliased\n0.1,0.9,false\n0.45,0.1,false\n0.6,0.1,true\n";
        let l = ChartCurve {
            chart_mtf: vec![0.9, 0.2, f64::NAN],
            camera_mtf: vec![1.0, f64::NAN, f64::NAN],
            camera_mtf_err: vec![0.01, f64::NAN, f64::NAN],
            flag: vec![ChartFlag::Ok, ChartFlag::BelowFloor, ChartFlag::Aliased],
        };
        let out = String::from_utf8(add_chart_columns(text, &[l])).unwrap();
        assert_eq!(
            out,
            "freq_cy_px,mtf,aliased,chart_mtf,camera_mtf,camera_mtf_err,chart_flag\n\
             0.1,0.9,false,0.900000,1.000000,0.010000,ok\n\
             0.45,0.1,false,0.200000,,,chart_below_floor\n\
             0.6,0.1,true,,,,aliased\n"
        );
    }
}
