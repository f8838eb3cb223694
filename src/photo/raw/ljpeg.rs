//! Lossless JPEG (ITU T.81 process 14) encoding of one DNG strip or tile of a CFA
//! mosaic, through rawler's encoder (kept here so that only `photo::raw`
//! names the crate). Used by the simulator to write compressed DNGs.

/// Encodes a `width × height` tile of 16-bit CFA samples (row-major, `width`
/// even) as a lossless JPEG the way DNG writers do: two interleaved components
/// of `width / 2` columns, predictor 1 (left neighbour).
pub fn lossless_jpeg_cfa_tile(
    tile: &[u16],
    width: usize,
    height: usize,
) -> Result<Vec<u8>, String> {
    if width == 0 || height == 0 || !width.is_multiple_of(2) || tile.len() != width * height {
        return Err(format!(
            "a {width}×{height} tile with {} samples cannot be encoded (width must be even)",
            tile.len()
        ));
    }
    let encode = || {
        rawler::ljpeg92::LjpegCompressor::new(tile, width / 2, height, 2, 16, 1, 0, 0)
            .and_then(|c| c.encode())
            .map_err(|e| e.to_string())
    };
    super::guard::contain(encode)?
}
