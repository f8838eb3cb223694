//! Camera raw files: decoding through `rawler` behind our own [`RawFrame`]
//! (no other module sees the crate), linear CFA data with black levels
//! subtracted per CFA site and scaled by the white level, the active area
//! respected, clipped sites counted, and colour planes handed out as sparse
//! [`super::Plane`]s without demosaicing. Decoder panics are contained and
//! become errors for that file.

mod decode;
mod dng;
mod frame;
mod greens;
mod guard;
mod ljpeg;
mod tiff_bounds;

pub use decode::{
    RAW_EXTENSIONS, RawError, decode_raw, decode_raw_with_rawler, decode_raw_within, is_raw_path,
    read_raw_facts,
};
pub use frame::{BlackLevels, CfaColour, CfaPattern, RawChannel, RawFrame};
pub use greens::{GreenBalance, balance as balance_greens, green_name};
pub use ljpeg::lossless_jpeg_cfa_tile;
