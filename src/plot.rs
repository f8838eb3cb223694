//! Shared plotting set-up: the embedded DejaVu Sans font, registered once with
//! plotters so that no system font library is ever needed.

use std::sync::Once;

static REGISTER: Once = Once::new();

/// Font family name to use in every plot.
pub const FONT: &str = "sans-serif";

/// Registers the embedded font with plotters; call before drawing any text.
pub fn ensure_font() {
    REGISTER.call_once(|| {
        // The embedded font is a valid TTF; registration cannot fail for it.
        let _ = plotters::style::register_font(
            FONT,
            plotters::style::FontStyle::Normal,
            dejavu::sans::regular(),
        );
        let _ = plotters::style::register_font(
            FONT,
            plotters::style::FontStyle::Bold,
            dejavu::sans::bold(),
        );
    });
}

/// Encodes 8-bit RGB pixels (`w`×`h`, row-major) as PNG bytes at the fast
/// compression level: every plot and picture of the crate goes through here
/// (they are written on every run; a smaller file is not worth the time).
pub fn encode_png(rgb: &[u8], w: u32, h: u32) -> Result<Vec<u8>, String> {
    encode_png_with(rgb, w, h, png::Compression::Fast)
}

/// [`encode_png`] for a photograph (the region picture, a magnified view):
/// every row filtered by its difference from the row above, instead of the
/// best of five filters tried per row. On the target shot's 1029 × 811
/// region picture: 6.1 → 5.2 ms, 878 → 926 kB (a plot's flat areas need the
/// search: its file grows six-fold this way).
pub fn encode_png_photo(rgb: &[u8], w: u32, h: u32) -> Result<Vec<u8>, String> {
    encode_png_with(rgb, w, h, png::Compression::Fastest)
}

fn encode_png_with(rgb: &[u8], w: u32, h: u32, level: png::Compression) -> Result<Vec<u8>, String> {
    if rgb.len() as u64 != w as u64 * h as u64 * 3 {
        return Err(format!("{} bytes for a {w}×{h} RGB picture", rgb.len()));
    }
    // Room for the whole file at once (a photograph compresses to about a
    // third of its bytes; a plot to far less): growing the vector by
    // doubling copied it each time into freshly faulted pages.
    let mut out = Vec::with_capacity(rgb.len() / 2 + 4096);
    {
        let mut enc = png::Encoder::new(&mut out, w, h);
        enc.set_color(png::ColorType::Rgb);
        enc.set_depth(png::BitDepth::Eight);
        enc.set_compression(level);
        let mut wr = enc.write_header().map_err(|e| e.to_string())?;
        wr.write_image_data(rgb).map_err(|e| e.to_string())?;
    }
    Ok(out)
}
