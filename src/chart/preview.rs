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

/// Accumulates full-resolution rows into a box-averaged preview.
#[derive(Debug)]
pub struct PreviewBuilder {
    factor: usize,
    src_width: usize,
    width: usize,
    acc: Vec<u64>,
    count: Vec<u64>,
    rows_in: usize,
    pixels: Vec<u8>,
}

impl PreviewBuilder {
    /// A builder for a `src_width`×`src_height` raster, longest preview side ≤ `max_side`.
    pub fn new(src_width: usize, src_height: usize, max_side: usize) -> PreviewBuilder {
        let factor = src_width.max(src_height).div_ceil(max_side.max(1)).max(1);
        let width = src_width.div_ceil(factor);
        PreviewBuilder {
            factor,
            src_width,
            width,
            acc: vec![0; width],
            count: vec![0; width],
            rows_in: 0,
            pixels: Vec::new(),
        }
    }

    /// Adds the next full-resolution row (16-bit values).
    pub fn push(&mut self, row: &[u16]) {
        for (i, &v) in row.iter().enumerate().take(self.src_width) {
            let k = i / self.factor;
            self.acc[k] += v as u64;
            self.count[k] += 1;
        }
        self.rows_in += 1;
        if self.rows_in == self.factor {
            self.flush();
        }
    }

    fn flush(&mut self) {
        if self.rows_in == 0 {
            return;
        }
        for (a, c) in self.acc.iter_mut().zip(self.count.iter_mut()) {
            let mean = if *c > 0 { *a as f64 / *c as f64 } else { 0.0 };
            self.pixels
                .push((mean / 257.0).round().clamp(0.0, 255.0) as u8);
            *a = 0;
            *c = 0;
        }
        self.rows_in = 0;
    }

    /// The finished preview.
    pub fn finish(mut self) -> Preview {
        self.flush();
        Preview {
            width: self.width,
            height: self.pixels.len() / self.width.max(1),
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
    fn box_average() {
        let mut b = PreviewBuilder::new(5, 3, 2);
        // factor 3: preview 2×1
        for _ in 0..3 {
            b.push(&[0, 257 * 3, 257 * 6, 257 * 10, 257 * 20]);
        }
        let p = b.finish();
        assert_eq!((p.width, p.height), (2, 1));
        assert_eq!(p.pixels, vec![3, 15]);
    }
}
