//! A small preview of the chart, built from the streamed rows by box
//! averaging (so it shows what the print looks like from afar), and its
//! 8-bit PNG encoding.

/// An 8-bit grey preview image.
#[derive(Debug, Clone)]
pub struct Preview {
    /// Width (pixels).
    pub width: usize,
    /// Height (pixels).
    pub height: usize,
    /// Row-major 8-bit grey values (same encoding as the chart).
    pub pixels: Vec<u8>,
}

/// Accumulates full-resolution rows into a tent-filtered, decimated preview
/// (each source pixel is shared between its two nearest preview pixels in x
/// and in y, a triangle filter twice the decimation factor wide: much less
/// moiré from the fine sines than a plain box average).
#[derive(Debug)]
pub struct PreviewBuilder {
    factor: usize,
    width: usize,
    height: usize,
    /// Per source column: first preview column and its weight (the next gets 1 − weight).
    cols: Vec<(usize, f64)>,
    col_weight: Vec<f64>,
    /// Open preview rows: (row index, weighted sums, total row weight).
    open: std::collections::VecDeque<(usize, Vec<f64>, f64)>,
    row_in: usize,
    pixels: Vec<u8>,
    hrow: Vec<f64>,
}

fn split(i: usize, factor: usize, n: usize) -> (usize, f64) {
    let u = (i as f64 + 0.5) / factor as f64 - 0.5;
    if u <= 0.0 {
        return (0, 1.0);
    }
    let q = u.floor() as usize;
    if q + 1 >= n {
        return (n - 1, 1.0);
    }
    (q, 1.0 - (u - q as f64))
}

impl PreviewBuilder {
    /// A builder for a `src_width`×`src_height` raster, longest preview side ≤ `max_side`.
    pub fn new(src_width: usize, src_height: usize, max_side: usize) -> PreviewBuilder {
        let factor = src_width.max(src_height).div_ceil(max_side.max(1)).max(1);
        let width = src_width.div_ceil(factor).max(1);
        let height = src_height.div_ceil(factor).max(1);
        let cols: Vec<(usize, f64)> = (0..src_width).map(|i| split(i, factor, width)).collect();
        let mut col_weight = vec![0.0; width];
        for &(q, w) in &cols {
            col_weight[q] += w;
            if w < 1.0 {
                col_weight[q + 1] += 1.0 - w;
            }
        }
        PreviewBuilder {
            factor,
            width,
            height,
            cols,
            col_weight,
            open: std::collections::VecDeque::new(),
            row_in: 0,
            pixels: Vec::with_capacity(width * height),
            hrow: vec![0.0; width],
        }
    }

    fn add(&mut self, r: usize, w: f64) {
        if self.open.back().is_none_or(|b| b.0 < r) {
            self.open.push_back((r, vec![0.0; self.width], 0.0));
        }
        let slot = self
            .open
            .iter_mut()
            .find(|o| o.0 == r)
            .expect("row opened above");
        for (a, h) in slot.1.iter_mut().zip(&self.hrow) {
            *a += w * h;
        }
        slot.2 += w;
    }

    fn emit_before(&mut self, r: usize) {
        while self.open.front().is_some_and(|o| o.0 < r) {
            let (_, sums, rw) = self.open.pop_front().expect("checked");
            for (s, cw) in sums.iter().zip(&self.col_weight) {
                let v = if rw > 0.0 && *cw > 0.0 {
                    s / (rw * cw)
                } else {
                    0.0
                };
                self.pixels
                    .push((v / 257.0).round().clamp(0.0, 255.0) as u8);
            }
        }
    }

    /// Adds the next full-resolution row (16-bit values).
    pub fn push(&mut self, row: &[u16]) {
        self.hrow.fill(0.0);
        for (&(q, w), &v) in self.cols.iter().zip(row) {
            let v = v as f64;
            self.hrow[q] += w * v;
            if w < 1.0 {
                self.hrow[q + 1] += (1.0 - w) * v;
            }
        }
        let (r, w) = split(self.row_in, self.factor, self.height);
        self.row_in += 1;
        self.emit_before(r);
        self.add(r, w);
        if w < 1.0 {
            self.add(r + 1, 1.0 - w);
        }
    }

    /// The finished preview.
    pub fn finish(mut self) -> Preview {
        self.emit_before(usize::MAX);
        Preview {
            width: self.width,
            height: self.pixels.len() / self.width,
            pixels: self.pixels,
        }
    }
}

impl Preview {
    /// Encodes the preview as an 8-bit grey PNG.
    pub fn write_png<W: std::io::Write>(&self, out: W) -> Result<(), png::EncodingError> {
        let mut enc = png::Encoder::new(out, self.width as u32, self.height as u32);
        enc.set_color(png::ColorType::Grayscale);
        enc.set_depth(png::BitDepth::Eight);
        let mut w = enc.write_header()?;
        w.write_image_data(&self.pixels)?;
        w.finish()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn constant_stays_constant_and_factor_one_is_identity() {
        let mut b = PreviewBuilder::new(7, 5, 3);
        for _ in 0..5 {
            b.push(&[257 * 40; 7]);
        }
        let p = b.finish();
        assert_eq!((p.width, p.height), (3, 2));
        assert!(p.pixels.iter().all(|&v| v == 40));
        let mut b = PreviewBuilder::new(3, 2, 10);
        b.push(&[0, 257, 514]);
        b.push(&[771, 1028, 65535]);
        assert_eq!(b.finish().pixels, vec![0, 1, 2, 3, 4, 255]);
    }

    #[test]
    fn tent_weights_by_hand() {
        // factor 2: source column i sits at preview coordinate (i + 0.5)/2 − 0.5.
        let mut b = PreviewBuilder::new(4, 2, 2);
        b.push(&[0, 257 * 8, 257 * 16, 257 * 24]);
        b.push(&[0, 257 * 8, 257 * 16, 257 * 24]);
        let p = b.finish();
        // Column 0 gets i=0 (w 1), i=1 (0.75), i=2 (0.25); column 1 gets i=1 (0.25),
        // i=2 (0.75), i=3 (1, clamped at the edge).
        let c0: f64 = (0.0 + 0.75 * 8.0 + 0.25 * 16.0) / 2.0;
        let c1: f64 = (0.25 * 8.0 + 0.75 * 16.0 + 24.0) / 2.0;
        assert_eq!(p.pixels, vec![c0.round() as u8, c1.round() as u8]);
    }
}
