//! [`RawFrame`]: the linear sensor data of one raw file, cropped to its
//! active area, with the CFA pattern and black/white levels needed to turn
//! any site into linear light, and the clipped-site count. Colour planes are
//! cut out on request ([`RawFrame::channel_planes`]) as sparse [`Plane`]s, one
//! per site of the CFA repeat, so nothing is demosaiced and only the sites
//! measured are converted to f32.

use super::super::Plane;
use crate::photo::exif::ExifFacts;
use rayon::prelude::*;
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

/// Black levels in raw units: a pattern repeating from the frame's top-left
/// pixel, `levels[((y % height) * width + x % width) * samples + s]`, plus a
/// per-column and a per-row offset (DNG BlackLevelDeltaH/V) when the file has them.
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
    /// Added to the level of every sample in frame column x (DN): one value per
    /// frame column, or empty for none (DNG BlackLevelDeltaH).
    pub delta_h: Vec<f64>,
    /// Added to the level of every sample in frame row y (DN): one value per
    /// frame row, or empty for none (DNG BlackLevelDeltaV).
    pub delta_v: Vec<f64>,
}

impl BlackLevels {
    /// One level for every site and sample.
    pub fn uniform(level: f64, samples: usize) -> BlackLevels {
        BlackLevels::repeat(1, 1, samples, vec![level; samples])
    }

    /// A repeating pattern of levels (`width × height × samples`, row-major) without deltas.
    pub fn repeat(width: usize, height: usize, samples: usize, levels: Vec<f64>) -> BlackLevels {
        BlackLevels {
            width,
            height,
            samples,
            levels,
            delta_h: Vec::new(),
            delta_v: Vec::new(),
        }
    }

    /// A `width × height` repeat of `levels` (DN, row-major, `samples` per
    /// site) anchored at buffer pixel `anchor`, re-anchored at the frame's
    /// top-left pixel `origin`; one uniform level (the first) when the
    /// levels do not fill the repeat.
    pub fn reanchored(
        levels: Vec<f64>,
        width: usize,
        height: usize,
        samples: usize,
        anchor: (usize, usize),
        origin: (usize, usize),
    ) -> BlackLevels {
        if width == 0 || height == 0 || levels.len() != width * height * samples {
            let first = levels.first().copied().unwrap_or(0.0);
            return BlackLevels::uniform(first, samples);
        }
        let dx = origin.0.saturating_sub(anchor.0);
        let dy = origin.1.saturating_sub(anchor.1);
        let mut out = Vec::with_capacity(levels.len());
        for y in 0..height {
            for x in 0..width {
                let src = (((y + dy) % height) * width + (x + dx) % width) * samples;
                out.extend_from_slice(&levels[src..src + samples]);
            }
        }
        BlackLevels::repeat(width, height, samples, out)
    }

    /// The black level (DN) of sample `s` at frame pixel (x, y).
    pub fn at(&self, x: usize, y: usize, s: usize) -> f64 {
        self.levels[((y % self.height) * self.width + x % self.width) * self.samples + s]
            + self.delta_h.get(x).copied().unwrap_or(0.0)
            + self.delta_v.get(y).copied().unwrap_or(0.0)
    }

    fn is_valid(&self, frame_width: usize, frame_height: usize) -> bool {
        self.width > 0
            && self.height > 0
            && self.samples > 0
            && self.levels.len() == self.width * self.height * self.samples
            && (self.delta_h.is_empty() || self.delta_h.len() == frame_width)
            && (self.delta_v.is_empty() || self.delta_v.len() == frame_height)
            && self
                .levels
                .iter()
                .chain(&self.delta_h)
                .chain(&self.delta_v)
                .all(|l| l.is_finite())
    }

    /// The largest black level over the frame, per sample (DN).
    fn max_per_sample(&self) -> Vec<f64> {
        let dh = self.delta_h.iter().copied().fold(0.0, f64::max);
        let dv = self.delta_v.iter().copied().fold(0.0, f64::max);
        (0..self.samples)
            .map(|s| {
                self.levels
                    .iter()
                    .skip(s)
                    .step_by(self.samples)
                    .copied()
                    .fold(f64::NEG_INFINITY, f64::max)
                    + dh
                    + dv
            })
            .collect()
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
    /// The frame rectangle whose samples were decoded (see [`RawFrame::decoded_rect`]).
    pub(crate) decoded: (usize, usize, usize, usize),
    /// Which decoder read the file, and why rawler when a DNG was not read windowed.
    pub decoder: String,
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

    /// Checks the parts and builds the frame.
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
        if !black.is_valid(w, h) || black.samples != spp {
            return Err(format!(
                "inconsistent black levels ({}×{} repeat of {} levels, {} column and {} row deltas for a {w}×{h} frame)",
                black.width,
                black.height,
                black.levels.len(),
                black.delta_h.len(),
                black.delta_v.len()
            ));
        }
        if white.len() != spp {
            return Err(format!("{} white levels for {spp} samples", white.len()));
        }
        for (&w, b) in white.iter().zip(black.max_per_sample()) {
            if w.partial_cmp(&b) != Some(std::cmp::Ordering::Greater) {
                return Err(format!("white level {w} is not above black level {b}"));
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
        let frame = RawFrame {
            width: w,
            height: h,
            cfa,
            samples_per_pixel: spp,
            black,
            white,
            make: ids.make,
            model: ids.model,
            format: ids.format,
            bits_per_sample: ids.bits_per_sample,
            facts: ids.facts,
            samples,
            layout,
            decoded: (0, 0, w, h),
            decoder: String::new(),
        };
        Ok(frame)
    }

    fn row_range(&self, y: usize) -> std::ops::Range<usize> {
        let l = &self.layout;
        let start = ((l.origin.1 + y) * l.full_width + l.origin.0) * l.samples;
        start..start + self.width * l.samples
    }

    /// Samples in the frame at or above their white level (counted on each call:
    /// a measurement counts the clipped samples of its own region instead).
    pub fn clipped_sites(&self) -> usize {
        let spp = self.samples_per_pixel;
        let white: Vec<f32> = self.white.iter().map(|&w| w as f32).collect();
        // DN ≥ white ⇔ DN ≥ ceil(white) for integers; above u16::MAX nothing clips.
        let white_dn: Vec<u32> = self
            .white
            .iter()
            .map(|&w| w.ceil().clamp(0.0, 65536.0) as u32)
            .collect();
        let mut n = 0;
        for y in 0..self.height {
            let r = self.row_range(y);
            match &self.samples {
                // One sample per pixel: a branch-free count the compiler vectorises.
                Samples::U16(v) if spp == 1 => {
                    let w = white_dn[0].min(65536);
                    if w <= u16::MAX as u32 {
                        let w = w as u16;
                        n += v[r].iter().map(|&d| usize::from(d >= w)).sum::<usize>();
                    }
                }
                Samples::U16(v) => {
                    for px in v[r].chunks_exact(spp) {
                        for (&d, &w) in px.iter().zip(&white_dn) {
                            n += usize::from(d as u32 >= w);
                        }
                    }
                }
                Samples::F32(v) => {
                    for px in v[r].chunks_exact(spp) {
                        for (&d, &w) in px.iter().zip(&white) {
                            n += usize::from(d >= w);
                        }
                    }
                }
            }
        }
        n
    }

    /// [`RawFrame::clipped_sites`] over all samples of the frame.
    pub fn clipped_fraction(&self) -> f64 {
        self.clipped_sites() as f64 / (self.width * self.height * self.samples_per_pixel) as f64
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
        let all = (0, 0, self.width, self.height);
        self.channel_groups_within(channel, all, &|_| (0, self.width))
    }

    /// Like [`RawFrame::channel_groups`], but the planes cover only the frame
    /// rectangle `rect` = (x0, y0, x1, y1) (pixels, end exclusive), and in frame
    /// row y only the columns `span(y)` = [a, b) are converted; other samples
    /// stay 0 (their memory is never touched). A measurement region's rows are
    /// all a measurement reads, so a whole-frame f32 copy is never made.
    pub fn channel_groups_within(
        &self,
        channel: RawChannel,
        rect: (usize, usize, usize, usize),
        span: &(dyn Fn(usize) -> (usize, usize) + Sync),
    ) -> Vec<(&'static str, Vec<Plane>)> {
        let name = |c: CfaColour| match c {
            CfaColour::Red => "r",
            CfaColour::Green => "g",
            CfaColour::Blue => "b",
        };
        let rect = (
            rect.0.min(self.width),
            rect.1.min(self.height),
            rect.2.min(self.width),
            rect.3.min(self.height),
        );
        let site = |offset, step, s| self.site_plane(offset, step, s, rect, span);
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
                            .map(|(x, y)| site((x, y), (pw, ph), 0))
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
                    (name(c), vec![site((0, 0), (1, 1), s)])
                })
                .collect(),
            (None, _) => vec![("grey", vec![site((0, 0), (1, 1), 0)])],
        }
    }

    /// One whole-frame plane for finding the chart: on a Bayer mosaic the
    /// first green lattice (a quarter of the pixels, at their true positions);
    /// on other mosaics every site (colours unbalanced); on linear RGB the G
    /// samples; on a monochrome raw its one plane.
    pub fn location_plane(&self) -> Plane {
        self.location_plane_within((0, 0, self.width, self.height))
    }

    /// [`RawFrame::location_plane`] over the frame rectangle `rect` = (x0, y0,
    /// x1, y1) only (pixels, end exclusive), e.g. around given corners.
    pub fn location_plane_within(&self, rect: (usize, usize, usize, usize)) -> Plane {
        let all = rect;
        let span = |_| (0, self.width);
        match (&self.cfa, self.samples_per_pixel) {
            (Some(cfa), _) if cfa.size() == (2, 2) => {
                let g = self.green_site().unwrap_or((0, 0));
                self.site_plane(g, (2, 2), 0, all, &span)
            }
            (None, 3) => self.site_plane((0, 0), (1, 1), 1, all, &span),
            _ => self.site_plane((0, 0), (1, 1), 0, all, &span),
        }
    }

    /// The position (x, y) in the CFA repeat of a Bayer mosaic's first green
    /// site (the one [`RawFrame::location_plane`] uses); `None` without a 2×2 CFA.
    pub fn green_site(&self) -> Option<(usize, usize)> {
        let cfa = self.cfa.as_ref().filter(|c| c.size() == (2, 2))?;
        [(0, 0), (1, 0), (0, 1), (1, 1)]
            .into_iter()
            .find(|&(x, y)| cfa.colour_at(x, y) == CfaColour::Green)
    }

    /// The linear plane of sample `s` on the lattice of frame pixels
    /// `offset + k·step` inside the frame rectangle `rect` = (x0, y0, x1, y1)
    /// (pixels, end exclusive), e.g. a preview's sparse grid.
    pub fn lattice_plane(
        &self,
        offset: (usize, usize),
        step: (usize, usize),
        s: usize,
        rect: (usize, usize, usize, usize),
    ) -> Plane {
        let rect = (
            rect.0.min(self.width),
            rect.1.min(self.height),
            rect.2.min(self.width),
            rect.3.min(self.height),
        );
        self.site_plane(
            offset,
            step,
            s.min(self.samples_per_pixel - 1),
            rect,
            &|_| (0, self.width),
        )
    }

    /// The plane of sample `s` on the lattice with `step` and `offset` (frame
    /// pixels), over the sites inside `rect`, converting only columns `span(y)`.
    fn site_plane(
        &self,
        offset: (usize, usize),
        step: (usize, usize),
        s: usize,
        rect: (usize, usize, usize, usize),
        span: &(dyn Fn(usize) -> (usize, usize) + Sync),
    ) -> Plane {
        // First lattice index at or after `lo`, and the count of sites in [lo, hi).
        let range = |off: usize, st: usize, lo: usize, hi: usize| {
            let first = if lo > off { (lo - off).div_ceil(st) } else { 0 };
            let start = off + first * st;
            let n = if start < hi {
                (hi - start).div_ceil(st)
            } else {
                0
            };
            (start, n)
        };
        let (x0, pw) = range(offset.0, step.0, rect.0, rect.2);
        let (y0, ph) = range(offset.1, step.1, rect.1, rect.3);
        let spp = self.samples_per_pixel;
        let mut data = crate::photo::hugebuf::zeroed::<f32>(pw * ph);
        // Constant black along the plane when the black repeat divides the lattice step.
        let constant = step.0.is_multiple_of(self.black.width)
            && step.1.is_multiple_of(self.black.height)
            && self.black.delta_h.is_empty();
        let fill_row = |j: usize, out: &mut [f32]| {
            let y = y0 + j * step.1;
            let (a, b) = span(y);
            let (a, b) = (a.max(x0), b.min(rect.2));
            if a >= b {
                return;
            }
            // Lattice columns i with x = x0 + i·step in [a, b).
            let i0 = (a - x0).div_ceil(step.0);
            let i1 = ((b - x0).div_ceil(step.0)).min(pw);
            if i0 >= i1 {
                return;
            }
            let out = &mut out[i0..i1];
            let row = self.row_range(y);
            let first = (x0 + i0 * step.0) * spp + s;
            let stride = step.0 * spp;
            if constant {
                let b = self.black.at(x0, y, s);
                let scale = 1.0 / (self.white[s] - b);
                let (b, scale) = (b as f32, scale as f32);
                match &self.samples {
                    Samples::U16(v) => {
                        for (o, &d) in out
                            .iter_mut()
                            .zip(v[row].iter().skip(first).step_by(stride))
                        {
                            *o = (d as f32 - b) * scale;
                        }
                    }
                    Samples::F32(v) => {
                        for (o, &d) in out
                            .iter_mut()
                            .zip(v[row].iter().skip(first).step_by(stride))
                        {
                            *o = (d - b) * scale;
                        }
                    }
                }
            } else {
                for (k, o) in out.iter_mut().enumerate() {
                    *o = self.value(x0 + (i0 + k) * step.0, y, s);
                }
            }
        };
        if pw > 0 {
            data.par_chunks_mut(pw)
                .enumerate()
                .for_each(|(j, out)| fill_row(j, out));
        }
        Plane {
            width: pw,
            height: ph,
            step,
            offset: (x0, y0),
            data,
        }
    }

    /// The frame rectangle (x0, y0, x1, y1), pixels, end exclusive, whose
    /// samples were decoded: the whole frame unless the file was read for a
    /// region only; samples outside it read as 0 DN.
    pub fn decoded_rect(&self) -> (usize, usize, usize, usize) {
        self.decoded
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
        let black = BlackLevels::repeat(2, 2, 1, vec![100.0, 90.0, 80.0, 70.0]);
        RawFrame::from_mosaic_u16(w, h, CfaPattern::Rggb, black, 440.0, data).unwrap()
    }

    #[test]
    fn lattice_planes_hold_the_pixels_they_name() {
        // Per-site black, so an odd step takes the per-pixel path and an even
        // one the constant-black path; both against the hand formula.
        let f = mosaic();
        assert_eq!(f.green_site(), Some((1, 0)));
        let black = [[100.0, 90.0], [80.0, 70.0]];
        for (offset, step, rect) in [
            ((1, 0), (2, 2), (0, 0, 7, 5)),
            ((0, 0), (3, 3), (0, 0, 7, 5)),
            ((2, 1), (2, 3), (2, 1, 6, 5)),
            ((5, 4), (4, 4), (1, 1, 99, 99)),
        ] {
            let p = f.lattice_plane(offset, step, 0, rect);
            assert_eq!((p.offset, p.step), (offset, step));
            let count = |o: usize, s: usize, hi: usize| (hi.saturating_sub(o)).div_ceil(s);
            assert_eq!(p.width, count(offset.0, step.0, rect.2.min(7)));
            assert_eq!(p.height, count(offset.1, step.1, rect.3.min(5)));
            for j in 0..p.height {
                for i in 0..p.width {
                    let (x, y) = (offset.0 + i * step.0, offset.1 + j * step.1);
                    let dn = 100.0 + (y * 7 + x) as f64 * 10.0;
                    let b = black[y % 2][x % 2];
                    let want = (dn - b) / (440.0 - b);
                    assert!(
                        (p.get(i, j) as f64 - want).abs() < 1e-6,
                        "{offset:?} {step:?} ({x}, {y})"
                    );
                }
            }
        }
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
        assert_eq!(f.clipped_sites(), 1);
    }

    #[test]
    fn windowed_planes_hold_exactly_the_sites_in_the_rectangle_and_spans() {
        let f = mosaic();
        let rect = (1, 1, 6, 5);
        // Row y converts columns [y, y + 3) only.
        let span = |y: usize| (y, y + 3);
        for ch in [RawChannel::R, RawChannel::G, RawChannel::B] {
            let planes = f.channel_groups_within(ch, rect, &span);
            let planes: Vec<&Plane> = planes.iter().flat_map(|g| &g.1).collect();
            let mut seen = 0;
            for p in &planes {
                for j in 0..p.height {
                    for i in 0..p.width {
                        let (cx, cy) = p.centre(i, j);
                        let (x, y) = ((cx - 0.5) as usize, (cy - 0.5) as usize);
                        assert!(x >= rect.0 && x < rect.2 && y >= rect.1 && y < rect.3);
                        assert!(ch.colours().contains(&CfaPattern::Rggb.colour_at(x, y)));
                        let want = if x >= y && x < y + 3 {
                            f.value(x, y, 0)
                        } else {
                            0.0
                        };
                        assert!((p.get(i, j) - want).abs() < 1e-6, "({x},{y})");
                        seen += 1;
                    }
                }
            }
            let all = (rect.1..rect.3)
                .flat_map(|y| (rect.0..rect.2).map(move |x| (x, y)))
                .filter(|&(x, y)| ch.colours().contains(&CfaPattern::Rggb.colour_at(x, y)))
                .count();
            assert_eq!(seen, all, "{ch:?}: every site of the rectangle once");
        }
    }

    #[test]
    fn the_location_plane_is_one_green_lattice_at_true_positions() {
        let f = mosaic();
        let p = f.location_plane();
        assert_eq!(
            (p.step, p.offset, p.width, p.height),
            ((2, 2), (1, 0), 3, 3)
        );
        for j in 0..p.height {
            for i in 0..p.width {
                let (x, y) = (1 + 2 * i, 2 * j);
                assert_eq!(CfaPattern::Rggb.colour_at(x, y), CfaColour::Green);
                assert!((p.get(i, j) - f.value(x, y, 0)).abs() < 1e-6);
            }
        }
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
