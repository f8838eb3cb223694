//! Outputs of the model beside the measurement: the `mtf_model` column added
//! after `mtf` in the curves CSV, the model and EXIF fields of the JSON
//! summary, and the extras the MTF plot draws (dashed model curves, caption).

use crate::measure::Measurement;
use crate::measure::model_overlay::{CurveModel, ModelOverlay};
use crate::photo::exif::ExifFacts;
use plotters::coord::Shift;
use plotters::coord::types::RangedCoordf64;
use plotters::prelude::*;
use serde_json::{Value, json};

/// A dashed model curve for the MTF plot.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct ModelCurve {
    /// Legend label ("model: <name>").
    pub label: String,
    /// (frequency cycles/pixel, MTF) samples.
    pub points: Vec<(f64, f64)>,
}

/// What the MTF plot draws beyond the measurement.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct PlotExtras {
    /// Model curves, drawn dashed.
    pub model_curves: Vec<ModelCurve>,
    /// A caption line under the plot (EXIF facts), empty for none.
    pub caption: String,
}

/// Plot extras: one dashed model curve per distinct sweep direction (0–1 cy/px), and the EXIF caption.
pub fn plot_extras(
    model: Option<(&ModelOverlay, &[CurveModel])>,
    facts: Option<&ExifFacts>,
    m: &Measurement,
) -> PlotExtras {
    let mut curves: Vec<ModelCurve> = Vec::new();
    if let Some((o, cms)) = model {
        let mut dirs: Vec<[f64; 2]> = Vec::new();
        for (cm, c) in cms.iter().zip(&m.curves) {
            let d = cm.direction;
            if dirs.iter().any(|e| (e[0] - d[0]).hypot(e[1] - d[1]) < 1e-3) {
                continue;
            }
            dirs.push(d);
            let label = if dirs.len() == 1 {
                format!("model: {}", o.name)
            } else {
                format!("model along {}", c.sweep_id)
            };
            let n = 400;
            let points = (0..=n)
                .map(|i| {
                    let f = i as f64 / n as f64;
                    (f, o.mtf_cy_px(d, f))
                })
                .collect();
            curves.push(ModelCurve { label, points });
        }
    }
    let mut caption: Vec<String> = facts.map(|f| f.describe()).into_iter().collect();
    if let Some((_, cms)) = model
        && let Some(cm) = cms.first()
        && let Some(f50) = cm.mtf50_model_cy_px
    {
        let mut t = format!("model MTF50 {f50:.3} cy/px");
        if let Some(r) = cm.mtf50_ratio {
            t.push_str(&format!(", measured/model {r:.3}"));
        }
        caption.push(t);
    }
    PlotExtras {
        model_curves: curves,
        caption: caption.join("  ·  "),
    }
}

/// Inserts an `mtf_model` column after `mtf` in a curves CSV (rows in curve, then point order).
/// Returns the CSV unchanged when the row count does not match.
pub fn add_mtf_model_column(csv_bytes: &[u8], cms: &[CurveModel]) -> Vec<u8> {
    let values: Vec<f64> = cms
        .iter()
        .flat_map(|c| c.mtf_model.iter().copied())
        .collect();
    add_model_values(csv_bytes, &values)
}

/// Inserts an `mtf_model` column after `mtf` holding `values`, one per data row
/// in order (the CSV is returned unchanged when the counts differ).
pub fn add_model_values(csv_bytes: &[u8], values: &[f64]) -> Vec<u8> {
    let mut r = csv::ReaderBuilder::new()
        .has_headers(false)
        .from_reader(csv_bytes);
    let rows: Vec<csv::StringRecord> = match r.records().collect() {
        Ok(v) => v,
        Err(_) => return csv_bytes.to_vec(),
    };
    let Some(head) = rows.first() else {
        return csv_bytes.to_vec();
    };
    let Some(col) = head.iter().position(|h| h == "mtf") else {
        return csv_bytes.to_vec();
    };
    if rows.len() - 1 != values.len() {
        return csv_bytes.to_vec();
    }
    let mut w = csv::Writer::from_writer(Vec::new());
    for (i, row) in rows.iter().enumerate() {
        let mut cells: Vec<String> = row.iter().map(str::to_string).collect();
        let extra = if i == 0 {
            "mtf_model".to_string()
        } else {
            format!("{:.6}", values[i - 1])
        };
        cells.insert(col + 1, extra);
        let _ = w.write_record(&cells);
    }
    w.into_inner().unwrap_or_else(|_| csv_bytes.to_vec())
}

/// Splits off a 26-pixel strip at the bottom of `root` for the caption and
/// writes it there; returns the area left for the chart (`root` itself when the caption is empty).
pub fn caption_area<DB: DrawingBackend>(
    root: &DrawingArea<DB, Shift>,
    caption: &str,
) -> Result<DrawingArea<DB, Shift>, DrawingAreaErrorKind<DB::ErrorType>> {
    if caption.is_empty() {
        return Ok(root.clone());
    }
    let (_, h) = root.dim_in_pixel();
    let (upper, lower) = root.split_vertically(h.saturating_sub(26));
    lower.draw(&Text::new(
        caption.to_string(),
        (14, 4),
        (crate::plot::FONT, 15)
            .into_font()
            .color(&RGBColor(60, 60, 60)),
    ))?;
    Ok(upper)
}

/// Draws the model curves dashed (black, then dark grey), clipped to the chart's range.
pub fn draw_model_curves<'a, DB: DrawingBackend + 'a>(
    chart: &mut ChartContext<'a, DB, Cartesian2d<RangedCoordf64, RangedCoordf64>>,
    extras: &PlotExtras,
    xmax: f64,
    ymax: f64,
) -> Result<(), DrawingAreaErrorKind<DB::ErrorType>> {
    for (k, mc) in extras.model_curves.iter().enumerate() {
        let col = if k == 0 {
            RGBColor(0, 0, 0)
        } else {
            RGBColor(110, 110, 110)
        };
        let style = col.stroke_width(2);
        chart
            .draw_series(DashedLineSeries::new(
                mc.points
                    .iter()
                    .filter(|p| p.0 <= xmax)
                    .map(|&(f, v)| (f, v.clamp(0.0, ymax))),
                8,
                5,
                style,
            ))?
            .label(mc.label.clone())
            .legend(move |(x, y)| {
                EmptyElement::at((x, y))
                    + PathElement::new([(0, 0), (7, 0)], style)
                    + PathElement::new([(11, 0), (18, 0)], style)
            });
    }
    Ok(())
}

fn freq(f: Option<f64>, pitch_mm: f64) -> Value {
    match f {
        Some(f) => json!({ "cy_px": f, "cy_mm": f / pitch_mm }),
        None => Value::Null,
    }
}

/// Adds `exif` (facts and their one-line description) to a JSON summary.
pub fn add_exif(v: &mut Value, facts: &ExifFacts) {
    let mut e = serde_json::to_value(facts).unwrap_or(Value::Null);
    if let Value::Object(o) = &mut e {
        o.insert("description".into(), json!(facts.describe()));
    }
    v["exif"] = e;
}

/// Adds `model` (name, description, left-out factors) and per-curve
/// `mtf50_model` and `mtf50_measured_over_model` to a JSON summary.
pub fn add_model(v: &mut Value, o: &ModelOverlay, cms: &[CurveModel]) {
    v["model"] = json!({
        "name": o.name,
        "description": o.description,
        "pixel_pitch_um": o.pitch_mm * 1e3,
        "factors_left_out": o.left_out,
        "note": "presampling MTF of the model along each sweep; sampling-grid factors are left out",
    });
    if let Some(Value::Array(curves)) = v.get_mut("curves") {
        for (c, cm) in curves.iter_mut().zip(cms) {
            c["model_direction_px"] = json!(cm.direction);
            c["mtf50_model"] = freq(cm.mtf50_model_cy_px, o.pitch_mm);
            c["mtf50_measured_over_model"] = json!(cm.mtf50_ratio);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn column_goes_after_mtf() {
        let text = b"freq_cy_px,mtf,freq_lw_ph\n0.1,0.9,10\n0.2,0.8,20\n";
        let cm = CurveModel {
            direction: [1.0, 0.0],
            mtf_model: vec![0.95, 0.85],
            mtf50_model_cy_px: None,
            mtf50_ratio: None,
        };
        let out = String::from_utf8(add_mtf_model_column(text, &[cm])).unwrap();
        assert_eq!(
            out,
            "freq_cy_px,mtf,mtf_model,freq_lw_ph\n0.1,0.9,0.950000,10\n0.2,0.8,0.850000,20\n"
        );
    }
}
