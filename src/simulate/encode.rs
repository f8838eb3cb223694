//! Stored code values and file formats: the transfer curve (sRGB, gamma,
//! linear), quantisation to 8 or 16 bits, and PNG, TIFF or JPEG (at a given
//! quality, through the `image` crate's encoder) as grey images; a Bayer mosaic
//! is one 16-bit linear channel (TIFF files also carry the TIFF/EP CFA tags),
//! or a camera-raw DNG ([`super::dng`]).

use super::{BayerOrder, Camera, Chroma, Encoding, SimError};
use image::ImageEncoder;
use image::codecs::jpeg::JpegEncoder;
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
    encode_codes(camera, &quantise(camera, linear), false, format)
}

/// Encodes a colour shot's recorded linear R, G, B planes (1.0 = clipping) in
/// `format`: RGB PNG or TIFF (8 or 16 bits), or JPEG with the camera's chroma
/// sampling (through the `jpeg-encoder` crate, which writes 4:2:0 and 4:2:2).
pub fn encode_rgb(
    camera: &Camera,
    rgb: &[Vec<f32>; 3],
    format: PhotoFormat,
) -> Result<Vec<u8>, SimError> {
    if format == PhotoFormat::Dng {
        return Err(SimError::Parameter(
            "a DNG holds a Bayer mosaic, not a colour image".into(),
        ));
    }
    let planes: Vec<Vec<u16>> = rgb.iter().map(|p| quantise(camera, p)).collect();
    let interleaved: Vec<u16> = (0..planes[0].len())
        .flat_map(|i| [planes[0][i], planes[1][i], planes[2][i]])
        .collect();
    encode_codes(camera, &interleaved, true, format)
}

/// Encodes code values (grey, or interleaved RGB when `rgb`) as PNG, TIFF or JPEG.
fn encode_codes(
    camera: &Camera,
    codes: &[u16],
    rgb: bool,
    format: PhotoFormat,
) -> Result<Vec<u8>, SimError> {
    let (w, h) = (camera.width_px as u32, camera.height_px as u32);
    let eight = camera.stored_bits() == 8;
    let bytes8 = || codes.iter().map(|&c| c as u8).collect::<Vec<u8>>();
    let mut out = Vec::new();
    match format {
        PhotoFormat::Dng => {
            return Err(SimError::Internal(
                "a DNG is written from linear data".into(),
            ));
        }
        PhotoFormat::Jpeg => {
            if !eight {
                return Err(SimError::Parameter(
                    "JPEG stores 8 bits: use --bits 8 or a PNG/TIFF name".into(),
                ));
            }
            let q = camera.jpeg_quality.unwrap_or(90);
            if rgb {
                let (ww, hh) = (
                    u16::try_from(w).map_err(img_err)?,
                    u16::try_from(h).map_err(img_err)?,
                );
                let mut enc = jpeg_encoder::Encoder::new(&mut out, q);
                enc.set_sampling_factor(match camera.chroma {
                    Chroma::S420 => jpeg_encoder::SamplingFactor::R_4_2_0,
                    Chroma::S422 => jpeg_encoder::SamplingFactor::R_4_2_2,
                    Chroma::S444 => jpeg_encoder::SamplingFactor::R_4_4_4,
                });
                enc.encode(&bytes8(), ww, hh, jpeg_encoder::ColorType::Rgb)
                    .map_err(img_err)?;
            } else {
                JpegEncoder::new_with_quality(&mut out, q)
                    .write_image(&bytes8(), w, h, image::ExtendedColorType::L8)
                    .map_err(img_err)?;
            }
        }
        PhotoFormat::Png => {
            let colour = if rgb {
                png::ColorType::Rgb
            } else {
                png::ColorType::Grayscale
            };
            out = png_bytes(camera, codes, w, h, colour)?;
        }
        PhotoFormat::Tiff => {
            let mut cur = Cursor::new(Vec::new());
            {
                use tiff::encoder::{TiffEncoder, colortype};
                let mut enc = TiffEncoder::new(&mut cur).map_err(img_err)?;
                match (rgb, eight) {
                    (true, true) => enc.write_image::<colortype::RGB8>(w, h, &bytes8()),
                    (true, false) => enc.write_image::<colortype::RGB16>(w, h, codes),
                    (false, true) => enc.write_image::<colortype::Gray8>(w, h, &bytes8()),
                    (false, false) => {
                        let mut im = enc.new_image::<colortype::Gray16>(w, h).map_err(img_err)?;
                        if let Some(order) = camera.bayer {
                            write_cfa_tags(&mut im, order).map_err(img_err)?;
                        }
                        im.write_data(codes)
                    }
                }
                .map_err(img_err)?;
            }
            out = cur.into_inner();
        }
    }
    Ok(out)
}

/// A PNG of `codes` (grey or interleaved RGB, 8 or 16 bits as the camera
/// stores) whose header names its transfer curve: an sRGB chunk, or a gAMA
/// chunk for a power law or linear data, so that readers need not guess.
fn png_bytes(
    camera: &Camera,
    codes: &[u16],
    w: u32,
    h: u32,
    colour: png::ColorType,
) -> Result<Vec<u8>, SimError> {
    let mut out = Vec::new();
    let mut enc = png::Encoder::new(&mut out, w, h);
    // Fast deflate, as for every picture the crate writes: a simulated shot
    // is written once and read by a measurement; size matters less than time.
    enc.set_compression(png::Compression::Fast);
    enc.set_color(colour);
    let eight = camera.stored_bits() == 8;
    enc.set_depth(if eight {
        png::BitDepth::Eight
    } else {
        png::BitDepth::Sixteen
    });
    match camera.stored_encoding() {
        Encoding::Srgb => enc.set_source_srgb(png::SrgbRenderingIntent::RelativeColorimetric),
        Encoding::Gamma(g) => enc.set_source_gamma(png::ScaledFloat::new((1.0 / g) as f32)),
        Encoding::Linear => enc.set_source_gamma(png::ScaledFloat::new(1.0)),
    }
    let data: Vec<u8> = if eight {
        codes.iter().map(|&c| c as u8).collect()
    } else {
        codes.iter().flat_map(|c| c.to_be_bytes()).collect()
    };
    let mut writer = enc.write_header().map_err(img_err)?;
    writer.write_image_data(&data).map_err(img_err)?;
    writer.finish().map_err(img_err)?;
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
