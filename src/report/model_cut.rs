//! A 1-D cut through the model (`sweepmtf model --cut u|v|deg=θ`): the total
//! MTF and each factor's MTF along a ray from the origin, as CSV and as a
//! plot (PNG, or SVG by extension) with the Nyquist frequency marked when the
//! system has a sampling grid.

use super::model_io::{OutputError, encode_png, factor_columns, fmt_f64, write_atomic};
use crate::model::System;
use crate::plot::{FONT, ensure_font};
use num_complex::Complex64;
use plotters::prelude::*;
use std::path::Path;

/// The direction of a cut in the (u, v) plane.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum CutDirection {
    /// Along u (v = 0).
    U,
    /// Along v (u = 0).
    V,
    /// At θ degrees from the u axis, counter-clockwise.
    Deg(f64),
}

impl CutDirection {
    /// Parses `u`, `v` or `deg=θ`.
    pub fn parse(text: &str) -> Result<CutDirection, String> {
        match text.trim() {
            "u" => Ok(CutDirection::U),
            "v" => Ok(CutDirection::V),
            t => match t.strip_prefix("deg=").map(|d| d.trim().parse::<f64>()) {
                Some(Ok(d)) if d.is_finite() => Ok(CutDirection::Deg(d)),
                _ => Err(format!(
                    "'{t}' is not a cut direction; allowed: u, v, deg=<angle in degrees>"
                )),
            },
        }
    }

    /// Unit vector (cos θ, sin θ), exact on the axes.
    pub fn unit(&self) -> (f64, f64) {
        match *self {
            CutDirection::U => (1.0, 0.0),
            CutDirection::V => (0.0, 1.0),
            CutDirection::Deg(d) => {
                let r = d.rem_euclid(360.0);
                match r {
                    0.0 => (1.0, 0.0),
                    90.0 => (0.0, 1.0),
                    180.0 => (-1.0, 0.0),
                    270.0 => (0.0, -1.0),
                    _ => {
                        let (s, c) = r.to_radians().sin_cos();
                        (c, s)
                    }
                }
            }
        }
    }

    /// Short label for plots ("u", "v", "30°").
    pub fn label(&self) -> String {
        match *self {
            CutDirection::U => "u (v = 0)".into(),
            CutDirection::V => "v (u = 0)".into(),
            CutDirection::Deg(d) => format!("{d}° from u"),
        }
    }
}

/// A cut: frequencies along the ray and the OTF values there.
#[derive(Debug, Clone)]
pub struct Cut {
    /// Direction of the ray.
    pub direction: CutDirection,
    /// Radial frequency along the ray, cycles/mm.
    pub freq: Vec<f64>,
    /// (u, v) of each sample, cycles/mm.
    pub uv: Vec<(f64, f64)>,
    /// Total OTF per sample.
    pub otf: Vec<Complex64>,
    /// Per factor: its name and MTF per sample.
    pub factors: Vec<(String, Vec<f64>)>,
    /// Nyquist frequency along the ray, cycles/mm, if the system has a grid.
    pub nyquist: Option<f64>,
}

/// The highest frequency a cut or map may reach, cycles/mm (one cycle per
/// nanometre: beyond any optics or pixel; larger values only make the plot's
/// axis arithmetic overflow).
pub const F_MAX_LIMIT_CY_MM: f64 = 1e6;

/// The most samples a cut may have (its CSV is then about 100 MB).
pub const POINTS_LIMIT: usize = 1_000_000;

/// Evaluates `system` at `n` ≥ 2 equally spaced frequencies 0..=f_max along `dir`.
pub fn compute_cut(system: &System, dir: CutDirection, f_max: f64, n: usize) -> Cut {
    let n = n.max(2);
    let (cu, cv) = dir.unit();
    let freq: Vec<f64> = (0..n).map(|i| f_max * i as f64 / (n - 1) as f64).collect();
    let uv: Vec<(f64, f64)> = freq.iter().map(|&f| (f * cu, f * cv)).collect();
    let mut otf = vec![Complex64::new(1.0, 0.0); n];
    let mut factors = Vec::new();
    for fac in &system.factors {
        let vals: Vec<Complex64> = uv.iter().map(|&(u, v)| fac.otf(u, v)).collect();
        for (t, o) in otf.iter_mut().zip(&vals) {
            *t *= o;
        }
        factors.push((fac.name(), vals.iter().map(|o| o.norm()).collect()));
    }
    let nyquist = system.nyquist().and_then(|(nu, nv)| {
        let a = if cu != 0.0 {
            nu / cu.abs()
        } else {
            f64::INFINITY
        };
        let b = if cv != 0.0 {
            nv / cv.abs()
        } else {
            f64::INFINITY
        };
        let f = a.min(b);
        f.is_finite().then_some(f)
    });
    Cut {
        direction: dir,
        freq,
        uv,
        otf,
        factors,
        nyquist,
    }
}

/// CSV text of a cut: `freq_cy_mm,u_cy_mm,v_cy_mm,otf_re,otf_im,mtf,mtf_<factor>…`.
pub fn cut_csv(cut: &Cut) -> String {
    let names: Vec<String> = cut.factors.iter().map(|(n, _)| n.clone()).collect();
    let mut out = String::from("freq_cy_mm,u_cy_mm,v_cy_mm,otf_re,otf_im,mtf");
    for c in factor_columns(&names) {
        out.push(',');
        out.push_str(&c);
    }
    out.push('\n');
    for i in 0..cut.freq.len() {
        let (u, v) = cut.uv[i];
        let o = cut.otf[i];
        let row = [cut.freq[i], u, v, o.re, o.im, o.norm()]
            .map(fmt_f64)
            .join(",");
        out.push_str(&row);
        for (_, vals) in &cut.factors {
            out.push(',');
            out.push_str(&fmt_f64(vals[i]));
        }
        out.push('\n');
    }
    out
}

/// Writes the cut's CSV to `path`, atomically.
pub fn write_cut_csv(cut: &Cut, path: &Path) -> Result<(), OutputError> {
    write_atomic(path, cut_csv(cut).as_bytes())
}

/// Line colours for the factors (the total is black).
const PALETTE: [RGBColor; 8] = [
    RGBColor(31, 119, 180),
    RGBColor(255, 127, 14),
    RGBColor(44, 160, 44),
    RGBColor(214, 39, 40),
    RGBColor(148, 103, 189),
    RGBColor(140, 86, 75),
    RGBColor(227, 119, 194),
    RGBColor(23, 190, 207),
];

/// Plot size in pixels.
const SIZE: (u32, u32) = (1000, 640);

fn draw<DB: DrawingBackend>(
    root: DrawingArea<DB, plotters::coord::Shift>,
    cut: &Cut,
    title: &str,
) -> Result<(), String>
where
    DB::ErrorType: 'static,
{
    let e = |e: DrawingAreaErrorKind<DB::ErrorType>| e.to_string();
    root.fill(&WHITE).map_err(e)?;
    let f_max = cut
        .freq
        .last()
        .copied()
        .unwrap_or(1.0)
        .max(f64::MIN_POSITIVE);
    let mut chart = ChartBuilder::on(&root)
        .caption(title, (FONT, 24))
        .margin(16)
        .margin_right(32)
        .x_label_area_size(50)
        .y_label_area_size(60)
        .build_cartesian_2d(0.0..f_max, 0.0..1.05f64)
        .map_err(e)?;
    chart
        .configure_mesh()
        .x_desc(format!(
            "spatial frequency along {} (lp/mm)",
            cut.direction.label()
        ))
        .y_desc("MTF")
        .label_style((FONT, 16))
        .axis_desc_style((FONT, 18))
        .light_line_style(RGBColor(244, 244, 244))
        .bold_line_style(RGBColor(210, 210, 210))
        .draw()
        .map_err(e)?;
    // Solid curves first, then every second factor dashed on top of them,
    // so that coinciding curves stay visible.
    let order = (0..cut.factors.len())
        .filter(|k| k % 2 == 0)
        .chain((0..cut.factors.len()).filter(|k| k % 2 == 1));
    for k in order {
        let (name, vals) = &cut.factors[k];
        let colour = PALETTE[k % PALETTE.len()];
        let style = ShapeStyle::from(&colour).stroke_width(2);
        let pts = cut.freq.iter().copied().zip(vals.iter().copied());
        if k % 2 == 1 {
            chart
                .draw_series(DashedLineSeries::new(pts, 10, 6, style))
                .map_err(e)?
                .label(name.clone())
                .legend(move |(x, y)| {
                    EmptyElement::at((x, y))
                        + PathElement::new(vec![(0, 0), (9, 0)], style)
                        + PathElement::new(vec![(15, 0), (24, 0)], style)
                });
        } else {
            chart
                .draw_series(LineSeries::new(pts, style))
                .map_err(e)?
                .label(name.clone())
                .legend(move |(x, y)| PathElement::new(vec![(x, y), (x + 24, y)], style));
        }
    }
    if !cut.factors.is_empty() {
        let style = ShapeStyle::from(&BLACK).stroke_width(2);
        chart
            .draw_series(LineSeries::new(
                cut.freq
                    .iter()
                    .copied()
                    .zip(cut.otf.iter().map(|o| o.norm())),
                style,
            ))
            .map_err(e)?
            .label("total")
            .legend(move |(x, y)| PathElement::new(vec![(x, y), (x + 24, y)], style));
    }
    if let Some(ny) = cut.nyquist.filter(|&n| n <= f_max) {
        let style = ShapeStyle::from(&RGBColor(90, 90, 90)).stroke_width(2);
        chart
            .draw_series(DashedLineSeries::new(
                vec![(ny, 0.0), (ny, 1.05)],
                8,
                6,
                style,
            ))
            .map_err(e)?;
        chart
            .draw_series(std::iter::once(Text::new(
                format!("Nyquist {ny:.1} lp/mm"),
                (ny + f_max * 0.008, 1.0),
                (FONT, 16).into_font().color(&RGBColor(60, 60, 60)),
            )))
            .map_err(e)?;
    }
    chart
        .configure_series_labels()
        .position(SeriesLabelPosition::UpperRight)
        .label_font((FONT, 16))
        .border_style(RGBColor(160, 160, 160))
        .background_style(WHITE.mix(0.9))
        .draw()
        .map_err(e)?;
    root.present().map_err(e)?;
    Ok(())
}

/// Draws the cut (total and each factor) to `path`: SVG if it ends in `.svg`, else PNG.
pub fn plot_cut(cut: &Cut, title: &str, path: &Path) -> Result<(), OutputError> {
    write_atomic(path, &plot_cut_bytes(cut, title, path)?)
}

/// The plot of the cut as file bytes for `path` (SVG if it ends in `.svg`, else PNG).
pub fn plot_cut_bytes(cut: &Cut, title: &str, path: &Path) -> Result<Vec<u8>, OutputError> {
    ensure_font();
    let svg = path
        .extension()
        .is_some_and(|x| x.eq_ignore_ascii_case("svg"));
    let bytes = if svg {
        let mut s = String::new();
        draw(
            SVGBackend::with_string(&mut s, SIZE).into_drawing_area(),
            cut,
            title,
        )
        .map_err(|c| OutputError::new(path, c))?;
        s.into_bytes()
    } else {
        let mut buf = vec![0u8; (SIZE.0 * SIZE.1 * 3) as usize];
        draw(
            BitMapBackend::with_buffer(&mut buf, SIZE).into_drawing_area(),
            cut,
            title,
        )
        .map_err(|c| OutputError::new(path, c))?;
        encode_png(&buf, SIZE.0, SIZE.1).map_err(|c| OutputError::new(path, c))?
    };
    Ok(bytes)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn directions() {
        assert_eq!(CutDirection::parse("u").unwrap(), CutDirection::U);
        assert_eq!(
            CutDirection::parse("deg=30").unwrap(),
            CutDirection::Deg(30.0)
        );
        assert!(CutDirection::parse("deg=x").is_err());
        assert!(CutDirection::parse("w").is_err());
        assert_eq!(CutDirection::Deg(90.0).unit(), (0.0, 1.0));
        assert_eq!(CutDirection::Deg(-90.0).unit(), (0.0, -1.0));
    }
}
