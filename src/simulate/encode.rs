//! Stored code values and file formats: the transfer curve (sRGB, gamma,
//! linear), quantisation to 8 or 16 bits, and PNG, TIFF or JPEG (at a given
//! quality, through the `image` crate's encoder) as grey images; a Bayer mosaic
//! is one 16-bit linear channel (TIFF files also carry the TIFF/EP CFA tags),
//! or a camera-raw DNG ([`super::dng`]).

use super::{BayerOrder, Camera, SimError};
use image::ImageEncoder;
use image::codecs::jpeg::JpegEncoder;
use image::codecs::png::PngEncoder;
use std::io::Cursor;
use std::path::Path;

/// A photo file format.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum PhotoFormat {
    /// PNG, 8 or 16 bits.
    Png,
    /// Baseline JPEG, 8 bits.
    Jpeg,
    /// TIFF, 8 or 16 bits.
    Tiff,
    /// DNG camera raw of a Bayer mosaic (16-bit, black and white levels, active area).
    Dng,
}

impl PhotoFormat {
    /// The format named by a file's extension (.png, .jpg/.jpeg, .tif/.tiff, .dng).
    pub fn from_path(path: &Path) -> Result<PhotoFormat, SimError> {
        let ext = path
            .extension()
            .and_then(|e| e.to_str())
            .map(str::to_ascii_lowercase)
            .unwrap_or_default();
        match ext.as_str() {
            "png" => Ok(PhotoFormat::Png),
            "jpg" | "jpeg" => Ok(PhotoFormat::Jpeg),
            "tif" | "tiff" => Ok(PhotoFormat::Tiff),
            "dng" => Ok(PhotoFormat::Dng),
            _ => Err(SimError::Parameter(format!(
                "{}: the photo's name must end in .png, .jpg, .tif or .dng (with --bayer)",
                path.display()
            ))),
        }
    }
}

/// Code values of the recorded linear image: `bits`-bit integers after the transfer curve.
pub fn quantise(camera: &Camera, linear: &[f32]) -> Vec<u16> {
    let max = if camera.stored_bits() == 8 {
        255.0
    } else {
        65535.0
    };
    let enc = camera.stored_encoding();
    // A table for 8-bit output would be coarse for 16-bit input; evaluate directly.
    linear
        .iter()
        .map(|&v| (enc.encode(v as f64) * max).round() as u16)
        .collect()
}

fn img_err(e: impl std::fmt::Display) -> SimError {
    SimError::Encode(e.to_string())
}

/// Encodes the recorded image (`linear`, width × height, 1.0 = clipping) in `format`.
pub fn encode(camera: &Camera, linear: &[f32], format: PhotoFormat) -> Result<Vec<u8>, SimError> {
    if format == PhotoFormat::Dng {
        return super::dng::encode(camera, linear);
    }
    let (w, h) = (camera.width_px as u32, camera.height_px as u32);
    let codes = quantise(camera, linear);
    let bytes8 = || codes.iter().map(|&c| c as u8).collect::<Vec<u8>>();
    let bytes16 = || {
        codes
            .iter()
            .flat_map(|c| c.to_ne_bytes())
            .collect::<Vec<u8>>()
    };
    let mut out = Vec::new();
    match format {
        PhotoFormat::Dng => return super::dng::encode(camera, linear),
        PhotoFormat::Jpeg => {
            if camera.stored_bits() != 8 {
                return Err(SimError::Parameter(
                    "JPEG stores 8 bits: use --bits 8 or a PNG/TIFF name".into(),
                ));
            }
            let q = camera.jpeg_quality.unwrap_or(90);
            JpegEncoder::new_with_quality(&mut out, q)
                .write_image(&bytes8(), w, h, image::ExtendedColorType::L8)
                .map_err(img_err)?;
        }
        PhotoFormat::Png => {
            let (buf, ct) = if camera.stored_bits() == 8 {
                (bytes8(), image::ExtendedColorType::L8)
            } else {
                (bytes16(), image::ExtendedColorType::L16)
            };
            PngEncoder::new(&mut out)
                .write_image(&buf, w, h, ct)
                .map_err(img_err)?;
        }
        PhotoFormat::Tiff => {
            let mut cur = Cursor::new(Vec::new());
            {
                use tiff::encoder::{TiffEncoder, colortype};
                let mut enc = TiffEncoder::new(&mut cur).map_err(img_err)?;
                if camera.stored_bits() == 8 {
                    let buf = bytes8();
                    enc.write_image::<colortype::Gray8>(w, h, &buf)
                        .map_err(img_err)?;
                } else {
                    let mut im = enc.new_image::<colortype::Gray16>(w, h).map_err(img_err)?;
                    if let Some(order) = camera.bayer {
                        write_cfa_tags(&mut im, order).map_err(img_err)?;
                    }
                    im.write_data(&codes).map_err(img_err)?;
                }
            }
            out = cur.into_inner();
        }
    }
    Ok(out)
}

/// Writes the TIFF/EP tags CFARepeatPatternDim (33421) and CFAPattern (33422).
fn write_cfa_tags<W: std::io::Write + std::io::Seek, K: tiff::encoder::TiffKind>(
    im: &mut tiff::encoder::ImageEncoder<W, tiff::encoder::colortype::Gray16, K>,
    order: BayerOrder,
) -> tiff::TiffResult<()> {
    use tiff::tags::Tag;
    let pattern: [u8; 4] = [
        order.colour_at(0, 0) as u8,
        order.colour_at(1, 0) as u8,
        order.colour_at(0, 1) as u8,
        order.colour_at(1, 1) as u8,
    ];
    let d = im.encoder();
    d.write_tag(Tag::Unknown(33421), &[2u16, 2u16][..])?;
    d.write_tag(Tag::Unknown(33422), &pattern[..])?;
    Ok(())
}
