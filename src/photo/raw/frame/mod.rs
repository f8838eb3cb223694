//! [`RawFrame`]: the linear sensor data of one raw file, cropped to its
//! active area, with the CFA pattern and black/white levels needed to turn
//! any site into linear light, and the clipped-site count. Colour planes are
//! cut out on request ([`RawFrame::channel_planes`]) as sparse [`Plane`]s, one
//! per site of the CFA repeat, so nothing is demosaiced and only the sites
//! measured are converted to f32.
//!
//! [`Plane`]: crate::photo::Plane

mod cfa;
mod planes;
#[cfg(test)]
mod tests;

use crate::photo::exif::ExifFacts;
use serde::Serialize;

pub use cfa::{CfaColour, CfaPattern, RawChannel};

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
