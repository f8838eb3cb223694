//! The picture of `chart-check --plot`: the print's MTF against image
//! frequency (cycles/pixel) for the camera set-up, the levels 0.99 (sharp
//! enough), 0.9, 0.5 and 0.3 (compensation floor) as dotted lines with a mark
//! where the print falls through each, and Nyquist.

use super::atomic::ReportError;
use crate::chart::suitability::LevelReach;
use crate::measure::chart_mtf::ChartMtf;
use plotters::prelude::*;

const W: u32 = 900;
const H: u32 = 540;

fn err(e: impl std::fmt::Display) -> ReportError {
    ReportError::Plot {
        what: "the chart-check plot".into(),
        cause: e.to_string(),
    }
}

/// PNG bytes of the check: the print `chart` seen at `px_per_chart_mm`, with its `levels`.
pub fn chart_check_png(
    chart: &ChartMtf,
    px_per_chart_mm: f64,
    levels: &[LevelReach],
) -> Result<Vec<u8>, ReportError> {
    crate::plot::ensure_font();
    let mut buf = vec![255u8; (W * H * 3) as usize];
    {
        let root = BitMapBackend::with_buffer(&mut buf, (W, H)).into_drawing_area();
        root.fill(&WHITE).map_err(err)?;
        // Up to 1 cy/px, or further when the floor lies beyond it (capped at 4).
        let xmax = levels
            .iter()
            .filter_map(|r| r.cy_px.filter(|f| f.is_finite()))
            .fold(1.0f64, f64::max)
            .min(4.0)
            * 1.05;
        let mut c = ChartBuilder::on(&root)
            .caption(
                format!(
                    "print {} at {px_per_chart_mm:.2} px per chart mm",
                    chart.describe()
                ),
                (crate::plot::FONT, 20),
            )
            .margin(14)
            .x_label_area_size(46)
            .y_label_area_size(56)
            .build_cartesian_2d(0.0..xmax, 0.0..1.05)
            .map_err(err)?;
        c.configure_mesh()
            .x_desc(format!(
                "image frequency (cycles/pixel; 0.5 cy/px = {:.2} cy/mm on the print)",
                0.5 * px_per_chart_mm
            ))
            .y_desc("print MTF")
            .label_style((crate::plot::FONT, 14))
            .axis_desc_style((crate::plot::FONT, 15))
            .draw()
            .map_err(err)?;
        let grey = RGBColor(40, 40, 40);
        c.draw_series(LineSeries::new(
            [(0.5, 0.0), (0.5, 1.05)],
            grey.stroke_width(2),
        ))
        .map_err(err)?
        .label("Nyquist")
        .legend(move |(x, y)| PathElement::new([(x, y), (x + 18, y)], grey));
        let purple = RGBColor(150, 60, 160);
        let n = 400;
        let pts: Vec<(f64, f64)> = (0..=n)
            .filter_map(|i| {
                let f = xmax * i as f64 / n as f64;
                chart
                    .at(f * px_per_chart_mm)
                    .map(|(m, _)| (f, m.clamp(0.0, 1.05)))
            })
            .collect();
        c.draw_series(LineSeries::new(pts, purple.stroke_width(2)))
            .map_err(err)?
            .label("print MTF")
            .legend(move |(x, y)| PathElement::new([(x, y), (x + 18, y)], purple.stroke_width(2)));
        for r in levels {
            let col = if r.level >= 0.99 {
                RGBColor(0, 140, 60)
            } else if r.level <= 0.3 {
                RGBColor(200, 40, 40)
            } else {
                RGBColor(90, 90, 90)
            };
            c.draw_series(DashedLineSeries::new(
                [(0.0, r.level), (xmax, r.level)],
                3,
                4,
                col.stroke_width(1),
            ))
            .map_err(err)?;
            if let Some(f) = r.cy_px.filter(|f| f.is_finite() && *f <= xmax) {
                c.draw_series([Circle::new((f, r.level), 5, col.filled())])
                    .map_err(err)?;
                let what = if r.level >= 0.99 {
                    " sharp enough"
                } else if r.level <= 0.3 {
                    " compensation floor"
                } else {
                    ""
                };
                // Text above its dotted line; the top level's below it.
                let y = if r.level >= 0.99 {
                    r.level - 0.02
                } else {
                    r.level + 0.045
                };
                c.draw_series([Text::new(
                    format!("{}{what}: {f:.3} cy/px", r.level),
                    (f + 0.012 * xmax, y),
                    (crate::plot::FONT, 14).into_font().color(&col),
                )])
                .map_err(err)?;
            }
        }
        c.configure_series_labels()
            .background_style(WHITE.mix(0.9))
            .border_style(BLACK)
            .label_font((crate::plot::FONT, 14))
            .position(SeriesLabelPosition::UpperRight)
            .draw()
            .map_err(err)?;
        root.present().map_err(err)?;
    }
    crate::plot::encode_png(&buf, W, H).map_err(err)
}
