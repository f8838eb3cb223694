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
