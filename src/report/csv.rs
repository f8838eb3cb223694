//! CSV of a measurement: one row per MTF point (sweeps) or per patch (sine-patch
//! targets). Every column carries its unit in its name.

use crate::measure::Measurement;

/// Sensor frequency (cycles/mm) for a frequency in cycles/pixel, when the pitch (mm) is known.
fn cy_mm(f_px: f64, pitch_mm: Option<f64>) -> Option<f64> {
    pitch_mm.map(|p| f_px / p)
}

/// Line widths per picture height for a frequency in cycles/pixel.
pub fn lw_ph(f_px: f64, height_px: usize) -> f64 {
    2.0 * f_px * height_px as f64
}

fn num(v: f64) -> String {
    format!("{v:.6}")
}

/// The sweep curves as CSV: `freq_cy_px,mtf,[freq_cy_mm,]freq_lw_ph,modulation,mtf_err,aliased,jpeg_limited`
/// (+ `freq_chart_cy_mm` with a target, + `channel,sweep` when there are several curves,
/// + `rb_spread` with colour moiré: |MTF_R − MTF_B| on the red rows, empty on the others).
pub fn curves_csv(m: &Measurement) -> Vec<u8> {
    let pitch = m.pixel_pitch_mm;
    let several = m.curves.len() > 1;
    let chart_mm = m.curves.iter().any(|c| c.strip_unit == "mm");
    let mut w = csv::Writer::from_writer(Vec::new());
    let mut head = vec!["freq_cy_px", "mtf"];
    if pitch.is_some() {
        head.push("freq_cy_mm");
    }
    head.extend([
        "freq_lw_ph",
        "modulation",
        "mtf_err",
        "aliased",
        "jpeg_limited",
    ]);
    if chart_mm {
        head.push("freq_chart_cy_mm");
    }
    if several {
        head.extend(["channel", "sweep"]);
    }
    let moire = !m.colour_moire.is_empty();
    if moire {
        head.push("rb_spread");
    }
    let _ = w.write_record(&head);
    for c in &m.curves {
        // The R−B spread sits on the red rows (it is computed at red's points).
        let spread = m
            .colour_moire
            .iter()
            .find(|cm| c.channel == "r" && cm.sweep_id == c.sweep_id);
        for p in &c.points {
            let mut row = vec![num(p.freq_cy_px), num(p.mtf)];
            if let Some(f) = cy_mm(p.freq_cy_px, pitch) {
                row.push(num(f));
            }
            row.push(num(lw_ph(p.freq_cy_px, m.image_height)));
            row.push(num(p.modulation));
            row.push(num(p.mtf_err));
            row.push(p.aliased.to_string());
            row.push(p.jpeg_limited.to_string());
            if chart_mm {
                row.push(num(p.freq_chart));
            }
            if several {
                row.push(c.channel.clone());
                row.push(c.sweep_id.clone());
            }
            if moire {
                row.push(
                    spread
                        .and_then(|cm| cm.points.iter().find(|q| q.freq_cy_px == p.freq_cy_px))
                        .map(|q| num(q.spread))
                        .unwrap_or_default(),
                );
            }
            let _ = w.write_record(&row);
        }
    }
    w.into_inner().unwrap_or_default()
}

/// The sine patches as CSV, one row per patch.
pub fn patches_csv(m: &Measurement) -> Vec<u8> {
    let pitch = m.pixel_pitch_mm;
    let mut w = csv::Writer::from_writer(Vec::new());
    let mut head = vec!["patch", "freq_chart_cy_mm", "freq_cy_px", "mtf"];
    if pitch.is_some() {
        head.push("freq_cy_mm");
    }
    head.extend([
        "freq_lw_ph",
        "modulation",
        "chart_modulation",
        "mtf_err",
        "aliased",
        "channel",
    ]);
    let _ = w.write_record(&head);
    for p in &m.patches {
        let mut row = vec![
            p.patch_id.clone(),
            num(p.freq_chart_cy_mm),
            num(p.freq_cy_px),
            num(p.mtf),
        ];
        if let Some(f) = cy_mm(p.freq_cy_px, pitch) {
            row.push(num(f));
        }
        row.extend([
            num(lw_ph(p.freq_cy_px, m.image_height)),
            num(p.modulation),
            num(p.chart_modulation),
            num(p.mtf_err),
            p.aliased.to_string(),
            p.channel.clone(),
        ]);
        let _ = w.write_record(&row);
    }
    w.into_inner().unwrap_or_default()
}
