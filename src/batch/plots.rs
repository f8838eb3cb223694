//! Summary pictures: every shot's MTF curve overlaid (`curves.png`), and
//! MTF50 against f-number (`mtf50_vs_f_number.png`) when the shots carry
//! f-numbers, marking the sharpest aperture. Drawn with plotters into memory,
//! encoded as PNG and written atomically.

use super::record::ShotRecord;
use crate::plot::{FONT, ensure_font};
use plotters::prelude::*;

/// Picture size in pixels (width, height).
pub const SIZE: (u32, u32) = (960, 600);

/// Ten distinguishable colours (Tableau 10).
const TAB10: [(u8, u8, u8); 10] = [
    (31, 119, 180),
    (255, 127, 14),
    (44, 160, 44),
    (214, 39, 40),
    (148, 103, 189),
    (140, 86, 75),
    (227, 119, 194),
    (127, 127, 127),
    (188, 189, 34),
    (23, 190, 207),
];

/// Colour of curve `i` of `n`: Tableau 10 for few curves, a blue→yellow
/// ramp (in the curves' order) for many.
fn colour(i: usize, n: usize) -> RGBColor {
    if n <= TAB10.len() {
        let (r, g, b) = TAB10[i];
        return RGBColor(r, g, b);
    }
    let t = i as f64 / (n - 1).max(1) as f64;
    // Approximation of viridis through three anchors.
    let anchors = [
        (68.0, 1.0, 84.0),
        (33.0, 145.0, 140.0),
        (253.0, 231.0, 37.0),
    ];
    let (a, b, u) = if t < 0.5 {
        (anchors[0], anchors[1], t * 2.0)
    } else {
        (anchors[1], anchors[2], (t - 0.5) * 2.0)
    };
    let lerp = |x: f64, y: f64| (x + (y - x) * u).round() as u8;
    RGBColor(lerp(a.0, b.0), lerp(a.1, b.1), lerp(a.2, b.2))
}

/// Label of a shot in legends: `f/4 · stem` when the f-number is known.
fn label(r: &ShotRecord) -> String {
    match r.result.f_number {
        Some(n) => format!("f/{} · {}", fmt_fnumber(n), r.stem),
        None => r.stem.clone(),
    }
}

/// Standard f-numbers in third stops, as lenses mark them.
const F_STOPS: [f64; 37] = [
    1.0, 1.1, 1.2, 1.4, 1.6, 1.8, 2.0, 2.2, 2.5, 2.8, 3.2, 3.5, 4.0, 4.5, 5.0, 5.6, 6.3, 7.1, 8.0,
    9.0, 10.0, 11.0, 13.0, 14.0, 16.0, 18.0, 20.0, 22.0, 25.0, 29.0, 32.0, 36.0, 40.0, 45.0, 51.0,
    57.0, 64.0,
];

/// An f-number as photographers write it (4, 5.6, 11): the nearest marked
/// third stop when within 3 %, else one decimal.
pub fn fmt_fnumber(n: f64) -> String {
    let near = F_STOPS
        .iter()
        .copied()
        .min_by(|a, b| (a / n).ln().abs().total_cmp(&(b / n).ln().abs()))
        .filter(|s| (s / n - 1.0).abs() < 0.03);
    let s = format!("{:.1}", near.unwrap_or(n));
    s.trim_end_matches(".0").to_string()
}

/// Draws the overlay of `curves` (one shot's record and its unaliased
/// points each) as PNG bytes.
pub fn curves_png(curves: &[(&ShotRecord, Vec<(f64, f64)>)]) -> Result<Vec<u8>, String> {
    ensure_font();
    let mut buf = vec![255u8; (SIZE.0 * SIZE.1 * 3) as usize];
    let mut order: Vec<usize> = (0..curves.len()).collect();
    order.sort_by(|&a, &b| {
        let fa = curves[a].0.result.f_number.unwrap_or(f64::INFINITY);
        let fb = curves[b].0.result.f_number.unwrap_or(f64::INFINITY);
        fa.total_cmp(&fb)
            .then(curves[a].0.index.cmp(&curves[b].0.index))
    });
    let f_max = curves
        .iter()
        .flat_map(|(_, p)| p.iter().map(|q| q.0))
        .fold(0.5f64, f64::max)
        .min(1.0)
        * 1.02;
    let m_max = curves
        .iter()
        .flat_map(|(_, p)| p.iter().map(|q| q.1))
        .fold(1.0f64, f64::max)
        .min(2.0)
        * 1.05;
    {
        let root = BitMapBackend::with_buffer(&mut buf, SIZE).into_drawing_area();
        root.fill(&WHITE).map_err(|e| e.to_string())?;
        let title = format!(
            "MTF of {} shot{}",
            curves.len(),
            if curves.len() == 1 { "" } else { "s" }
        );
        let mut chart = ChartBuilder::on(&root)
            .caption(title, (FONT, 24))
            .margin(16)
            .x_label_area_size(48)
            .y_label_area_size(60)
            .build_cartesian_2d(0.0..f_max, 0.0..m_max)
            .map_err(|e| e.to_string())?;
        chart
            .configure_mesh()
            .x_desc("spatial frequency (cycles/pixel)")
            .y_desc("MTF")
            .label_style((FONT, 15))
            .axis_desc_style((FONT, 17))
            .light_line_style(RGBColor(235, 235, 235))
            .draw()
            .map_err(|e| e.to_string())?;
        // Reference lines: Nyquist and MTF50.
        let grey = RGBColor(120, 120, 120);
        chart
            .draw_series(DashedLineSeries::new(
                vec![(0.5, 0.0), (0.5, m_max)],
                6,
                4,
                grey.stroke_width(1),
            ))
            .map_err(|e| e.to_string())?;
        chart
            .draw_series(DashedLineSeries::new(
                vec![(0.0, 0.5), (f_max, 0.5)],
                6,
                4,
                grey.stroke_width(1),
            ))
            .map_err(|e| e.to_string())?;
        chart
            .draw_series(std::iter::once(Text::new(
                "Nyquist",
                (0.5 - f_max * 0.075, m_max * 0.985),
                (FONT, 14).into_font().color(&grey),
            )))
            .map_err(|e| e.to_string())?;
        // With many curves there is no legend: say what the colours mean.
        let fnums: Vec<f64> = curves.iter().filter_map(|c| c.0.result.f_number).collect();
        if curves.len() > TAB10.len() {
            let note = if fnums.len() == curves.len() {
                let lo = fnums.iter().copied().fold(f64::INFINITY, f64::min);
                let hi = fnums.iter().copied().fold(0.0, f64::max);
                format!(
                    "colour: f/{} (dark purple) → f/{} (yellow)",
                    fmt_fnumber(lo),
                    fmt_fnumber(hi)
                )
            } else {
                "colour: file order, dark purple → yellow".to_string()
            };
            chart
                .draw_series(std::iter::once(Text::new(
                    note,
                    (f_max * 0.02, m_max * 0.06),
                    (FONT, 14).into_font().color(&grey),
                )))
                .map_err(|e| e.to_string())?;
        }
        let legend = curves.len() <= 12;
        for (rank, &i) in order.iter().enumerate() {
            let (rec, pts) = &curves[i];
            let c = colour(rank, curves.len());
            let s = chart
                .draw_series(LineSeries::new(pts.iter().copied(), c.stroke_width(2)))
                .map_err(|e| e.to_string())?;
            if legend {
                s.label(label(rec)).legend(move |(x, y)| {
                    PathElement::new(vec![(x, y), (x + 20, y)], c.stroke_width(2))
                });
            }
        }
        if legend && !curves.is_empty() {
            chart
                .configure_series_labels()
                .position(SeriesLabelPosition::UpperRight)
                .background_style(WHITE.mix(0.85))
                .border_style(RGBColor(180, 180, 180))
                .label_font((FONT, 14))
                .draw()
                .map_err(|e| e.to_string())?;
        }
        root.present().map_err(|e| e.to_string())?;
    }
    crate::plot::encode_png(&buf, SIZE.0, SIZE.1)
}

/// Median of a non-empty slice.
fn median(v: &mut [f64]) -> f64 {
    v.sort_by(f64::total_cmp);
    let n = v.len();
    if n % 2 == 1 {
        v[n / 2]
    } else {
        0.5 * (v[n / 2 - 1] + v[n / 2])
    }
}

/// Per f-number medians of MTF50 (cy/px) of the ok shots, sorted by f-number;
/// f-numbers within 1 % count as the same aperture.
pub fn mtf50_by_f_number(records: &[ShotRecord]) -> Vec<(f64, f64, usize)> {
    let mut pts: Vec<(f64, f64)> = records
        .iter()
        .filter(|r| r.is_ok())
        .filter_map(|r| Some((r.result.f_number?, r.result.mtf50_cy_px?)))
        .filter(|(n, m)| n.is_finite() && *n > 0.0 && m.is_finite())
        .collect();
    pts.sort_by(|a, b| a.0.total_cmp(&b.0));
    let mut out = Vec::new();
    let mut i = 0;
    while i < pts.len() {
        let n0 = pts[i].0;
        let mut group: Vec<f64> = Vec::new();
        while i < pts.len() && pts[i].0 <= n0 * 1.01 {
            group.push(pts[i].1);
            i += 1;
        }
        let count = group.len();
        out.push((n0, median(&mut group), count));
    }
    out
}

/// Draws MTF50 against f-number (log axis) as PNG bytes; `None` when no ok
/// shot carries both an f-number and an MTF50.
pub fn mtf50_f_number_png(records: &[ShotRecord]) -> Result<Option<Vec<u8>>, String> {
    let groups = mtf50_by_f_number(records);
    if groups.is_empty() {
        return Ok(None);
    }
    ensure_font();
    let pts: Vec<(f64, f64)> = records
        .iter()
        .filter(|r| r.is_ok())
        .filter_map(|r| Some((r.result.f_number?, r.result.mtf50_cy_px?)))
        .filter(|(n, m)| n.is_finite() && *n > 0.0 && m.is_finite())
        .collect();
    // The x axis is in stops (log2 of the f-number squared), labelled as f-numbers.
    let stop = |n: f64| 2.0 * n.log2();
    let x_lo = stop(groups.first().map(|g| g.0).unwrap_or(1.0)) - 0.5;
    let x_hi = stop(groups.last().map(|g| g.0).unwrap_or(1.0)) + 0.5;
    let m_hi = pts.iter().map(|p| p.1).fold(0.0f64, f64::max).max(0.05) * 1.2;
    let best = groups
        .iter()
        .copied()
        .max_by(|a, b| a.1.total_cmp(&b.1))
        .expect("non-empty");
    let mut buf = vec![255u8; (SIZE.0 * SIZE.1 * 3) as usize];
    {
        let root = BitMapBackend::with_buffer(&mut buf, SIZE).into_drawing_area();
        root.fill(&WHITE).map_err(|e| e.to_string())?;
        let mut chart = ChartBuilder::on(&root)
            .caption("MTF50 against f-number", (FONT, 24))
            .margin(16)
            .x_label_area_size(48)
            .y_label_area_size(70)
            .build_cartesian_2d(x_lo..x_hi, 0.0..m_hi)
            .map_err(|e| e.to_string())?;
        chart
            .configure_mesh()
            .x_desc("f-number")
            .y_desc("MTF50 (cycles/pixel)")
            .x_labels(((x_hi - x_lo).ceil() as usize + 1).max(2))
            .x_label_formatter(&|x| format!("f/{}", fmt_fnumber(2f64.powf(x / 2.0))))
            .label_style((FONT, 15))
            .axis_desc_style((FONT, 17))
            .light_line_style(RGBColor(235, 235, 235))
            .draw()
            .map_err(|e| e.to_string())?;
        let blue = RGBColor(31, 119, 180);
        chart
            .draw_series(LineSeries::new(
                groups.iter().map(|g| (stop(g.0), g.1)),
                blue.stroke_width(2),
            ))
            .map_err(|e| e.to_string())?;
        chart
            .draw_series(
                pts.iter()
                    .map(|&(n, m)| Circle::new((stop(n), m), 4, blue.mix(0.6).filled())),
            )
            .map_err(|e| e.to_string())?;
        let red = RGBColor(214, 39, 40);
        chart
            .draw_series(std::iter::once(Circle::new(
                (stop(best.0), best.1),
                8,
                red.stroke_width(2),
            )))
            .map_err(|e| e.to_string())?;
        chart
            .draw_series(std::iter::once(Text::new(
                format!(
                    "sharpest: f/{} (MTF50 {:.3} cy/px)",
                    fmt_fnumber(best.0),
                    best.1
                ),
                (stop(best.0) - 0.3, best.1 + m_hi * 0.05),
                (FONT, 15).into_font().color(&red),
            )))
            .map_err(|e| e.to_string())?;
        root.present().map_err(|e| e.to_string())?;
    }
    crate::plot::encode_png(&buf, SIZE.0, SIZE.1).map(Some)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::batch::record::{ShotResult, Status};

    fn rec(i: usize, n: Option<f64>, m: Option<f64>, ok: bool) -> ShotRecord {
        ShotRecord {
            index: i,
            file: format!("{i}.jpg"),
            stem: format!("{i}"),
            status: if ok { Status::Ok } else { Status::Error },
            error_kind: None,
            error: None,
            result: ShotResult {
                f_number: n,
                mtf50_cy_px: m,
                ..Default::default()
            },
            run_time_s: 0.0,
        }
    }

    #[test]
    fn groups_f_numbers_with_medians_and_skips_errors() {
        let r = vec![
            rec(0, Some(4.0), Some(0.30), true),
            rec(1, Some(4.0), Some(0.20), true),
            rec(2, Some(4.0), Some(0.10), true),
            rec(3, Some(5.6), Some(0.35), true),
            rec(4, Some(8.0), Some(0.9), false),
            rec(5, None, Some(0.2), true),
        ];
        let g = mtf50_by_f_number(&r);
        assert_eq!(g, vec![(4.0, 0.20, 3), (5.6, 0.35, 1)]);
    }

    #[test]
    fn f_numbers_print_like_a_lens_ring() {
        assert_eq!(fmt_fnumber(4.0), "4");
        assert_eq!(fmt_fnumber(5.6), "5.6");
        assert_eq!(fmt_fnumber(11.0), "11");
        // 2^(5/2) = 5.66 and 2^(7/2) = 11.3 are marked 5.6 and 11.
        assert_eq!(fmt_fnumber(2f64.powf(2.5)), "5.6");
        assert_eq!(fmt_fnumber(2f64.powf(3.5)), "11");
        assert_eq!(fmt_fnumber(3.0), "3");
    }
}
