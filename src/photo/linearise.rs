//! Linearisation: code values → linear light, and the choice of channel.
//!
//! 8-bit data goes through the sRGB curve by default, 16-bit data is taken as
//! linear (with a notice), `--gamma G` applies a power law, and `--tone chart`
//! uses a tone curve measured from the target's grey patches in the same shot
//! ([`ToneCurve::from_patches`]). Every tone is applied through a lookup table
//! (256 or 65536 entries), and only over the requested crop, so that a large
//! photo is never converted to floating point as a whole. The channel is the
//! luminance of linear RGB (Rec. 709 weights), one of r, g, b, or all four
//! (luma, r, g, b) together.

use super::Plane;
use super::decode::{Decoded, Samples};
use super::plane_ref::{Codes, PlaneData, PlaneRef};
use rayon::prelude::*;
use serde::{Deserialize, Serialize};

/// Rec. 709 / sRGB luminance weights of linear R, G, B.
pub const LUMA_WEIGHTS: [f32; 3] = [0.2126, 0.7152, 0.0722];

/// How code values map to linear light.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum Tone {
    /// The sRGB transfer curve (IEC 61966-2-1).
    Srgb,
    /// A power law: linear = code^gamma (code scaled to 0–1); gamma 1 = already linear.
    Gamma(f64),
    /// A measured curve (from grey patches): code → linear, piecewise linear.
    Curve(ToneCurve),
}

/// A monotone, piecewise-linear tone curve: code value (0–1) → linear reflectance.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct ToneCurve {
    /// Code values (0–1), strictly increasing.
    pub code: Vec<f64>,
    /// Linear values at those codes (non-decreasing).
    pub linear: Vec<f64>,
}

/// Which channel of a colour photo is measured.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize, Default)]
#[serde(rename_all = "lowercase")]
pub enum Channel {
    /// Luminance of linear RGB (Rec. 709 weights).
    #[default]
    Luma,
    /// Red.
    R,
    /// Green.
    G,
    /// Blue.
    B,
    /// Luminance and one plane per colour channel (luma, r, g, b), measured together.
    All,
}

impl Channel {
    /// Parses `luma|r|g|b|all`.
    pub fn parse(s: &str) -> Option<Channel> {
        Some(match s.to_ascii_lowercase().as_str() {
            "luma" | "y" | "luminance" => Channel::Luma,
            "r" | "red" => Channel::R,
            "g" | "green" => Channel::G,
            "b" | "blue" => Channel::B,
            "all" => Channel::All,
            _ => return None,
        })
    }
}

/// A pixel rectangle [x0, x1) × [y0, y1) of the image.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Crop {
    /// First column.
    pub x0: usize,
    /// First row.
    pub y0: usize,
    /// One past the last column.
    pub x1: usize,
    /// One past the last row.
    pub y1: usize,
}

/// sRGB decoding curve: encoded value (0–1) → linear.
pub fn srgb_to_linear(v: f64) -> f64 {
    if v <= 0.04045 {
        v / 12.92
    } else {
        ((v + 0.055) / 1.055).powf(2.4)
    }
}

/// sRGB encoding curve: linear (0–1) → encoded value.
pub fn linear_to_srgb(v: f64) -> f64 {
    if v <= 0.0031308 {
        12.92 * v
    } else {
        1.055 * v.powf(1.0 / 2.4) - 0.055
    }
}

/// The default tone for data of `bits` bits per sample, and a notice when the choice is a guess.
pub fn default_tone(bits: u32) -> (Tone, Option<String>) {
    if bits > 8 {
        (
            Tone::Gamma(1.0),
            Some(format!(
                "{bits}-bit data taken as linear (use --gamma or --tone chart if it is not)"
            )),
        )
    } else {
        (Tone::Srgb, None)
    }
}

/// The tone a photo's codes are read with when none is asked for: the curve
/// the file declares (see [`super::transfer`]), else [`default_tone`]; with
/// the note saying which.
pub fn file_tone(dec: &Decoded) -> (Tone, Option<String>) {
    match &dec.declared_tone {
        Some(d) => (d.tone.clone(), Some(format!("tone from {}", d.source))),
        None => default_tone(dec.bits()),
    }
}

impl Tone {
    /// A short name: `srgb`, `gamma G` or `curve`.
    pub fn name(&self) -> String {
        match self {
            Tone::Srgb => "srgb".into(),
            Tone::Gamma(g) => format!("gamma {g}"),
            Tone::Curve(_) => "curve".into(),
        }
    }

    /// Linear value of a code value scaled to 0–1.
    pub fn apply(&self, code: f64) -> f64 {
        match self {
            Tone::Srgb => srgb_to_linear(code),
            Tone::Gamma(g) => code.max(0.0).powf(*g),
            Tone::Curve(c) => c.apply(code),
        }
    }

    /// A lookup table of `levels` entries (256 or 65536): code index → linear value.
    pub fn lut(&self, levels: usize) -> Vec<f32> {
        let top = (levels - 1) as f64;
        (0..levels)
            .map(|i| self.apply(i as f64 / top) as f32)
            .collect()
    }
}

impl ToneCurve {
    /// Builds a curve from (code 0–1, known linear reflectance) pairs of grey patches.
    ///
    /// Pairs are sorted by code; a reflectance that falls while the code rises
    /// is pooled with its neighbour (pool-adjacent-violators) so the curve is
    /// monotone. Needs at least two distinct codes.
    pub fn from_patches(pairs: &[(f64, f64)]) -> Result<ToneCurve, String> {
        let mut p: Vec<(f64, f64)> = pairs
            .iter()
            .copied()
            .filter(|(c, r)| c.is_finite() && r.is_finite())
            .collect();
        p.sort_by(|a, b| a.0.total_cmp(&b.0));
        // Merge equal codes.
        let mut blocks: Vec<(f64, f64, f64)> = Vec::new(); // (sum code, sum refl, n)
        for (c, r) in p {
            match blocks.last_mut() {
                Some(b) if (b.0 / b.2 - c).abs() < 1e-9 => {
                    b.0 += c;
                    b.1 += r;
                    b.2 += 1.0;
                }
                _ => blocks.push((c, r, 1.0)),
            }
            // Pool adjacent violators.
            while blocks.len() >= 2 {
                let n = blocks.len();
                let (a, b) = (blocks[n - 2], blocks[n - 1]);
                if b.1 / b.2 < a.1 / a.2 {
                    blocks[n - 2] = (a.0 + b.0, a.1 + b.1, a.2 + b.2);
                    blocks.pop();
                } else {
                    break;
                }
            }
        }
        if blocks.len() < 2 {
            return Err("the grey patches give fewer than two distinct levels".into());
        }
        Ok(ToneCurve {
            code: blocks.iter().map(|b| b.0 / b.2).collect(),
            linear: blocks.iter().map(|b| b.1 / b.2).collect(),
        })
    }

    /// Linear value at a code (0–1): linear interpolation, linear extrapolation beyond the ends, never below 0.
    pub fn apply(&self, code: f64) -> f64 {
        let n = self.code.len();
        let k = match self.code.iter().position(|&c| c > code) {
            Some(0) => 0,
            Some(i) => i - 1,
            None => n - 2,
        }
        .min(n - 2);
        let (c0, c1) = (self.code[k], self.code[k + 1]);
        let (l0, l1) = (self.linear[k], self.linear[k + 1]);
        (l0 + (l1 - l0) * (code - c0) / (c1 - c0)).max(0.0)
    }
}

/// Names of the planes [`planes`] returns for a channel choice on data with `channels` samples per pixel.
pub fn plane_names(channel: Channel, channels: usize) -> Vec<&'static str> {
    match (channel, channels) {
        (_, 1) => vec!["grey"],
        (Channel::Luma, _) => vec!["luma"],
        (Channel::R, _) => vec!["r"],
        (Channel::G, _) => vec!["g"],
        (Channel::B, _) => vec!["b"],
        (Channel::All, _) => vec!["luma", "r", "g", "b"],
    }
}

/// Linear planes of the crop, one per name of [`plane_names`] (a grey photo gives one plane for any channel).
pub fn planes(dec: &Decoded, crop: Crop, tone: &Tone, channel: Channel) -> Vec<Plane> {
    planes_within(dec, crop, tone, channel, &|_| (crop.x0, crop.x1))
}

/// Like [`planes`], but converts only the columns `span(y)` = [x0, x1) of each
/// image row y (the rest of the crop stays 0): a rotated region's bounding box
/// is mostly outside it, and conversion is the largest cost after decoding.
pub fn planes_within(
    dec: &Decoded,
    crop: Crop,
    tone: &Tone,
    channel: Channel,
    span: &(dyn Fn(usize) -> (usize, usize) + Sync),
) -> Vec<Plane> {
    debug_assert!(crop.y1 <= dec.rows, "rows below the decoded part are read");
    let (w, h) = (crop.x1 - crop.x0, crop.y1 - crop.y0);
    let lut = code_lut(dec, tone);
    let nc = dec.channels;
    mixes(channel, nc)
        .iter()
        .map(|mix| {
            // Huge pages: a 24 MP region faults in as a few dozen pages, not thousands.
            let mut out = super::hugebuf::zeroed::<f32>(w * h);
            out.par_chunks_mut(w).enumerate().for_each(|(dy, row)| {
                let y = crop.y0 + dy;
                let (a, b) = span(y);
                let (a, b) = (a.clamp(crop.x0, crop.x1), b.clamp(crop.x0, crop.x1));
                if a >= b {
                    return;
                }
                let row = &mut row[a - crop.x0..b - crop.x0];
                let src = (y * dec.width + a) * nc..(y * dec.width + b) * nc;
                match &dec.samples {
                    Samples::U8(v) => convert_row(row, &v[src], nc, mix, &lut),
                    Samples::U16(v) => convert_row(row, &v[src], nc, mix, &lut),
                    Samples::F32(v) => convert_row_f32(row, &v[src], nc, mix, tone),
                }
            });
            Plane {
                width: w,
                height: h,
                step: (1, 1),
                offset: (crop.x0, crop.y0),
                data: out,
            }
        })
        .collect()
}

/// What reading a photo's integer codes in place needs ([`coded`]): the
/// tone's table and the channel mixes of [`planes`].
#[derive(Debug, Clone)]
pub struct CodedTone {
    lut: Vec<f32>,
    mixes: Vec<Vec<(usize, f32)>>,
}

/// The table and mixes to read `dec`'s codes in place as the planes
/// [`planes`] gives for `channel` (same values, bit for bit); `None` for
/// floating-point codes, which go through the tone itself.
pub fn coded(dec: &Decoded, tone: &Tone, channel: Channel) -> Option<CodedTone> {
    match dec.samples {
        Samples::F32(_) => None,
        _ => Some(CodedTone {
            lut: code_lut(dec, tone),
            mixes: mixes(channel, dec.channels),
        }),
    }
}

impl CodedTone {
    /// The whole decoded picture (its first [`Decoded::rows`] rows) as
    /// views, one per name of [`plane_names`]; none for floating-point codes.
    pub fn planes<'a>(&'a self, dec: &'a Decoded) -> Vec<PlaneRef<'a>> {
        let n = dec.width * dec.rows * dec.channels;
        let codes = |mix| match &dec.samples {
            Samples::U8(v) => Some(PlaneData::Codes8(self.codes(&v[..n], dec.channels, mix))),
            Samples::U16(v) => Some(PlaneData::Codes16(self.codes(&v[..n], dec.channels, mix))),
            Samples::F32(_) => None,
        };
        self.mixes
            .iter()
            .filter_map(|mix| {
                Some(PlaneRef {
                    width: dec.width,
                    height: dec.rows,
                    step: (1, 1),
                    offset: (0, 0),
                    data: codes(mix)?,
                })
            })
            .collect()
    }

    /// The code → linear table.
    pub fn table(&self) -> &[f32] {
        &self.lut
    }

    /// The first plane's channel weights `(channel, weight)`, as
    /// [`row_converter`] applies them: `table[code[c]]` for one weight, or
    /// `w0·table[code[c0]] + w1·table[code[c1]] + w2·table[code[c2]]` (summed
    /// in that order) for three.
    pub fn mix(&self) -> &[(usize, f32)] {
        &self.mixes[0]
    }

    fn codes<'a, T>(
        &'a self,
        codes: &'a [T],
        channels: usize,
        mix: &'a [(usize, f32)],
    ) -> Codes<'a, T> {
        Codes {
            codes,
            channels,
            mix,
            lut: &self.lut,
        }
    }
}

/// The linear value of every integer code of `dec` under `tone` (integer
/// codes go through this table; float codes through the tone itself: empty).
fn code_lut(dec: &Decoded, tone: &Tone) -> Vec<f32> {
    match dec.samples {
        Samples::U8(_) => tone.lut(256),
        Samples::U16(_) => tone.lut(65536),
        Samples::F32(_) => Vec::new(),
    }
}

/// Which channels feed each plane of [`planes`], and with what weight.
fn mixes(channel: Channel, nc: usize) -> Vec<Vec<(usize, f32)>> {
    if nc == 1 {
        vec![vec![(0, 1.0)]]
    } else {
        match channel {
            Channel::R => vec![vec![(0, 1.0)]],
            Channel::G => vec![vec![(1, 1.0)]],
            Channel::B => vec![vec![(2, 1.0)]],
            Channel::All => std::iter::once((0..3).map(|c| (c, LUMA_WEIGHTS[c])).collect())
                .chain((0..3).map(|c| vec![(c, 1.0)]))
                .collect(),
            Channel::Luma => vec![(0..3).map(|c| (c, LUMA_WEIGHTS[c])).collect()],
        }
    }
}

/// A row converter for the first plane [`planes`] gives for `channel`:
/// `convert(y, x0, out)` fills `out` with the linear values of image row `y`
/// from column `x0` on (`out.len()` columns), exactly as the plane holds them.
pub fn row_converter<'a>(
    dec: &'a Decoded,
    tone: &Tone,
    channel: Channel,
) -> impl Fn(usize, usize, &mut [f32]) + Sync + use<'a> {
    let lut = code_lut(dec, tone);
    let nc = dec.channels;
    let mix = mixes(channel, nc).swap_remove(0);
    let tone = tone.clone();
    move |y: usize, x0: usize, out: &mut [f32]| {
        let src = (y * dec.width + x0) * nc..(y * dec.width + x0 + out.len()) * nc;
        match &dec.samples {
            Samples::U8(v) => convert_row(out, &v[src], nc, &mix, &lut),
            Samples::U16(v) => convert_row(out, &v[src], nc, &mix, &lut),
            Samples::F32(v) => convert_row_f32(out, &v[src], nc, &mix, &tone),
        }
    }
}

/// A pixel converter for the first plane [`planes`] gives for `channel`:
/// `at(x, y)` is the linear value of image pixel (x, y), exactly as the plane
/// holds it (the same table and sum as [`row_converter`]), for reading a few
/// scattered pixels without converting rows.
pub fn pixel_converter<'a>(
    dec: &'a Decoded,
    tone: &Tone,
    channel: Channel,
) -> impl Fn(usize, usize) -> f32 + Sync + use<'a> {
    let lut = code_lut(dec, tone);
    let nc = dec.channels;
    let mix = mixes(channel, nc).swap_remove(0);
    let tone = tone.clone();
    move |x: usize, y: usize| {
        let i = (y * dec.width + x) * nc;
        match &dec.samples {
            Samples::U8(v) => mixed(&mix, |c| lut[v[i + c] as usize]),
            Samples::U16(v) => mixed(&mix, |c| lut[v[i + c] as usize]),
            Samples::F32(v) => {
                let mut one = [0f32];
                convert_row_f32(&mut one, &v[i..i + nc], nc, &mix, &tone);
                one[0]
            }
        }
    }
}

/// One pixel's weighted sum of linear channels `lin(c)`, in [`convert_row`]'s order.
#[inline]
fn mixed(mix: &[(usize, f32)], lin: impl Fn(usize) -> f32) -> f32 {
    match mix {
        [(c, _)] => lin(*c),
        [(c0, w0), (c1, w1), (c2, w2)] => w0 * lin(*c0) + w1 * lin(*c1) + w2 * lin(*c2),
        _ => mix.iter().map(|&(c, wt)| wt * lin(c)).sum(),
    }
}

/// Converts one row of interleaved codes to a weighted sum of linear channels.
#[inline(always)]
pub(crate) fn convert_row<T: Copy + Into<usize>>(
    out: &mut [f32],
    codes: &[T],
    nc: usize,
    mix: &[(usize, f32)],
    lut: &[f32],
) {
    let px = codes.chunks_exact(nc);
    match mix {
        [(c, _)] => {
            for (o, p) in out.iter_mut().zip(px) {
                *o = lut[p[*c].into()];
            }
        }
        [(c0, w0), (c1, w1), (c2, w2)] => {
            for (o, p) in out.iter_mut().zip(px) {
                *o = w0 * lut[p[*c0].into()] + w1 * lut[p[*c1].into()] + w2 * lut[p[*c2].into()];
            }
        }
        _ => {
            for (o, p) in out.iter_mut().zip(px) {
                *o = mix.iter().map(|&(c, wt)| wt * lut[p[c].into()]).sum();
            }
        }
    }
}

/// Like [`convert_row`] for floating-point codes (0–1): the tone is applied
/// to each sample (no table); `Gamma(1)` (already linear) only clamps at 0.
fn convert_row_f32(out: &mut [f32], codes: &[f32], nc: usize, mix: &[(usize, f32)], tone: &Tone) {
    let identity = *tone == Tone::Gamma(1.0);
    let lin = |c: f32| {
        if identity {
            c.max(0.0)
        } else {
            tone.apply(c as f64) as f32
        }
    };
    for (o, p) in out.iter_mut().zip(codes.chunks_exact(nc)) {
        *o = mix.iter().map(|&(c, wt)| wt * lin(p[c])).sum();
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn srgb_matches_published_values() {
        // IEC 61966-2-1 reference points: code 0.5 → 0.2140, 128/255 → 0.21586.
        assert!((srgb_to_linear(0.5) - 0.214_041).abs() < 1e-6);
        assert!((srgb_to_linear(128.0 / 255.0) - 0.215_861).abs() < 1e-6);
        assert_eq!(srgb_to_linear(1.0), 1.0);
        for v in [0.001, 0.02, 0.3, 0.9] {
            assert!((linear_to_srgb(srgb_to_linear(v)) - v).abs() < 1e-12);
        }
    }

    #[test]
    fn luma_and_channels_of_a_crop() {
        let dec = Decoded {
            width: 3,
            height: 2,
            channels: 3,
            samples: Samples::U8(vec![
                255, 0, 0, 0, 255, 0, 0, 0, 255, //
                255, 255, 255, 0, 0, 0, 128, 128, 128,
            ]),
            format: "png",
            rows: 2,
            warnings: Vec::new(),
            declared_tone: None,
            jpeg_luma_quant: None,
        };
        let crop = Crop {
            x0: 1,
            y0: 0,
            x1: 3,
            y1: 2,
        };
        let p = planes(&dec, crop, &Tone::Srgb, Channel::Luma);
        assert_eq!(p.len(), 1);
        assert_eq!((p[0].width, p[0].height, p[0].offset), (2, 2, (1, 0)));
        assert!((p[0].get(0, 0) - 0.7152).abs() < 1e-6);
        assert!((p[0].get(1, 0) - 0.0722).abs() < 1e-6);
        assert!((p[0].get(1, 1) - 0.215_861).abs() < 1e-5);
        assert_eq!(p[0].centre(1, 1), (2.5, 1.5));
        let all = planes(&dec, crop, &Tone::Gamma(1.0), Channel::All);
        assert_eq!(all.len(), 4);
        assert_eq!(plane_names(Channel::All, 3), ["luma", "r", "g", "b"]);
        assert!((all[0].get(1, 0) - 0.0722).abs() < 1e-6);
        assert_eq!(all[3].get(1, 0), 1.0);
    }

    #[test]
    fn tone_curve_is_monotone_and_interpolates() {
        let c =
            ToneCurve::from_patches(&[(0.8, 0.7), (0.2, 0.1), (0.5, 0.3), (0.55, 0.25)]).unwrap();
        assert!(c.linear.windows(2).all(|w| w[1] >= w[0]));
        assert!((c.apply(0.2) - 0.1).abs() < 1e-12);
        assert!((c.apply(0.8) - 0.7).abs() < 1e-12);
        assert!(c.apply(0.0) >= 0.0);
        assert!(c.apply(1.0) > 0.7);
        assert!(ToneCurve::from_patches(&[(0.5, 0.2)]).is_err());
    }
}
