//! 16-bit grey PNG writer: rows streamed through the `png` crate's stream
//! writer (Up filter, fast deflate), with a pHYs chunk giving the printer
//! resolution and an sRGB/gAMA chunk naming the encoding.

use super::ChartError;
use super::encode::Encoding;
use super::preview::PreviewBuilder;
use super::raster::Renderer;
use std::io::Write;

/// Pixels per metre stored in pHYs for a resolution in dots per inch.
pub fn ppm_of_dpi(dpi: u32) -> u32 {
    (dpi as f64 / 0.0254).round() as u32
}

/// Streams the chart into `out` as a 16-bit grey PNG.
pub fn write<W: Write>(
    r: &Renderer<'_>,
    dpi: u32,
    encoding: &Encoding,
    out: W,
    preview: &mut PreviewBuilder,
    path: &str,
) -> Result<(), ChartError> {
    let err = |e: png::EncodingError| ChartError::Output {
        path: path.to_string(),
        cause: e.to_string(),
    };
    let mut enc = png::Encoder::new(out, r.width as u32, r.height as u32);
    enc.set_color(png::ColorType::Grayscale);
    enc.set_depth(png::BitDepth::Sixteen);
    enc.set_compression(png::Compression::Fast);
    enc.set_filter(png::Filter::Up);
    let ppm = ppm_of_dpi(dpi);
    enc.set_pixel_dims(Some(png::PixelDimensions {
        xppu: ppm,
        yppu: ppm,
        unit: png::Unit::Meter,
    }));
    match encoding {
        Encoding::Srgb => enc.set_source_srgb(png::SrgbRenderingIntent::RelativeColorimetric),
        Encoding::Gamma(g) => enc.set_source_gamma(png::ScaledFloat::new((1.0 / g) as f32)),
        Encoding::Printer(_) => {}
    }
    let mut writer = enc.write_header().map_err(err)?;
    let mut stream = writer.stream_writer_with_size(1 << 20).map_err(err)?;
    let mut bytes = vec![0u8; r.width * 2];
    let io = |e: std::io::Error| ChartError::Output {
        path: path.to_string(),
        cause: e.to_string(),
    };
    r.stream(|_, row| {
        for (b, v) in bytes.chunks_exact_mut(2).zip(row) {
            b.copy_from_slice(&v.to_be_bytes());
        }
        preview.push(row);
        stream.write_all(&bytes).map_err(io)
    })?;
    stream.finish().map_err(err)?;
    writer.finish().map_err(err)
}
