//! Streaming row renderer: produces the chart's 16-bit pixel rows one batch at
//! a time. Pixel (i, j) is `encode(Target::reflectance(x, y))` at its printer
//! dot centre x = (i + ½)·25.4/dpi mm, y = (j + ½)·25.4/dpi mm, except where a
//! label or tick (always on background) adds ink.
//!
//! Speed: regions that vary along x keep one precomputed row of encoded
//! values, so a row costs little more than copying; regions are painted in
//! reverse priority so that the result equals `Target::reflectance` exactly.

use super::encode::Encoding;
use super::labels::{Stamp, rect_stamp};
use super::layout::Chart;
use crate::target::{Direction, Fiducial, Rect, SinePatch, Sweep};
use rayon::prelude::*;

enum Kind {
    /// One precomputed value per column of the layer's range.
    Columns(Vec<u16>),
    /// Value constant along a row (region varying along y, or uniform).
    Sweep(Sweep),
    /// A sine patch varying along y.
    Patch(SinePatch),
    /// A uniform value.
    Const(u16),
    /// A fiducial, evaluated per pixel.
    Fiducial(Fiducial),
}

struct Layer {
    rect: Rect,
    c0: usize,
    c1: usize,
    kind: Kind,
}

/// Renders chart rows; holds only per-column caches and label stamps.
pub struct Renderer<'a> {
    /// Raster width (pixels).
    pub width: usize,
    /// Raster height (pixels).
    pub height: usize,
    pitch_mm: f64,
    col_x: Vec<f64>,
    background: u16,
    layers: Vec<Layer>,
    /// Label and tick stamps, sorted by first row.
    pub stamps: Vec<Stamp>,
    ink: Vec<u16>,
    encoding: &'a Encoding,
    fid_values: [u16; 2],
}

impl<'a> Renderer<'a> {
    /// Prepares the per-column caches and rasterises the labels.
    pub fn new(chart: &Chart, encoding: &'a Encoding) -> Renderer<'a> {
        let t = &chart.target;
        let (width, height) = (chart.width_px, chart.height_px);
        let pitch_mm = 25.4 / chart.dpi as f64;
        let col_x: Vec<f64> = (0..width).map(|i| (i as f64 + 0.5) * pitch_mm).collect();
        let cols = |r: &Rect| {
            let c0 = col_x.partition_point(|&x| x < r.x_mm);
            let c1 = col_x.partition_point(|&x| x < r.x_mm + r.width_mm);
            (c0, c1.max(c0))
        };
        let mut layers = Vec::new();
        for g in t.greys.iter().rev() {
            let (c0, c1) = cols(&g.rect);
            layers.push(Layer {
                rect: g.rect,
                c0,
                c1,
                kind: Kind::Const(encoding.value_u16(g.reflectance)),
            });
        }
        for p in t.patches.iter().rev() {
            let (c0, c1) = cols(&p.rect);
            let y = p.rect.y_mm;
            let kind = match p.direction {
                Direction::X => Kind::Columns(
                    col_x[c0..c1]
                        .iter()
                        .map(|&x| encoding.value_u16(p.reflectance_at(x, y)))
                        .collect(),
                ),
                Direction::Y => Kind::Patch(p.clone()),
            };
            layers.push(Layer {
                rect: p.rect,
                c0,
                c1,
                kind,
            });
        }
        for s in t.sweeps.iter().rev() {
            let (c0, c1) = cols(&s.rect);
            let y = s.rect.y_mm;
            let kind = match s.direction {
                Direction::X => Kind::Columns(
                    col_x[c0..c1]
                        .iter()
                        .map(|&x| encoding.value_u16(s.reflectance_at(s.s_of(x, y))))
                        .collect(),
                ),
                Direction::Y => Kind::Sweep(s.clone()),
            };
            layers.push(Layer {
                rect: s.rect,
                c0,
                c1,
                kind,
            });
        }
        for f in t.fiducials.iter().rev() {
            let r = Rect {
                x_mm: f.x_mm - f.diameter_mm,
                y_mm: f.y_mm - f.diameter_mm,
                width_mm: 2.0 * f.diameter_mm,
                height_mm: 2.0 * f.diameter_mm,
            };
            // One column of slack each side; the per-pixel test decides.
            let (c0, c1) = cols(&r);
            layers.push(Layer {
                rect: r,
                c0: c0.saturating_sub(1),
                c1: (c1 + 1).min(width),
                kind: Kind::Fiducial(f.clone()),
            });
        }
        let mut stamps: Vec<Stamp> = chart
            .texts
            .iter()
            .filter_map(|l| l.stamp(chart.dpi as f64, width, height))
            .chain(
                chart
                    .ticks
                    .iter()
                    .filter_map(|r| rect_stamp(r, chart.dpi as f64, width, height)),
            )
            .collect();
        stamps.sort_by_key(|s| s.y0);
        let bg = t.background;
        let ink = (0..256)
            .map(|a| encoding.value_u16(bg * (1.0 - a as f64 / 255.0)))
            .collect();
        Renderer {
            width,
            height,
            pitch_mm,
            col_x,
            background: encoding.value_u16(bg),
            layers,
            stamps,
            ink,
            encoding,
            fid_values: [encoding.value_u16(0.0), encoding.value_u16(1.0)],
        }
    }

    /// Fills `out` (length `width`) with row `j`.
    pub fn render_row(&self, j: usize, out: &mut [u16]) {
        let y = (j as f64 + 0.5) * self.pitch_mm;
        out.fill(self.background);
        for l in &self.layers {
            if l.c0 >= l.c1 {
                continue;
            }
            let dst = &mut out[l.c0..l.c1];
            match &l.kind {
                Kind::Fiducial(f) => {
                    if (y - f.y_mm).abs() >= f.diameter_mm {
                        continue;
                    }
                    for (o, &x) in dst.iter_mut().zip(&self.col_x[l.c0..l.c1]) {
                        if let Some(v) = f.reflectance_at(x, y) {
                            *o = if v >= 1.0 {
                                self.fid_values[1]
                            } else if v <= 0.0 {
                                self.fid_values[0]
                            } else {
                                self.encoding.value_u16(v)
                            };
                        }
                    }
                    continue;
                }
                _ => {
                    if !l.rect.contains(self.col_x[l.c0], y) {
                        continue;
                    }
                }
            }
            match &l.kind {
                Kind::Columns(v) => dst.copy_from_slice(v),
                Kind::Const(v) => dst.fill(*v),
                Kind::Sweep(s) => dst.fill(
                    self.encoding
                        .value_u16(s.reflectance_at(s.s_of(self.col_x[l.c0], y))),
                ),
                Kind::Patch(p) => dst.fill(
                    self.encoding
                        .value_u16(p.reflectance_at(self.col_x[l.c0], y)),
                ),
                Kind::Fiducial(_) => {}
            }
        }
        let end = self.stamps.partition_point(|s| s.y0 <= j);
        for s in &self.stamps[..end] {
            if j >= s.y0 + s.h {
                continue;
            }
            let a = &s.alpha[(j - s.y0) * s.w..(j - s.y0 + 1) * s.w];
            for (o, &al) in out[s.x0..s.x0 + s.w].iter_mut().zip(a) {
                if al > 0 {
                    *o = (*o).min(self.ink[al as usize]);
                }
            }
        }
    }

    /// Renders rows in parallel batches and hands each row, in order, to `sink`.
    pub fn stream<E>(&self, mut sink: impl FnMut(usize, &[u16]) -> Result<(), E>) -> Result<(), E> {
        let batch = 64usize;
        let mut buf = vec![0u16; batch * self.width];
        let mut j0 = 0;
        while j0 < self.height {
            let n = batch.min(self.height - j0);
            buf[..n * self.width]
                .par_chunks_mut(self.width)
                .enumerate()
                .for_each(|(k, row)| self.render_row(j0 + k, row));
            for k in 0..n {
                sink(j0 + k, &buf[k * self.width..(k + 1) * self.width])?;
            }
            j0 += n;
        }
        Ok(())
    }
}
