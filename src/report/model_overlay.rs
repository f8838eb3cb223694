//! Outputs of the model beside the measurement: the `mtf_model` column added
//! after `mtf` in the curves CSV, the model and EXIF fields of the JSON
//! summary, and the extras the MTF plot draws (dashed model curves, hollow
//! rings at the sine patches' model values, caption).

use crate::measure::Measurement;
use crate::measure::model_overlay::{
    CurveModel, ModelOverlay, PatchComparison, compare_patches, evaluate_patches, patch_direction,
};
use crate::photo::exif::ExifFacts;
use plotters::coord::Shift;
use plotters::coord::types::RangedCoordf64;
use plotters::prelude::*;
use serde_json::{Value, json};

/// A dashed model curve for the MTF plot.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct ModelCurve {
    /// Legend label ("model: `<name>`").
    pub label: String,
    /// (frequency cycles/pixel, MTF) samples.
    pub points: Vec<(f64, f64)>,
}

/// The model's value at one sine patch, drawn as a hollow ring.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PatchMark {
    /// The patch's measured image frequency (cycles/pixel).
    pub freq_cy_px: f64,
    /// Model MTF there (finite; dimensionless).
    pub mtf_model: f64,
    /// The patch lies above the sampling band (drawn grey like its measured point).
    pub aliased: bool,
}

/// What the MTF plot draws beyond the measurement.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct PlotExtras {
    /// Model curves, drawn dashed.
    pub model_curves: Vec<ModelCurve>,
    /// The model at each sine patch (one channel's patches; non-finite values left out).
    pub patch_marks: Vec<PatchMark>,
    /// A caption line under the plot (EXIF facts), empty for none.
    pub caption: String,
    /// Lens MTF curves (`--lens-mtf`), drawn solid in dark orange.
    pub lens_curves: Vec<ModelCurve>,
    /// Camera MTF curves (`--chart-mtf`: the print divided out), drawn solid in teal.
    pub chart_curves: Vec<ModelCurve>,
    /// The print's MTF against image frequency (`--chart-mtf`), drawn dashed in purple.
    pub print_curve: Option<ModelCurve>,
}

/// Plot extras: one dashed model curve per distinct sweep direction (0–1 cy/px),
/// one more per orientation of sine patches whose model differs from those
/// curves, a ring at each patch's model value, and the caption (EXIF facts,
/// model MTF50 and measured/model; for patch-only results the patch ratios).
pub fn plot_extras(
    model: Option<(&ModelOverlay, &[CurveModel])>,
    facts: Option<&ExifFacts>,
    m: &Measurement,
) -> PlotExtras {
    let mut curves: Vec<ModelCurve> = Vec::new();
    let mut patch_marks = Vec::new();
    let mut patch_cmp = None;
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
            curves.push(ModelCurve {
                label,
                points: sample(o, d),
            });
        }
        let values = evaluate_patches(m, o);
        patch_curves(o, m, &mut curves);
        patch_marks = marks(m, &values);
        patch_cmp = compare_patches(&m.patches, &values);
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
        if let Some(c) = &patch_cmp {
            t.push_str(&format!(
                "; patches measured/model median {:.3}",
                c.median_ratio
            ));
        }
        caption.push(t);
    } else if m.curves.is_empty()
        && let Some(c) = &patch_cmp
    {
        caption.push(patch_comparison_text(c, &m.patches));
    }
    PlotExtras {
        model_curves: curves,
        patch_marks,
        caption: caption.join("  ·  "),
        lens_curves: Vec::new(),
        chart_curves: Vec::new(),
        print_curve: None,
    }
}

/// The model along `d` at 401 frequencies from 0 to 1 cy/px.
fn sample(o: &ModelOverlay, d: [f64; 2]) -> Vec<(f64, f64)> {
    let n = 400;
    (0..=n)
        .map(|i| {
            let f = i as f64 / n as f64;
            (f, o.mtf_cy_px(d, f))
        })
        .collect()
}

/// Patches of the first channel (several channels share frequencies and model values).
fn first_channel(m: &Measurement) -> impl Iterator<Item = (usize, &crate::measure::PatchResult)> {
    let ch = m.patches.first().map(|p| p.channel.clone());
    m.patches
        .iter()
        .enumerate()
        .filter(move |(_, p)| Some(&p.channel) == ch.as_ref())
}

/// Adds a model curve for each orientation of the sine patches (sines within
/// 5° of each other share one) unless its values already lie on a curve (within
/// 0.002), so patch-only targets get the whole model curve through their rings.
fn patch_curves(o: &ModelOverlay, m: &Measurement, curves: &mut Vec<ModelCurve>) {
    let mut groups: Vec<([f64; 2], usize)> = Vec::new();
    for (_, p) in first_channel(m) {
        let d = patch_direction(p);
        // Sign does not matter for |OTF|: add d or −d, whichever points the group's way.
        match groups
            .iter_mut()
            .find(|(g, _)| (g[0] * d[1] - g[1] * d[0]).abs() < 0.087)
        {
            Some((g, n)) => {
                let s = if g[0] * d[0] + g[1] * d[1] < 0.0 {
                    -1.0
                } else {
                    1.0
                };
                g[0] += s * d[0];
                g[1] += s * d[1];
                *n += 1;
            }
            None => groups.push((d, 1)),
        }
    }
    for (g, _) in groups {
        let n = g[0].hypot(g[1]);
        if !(n.is_finite() && n > 0.0) {
            continue;
        }
        let d = [g[0] / n, g[1] / n];
        let points = sample(o, d);
        let known = curves.iter().any(|c| {
            c.points.len() == points.len()
                && c.points
                    .iter()
                    .zip(&points)
                    .all(|(a, b)| (a.1 - b.1).abs() < 2e-3)
        });
        if known {
            continue;
        }
        // On-screen angle of the sines, counter-clockwise from the image x axis, in 0–180°.
        let deg = (-d[1]).atan2(d[0]).to_degrees().rem_euclid(180.0);
        let label = if curves.is_empty() {
            format!("model: {}", o.name)
        } else {
            format!("model along patches at {deg:.0}°")
        };
        curves.push(ModelCurve { label, points });
    }
}

/// Rings for the first channel's patches with a finite model value.
fn marks(m: &Measurement, values: &[f64]) -> Vec<PatchMark> {
    first_channel(m)
        .filter_map(|(i, p)| {
            let v = *values.get(i)?;
            (v.is_finite() && p.freq_cy_px.is_finite()).then_some(PatchMark {
                freq_cy_px: p.freq_cy_px,
                mtf_model: v,
                aliased: p.aliased,
            })
        })
        .collect()
}

/// One phrase: "patches measured/model median 0.953 over 13 (2 left out), furthest 1.194 at patch 13 (0.406 cy/px)".
pub fn patch_comparison_text(
    c: &PatchComparison,
    patches: &[crate::measure::PatchResult],
) -> String {
    let mut t = format!(
        "patches measured/model median {:.3} over {}",
        c.median_ratio, c.n_used
    );
    if c.n_left_out > 0 {
        t.push_str(&format!(" ({} left out)", c.n_left_out));
    }
    if let Some(p) = patches.get(c.worst_index) {
        let several = patches.iter().any(|q| q.channel != p.channel);
        let ch = if several {
            format!("{} ", p.channel)
        } else {
            String::new()
        };
        t.push_str(&format!(
            ", furthest {:.3} at patch {ch}{} ({:.3} cy/px)",
            c.worst_ratio, p.patch_id, p.freq_cy_px
        ));
    }
    t
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

/// Draws the lens MTF curves (`--lens-mtf`) solid, dark orange then lighter, with small dots.
pub fn draw_lens_curves<'a, DB: DrawingBackend + 'a>(
    chart: &mut ChartContext<'a, DB, Cartesian2d<RangedCoordf64, RangedCoordf64>>,
    extras: &PlotExtras,
    xmax: f64,
    ymax: f64,
) -> Result<(), DrawingAreaErrorKind<DB::ErrorType>> {
    draw_solid(
        chart,
        &extras.lens_curves,
        [RGBColor(200, 90, 0), RGBColor(235, 160, 90)],
        xmax,
        ymax,
    )
}

/// Draws the camera MTF curves (`--chart-mtf`) solid, teal then lighter, and the print's MTF dashed purple.
pub fn draw_chart_curves<'a, DB: DrawingBackend + 'a>(
    chart: &mut ChartContext<'a, DB, Cartesian2d<RangedCoordf64, RangedCoordf64>>,
    extras: &PlotExtras,
    xmax: f64,
    ymax: f64,
) -> Result<(), DrawingAreaErrorKind<DB::ErrorType>> {
    if let Some(pc) = &extras.print_curve {
        let style = RGBColor(150, 60, 160).stroke_width(2);
        chart
            .draw_series(DashedLineSeries::new(
                pc.points
                    .iter()
                    .filter(|p| p.0 <= xmax)
                    .map(|&(f, v)| (f, v.clamp(0.0, ymax))),
                4,
                4,
                style,
            ))?
            .label(pc.label.clone())
            .legend(move |(x, y)| {
                EmptyElement::at((x, y))
                    + PathElement::new([(0, 0), (4, 0)], style)
                    + PathElement::new([(8, 0), (12, 0)], style)
                    + PathElement::new([(16, 0), (18, 0)], style)
            });
    }
    draw_solid(
        chart,
        &extras.chart_curves,
        [RGBColor(0, 130, 140), RGBColor(110, 190, 200)],
        xmax,
        ymax,
    )
}

/// Draws curves solid in the first colour, later ones in the second, clamped to 0..`ymax`.
fn draw_solid<'a, DB: DrawingBackend + 'a>(
    chart: &mut ChartContext<'a, DB, Cartesian2d<RangedCoordf64, RangedCoordf64>>,
    curves: &[ModelCurve],
    colours: [RGBColor; 2],
    xmax: f64,
    ymax: f64,
) -> Result<(), DrawingAreaErrorKind<DB::ErrorType>> {
    for (k, lc) in curves.iter().enumerate() {
        let col = colours[k.min(1)];
        let pts: Vec<(f64, f64)> = lc
            .points
            .iter()
            .filter(|p| p.0 <= xmax && p.1.is_finite())
            .map(|&(f, v)| (f, v.clamp(0.0, ymax)))
            .collect();
        chart
            .draw_series(LineSeries::new(pts, col.stroke_width(2)))?
            .label(lc.label.clone())
            .legend(move |(x, y)| PathElement::new([(x, y), (x + 18, y)], col.stroke_width(2)));
    }
    Ok(())
}

/// Legend colour of the rings at aliased patches (the grey of aliased measured points).
const ALIASED_GREY: RGBColor = RGBColor(160, 160, 160);

/// Draws a hollow ring at each patch's model value (black; grey for aliased
/// patches, like their measured points), clamped to 0..`ymax`, with one legend
/// entry "model at patches"; non-finite values were left out when the marks were made.
pub fn draw_patch_marks<'a, DB: DrawingBackend + 'a>(
    chart: &mut ChartContext<'a, DB, Cartesian2d<RangedCoordf64, RangedCoordf64>>,
    extras: &PlotExtras,
    xmax: f64,
    ymax: f64,
) -> Result<(), DrawingAreaErrorKind<DB::ErrorType>> {
    let shown: Vec<&PatchMark> = extras
        .patch_marks
        .iter()
        .filter(|k| k.freq_cy_px.is_finite() && k.mtf_model.is_finite() && k.freq_cy_px <= xmax)
        .collect();
    if shown.is_empty() {
        return Ok(());
    }
    let ring = |col: RGBColor| ShapeStyle::from(&col).stroke_width(2);
    chart
        .draw_series(shown.iter().map(|k| {
            let col = if k.aliased { ALIASED_GREY } else { BLACK };
            Circle::new((k.freq_cy_px, k.mtf_model.clamp(0.0, ymax)), 7, ring(col))
        }))?
        .label("model at patches")
        .legend(move |(x, y)| Circle::new((x + 9, y), 6, ring(BLACK)));
    Ok(())
}

/// Adds `model.patches_measured_over_model` (median, patches used and left
/// out, the furthest patch and its ratio) to a JSON summary that has `model`.
pub fn add_patch_comparison(
    v: &mut Value,
    c: &PatchComparison,
    patches: &[crate::measure::PatchResult],
) {
    let worst = patches.get(c.worst_index);
    v["model"]["patches_measured_over_model"] = json!({
        "median": c.median_ratio,
        "patches_used": c.n_used,
        "patches_left_out": c.n_left_out,
        "min_model_mtf": crate::measure::model_overlay::MIN_MODEL_FOR_RATIO,
        "furthest_patch": worst.map(|p| p.patch_id.clone()),
        "furthest_channel": worst.map(|p| p.channel.clone()),
        "furthest_ratio": c.worst_ratio,
    });
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
