//! Decoding of ordinary photo files (JPEG, PNG, TIFF; 8 or 16 bits per sample,
//! grey or RGB) into code values, via the `image` crate.
//!
//! The result keeps the file's own code values (no conversion to float, no
//! linearisation) so that a 24-megapixel JPEG costs exactly its decoded size;
//! [`super::linearise`] turns only the needed region into linear [`super::Plane`]s.
//! JPEGs go through [`super::jpeg`] (zune-jpeg directly, reading only the
//! rows and planes asked for). An alpha channel is dropped. Truncated JPEGs (no end-of-image marker) are
//! refused rather than silently filled with grey.

use super::jpeg::{JpegWant, decode_jpeg_observed};
use image::{ColorType, DynamicImage, ImageDecoder, ImageFormat, ImageReader};
use std::io::Cursor;
use std::path::Path;
use thiserror::Error;

/// Why a photo could not be decoded.
#[derive(Debug, Error)]
pub enum DecodeError {
    /// The file could not be read.
    #[error("{path}: cannot read: {source}")]
    Io {
        /// The file.
        path: String,
        /// The cause.
        source: std::io::Error,
    },
    /// The file is not a supported image format.
    #[error("{path}: unsupported format: {what}")]
    Unsupported {
        /// The file.
        path: String,
        /// What was found.
        what: String,
    },
    /// The file is damaged or truncated.
    #[error("{path}: corrupt or truncated image: {cause}")]
    Corrupt {
        /// The file.
        path: String,
        /// The decoder's complaint.
        cause: String,
    },
}

/// Decoded code values, interleaved by pixel.
#[derive(Debug, Clone, PartialEq)]
pub enum Samples {
    /// 8-bit code values (0–255).
    U8(Vec<u8>),
    /// 16-bit code values (0–65535).
    U16(Vec<u16>),
    /// Floating-point code values (0 = black, 1 = white), from an array in memory
    /// (see [`crate::measure::in_memory`]); no file format decodes to these.
    F32(Vec<f32>),
}

/// A decoded photo: code values as stored in the file.
#[derive(Debug, Clone, PartialEq)]
pub struct Decoded {
    /// Width in pixels.
    pub width: usize,
    /// Height in pixels.
    pub height: usize,
    /// Samples per pixel: 1 (grey) or 3 (RGB).
    pub channels: usize,
    /// The code values, row-major, `channels` per pixel.
    pub samples: Samples,
    /// The container format ("jpeg", "png", "tiff").
    pub format: &'static str,
    /// Rows from the top that hold the picture (`height` unless the decode
    /// was cut below the rows a caller asked for; rows below are zero).
    pub rows: usize,
    /// What the decoder had to forgive (e.g. corrupt scan data), one line each.
    pub warnings: Vec<String>,
    /// The transfer curve the file declares (PNG chunks, ICC profile), if any.
    pub declared_tone: Option<super::transfer::DeclaredTone>,
    /// A JPEG's luma quantisation table (natural order, DCT units), from its headers.
    pub jpeg_luma_quant: Option<Box<[u16; 64]>>,
}

impl Decoded {
    /// Bits per sample (8 or 16; 32 for floating-point samples).
    pub fn bits(&self) -> u32 {
        match self.samples {
            Samples::U8(_) => 8,
            Samples::U16(_) => 16,
            Samples::F32(_) => 32,
        }
    }

    /// Code value of channel `c` at pixel (x, y), scaled to 0–1.
    pub fn value(&self, x: usize, y: usize, c: usize) -> f32 {
        let i = (y * self.width + x) * self.channels + c;
        match &self.samples {
            Samples::U8(v) => v[i] as f32 / 255.0,
            Samples::U16(v) => v[i] as f32 / 65535.0,
            Samples::F32(v) => v[i],
        }
    }
}

/// Reads and decodes a JPEG, PNG or TIFF file.
pub fn decode_file(path: &Path) -> Result<Decoded, DecodeError> {
    let name = path.display().to_string();
    let bytes = std::fs::read(path).map_err(|source| DecodeError::Io {
        path: name.clone(),
        source,
    })?;
    decode_bytes(&bytes, &name)
}

/// Decodes an in-memory JPEG, PNG or TIFF file; `name` is used in error messages.
pub fn decode_bytes(bytes: &[u8], name: &str) -> Result<Decoded, DecodeError> {
    decode_bytes_want(bytes, name, JpegWant::default())
}

/// Decodes an in-memory photo file, a JPEG only as far as `want` asks
/// (see [`super::jpeg`]); other formats whole.
pub fn decode_bytes_want(bytes: &[u8], name: &str, want: JpegWant) -> Result<Decoded, DecodeError> {
    decode_bytes_observed(bytes, name, want, None)
}

/// [`decode_bytes_want`], a JPEG's luma rows shown as they are decoded
/// ([`super::jpeg::decode_jpeg_observed`]).
pub fn decode_bytes_observed(
    bytes: &[u8],
    name: &str,
    want: JpegWant,
    observe: Option<super::jpeg::ObserverFor<'_>>,
) -> Result<Decoded, DecodeError> {
    let unsupported = |what: String| DecodeError::Unsupported {
        path: name.to_string(),
        what,
    };
    let corrupt = |cause: String| DecodeError::Corrupt {
        path: name.to_string(),
        cause,
    };
    if bytes.is_empty() {
        return Err(corrupt("the file is empty".into()));
    }
    let format = image::guess_format(bytes)
        .map_err(|_| unsupported("not a JPEG, PNG or TIFF file (unrecognised signature)".into()))?;
    let format_name = match format {
        ImageFormat::Jpeg => "jpeg",
        ImageFormat::Png => "png",
        ImageFormat::Tiff => "tiff",
        other => {
            return Err(unsupported(format!(
                "{other:?} images are not read; use JPEG, PNG or TIFF"
            )));
        }
    };
    if format == ImageFormat::Jpeg && !has_jpeg_end(bytes) {
        return Err(corrupt(
            "JPEG data ends without an end-of-image marker (file truncated?)".into(),
        ));
    }
    if format == ImageFormat::Jpeg {
        return decode_jpeg_observed(bytes, name, want, observe).map(|mut d| {
            d.declared_tone = super::transfer::jpeg(bytes);
            d
        });
    }
    let declared_tone = match format {
        ImageFormat::Png => super::transfer::png(bytes),
        _ => super::transfer::tiff(bytes),
    };
    let mut reader = ImageReader::new(Cursor::new(bytes));
    reader.set_format(format);
    let fail = |e: image::ImageError| match e {
        image::ImageError::Unsupported(u) => unsupported(u.to_string()),
        other => corrupt(other.to_string()),
    };
    let decoder = reader.into_decoder().map_err(fail)?;
    let (width, height) = decoder.dimensions();
    let (width, height) = (width as usize, height as usize);
    if width == 0 || height == 0 {
        return Err(corrupt("the image has no pixels".into()));
    }
    // Grey and RGB (what cameras and scanners write) are decoded straight into
    // a buffer on huge pages (a 24 MP JPEG's 72 MB would otherwise fault in
    // as 18 000 small pages); other layouts go through `DynamicImage`.
    let direct = match decoder.color_type() {
        ColorType::L8 | ColorType::L16 => Some(1),
        ColorType::Rgb8 | ColorType::Rgb16 => Some(3),
        _ => None,
    };
    if let Some(channels) = direct {
        // The image crate's default allocation limit (512 MiB), as its own decode applies.
        image::Limits::default()
            .reserve(decoder.total_bytes())
            .map_err(fail)?;
        let n = width * height * channels;
        let samples = if decoder.color_type().bytes_per_pixel() as usize == channels {
            let mut buf = super::hugebuf::zeroed::<u8>(n);
            decoder.read_image(&mut buf).map_err(fail)?;
            Samples::U8(buf)
        } else {
            let mut buf = super::hugebuf::zeroed::<u16>(n);
            // Native-endian 16-bit samples, as `DynamicImage` reads them.
            decoder
                .read_image(bytemuck::cast_slice_mut(&mut buf))
                .map_err(fail)?;
            Samples::U16(buf)
        };
        return Ok(Decoded {
            width,
            height,
            channels,
            samples,
            format: format_name,
            rows: height,
            warnings: Vec::new(),
            declared_tone,
            jpeg_luma_quant: None,
        });
    }
    let img = DynamicImage::from_decoder(decoder).map_err(fail)?;
    let (channels, samples) = match img {
        DynamicImage::ImageLuma8(b) => (1, Samples::U8(b.into_raw())),
        DynamicImage::ImageRgb8(b) => (3, Samples::U8(b.into_raw())),
        DynamicImage::ImageLuma16(b) => (1, Samples::U16(b.into_raw())),
        DynamicImage::ImageRgb16(b) => (3, Samples::U16(b.into_raw())),
        DynamicImage::ImageLumaA8(_) => (1, Samples::U8(img.into_luma8().into_raw())),
        DynamicImage::ImageRgba8(_) => (3, Samples::U8(img.into_rgb8().into_raw())),
        DynamicImage::ImageLumaA16(_) => (1, Samples::U16(img.into_luma16().into_raw())),
        DynamicImage::ImageRgba16(_) => (3, Samples::U16(img.into_rgb16().into_raw())),
        other => {
            return Err(unsupported(format!(
                "{:?} samples are not read; use 8- or 16-bit grey or RGB",
                other.color()
            )));
        }
    };
    Ok(Decoded {
        width,
        height,
        channels,
        samples,
        format: format_name,
        rows: height,
        warnings: Vec::new(),
        declared_tone,
        jpeg_luma_quant: None,
    })
}

/// Whether JPEG data ends with the EOI marker (FF D9), allowing trailing padding.
fn has_jpeg_end(bytes: &[u8]) -> bool {
    let tail = &bytes[bytes.len().saturating_sub(4096)..];
    tail.windows(2).rev().any(|w| w == [0xFF, 0xD9])
}

#[cfg(test)]
mod tests {
    use super::*;

    fn encode(img: DynamicImage, format: ImageFormat) -> Vec<u8> {
        let mut out = Cursor::new(Vec::new());
        img.write_to(&mut out, format).unwrap();
        out.into_inner()
    }

    #[test]
    fn round_trips_png_and_tiff_grey_and_rgb() {
        let grey = image::GrayImage::from_fn(7, 5, |x, y| image::Luma([(x * 30 + y) as u8]));
        let d = decode_bytes(
            &encode(DynamicImage::ImageLuma8(grey), ImageFormat::Png),
            "g.png",
        )
        .unwrap();
        assert_eq!((d.width, d.height, d.channels, d.bits()), (7, 5, 1, 8));
        assert_eq!(d.value(3, 2, 0), 92.0 / 255.0);
        let rgb16 = image::ImageBuffer::<image::Rgb<u16>, _>::from_fn(4, 3, |x, y| {
            image::Rgb([x as u16 * 1000, y as u16 * 7, 65535])
        });
        let d = decode_bytes(
            &encode(DynamicImage::ImageRgb16(rgb16), ImageFormat::Tiff),
            "c.tif",
        )
        .unwrap();
        assert_eq!(
            (d.width, d.channels, d.bits(), d.format),
            (4, 3, 16, "tiff")
        );
        assert_eq!(d.value(2, 1, 0), 2000.0 / 65535.0);
        assert_eq!(d.value(2, 1, 1), 7.0 / 65535.0);
    }

    #[test]
    fn alpha_is_dropped_and_sixteen_bit_grey_kept() {
        // RGBA goes through `DynamicImage` (alpha dropped); 16-bit grey is read directly.
        let rgba =
            image::RgbaImage::from_fn(5, 4, |x, y| image::Rgba([x as u8 * 50, y as u8, 7, 128]));
        let d = decode_bytes(
            &encode(DynamicImage::ImageRgba8(rgba), ImageFormat::Png),
            "a.png",
        )
        .unwrap();
        assert_eq!((d.width, d.height, d.channels, d.bits()), (5, 4, 3, 8));
        assert_eq!(d.value(3, 2, 0), 150.0 / 255.0);
        assert_eq!(d.value(3, 2, 1), 2.0 / 255.0);
        let grey16 = image::ImageBuffer::<image::Luma<u16>, _>::from_fn(6, 2, |x, y| {
            image::Luma([x as u16 * 10_000 + y as u16])
        });
        let d = decode_bytes(
            &encode(DynamicImage::ImageLuma16(grey16), ImageFormat::Png),
            "g16.png",
        )
        .unwrap();
        assert_eq!((d.channels, d.bits()), (1, 16));
        assert_eq!(d.value(5, 1, 0), 50_001.0 / 65535.0);
    }

    #[test]
    fn a_header_promising_gigabytes_is_refused_before_allocating() {
        // A PNG header of 30000×30000 16-bit RGB (5.4 GB) with no pixel data.
        let mut bytes = Vec::new();
        {
            let mut enc = png::Encoder::new(&mut bytes, 30_000, 30_000);
            enc.set_color(png::ColorType::Rgb);
            enc.set_depth(png::BitDepth::Sixteen);
            let _writer = enc.write_header().unwrap();
        }
        let e = decode_bytes(&bytes, "huge.png").unwrap_err();
        assert!(e.to_string().starts_with("huge.png: "), "{e}");
    }

    #[test]
    fn refuses_truncated_empty_and_unknown() {
        let img = image::RgbImage::from_fn(64, 64, |x, y| image::Rgb([x as u8, y as u8, 9]));
        let jpg = encode(DynamicImage::ImageRgb8(img.clone()), ImageFormat::Jpeg);
        assert!(decode_bytes(&jpg, "ok.jpg").is_ok());
        let e = decode_bytes(&jpg[..jpg.len() / 2], "half.jpg").unwrap_err();
        assert!(matches!(e, DecodeError::Corrupt { .. }), "{e}");
        assert!(e.to_string().starts_with("half.jpg: "));
        let png = encode(DynamicImage::ImageRgb8(img), ImageFormat::Png);
        let e = decode_bytes(&png[..png.len() - 40], "half.png").unwrap_err();
        assert!(matches!(e, DecodeError::Corrupt { .. }), "{e}");
        assert!(matches!(
            decode_bytes(b"hello world, not an image", "x.txt"),
            Err(DecodeError::Unsupported { .. })
        ));
        assert!(matches!(
            decode_bytes(b"", "empty.jpg"),
            Err(DecodeError::Corrupt { .. })
        ));
    }
}
