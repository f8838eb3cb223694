//! The MTF plot: each curve with its ±1σ error band (several colour channels
//! in their own hues, lighter for each further sweep), aliased points in grey,
//! the Nyquist frequency and MTF50 marked (with a sharpening peak, the peak
//! and MTF50P too, when MTF50P differs from MTF50); sine patches as points with error
//! bars; with a model, dashed model curves and a hollow ring at each patch's
//! model value; with colour moiré, a panel below for the R−B spread. PNG or SVG.

use super::atomic::ReportError;
use super::model_overlay::PlotExtras;
use crate::measure::Measurement;
use plotters::coord::Shift;
use plotters::prelude::*;

/// Plot output format.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum PlotFormat {
    /// PNG raster.
    Png,
    /// SVG vector.
    Svg,
}

const W: u32 = 1000;
const H: u32 = 620;
const COLOURS: [RGBColor; 4] = [
    RGBColor(31, 119, 180),
    RGBColor(214, 39, 40),
    RGBColor(44, 160, 44),
    RGBColor(148, 103, 189),
];

/// The luma curve among colour channels: near black.
const LUMA_COLOUR: RGBColor = RGBColor(40, 40, 40);
/// The colour-moiré panel: its height (pixels) and the spread's colour (magenta).
const MOIRE_H: i32 = 170;
const MOIRE_COLOUR: RGBColor = RGBColor(200, 30, 160);

/// One colour per curve. When the curves are several colour channels of a
/// photo or raw (`--channel all`), each takes its channel's hue (r red, g
/// green, b blue), lighter for each further sweep (in order of appearance:
/// the main sweep darkest), so channels and sweeps stay apart however many
/// there are; otherwise the palette in curve order.
fn curve_colours(curves: &[(&str, &str)]) -> Vec<RGBColor> {
    let hue = |ch: &str| match ch {
        "r" => Some(COLOURS[1]),
        "g" => Some(COLOURS[2]),
        "b" => Some(COLOURS[0]),
        "luma" => Some(LUMA_COLOUR),
        _ => None,
    };
    let mut channels: Vec<&str> = curves.iter().map(|c| c.0).collect();
    channels.sort_unstable();
    channels.dedup();
    let by_channel = channels.len() > 1 && channels.iter().all(|c| hue(c).is_some());
    if !by_channel {
        return (0..curves.len())
            .map(|k| COLOURS[k % COLOURS.len()])
            .collect();
    }
    let mut sweeps: Vec<&str> = Vec::new();
    for c in curves {
        if !sweeps.contains(&c.1) {
            sweeps.push(c.1);
        }
    }
    curves
        .iter()
        .map(|&(channel, sweep)| {
            let RGBColor(r, g, b) = hue(channel).unwrap_or(COLOURS[0]);
            let k = sweeps.iter().position(|s| *s == sweep).unwrap_or(0);
            // Full strength for the first sweep, then 60 % and 35 % (mixed with white).
            let f = [1.0, 0.6, 0.35][k.min(2)];
            let mix = |v: u8| (f * v as f64 + (1.0 - f) * 255.0).round() as u8;
            RGBColor(mix(r), mix(g), mix(b))
        })
        .collect()
}

fn err(e: impl std::fmt::Display) -> ReportError {
    ReportError::Plot {
        what: "the MTF plot".into(),
        cause: e.to_string(),
    }
}

/// Renders the MTF plot to bytes (PNG or SVG).
pub fn mtf_plot(m: &Measurement, format: PlotFormat) -> Result<Vec<u8>, ReportError> {
    mtf_plot_with(m, format, &PlotExtras::default())
}

/// Renders the MTF plot with extras (dashed model curves, a caption line) to bytes.
pub fn mtf_plot_with(
    m: &Measurement,
    format: PlotFormat,
    extras: &PlotExtras,
) -> Result<Vec<u8>, ReportError> {
    crate::plot::ensure_font();
    match format {
        PlotFormat::Svg => {
            let mut s = String::new();
            {
                let root = SVGBackend::with_string(&mut s, (W, H)).into_drawing_area();
                draw(&root, m, extras)?;
                root.present().map_err(err)?;
            }
            Ok(s.into_bytes())
        }
        PlotFormat::Png => {
            let mut buf = vec![255u8; (W * H * 3) as usize];
            {
                let root = BitMapBackend::with_buffer(&mut buf, (W, H)).into_drawing_area();
                draw(&root, m, extras)?;
                root.present().map_err(err)?;
            }
            crate::plot::encode_png(&buf, W, H).map_err(err)
        }
    }
}

fn draw<DB: DrawingBackend>(
    root: &DrawingArea<DB, Shift>,
    m: &Measurement,
    extras: &PlotExtras,
) -> Result<(), ReportError>
where
    DB::ErrorType: 'static,
{
    root.fill(&WHITE).map_err(err)?;
    let fmax_data = m
        .curves
        .iter()
        .flat_map(|c| c.points.iter().map(|p| p.freq_cy_px))
        .chain(m.patches.iter().map(|p| p.freq_cy_px))
        .fold(0.0, f64::max);
    let xmax = (fmax_data * 1.02).clamp(0.55, 1.0);
    let ymax = m
        .curves
        .iter()
        .flat_map(|c| c.points.iter().filter(|p| !p.aliased).map(|p| p.mtf))
        .chain(m.patches.iter().map(|p| p.mtf))
        .chain(
            extras
                .lens_curves
                .iter()
                .chain(&extras.chart_curves)
                .flat_map(|c| c.points.iter().map(|p| p.1)),
        )
        .fold(1.05, f64::max);
    // Room above a sharpening peak for its label.
    let ymax = if ymax > 1.05 { ymax + 0.1 } else { ymax }.min(1.6);
    let name = std::path::Path::new(&m.source)
        .file_name()
        .map(|n| n.to_string_lossy().into_owned())
        .unwrap_or_default();
    let title = format!("MTF of {name} ({} method)", m.method.name());
    let xlabel = match m.pixel_pitch_mm {
        Some(p) => format!(
            "spatial frequency (cycles/pixel; 0.5 cy/px = {:.1} lp/mm at {:.2} µm pitch)",
            0.5 / p,
            p * 1e3
        ),
        None => "spatial frequency (cycles/pixel)".to_string(),
    };
    let root = &super::model_overlay::caption_area(root, &extras.caption).map_err(err)?;
    // With colour moiré, a panel below the MTF for the R−B spread.
    let moire = m.colour_moire.iter().any(|c| !c.points.is_empty());
    let (upper, lower) = if moire {
        let h = root.dim_in_pixel().1 as i32;
        let (a, b) = root.split_vertically(h - MOIRE_H);
        (a, Some(b))
    } else {
        (root.clone(), None)
    };
    let root = &upper;
    let mut chart = ChartBuilder::on(root)
        .caption(title, (crate::plot::FONT, 22))
        .margin(14)
        .x_label_area_size(46)
        .y_label_area_size(56)
        .build_cartesian_2d(0.0..xmax, 0.0..ymax)
        .map_err(err)?;
    chart
        .configure_mesh()
        .x_desc(xlabel)
        .y_desc("MTF")
        .label_style((crate::plot::FONT, 15))
        .axis_desc_style((crate::plot::FONT, 16))
        .draw()
        .map_err(err)?;
    // Nyquist.
    chart
        .draw_series(LineSeries::new(
            [(0.5, 0.0), (0.5, ymax)],
            ShapeStyle::from(&RGBColor(120, 120, 120)).stroke_width(1),
        ))
        .map_err(err)?
        .label("Nyquist (0.5 cy/px)")
        .legend(|(x, y)| PathElement::new([(x, y), (x + 18, y)], RGBColor(120, 120, 120)));
    let mut aliased_in_legend = false;
    let mut limited_in_legend = false;
    let names: Vec<(&str, &str)> = m
        .curves
        .iter()
        .map(|c| (c.channel.as_str(), c.sweep_id.as_str()))
        .collect();
    let colours = curve_colours(&names);
    // Every curve's aliased points first, so that no curve's grey dots cover
    // another curve's line (the greens reach Nyquist where R and B alias).
    for c in &m.curves {
        // Aliased points beyond the axis are left off rather than piled at its edge.
        let aliased: Vec<_> = c
            .points
            .iter()
            .filter(|p| p.aliased && p.freq_cy_px <= xmax)
            .collect();
        // One legend entry for the grey dots of every curve.
        let grey = RGBColor(160, 160, 160).filled();
        let dots = PointMarks {
            radius: 2,
            style: grey,
            label: "aliased (not MTF)",
            legend: grey,
        };
        draw_point_marks(&mut chart, &aliased, ymax, &dots, &mut aliased_in_legend)?;
    }
    for (k, c) in m.curves.iter().enumerate() {
        let col = colours[k];
        let good: Vec<_> = c.points.iter().filter(|p| !p.aliased).collect();
        // Error band.
        if good.len() >= 2 {
            let mut poly: Vec<(f64, f64)> = good
                .iter()
                .map(|p| (p.freq_cy_px, (p.mtf + p.mtf_err).min(ymax)))
                .collect();
            poly.extend(
                good.iter()
                    .rev()
                    .map(|p| (p.freq_cy_px, (p.mtf - p.mtf_err).max(0.0))),
            );
            chart
                .draw_series(std::iter::once(Polygon::new(poly, col.mix(0.25).filled())))
                .map_err(err)?;
        }
        let label = if m.curves.len() > 1 {
            format!("{}/{}", c.channel, c.sweep_id)
        } else {
            "MTF".to_string()
        };
        chart
            .draw_series(LineSeries::new(
                good.iter().map(|p| (p.freq_cy_px, p.mtf.min(ymax))),
                col.stroke_width(2),
            ))
            .map_err(err)?
            .label(label)
            .legend(move |(x, y)| PathElement::new([(x, y), (x + 18, y)], col.stroke_width(2)));
        if let Some(f50) = c.figures.mtf50_cy_px {
            chart
                .draw_series([
                    PathElement::new([(f50, 0.0), (f50, 0.5)], col.stroke_width(1)),
                    PathElement::new([(0.0, 0.5), (f50, 0.5)], col.stroke_width(1)),
                ])
                .map_err(err)?;
            chart
                .draw_series(std::iter::once(Text::new(
                    format!("MTF50 = {f50:.3} cy/px"),
                    // One label line per curve, stacked, so several rows stay readable.
                    (f50 + 0.01, 0.53 + 0.05 * k as f64),
                    (crate::plot::FONT, 15).into_font().color(&col),
                )))
                .map_err(err)?;
        }
        draw_peak_marks(&mut chart, c, col, k, ymax)?;
        // Points whose value is more the JPEG quantiser's than the lens's:
        // a hollow ring in the curve's colour, one legend entry for all curves.
        let limited: Vec<_> = good
            .iter()
            .copied()
            .filter(|p| p.jpeg_limited && p.freq_cy_px <= xmax)
            .collect();
        let rings = PointMarks {
            radius: 3,
            style: col.stroke_width(1),
            label: "JPEG-limited (the file's, not the lens's)",
            legend: BLACK.stroke_width(1),
        };
        draw_point_marks(&mut chart, &limited, ymax, &rings, &mut limited_in_legend)?;
    }
    super::model_overlay::draw_model_curves(&mut chart, extras, xmax, ymax).map_err(err)?;
    super::model_overlay::draw_lens_curves(&mut chart, extras, xmax, ymax).map_err(err)?;
    super::model_overlay::draw_chart_curves(&mut chart, extras, xmax, ymax).map_err(err)?;
    if !m.patches.is_empty() {
        let col = RGBColor(230, 120, 20);
        // Patches beyond the axis (aliased, far above Nyquist) are left off rather than pinned to its edge.
        let shown: Vec<_> = m
            .patches
            .iter()
            .filter(|p| p.freq_cy_px.is_finite() && p.freq_cy_px <= xmax && p.mtf.is_finite())
            .collect();
        chart
            .draw_series(shown.iter().map(|p| {
                PathElement::new(
                    [
                        (p.freq_cy_px, (p.mtf - p.mtf_err).max(0.0)),
                        (p.freq_cy_px, (p.mtf + p.mtf_err).min(ymax)),
                    ],
                    col.stroke_width(2),
                )
            }))
            .map_err(err)?;
        chart
            .draw_series(shown.iter().map(|p| {
                let c = if p.aliased {
                    RGBColor(160, 160, 160)
                } else {
                    col
                };
                Circle::new((p.freq_cy_px, p.mtf.min(ymax)), 4, c.filled())
            }))
            .map_err(err)?
            .label("sine patches")
            .legend(move |(x, y)| Circle::new((x + 9, y), 4, col.filled()));
        if !aliased_in_legend && m.patches.iter().any(|p| p.aliased) {
            chart
                .draw_series(std::iter::empty::<Circle<(f64, f64), i32>>())
                .map_err(err)?
                .label("aliased (not MTF)")
                .legend(|(x, y)| Circle::new((x + 9, y), 4, RGBColor(160, 160, 160).filled()));
        }
    }
    super::model_overlay::draw_patch_marks(&mut chart, extras, xmax, ymax).map_err(err)?;
    chart
        .configure_series_labels()
        .label_font((crate::plot::FONT, 15))
        .background_style(WHITE.mix(0.85))
        .border_style(BLACK)
        .position(SeriesLabelPosition::UpperRight)
        .draw()
        .map_err(err)?;
    if let Some(lower) = &lower {
        draw_moire_panel(lower, m, xmax)?;
    }
    Ok(())
}

/// The colour-moiré panel: the R−B spread |MTF_R − MTF_B| of each sweep (thin
/// magenta line over its ±1σ band), the onset threshold (dotted) and the
/// onset (a vertical line with its label).
fn draw_moire_panel<DB: DrawingBackend>(
    area: &DrawingArea<DB, Shift>,
    m: &Measurement,
    xmax: f64,
) -> Result<(), ReportError>
where
    DB::ErrorType: 'static,
{
    use crate::measure::moire::ONSET_SPREAD;
    let top = m
        .colour_moire
        .iter()
        .flat_map(|c| c.points.iter().filter(|p| p.freq_cy_px <= xmax))
        .map(|p| p.spread)
        .fold(2.0 * ONSET_SPREAD, f64::max);
    let ymax = (1.15 * top).min(1.5);
    let mut chart = ChartBuilder::on(area)
        .margin_left(14)
        .margin_right(14)
        .margin_bottom(6)
        .x_label_area_size(30)
        .y_label_area_size(56)
        .build_cartesian_2d(0.0..xmax, 0.0..ymax)
        .map_err(err)?;
    chart
        .configure_mesh()
        .y_desc("|MTF_R − MTF_B|")
        .y_labels(4)
        .label_style((crate::plot::FONT, 13))
        .axis_desc_style((crate::plot::FONT, 14))
        .draw()
        .map_err(err)?;
    let grey = RGBColor(120, 120, 120);
    chart
        .draw_series(DashedLineSeries::new(
            [(0.0, ONSET_SPREAD), (xmax, ONSET_SPREAD)],
            3,
            4,
            grey.stroke_width(1),
        ))
        .map_err(err)?;
    for (k, c) in m.colour_moire.iter().enumerate() {
        let col = if k == 0 {
            MOIRE_COLOUR
        } else {
            let f = [1.0, 0.6, 0.35][k.min(2)];
            let mix = |v: u8| (f * v as f64 + (1.0 - f) * 255.0).round() as u8;
            RGBColor(
                mix(MOIRE_COLOUR.0),
                mix(MOIRE_COLOUR.1),
                mix(MOIRE_COLOUR.2),
            )
        };
        let pts: Vec<_> = c.points.iter().filter(|p| p.freq_cy_px <= xmax).collect();
        if pts.len() >= 2 {
            let mut poly: Vec<(f64, f64)> = pts
                .iter()
                .map(|p| (p.freq_cy_px, (p.spread + p.spread_err).min(ymax)))
                .collect();
            poly.extend(
                pts.iter()
                    .rev()
                    .map(|p| (p.freq_cy_px, (p.spread - p.spread_err).max(0.0))),
            );
            chart
                .draw_series(std::iter::once(Polygon::new(poly, col.mix(0.2).filled())))
                .map_err(err)?;
        }
        let label = if m.colour_moire.len() > 1 {
            format!("R−B spread {}", c.sweep_id)
        } else {
            "R−B spread (colour moiré)".to_string()
        };
        chart
            .draw_series(LineSeries::new(
                pts.iter().map(|p| (p.freq_cy_px, p.spread.min(ymax))),
                col.stroke_width(1),
            ))
            .map_err(err)?
            .label(label)
            .legend(move |(x, y)| PathElement::new([(x, y), (x + 18, y)], col.stroke_width(2)));
        let text = match c.onset_cy_px {
            Some(f) => {
                chart
                    .draw_series(std::iter::once(PathElement::new(
                        [(f, 0.0), (f, ymax)],
                        col.stroke_width(1),
                    )))
                    .map_err(err)?;
                format!("onset {f:.3} cy/px")
            }
            None => "no onset".to_string(),
        };
        let max = match (c.max_spread, c.max_at_cy_px) {
            (Some(v), Some(f)) => format!(", max {v:.3} at {f:.3} cy/px"),
            _ => String::new(),
        };
        chart
            .draw_series(std::iter::once(Text::new(
                format!("{text}{max}"),
                (0.01 * xmax, ymax * (0.93 - 0.16 * k as f64)),
                (crate::plot::FONT, 14).into_font().color(&col),
            )))
            .map_err(err)?;
    }
    chart
        .configure_series_labels()
        .label_font((crate::plot::FONT, 13))
        .background_style(WHITE.mix(0.85))
        .border_style(BLACK)
        .position(SeriesLabelPosition::UpperRight)
        .draw()
        .map_err(err)?;
    Ok(())
}

/// Smallest |MTF50P − MTF50| (cy/px) for which MTF50P gets its own mark.
const MTF50P_MARK_MIN: f64 = 0.002;

/// With a sharpening peak: an open circle at the peak, and a filled diamond at
/// (MTF50P, half the peak) with its label above, when MTF50P differs from MTF50.
/// How [`draw_point_marks`] marks points: circles of `radius` px in `style`,
/// listed once in the legend as `label` with a 3-px circle in `legend`.
struct PointMarks {
    radius: i32,
    style: ShapeStyle,
    label: &'static str,
    legend: ShapeStyle,
}

/// Marks `points` as `marks` says (their MTF clamped to 0–`ymax`), and gives
/// them the legend entry unless `in_legend` says an earlier curve did.
fn draw_point_marks<DB: DrawingBackend>(
    chart: &mut ChartContext<
        '_,
        DB,
        Cartesian2d<plotters::coord::types::RangedCoordf64, plotters::coord::types::RangedCoordf64>,
    >,
    points: &[&crate::measure::MtfPoint],
    ymax: f64,
    marks: &PointMarks,
    in_legend: &mut bool,
) -> Result<(), ReportError>
where
    DB::ErrorType: 'static,
{
    if points.is_empty() {
        return Ok(());
    }
    let drawn = chart
        .draw_series(points.iter().map(|p| {
            Circle::new(
                (p.freq_cy_px, p.mtf.clamp(0.0, ymax)),
                marks.radius,
                marks.style,
            )
        }))
        .map_err(err)?;
    if !*in_legend {
        *in_legend = true;
        let legend = marks.legend;
        drawn
            .label(marks.label)
            .legend(move |(x, y)| Circle::new((x + 9, y), 3, legend));
    }
    Ok(())
}

fn draw_peak_marks<DB: DrawingBackend>(
    chart: &mut ChartContext<
        '_,
        DB,
        Cartesian2d<plotters::coord::types::RangedCoordf64, plotters::coord::types::RangedCoordf64>,
    >,
    c: &crate::measure::Curve,
    col: RGBColor,
    k: usize,
    ymax: f64,
) -> Result<(), ReportError>
where
    DB::ErrorType: 'static,
{
    let g = &c.figures;
    let (true, Some(pk), Some(fpk), Some(f50p)) =
        (g.sharpening_peak, g.peak_mtf, g.peak_cy_px, g.mtf50p_cy_px)
    else {
        return Ok(());
    };
    if g.mtf50_cy_px
        .is_some_and(|f50| (f50 - f50p).abs() < MTF50P_MARK_MIN)
    {
        return Ok(());
    }
    let font = (crate::plot::FONT, 15).into_font().color(&col);
    let half = 0.5 * pk;
    chart
        .draw_series([
            PathElement::new([(f50p, 0.0), (f50p, half)], col.mix(0.7).stroke_width(1)),
            PathElement::new([(fpk, half), (f50p, half)], col.mix(0.7).stroke_width(1)),
        ])
        .map_err(err)?;
    chart
        .draw_series(std::iter::once(Circle::new(
            (fpk, pk.min(ymax)),
            5,
            col.stroke_width(2),
        )))
        .map_err(err)?;
    chart
        .draw_series(std::iter::once(
            EmptyElement::at((f50p, half))
                + Polygon::new(vec![(0, -6), (6, 0), (0, 6), (-6, 0)], col.filled()),
        ))
        .map_err(err)?;
    chart
        .draw_series([
            Text::new(
                format!("MTF50P = {f50p:.3} cy/px"),
                (f50p + 0.01, (half + 0.05 + 0.05 * k as f64).min(ymax)),
                font.clone(),
            ),
            Text::new(
                format!("peak {pk:.3} at {fpk:.3} cy/px"),
                (fpk + 0.01, (pk + 0.04).min(ymax - 0.02)),
                font,
            ),
        ])
        .map_err(err)?;
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn colour_channels_keep_their_hue_and_sweeps_get_lighter() {
        let c = curve_colours(&[
            ("r", "main"),
            ("r", "c0.4"),
            ("g", "main"),
            ("g", "c0.4"),
            ("b", "main"),
            ("b", "c0.2"),
        ]);
        // Main sweeps: the pure hues.
        assert_eq!(c[0], RGBColor(214, 39, 40));
        assert_eq!(c[2], RGBColor(44, 160, 44));
        assert_eq!(c[4], RGBColor(31, 119, 180));
        // Further sweeps: the same hue mixed with white (60 %, then 35 %).
        assert_eq!(c[1], RGBColor(230, 125, 126));
        assert_eq!(c[3], RGBColor(128, 198, 128));
        assert_eq!(c[5], RGBColor(177, 207, 229));
        // Every curve its own colour.
        for i in 0..c.len() {
            for j in 0..i {
                assert_ne!(c[i], c[j], "{i} {j}");
            }
        }
    }

    #[test]
    fn one_channel_or_unknown_channels_use_the_palette() {
        assert_eq!(
            curve_colours(&[("luma", "main"), ("luma", "c0.4")]),
            vec![COLOURS[0], COLOURS[1]]
        );
        assert_eq!(
            curve_colours(&[("g", "main"), ("g", "c0.4")]),
            vec![COLOURS[0], COLOURS[1]]
        );
        assert_eq!(
            curve_colours(&[("r", "main"), ("grey", "main")]),
            vec![COLOURS[0], COLOURS[1]]
        );
    }
}
