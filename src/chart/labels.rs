//! Human-readable marks: text labels (title, frequency numbers) and filled
//! tick rectangles, rasterised once per chart into small coverage stamps
//! (embedded DejaVu Sans via plotters) that the row renderer overlays.

use crate::target::Rect;
use plotters::prelude::*;
use plotters::style::text_anchor::{HPos, Pos, VPos};

/// Horizontal anchoring of a text label.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Align {
    /// `x_mm` is the left edge.
    Left,
    /// `x_mm` is the centre.
    Center,
    /// `x_mm` is the right edge.
    Right,
}

/// A line of text on the chart.
#[derive(Debug, Clone, PartialEq)]
pub struct TextLabel {
    /// The text.
    pub text: String,
    /// Anchor x (mm), see `align`.
    pub x_mm: f64,
    /// Top of the text box (mm).
    pub y_mm: f64,
    /// Font size (mm, the em height).
    pub height_mm: f64,
    /// Horizontal anchoring.
    pub align: Align,
}

/// A rasterised mark: coverage (0 = none, 255 = full ink) over a pixel box.
#[derive(Debug, Clone)]
pub struct Stamp {
    /// Left pixel column.
    pub x0: usize,
    /// Top pixel row.
    pub y0: usize,
    /// Width (pixels).
    pub w: usize,
    /// Height (pixels).
    pub h: usize,
    /// Coverage, row-major, `w·h` bytes.
    pub alpha: Vec<u8>,
}

const PROBE_PX: f64 = 200.0;

/// Width and height (mm) of `text` set at font size `height_mm`.
pub fn text_size_mm(text: &str, height_mm: f64) -> (f64, f64) {
    crate::plot::ensure_font();
    let font = (crate::plot::FONT, PROBE_PX).into_font();
    let (w, h) = font.box_size(text).unwrap_or((
        (0.65 * PROBE_PX * text.chars().count() as f64) as u32,
        PROBE_PX as u32,
    ));
    (
        w as f64 / PROBE_PX * height_mm,
        h as f64 / PROBE_PX * height_mm,
    )
}

impl TextLabel {
    /// The label's box on the chart (mm).
    pub fn rect(&self) -> Rect {
        let (w, h) = text_size_mm(&self.text, self.height_mm);
        let x = match self.align {
            Align::Left => self.x_mm,
            Align::Center => self.x_mm - w / 2.0,
            Align::Right => self.x_mm - w,
        };
        Rect {
            x_mm: x,
            y_mm: self.y_mm,
            width_mm: w,
            height_mm: h,
        }
    }

    /// Rasterises the label at `dpi`, clipped to a `width_px`×`height_px` raster.
    pub fn stamp(&self, dpi: f64, width_px: usize, height_px: usize) -> Option<Stamp> {
        crate::plot::ensure_font();
        let px_per_mm = dpi / 25.4;
        let size_px = self.height_mm * px_per_mm;
        let font = (crate::plot::FONT, size_px).into_font();
        let (tw, th) = font.box_size(&self.text).ok()?;
        // Generous padding: glyphs may reach beyond the font's reported box.
        let pad = (0.4 * size_px).ceil().max(2.0) as usize;
        let (bw, bh) = (tw as usize + 2 * pad, th as usize + 2 * pad);
        let r = self.rect();
        let x0 = (r.x_mm * px_per_mm).round() as i64 - pad as i64;
        let y0 = (r.y_mm * px_per_mm).round() as i64 - pad as i64;
        let mut rgb = vec![255u8; bw * bh * 3];
        {
            let backend = BitMapBackend::with_buffer(&mut rgb, (bw as u32, bh as u32));
            let root = backend.into_drawing_area();
            let style = TextStyle::from(font)
                .color(&BLACK)
                .pos(Pos::new(HPos::Left, VPos::Top));
            root.draw_text(&self.text, &style, (pad as i32, pad as i32))
                .ok()?;
            root.present().ok()?;
        }
        let alpha: Vec<u8> = rgb.chunks_exact(3).map(|p| 255 - p[0]).collect();
        clip(x0, y0, bw, bh, &alpha, width_px, height_px)
    }
}

/// A filled rectangle (tick mark) as a stamp: pixels whose centres lie inside `r`.
pub fn rect_stamp(r: &Rect, dpi: f64, width_px: usize, height_px: usize) -> Option<Stamp> {
    let p = 25.4 / dpi;
    let first = |a: f64| ((a / p) - 0.5).ceil().max(0.0) as i64;
    let (x0, x1) = (first(r.x_mm), first(r.x_mm + r.width_mm));
    let (y0, y1) = (first(r.y_mm), first(r.y_mm + r.height_mm));
    if x1 <= x0 || y1 <= y0 {
        return None;
    }
    let (w, h) = ((x1 - x0) as usize, (y1 - y0) as usize);
    clip(x0, y0, w, h, &vec![255u8; w * h], width_px, height_px)
}

fn clip(
    x0: i64,
    y0: i64,
    w: usize,
    h: usize,
    alpha: &[u8],
    width_px: usize,
    height_px: usize,
) -> Option<Stamp> {
    let cx0 = x0.max(0);
    let cy0 = y0.max(0);
    let cx1 = (x0 + w as i64).min(width_px as i64);
    let cy1 = (y0 + h as i64).min(height_px as i64);
    if cx1 <= cx0 || cy1 <= cy0 {
        return None;
    }
    let (nw, nh) = ((cx1 - cx0) as usize, (cy1 - cy0) as usize);
    let mut out = Vec::with_capacity(nw * nh);
    for y in cy0..cy1 {
        let row = (y - y0) as usize * w;
        let a = row + (cx0 - x0) as usize;
        out.extend_from_slice(&alpha[a..a + nw]);
    }
    Some(Stamp {
        x0: cx0 as usize,
        y0: cy0 as usize,
        w: nw,
        h: nh,
        alpha: out,
    })
}

/// Formats a frequency for a tick label with at most three significant digits.
pub fn format_freq(f: f64) -> String {
    if f <= 0.0 || !f.is_finite() {
        return format!("{f}");
    }
    let digits = (2 - f.log10().floor() as i32).clamp(0, 6) as usize;
    let s = format!("{f:.digits$}");
    if s.contains('.') {
        s.trim_end_matches('0').trim_end_matches('.').to_string()
    } else {
        s
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn freq_format() {
        assert_eq!(format_freq(0.5), "0.5");
        assert_eq!(format_freq(20.0), "20");
        assert_eq!(format_freq(0.125), "0.125");
        assert_eq!(format_freq(1.234_56), "1.23");
        assert_eq!(format_freq(0.0298), "0.0298");
    }

    #[test]
    fn text_has_ink_inside_its_box() {
        let l = TextLabel {
            text: "12.5".into(),
            x_mm: 20.0,
            y_mm: 10.0,
            height_mm: 3.0,
            align: Align::Center,
        };
        let s = l.stamp(300.0, 1000, 1000).unwrap();
        let ink: usize = s.alpha.iter().filter(|&&a| a > 128).count();
        assert!(ink > 50, "{ink}");
        let r = l.rect();
        assert!(r.width_mm > 4.0 && r.width_mm < 12.0, "{:?}", r);
    }
}
