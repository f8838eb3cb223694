//! The region picture: a crop of the photo with the given region (yellow),
//! the binned part of each strip (cyan), the extent of the measured points
//! (green), where aliasing starts (red) and the paper read for a tone
//! curve's black level (magenta), so a user sees where it measured.

use super::atomic::ReportError;
use crate::geometry::Point;
use crate::measure::Measurement;
use plotters::prelude::*;

fn err(e: impl std::fmt::Display) -> ReportError {
    ReportError::Plot {
        what: "the region picture".into(),
        cause: e.to_string(),
    }
}

/// Encodes an RGB8 photograph as PNG ([`crate::plot::encode_png_photo`]), errors as the region picture's.
pub fn encode_png(buf: Vec<u8>, w: u32, h: u32) -> Result<Vec<u8>, ReportError> {
    crate::plot::encode_png_photo(&buf, w, h).map_err(err)
}

/// Renders the region picture (PNG bytes).
pub fn roi_plot(m: &Measurement) -> Result<Vec<u8>, ReportError> {
    crate::plot::ensure_font();
    let pv = &m.preview;
    if pv.width == 0 || pv.height == 0 {
        return Err(err("no preview of the photo"));
    }
    let yellow = RGBColor(255, 200, 0);
    let cyan = RGBColor(0, 190, 230);
    let green = RGBColor(0, 200, 60);
    let red = RGBColor(230, 30, 30);
    let magenta = RGBColor(220, 0, 200);
    let paper = m.curves.iter().any(|c| !c.paper_bands_px.is_empty());
    let items: Vec<(&str, RGBColor)> = [
        ("region (corner 1 dot)", yellow),
        ("binned", cyan),
        ("measured extent", green),
        ("aliasing starts", red),
    ]
    .into_iter()
    .chain(paper.then_some(("paper read for the black level", magenta)))
    .collect();
    let w = pv.width.max(360) as i32;
    // The legend's entries, (x, row), wrapped to the picture's width.
    let mut at = Vec::with_capacity(items.len());
    let (mut x, mut row) = (6, 0);
    for (label, _) in &items {
        let span = 26 + 8 * label.chars().count() as i32;
        if x > 6 && x + span > w {
            (x, row) = (6, row + 1);
        }
        at.push((x, row));
        x += span;
    }
    let legend_h = 26 * (row as u32 + 1);
    let (w, h) = (w as u32, pv.height as u32 + legend_h);
    let mut buf = vec![255u8; (w * h * 3) as usize];
    for y in 0..pv.height {
        let src = &pv.rgb[y * pv.width * 3..(y + 1) * pv.width * 3];
        let dst = (y * w as usize) * 3;
        buf[dst..dst + src.len()].copy_from_slice(src);
    }
    {
        let root = BitMapBackend::with_buffer(&mut buf, (w, h)).into_drawing_area();
        let to = |p: Point| -> (i32, i32) {
            (
                ((p[0] - pv.x0) / pv.scale).round() as i32,
                ((p[1] - pv.y0) / pv.scale).round() as i32,
            )
        };
        let quad = |q: &[Point; 4]| -> Vec<(i32, i32)> {
            let mut v: Vec<_> = q.iter().map(|&p| to(p)).collect();
            v.push(v[0]);
            v
        };
        root.draw(&PathElement::new(quad(&m.roi), yellow.stroke_width(2)))
            .map_err(err)?;
        let c1 = to(m.roi[0]);
        root.draw(&Circle::new(c1, 5, yellow.filled()))
            .map_err(err)?;
        for p in &m.patches {
            let col = if p.aliased { red } else { cyan };
            root.draw(&PathElement::new(quad(&p.region_px), col.stroke_width(1)))
                .map_err(err)?;
        }
        for c in &m.curves {
            let outline = if c.outline_px.is_empty() {
                quad(&c.region_px)
            } else {
                let mut v: Vec<_> = c.outline_px.iter().map(|&p| to(p)).collect();
                v.push(v[0]);
                v
            };
            root.draw(&PathElement::new(outline, cyan.stroke_width(1)))
                .map_err(err)?;
            for band in &c.paper_bands_px {
                let mut v: Vec<_> = band.iter().map(|&p| to(p)).collect();
                v.extend(v.first().copied());
                root.draw(&PathElement::new(v, magenta.stroke_width(1)))
                    .map_err(err)?;
            }
            for l in &c.measured_lines_px {
                root.draw(&PathElement::new(
                    vec![to(l[0]), to(l[1])],
                    green.stroke_width(3),
                ))
                .map_err(err)?;
            }
            if let Some(l) = c.alias_line_px {
                root.draw(&PathElement::new(
                    vec![to(l[0]), to(l[1])],
                    red.stroke_width(3),
                ))
                .map_err(err)?;
            }
        }
        let font = (crate::plot::FONT, 15).into_font();
        for ((label, col), (x, row)) in items.into_iter().zip(at) {
            let y = pv.height as i32 + 5 + 26 * row;
            root.draw(&Rectangle::new(
                [(x, y + 3), (x + 14, y + 13)],
                col.filled(),
            ))
            .map_err(err)?;
            root.draw(&Text::new(label, (x + 18, y), font.clone().color(&BLACK)))
                .map_err(err)?;
        }
        root.present().map_err(err)?;
    }
    encode_png(buf, w, h)
}
