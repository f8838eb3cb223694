//! [`RawFrame`]: the linear sensor data of one raw file, cropped to its
//! active area, with the CFA pattern and black/white levels needed to turn
//! any site into linear light, and the clipped-site count. Colour planes are
//! cut out on request ([`RawFrame::channel_planes`]) as sparse [`Plane`]s, one
//! per site of the CFA repeat, so nothing is demosaiced and only the sites
//! measured are converted to f32.

use super::super::Plane;
use crate::photo::exif::ExifFacts;
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
    fn colours(&self) -> &'static [CfaColour] {
        match self {
            RawChannel::R => &[CfaColour::Red],
            RawChannel::G => &[CfaColour::Green],
            RawChannel::B => &[CfaColour::Blue],
            RawChannel::All => &[CfaColour::Red, CfaColour::Green, CfaColour::Blue],
        }
    }
}

/// Black levels in raw units, a pattern repeating from the frame's top-left
/// pixel: `levels[((y % height) * width + x % width) * samples + s]`.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct BlackLevels {
    /// Repeat width in pixels.
    pub width: usize,
    /// Repeat height in pixels.
    pub height: usize,
    /// Samples per pixel (1 for a mosaic, 3 for linear RGB).
    pub samples: usize,
    /// Levels in raw units (DN).
    pub levels: Vec<f64>,
}

impl BlackLevels {
    /// One level for every site and sample.
    pub fn uniform(level: f64, samples: usize) -> BlackLevels {
        BlackLevels {
            width: 1,
            height: 1,
            samples,
            levels: vec![level; samples],
        }
    }

    /// The black level (DN) of sample `s` at frame pixel (x, y).
    pub fn at(&self, x: usize, y: usize, s: usize) -> f64 {
        self.levels[((y % self.height) * self.width + x % self.width) * self.samples + s]
    }

    fn is_valid(&self) -> bool {
        self.width > 0
            && self.height > 0
            && self.samples > 0
            && self.levels.len() == self.width * self.height * self.samples
            && self.levels.iter().all(|l| l.is_finite())
    }
}

/// The decoded samples, kept in the decoder's own type (no f32 copy of the frame).
#[derive(Debug, Clone)]
pub(crate) enum Samples {
    /// Integer DN.
    U16(Vec<u16>),
    /// Floating-point DN (some DNGs).
    F32(Vec<f32>),
}

impl Samples {
    fn len(&self) -> usize {
        match self {
            Samples::U16(v) => v.len(),
            Samples::F32(v) => v.len(),
        }
    }
}

/// Where the frame sits in the decoded buffer.
#[derive(Debug, Clone, Copy)]
pub(crate) struct Layout {
    /// Pixels per row of the decoded buffer.
    pub full_width: usize,
    /// Rows of the decoded buffer.
    pub full_height: usize,
    /// Top-left pixel (x, y) of the frame in the decoded buffer.
    pub origin: (usize, usize),
    /// Frame size (width, height) in pixels.
    pub size: (usize, usize),
    /// Samples per pixel.
    pub samples: usize,
}

/// Linear sensor data of one raw file, cropped to its active area.
///
/// Values are read as `(DN − black) / (white − black)`: 0 = black, 1 = the
/// white (clipping) level; noise may take dark sites slightly below 0 and
/// they are not clamped. A sample ≥ 1 is clipped.
#[derive(Debug, Clone)]
pub struct RawFrame {
    /// Frame width in pixels (the active area / default crop).
    pub width: usize,
    /// Frame height in pixels.
    pub height: usize,
    /// The CFA pattern from the frame's top-left pixel; `None` = no mosaic (linear RGB or monochrome).
    pub cfa: Option<CfaPattern>,
    /// Samples per pixel: 1 for a mosaic or monochrome, 3 for linear RGB (e.g. a linear DNG).
    pub samples_per_pixel: usize,
    /// Black levels (DN), anchored at the frame's top-left pixel.
    pub black: BlackLevels,
    /// White (clipping) level per sample (DN).
    pub white: Vec<f64>,
    /// Samples in the frame at or above their white level.
    pub clipped_sites: usize,
    /// `clipped_sites` over all samples of the frame.
    pub clipped_fraction: f64,
    /// Camera make as written in the file.
    pub make: String,
    /// Camera model as written in the file.
    pub model: String,
    /// Raw container format, e.g. "DNG", "CR2".
    pub format: String,
    /// Bits per sample the camera recorded.
    pub bits_per_sample: usize,
    /// EXIF facts of the file.
    pub facts: ExifFacts,
    pub(crate) samples: Samples,
    pub(crate) layout: Layout,
}

impl RawFrame {
    /// A frame from a 16-bit mosaic (e.g. a simulated Bayer shot): `data` is
    /// `width × height` DN row-major, `cfa` starts at its top-left pixel.
    pub fn from_mosaic_u16(
        width: usize,
        height: usize,
        cfa: CfaPattern,
        black: BlackLevels,
        white: f64,
        data: Vec<u16>,
    ) -> Result<RawFrame, String> {
        let layout = Layout {
            full_width: width,
            full_height: height,
            origin: (0, 0),
            size: (width, height),
            samples: 1,
        };
        RawFrame::assemble(
            layout,
            Some(cfa),
            black,
            vec![white],
            Samples::U16(data),
            Default::default(),
        )
    }

    /// Checks the parts, counts clipped samples, and builds the frame.
    pub(crate) fn assemble(
        layout: Layout,
        cfa: Option<CfaPattern>,
        black: BlackLevels,
        white: Vec<f64>,
        samples: Samples,
        ids: Ids,
    ) -> Result<RawFrame, String> {
        let (w, h) = layout.size;
        let spp = layout.samples;
        if w == 0 || h == 0 {
            return Err(format!("empty frame ({w}×{h} px)"));
        }
        if layout.origin.0 + w > layout.full_width || layout.origin.1 + h > layout.full_height {
            return Err(format!(
                "frame {w}×{h} at ({}, {}) does not fit in the {}×{} px of data",
                layout.origin.0, layout.origin.1, layout.full_width, layout.full_height
            ));
        }
        let needed = layout.full_width * layout.full_height * spp;
        if samples.len() < needed {
            return Err(format!(
                "{} samples decoded where {}×{}×{} = {needed} are needed",
                samples.len(),
                layout.full_width,
                layout.full_height,
                spp
            ));
        }
        if !black.is_valid() || black.samples != spp {
            return Err(format!("inconsistent black levels {black:?}"));
        }
        if white.len() != spp {
            return Err(format!("{} white levels for {spp} samples", white.len()));
        }
        for (s, &w) in white.iter().enumerate() {
            for &b in black.levels.iter().skip(s).step_by(spp) {
                if w.partial_cmp(&b) != Some(std::cmp::Ordering::Greater) {
                    return Err(format!("white level {w} is not above black level {b}"));
                }
            }
        }
        if let Some(c) = &cfa {
            if spp != 1 {
                return Err(format!("a CFA mosaic with {spp} samples per pixel"));
            }
            if let CfaPattern::Other {
                width,
                height,
                colours,
            } = c
                && (*width == 0 || *height == 0 || colours.len() != width * height)
            {
                return Err("malformed CFA pattern".to_string());
            }
        }
        let mut frame = RawFrame {
            width: w,
            height: h,
            cfa,
            samples_per_pixel: spp,
            black,
            white,
            clipped_sites: 0,
            clipped_fraction: 0.0,
            make: ids.make,
            model: ids.model,
            format: ids.format,
            bits_per_sample: ids.bits_per_sample,
            facts: ids.facts,
            samples,
            layout,
        };
        frame.clipped_sites = frame.count_clipped();
        frame.clipped_fraction = frame.clipped_sites as f64 / (w * h * spp) as f64;
        Ok(frame)
    }

    fn row_range(&self, y: usize) -> std::ops::Range<usize> {
        let l = &self.layout;
        let start = ((l.origin.1 + y) * l.full_width + l.origin.0) * l.samples;
        start..start + self.width * l.samples
    }

    fn count_clipped(&self) -> usize {
        let spp = self.samples_per_pixel;
        let white: Vec<f32> = self.white.iter().map(|&w| w as f32).collect();
        // DN ≥ white ⇔ DN ≥ ceil(white) for integers; 65536 never happens in u16.
        let white_dn: Vec<u32> = self
            .white
            .iter()
            .map(|&w| w.ceil().clamp(0.0, 65536.0) as u32)
            .collect();
        let mut n = 0;
        for y in 0..self.height {
            let r = self.row_range(y);
            match &self.samples {
                Samples::U16(v) => {
                    for (i, &d) in v[r].iter().enumerate() {
                        if d as u32 >= white_dn[i % spp] {
                            n += 1;
                        }
                    }
                }
                Samples::F32(v) => {
                    for (i, &d) in v[r].iter().enumerate() {
                        if d >= white[i % spp] {
                            n += 1;
                        }
                    }
                }
            }
        }
        n
    }

    /// Linear value of sample `s` of frame pixel (x, y): (DN − black)/(white − black).
    pub fn value(&self, x: usize, y: usize, s: usize) -> f32 {
        let i = self.row_range(y).start + x * self.samples_per_pixel + s;
        let dn = match &self.samples {
            Samples::U16(v) => v[i] as f64,
            Samples::F32(v) => v[i] as f64,
        };
        let b = self.black.at(x, y, s);
        ((dn - b) / (self.white[s] - b)) as f32
    }

    /// The raw DN of sample `s` at frame pixel (x, y), as decoded.
    pub fn dn(&self, x: usize, y: usize, s: usize) -> f64 {
        let i = self.row_range(y).start + x * self.samples_per_pixel + s;
        match &self.samples {
            Samples::U16(v) => v[i] as f64,
            Samples::F32(v) => v[i] as f64,
        }
    }

    /// Linear planes of `channel`. A mosaic gives one sparse plane per site
    /// of the CFA repeat with that colour (Bayer: step (2, 2); `G` gives both
    /// greens, `All` gives R, G…, B in that order); linear RGB gives full
    /// planes of the chosen samples (R, G, B for `All`); a monochrome raw
    /// gives its one plane for any channel.
    pub fn channel_planes(&self, channel: RawChannel) -> Vec<Plane> {
        self.channel_groups(channel)
            .into_iter()
            .flat_map(|(_, planes)| planes)
            .collect()
    }

    /// Planes of `channel` grouped by colour, named "r", "g", "b" (or "grey"
    /// for a monochrome raw): one group per CSV column / plot curve.
    pub fn channel_groups(&self, channel: RawChannel) -> Vec<(&'static str, Vec<Plane>)> {
        let name = |c: CfaColour| match c {
            CfaColour::Red => "r",
            CfaColour::Green => "g",
            CfaColour::Blue => "b",
        };
        match (&self.cfa, self.samples_per_pixel) {
            (Some(cfa), _) => {
                let (pw, ph) = cfa.size();
                channel
                    .colours()
                    .iter()
                    .map(|&c| {
                        let planes = (0..ph)
                            .flat_map(|y| (0..pw).map(move |x| (x, y)))
                            .filter(|&(x, y)| cfa.colour_at(x, y) == c)
                            .map(|(x, y)| self.site_plane((x, y), (pw, ph), 0))
                            .filter(|p| p.width > 0 && p.height > 0)
                            .collect();
                        (name(c), planes)
                    })
                    .filter(|(_, planes): &(&str, Vec<Plane>)| !planes.is_empty())
                    .collect()
            }
            (None, 3) => channel
                .colours()
                .iter()
                .map(|&c| {
                    let s = match c {
                        CfaColour::Red => 0,
                        CfaColour::Green => 1,
                        CfaColour::Blue => 2,
                    };
                    (name(c), vec![self.site_plane((0, 0), (1, 1), s)])
                })
                .collect(),
            (None, _) => vec![("grey", vec![self.site_plane((0, 0), (1, 1), 0)])],
        }
    }

    /// The plane of sample `s` on the lattice with `step` and `offset` (frame pixels).
    fn site_plane(&self, offset: (usize, usize), step: (usize, usize), s: usize) -> Plane {
        let pw = if offset.0 < self.width {
            (self.width - offset.0).div_ceil(step.0)
        } else {
            0
        };
        let ph = if offset.1 < self.height {
            (self.height - offset.1).div_ceil(step.1)
        } else {
            0
        };
        let spp = self.samples_per_pixel;
        let mut data = Vec::with_capacity(pw * ph);
        // Constant black along the plane when the black repeat divides the lattice step.
        let constant =
            step.0.is_multiple_of(self.black.width) && step.1.is_multiple_of(self.black.height);
        for j in 0..ph {
            let y = offset.1 + j * step.1;
            let row = self.row_range(y);
            let first = offset.0 * spp + s;
            let stride = step.0 * spp;
            if constant {
                let b = self.black.at(offset.0, y, s);
                let scale = 1.0 / (self.white[s] - b);
                let (b, scale) = (b as f32, scale as f32);
                match &self.samples {
                    Samples::U16(v) => data.extend(
                        v[row]
                            .iter()
                            .skip(first)
                            .step_by(stride)
                            .take(pw)
                            .map(|&d| (d as f32 - b) * scale),
                    ),
                    Samples::F32(v) => data.extend(
                        v[row]
                            .iter()
                            .skip(first)
                            .step_by(stride)
                            .take(pw)
                            .map(|&d| (d - b) * scale),
                    ),
                }
            } else {
                for i in 0..pw {
                    data.push(self.value(offset.0 + i * step.0, y, s));
                }
            }
        }
        Plane {
            width: pw,
            height: ph,
            step,
            offset,
            data,
        }
    }

    /// Bytes held by the decoded samples (the whole decoded buffer, not only the frame).
    pub fn decoded_bytes(&self) -> usize {
        match &self.samples {
            Samples::U16(v) => v.len() * 2,
            Samples::F32(v) => v.len() * 4,
        }
    }
}

/// Identity and facts carried into a frame.
#[derive(Debug, Clone, Default)]
pub(crate) struct Ids {
    pub make: String,
    pub model: String,
    pub format: String,
    pub bits_per_sample: usize,
    pub facts: ExifFacts,
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A 7×5 RGGB mosaic whose DN encode the pixel position.
    fn mosaic() -> RawFrame {
        let (w, h) = (7, 5);
        let data: Vec<u16> = (0..w * h).map(|i| 100 + i as u16 * 10).collect();
        let black = BlackLevels {
            width: 2,
            height: 2,
            samples: 1,
            levels: vec![100.0, 90.0, 80.0, 70.0],
        };
        RawFrame::from_mosaic_u16(w, h, CfaPattern::Rggb, black, 440.0, data).unwrap()
    }

    #[test]
    fn bayer_planes_match_a_brute_force_walk_over_every_pixel() {
        let f = mosaic();
        let black = [[100.0, 90.0], [80.0, 70.0]];
        for ch in [RawChannel::R, RawChannel::G, RawChannel::B, RawChannel::All] {
            let planes = f.channel_planes(ch);
            let mut seen = 0;
            for p in &planes {
                assert_eq!(p.step, (2, 2));
                for j in 0..p.height {
                    for i in 0..p.width {
                        let (cx, cy) = p.centre(i, j);
                        let (x, y) = ((cx - 0.5) as usize, (cy - 0.5) as usize);
                        let dn = 100.0 + (y * 7 + x) as f64 * 10.0;
                        let b = black[y % 2][x % 2];
                        let want = (dn - b) / (440.0 - b);
                        assert!((p.get(i, j) as f64 - want).abs() < 1e-6);
                        let c = CfaPattern::Rggb.colour_at(x, y);
                        assert!(ch.colours().contains(&c));
                        seen += 1;
                    }
                }
            }
            // every pixel of the wanted colours, once
            let expected = (0..5)
                .flat_map(|y| (0..7).map(move |x| (x, y)))
                .filter(|&(x, y)| ch.colours().contains(&CfaPattern::Rggb.colour_at(x, y)))
                .count();
            assert_eq!(seen, expected, "{ch:?}");
        }
        let g = f.channel_planes(RawChannel::G);
        assert_eq!(g.len(), 2);
        assert_eq!((g[0].offset, g[0].width, g[0].height), ((1, 0), 3, 3));
        assert_eq!((g[1].offset, g[1].width, g[1].height), ((0, 1), 4, 2));
        // DN 440 and above are clipped: pixels with 100 + 10 i >= 440 → i >= 34 → one pixel
        assert_eq!(f.clipped_sites, 1);
    }

    #[test]
    fn patterns_shift_and_parse() {
        assert_eq!(CfaPattern::Rggb.shifted(1, 0), CfaPattern::Grbg);
        assert_eq!(CfaPattern::Rggb.shifted(0, 1), CfaPattern::Gbrg);
        assert_eq!(CfaPattern::Rggb.shifted(1, 1), CfaPattern::Bggr);
        assert_eq!(CfaPattern::parse("bggr"), Some(CfaPattern::Bggr));
        assert_eq!(CfaPattern::Gbrg.name(), "GBRG");
        assert_eq!(CfaPattern::parse("RGB"), None);
        let x = CfaPattern::parse("GGRGGBGGBGGRBRGRBGGGBGGRGGRGGBRBGBRG").unwrap();
        assert_eq!(x.size(), (6, 6));
    }

    #[test]
    fn inconsistent_parts_are_refused() {
        let b = BlackLevels::uniform(10.0, 1);
        assert!(
            RawFrame::from_mosaic_u16(4, 4, CfaPattern::Rggb, b.clone(), 5.0, vec![0; 16]).is_err()
        );
        assert!(
            RawFrame::from_mosaic_u16(4, 4, CfaPattern::Rggb, b.clone(), 500.0, vec![0; 15])
                .is_err()
        );
        assert!(RawFrame::from_mosaic_u16(0, 4, CfaPattern::Rggb, b, 500.0, vec![]).is_err());
    }
}
