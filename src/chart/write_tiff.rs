//! 16-bit grey TIFF writer: uncompressed strips streamed through the `tiff`
//! crate, with XResolution/YResolution = dpi and ResolutionUnit = inch.
//! (Uncompressed because the crate compresses only whole images, not strips
//! written one at a time.)

use super::ChartError;
use super::preview::PreviewBuilder;
use super::raster::Renderer;
use std::io::{Seek, Write};
use tiff::encoder::{Rational, TiffEncoder, colortype::Gray16};
use tiff::tags::ResolutionUnit;

/// Rows per TIFF strip.
const STRIP_ROWS: usize = 16;

/// Streams the chart into `out` as a 16-bit grey TIFF.
pub fn write<W: Write + Seek>(
    r: &Renderer<'_>,
    dpi: u32,
    out: W,
    preview: &mut PreviewBuilder,
    path: &str,
) -> Result<(), ChartError> {
    let err = |e: tiff::TiffError| ChartError::Output {
        path: path.to_string(),
        cause: e.to_string(),
    };
    let mut enc = TiffEncoder::new(out).map_err(err)?;
    let mut img = enc
        .new_image::<Gray16>(r.width as u32, r.height as u32)
        .map_err(err)?;
    img.rows_per_strip(STRIP_ROWS as u32).map_err(err)?;
    img.resolution(ResolutionUnit::Inch, Rational { n: dpi, d: 1 });
    let mut strip: Vec<u16> = Vec::with_capacity(STRIP_ROWS * r.width);
    r.stream(|j, row| {
        preview.push(row);
        strip.extend_from_slice(row);
        if strip.len() == STRIP_ROWS * r.width || j + 1 == r.height {
            img.write_strip(&strip).map_err(err)?;
            strip.clear();
        }
        Ok(())
    })?;
    img.finish().map_err(err)
}
