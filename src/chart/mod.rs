//! Printable sine-sweep and sine-patch charts at true physical size (PNG, TIFF, PDF).
//!
//! [`layout`](fn@layout) turns a [`ChartSpec`] into a [`Chart`]: the target description
//! (`Target`, the single truth of what is printed) plus the human-readable
//! marks (frequency ticks and numbers, title) that sit only where the
//! description leaves background. [`write_chart`] streams the raster row by
//! row into the chosen encoder (never holding the whole raster), and returns
//! a small preview. Pixel values are pre-compensated with an [`Encoding`] so
//! that the printed reflectance is the described one.

use std::path::Path;
use thiserror::Error;

pub mod encode;
pub mod labels;
pub mod layout;
pub mod preview;
pub mod raster;
pub mod setup;
pub mod suitability;
pub mod write_pdf;
pub mod write_png;
pub mod write_tiff;

pub use encode::{Encoding, PrinterCurve};
pub use labels::{Align, TextLabel};
pub use layout::{Chart, ChartSpec, Law, layout};
pub use setup::Setup;

/// Fewest printer dots per cycle at the highest frequency before a chart is refused.
pub const MIN_DOTS_PER_CYCLE: f64 = 2.0;
/// Fewest printer dots per cycle at the highest frequency before a warning.
pub const WARN_DOTS_PER_CYCLE: f64 = 4.0;

/// Why a chart could not be made or written.
#[derive(Debug, Error)]
pub enum ChartError {
    /// A parameter is out of range (frequencies, contrast, size, dpi, …).
    #[error("{0}")]
    Invalid(String),
    /// The chart does not fit the output format (pixel count, file size, page size).
    #[error("{0}")]
    TooLarge(String),
    /// The printer curve file is unusable.
    #[error("printer curve {0}")]
    PrinterCurve(String),
    /// The output could not be written.
    #[error("{path}: cannot write: {cause}")]
    Output {
        /// The file.
        path: String,
        /// The cause.
        cause: String,
    },
}

/// The raster file formats.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Format {
    /// 16-bit grey PNG with a pHYs resolution chunk.
    Png,
    /// 16-bit grey TIFF with X/YResolution in inches.
    Tiff,
    /// PDF page at the chart's physical size with the 16-bit raster at its DPI.
    Pdf,
}

impl Format {
    /// The format named by a file's extension (`.png`, `.tif`/`.tiff`, `.pdf`).
    pub fn from_path(path: &Path) -> Option<Format> {
        let ext = path.extension()?.to_str()?.to_ascii_lowercase();
        match ext.as_str() {
            "png" => Some(Format::Png),
            "tif" | "tiff" => Some(Format::Tiff),
            "pdf" => Some(Format::Pdf),
            _ => None,
        }
    }

    /// Checks that a raster of this size can be stored in the format.
    pub fn check_size(&self, chart: &Chart) -> Result<(), ChartError> {
        let (w, h) = (chart.width_px as u64, chart.height_px as u64);
        match self {
            Format::Png if w > i32::MAX as u64 || h > i32::MAX as u64 => Err(ChartError::TooLarge(
                format!("{w}×{h} pixels exceed PNG's limit of 2^31−1 per side"),
            )),
            Format::Tiff if w * h * 2 > 4_000_000_000 => Err(ChartError::TooLarge(format!(
                "{w}×{h} pixels at 16 bits ({:.1} GB) exceed the 4 GB of a classic TIFF; \
                 lower --dpi or use .png",
                (w * h * 2) as f64 / 1e9
            ))),
            Format::Pdf
                if chart.target.width_mm > write_pdf::MAX_PAGE_MM
                    || chart.target.height_mm > write_pdf::MAX_PAGE_MM =>
            {
                Err(ChartError::TooLarge(format!(
                    "a {}×{} mm page exceeds PDF's 200-inch ({} mm) page limit",
                    chart.target.width_mm,
                    chart.target.height_mm,
                    write_pdf::MAX_PAGE_MM
                )))
            }
            _ => Ok(()),
        }
    }
}

/// What [`write_chart`] produced besides the file.
#[derive(Debug, Clone)]
pub struct Written {
    /// The preview: 8-bit grey pixels, row-major.
    pub preview: preview::Preview,
}

/// Streams the chart's raster into `out` in the given format.
///
/// Rows are rendered in small parallel batches and handed to the encoder as
/// they are made; memory stays at a few rows plus the label stamps.
pub fn write_chart<W: std::io::Write + std::io::Seek>(
    chart: &Chart,
    encoding: &Encoding,
    format: Format,
    out: &mut W,
    path_for_errors: &str,
) -> Result<Written, ChartError> {
    format.check_size(chart)?;
    let renderer = raster::Renderer::new(chart, encoding);
    let mut preview = preview::PreviewBuilder::new(chart.width_px, chart.height_px, 1200);
    let io = |e: std::io::Error| ChartError::Output {
        path: path_for_errors.to_string(),
        cause: e.to_string(),
    };
    match format {
        Format::Png => write_png::write(
            &renderer,
            chart.dpi,
            encoding,
            &mut *out,
            &mut preview,
            path_for_errors,
        )?,
        Format::Tiff => write_tiff::write(
            &renderer,
            chart.dpi,
            &mut *out,
            &mut preview,
            path_for_errors,
        )?,
        Format::Pdf => write_pdf::write(
            &renderer,
            chart.dpi,
            chart.target.width_mm,
            chart.target.height_mm,
            &mut *out,
            &mut preview,
        )
        .map_err(io)?,
    }
    out.flush().map_err(io)?;
    Ok(Written {
        preview: preview.finish(),
    })
}
