//! The CFA side of a raw frame: site colours, the repeating colour-filter
//! pattern, and the colour planes a `--channel` asks for.

use serde::Serialize;
use std::str::FromStr;

/// The colour of a CFA site (only RGB mosaics are supported).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Serialize)]
#[serde(rename_all = "lowercase")]
pub enum CfaColour {
    /// Red filter.
    Red,
    /// Green filter.
    Green,
    /// Blue filter.
    Blue,
}

impl CfaColour {
    /// One letter: R, G or B.
    pub fn letter(&self) -> char {
        match self {
            CfaColour::Red => 'R',
            CfaColour::Green => 'G',
            CfaColour::Blue => 'B',
        }
    }

    /// The colour of a letter R, G or B (case-insensitive).
    pub fn from_letter(c: char) -> Option<CfaColour> {
        match c.to_ascii_uppercase() {
            'R' => Some(CfaColour::Red),
            'G' => Some(CfaColour::Green),
            'B' => Some(CfaColour::Blue),
            _ => None,
        }
    }
}

/// The colour filter arrangement, repeating from the frame's top-left pixel.
#[derive(Debug, Clone, PartialEq, Eq, Serialize)]
pub enum CfaPattern {
    /// Row 0: R G; row 1: G B.
    Rggb,
    /// Row 0: B G; row 1: G R.
    Bggr,
    /// Row 0: G R; row 1: B G.
    Grbg,
    /// Row 0: G B; row 1: R G.
    Gbrg,
    /// Any other RGB repeat (e.g. Fujifilm X-Trans 6×6), row-major colours.
    Other {
        /// Repeat width in pixels.
        width: usize,
        /// Repeat height in pixels.
        height: usize,
        /// Colours of the repeat, row-major, `width × height`.
        colours: Vec<CfaColour>,
    },
}

impl CfaPattern {
    /// The pattern with these row-major colours (named when it is a 2×2 Bayer).
    pub fn from_colours(width: usize, height: usize, colours: Vec<CfaColour>) -> CfaPattern {
        use CfaColour::*;
        if width == 2 && height == 2 {
            match colours.as_slice() {
                [Red, Green, Green, Blue] => return CfaPattern::Rggb,
                [Blue, Green, Green, Red] => return CfaPattern::Bggr,
                [Green, Red, Blue, Green] => return CfaPattern::Grbg,
                [Green, Blue, Red, Green] => return CfaPattern::Gbrg,
                _ => {}
            }
        }
        CfaPattern::Other {
            width,
            height,
            colours,
        }
    }

    /// Reads a square pattern written as letters row by row ("RGGB", 36 letters for 6×6).
    pub fn parse(name: &str) -> Option<CfaPattern> {
        let colours: Option<Vec<CfaColour>> = name.chars().map(CfaColour::from_letter).collect();
        let colours = colours?;
        let side = (colours.len() as f64).sqrt().round() as usize;
        if side == 0 || side * side != colours.len() {
            return None;
        }
        Some(CfaPattern::from_colours(side, side, colours))
    }

    /// Repeat size in pixels (width, height).
    pub fn size(&self) -> (usize, usize) {
        match self {
            CfaPattern::Other { width, height, .. } => (*width, *height),
            _ => (2, 2),
        }
    }

    /// Colour of the pixel at (x, y) of the frame (column, row from the top-left).
    pub fn colour_at(&self, x: usize, y: usize) -> CfaColour {
        use CfaColour::*;
        let (xi, yi) = (x % 2, y % 2);
        match self {
            CfaPattern::Rggb => [[Red, Green], [Green, Blue]][yi][xi],
            CfaPattern::Bggr => [[Blue, Green], [Green, Red]][yi][xi],
            CfaPattern::Grbg => [[Green, Red], [Blue, Green]][yi][xi],
            CfaPattern::Gbrg => [[Green, Blue], [Red, Green]][yi][xi],
            CfaPattern::Other {
                width,
                height,
                colours,
            } => colours[(y % height) * width + x % width],
        }
    }

    /// The pattern's letters row by row, e.g. "RGGB".
    pub fn name(&self) -> String {
        let (w, h) = self.size();
        (0..h)
            .flat_map(|y| (0..w).map(move |x| (x, y)))
            .map(|(x, y)| self.colour_at(x, y).letter())
            .collect()
    }

    /// The pattern as seen from pixel (dx, dy) of this one taken as the new origin.
    pub fn shifted(&self, dx: usize, dy: usize) -> CfaPattern {
        let (w, h) = self.size();
        let colours = (0..h)
            .flat_map(|y| (0..w).map(move |x| (x, y)))
            .map(|(x, y)| self.colour_at(x + dx, y + dy))
            .collect();
        CfaPattern::from_colours(w, h, colours)
    }
}

/// Which colour planes to take from a raw frame (`--channel`).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(rename_all = "lowercase")]
pub enum RawChannel {
    /// Red sites.
    R,
    /// Green sites (both greens of a Bayer mosaic).
    G,
    /// Blue sites.
    B,
    /// Every colour, each separately.
    All,
}

impl FromStr for RawChannel {
    type Err = String;
    fn from_str(s: &str) -> Result<Self, Self::Err> {
        match s.to_ascii_lowercase().as_str() {
            "r" | "red" => Ok(RawChannel::R),
            "g" | "green" => Ok(RawChannel::G),
            "b" | "blue" => Ok(RawChannel::B),
            "all" => Ok(RawChannel::All),
            _ => Err(format!("'{s}' is not a raw channel; use r, g, b or all")),
        }
    }
}

impl RawChannel {
    pub(super) fn colours(&self) -> &'static [CfaColour] {
        match self {
            RawChannel::R => &[CfaColour::Red],
            RawChannel::G => &[CfaColour::Green],
            RawChannel::B => &[CfaColour::Blue],
            RawChannel::All => &[CfaColour::Red, CfaColour::Green, CfaColour::Blue],
        }
    }
}
