//! The transfer curve a photo file declares for its code values: a PNG's
//! `sRGB`, `iCCP` or `gAMA` chunk, or the tone reproduction curve of an
//! embedded ICC profile (JPEG APP2 `ICC_PROFILE` segments, TIFF tag 34675).
//! Read from the file's header only, before any pixel is decoded.
//!
//! Precedence follows the PNG specification (11.3.3.5): an `iCCP` or `sRGB`
//! chunk overrides `gAMA`. An ICC profile's curve is its grey TRC (`kTRC`) or,
//! for an RGB matrix/TRC profile, the green TRC (`gTRC`: the channel that
//! carries most of the luminance; for a neutral chart all three agree). Curve
//! types are read as ICC.1:2010 defines them (10.6 `curv`: identity, a
//! u8.8 gamma, or a sampled table; 10.18 `para`: function types 0–4). A
//! profile that describes its curve otherwise (lutAtoB) gives nothing, and the
//! default for the bit depth applies.
//!
//! A hand-written reader rather than a colour-management crate: the only pure
//! Rust one (`qcms`) builds transforms to a display, not the curve alone; the
//! parts read here are ~150 lines, bounded by the data's own lengths.

use super::linearise::{Tone, ToneCurve, srgb_to_linear};
use std::io::Read;

/// A curve a file declares, and where it came from (for the summary's notes).
#[derive(Debug, Clone, PartialEq)]
pub struct DeclaredTone {
    /// Code value → linear light.
    pub tone: Tone,
    /// Where it was read, e.g. "the PNG's sRGB chunk".
    pub source: String,
}

/// Largest ICC profile read, bytes (real ones are 0.5–4 KB; a few carry 1 MB LUTs).
const MAX_ICC: usize = 4 << 20;

/// The curve declared in a PNG's header chunks (before the first IDAT).
pub fn png(bytes: &[u8]) -> Option<DeclaredTone> {
    let mut i = 8;
    let (mut srgb, mut gama, mut icc) = (false, None, None);
    while i + 8 <= bytes.len() {
        let len = u32::from_be_bytes(bytes[i..i + 4].try_into().ok()?) as usize;
        let kind = &bytes[i + 4..i + 8];
        let data = bytes.get(i + 8..(i + 8).checked_add(len)?)?;
        match kind {
            b"IDAT" | b"IEND" => break,
            b"sRGB" => srgb = true,
            b"gAMA" if len == 4 => {
                gama = Some(u32::from_be_bytes(data.try_into().ok()?) as f64 / 100_000.0)
            }
            b"iCCP" => {
                // Name (1–79 bytes), NUL, compression method 0, zlib stream.
                let nul = data.iter().position(|&b| b == 0)?;
                let z = data.get(nul + 2..)?;
                let mut out = Vec::new();
                flate2::read::ZlibDecoder::new(z)
                    .take(MAX_ICC as u64)
                    .read_to_end(&mut out)
                    .ok()?;
                icc = Some(out);
            }
            _ => {}
        }
        i = i.checked_add(12 + len)?;
    }
    if let Some(p) = icc
        && let Some(t) = icc_tone(&p)
    {
        return Some(DeclaredTone {
            tone: t,
            source: "the PNG's ICC profile".into(),
        });
    }
    if srgb {
        return Some(DeclaredTone {
            tone: Tone::Srgb,
            source: "the PNG's sRGB chunk".into(),
        });
    }
    // gAMA holds the encoding exponent: code = linear^gama.
    let g = gama.filter(|g| g.is_finite() && (0.05..=5.0).contains(g))?;
    Some(DeclaredTone {
        tone: Tone::Gamma(1.0 / g),
        source: format!("the PNG's gAMA chunk ({g:.5})"),
    })
}

/// The curve of the ICC profile in a JPEG's APP2 `ICC_PROFILE` segments.
pub fn jpeg(bytes: &[u8]) -> Option<DeclaredTone> {
    let mut parts: Vec<(u8, &[u8])> = Vec::new();
    let mut i = 2;
    while i + 4 <= bytes.len() && bytes[i] == 0xFF {
        let marker = bytes[i + 1];
        if marker == 0xDA || marker == 0xD9 {
            break;
        }
        if marker == 0xFF || (0xD0..=0xD7).contains(&marker) || marker == 0x01 {
            i += if marker == 0xFF { 1 } else { 2 };
            continue;
        }
        let len = u16::from_be_bytes([bytes[i + 2], bytes[i + 3]]) as usize;
        let seg = bytes.get(i + 4..(i + 2 + len).max(i + 4))?;
        if marker == 0xE2 && seg.len() > 14 && seg.starts_with(b"ICC_PROFILE\0") {
            parts.push((seg[12], &seg[14..]));
        }
        i += 2 + len;
    }
    if parts.is_empty() {
        return None;
    }
    parts.sort_by_key(|p| p.0);
    let icc: Vec<u8> = parts
        .iter()
        .flat_map(|p| p.1.iter().copied())
        .take(MAX_ICC)
        .collect();
    Some(DeclaredTone {
        tone: icc_tone(&icc)?,
        source: "the JPEG's ICC profile".into(),
    })
}

/// The curve of the ICC profile in a TIFF's first image (tag 34675).
pub fn tiff(bytes: &[u8]) -> Option<DeclaredTone> {
    let mut d = tiff::decoder::Decoder::new(std::io::Cursor::new(bytes)).ok()?;
    let icc = d
        .get_tag_u8_vec(tiff::tags::Tag::Unknown(34675))
        .ok()
        .filter(|v| v.len() <= MAX_ICC)?;
    Some(DeclaredTone {
        tone: icc_tone(&icc)?,
        source: "the TIFF's ICC profile".into(),
    })
}

fn be32(b: &[u8], at: usize) -> Option<u32> {
    Some(u32::from_be_bytes(b.get(at..at + 4)?.try_into().ok()?))
}

fn s15f16(b: &[u8], at: usize) -> Option<f64> {
    Some(be32(b, at)? as i32 as f64 / 65536.0)
}

/// The tone reproduction curve of an ICC profile (grey `kTRC`, else green `gTRC`).
pub fn icc_tone(p: &[u8]) -> Option<Tone> {
    if p.len() < 132 || p.get(36..40)? != b"acsp" {
        return None;
    }
    let n = be32(p, 128)? as usize;
    let table = |sig: &[u8; 4]| -> Option<&[u8]> {
        (0..n.min(200)).find_map(|k| {
            let e = 132 + 12 * k;
            (p.get(e..e + 4)? == sig).then_some(())?;
            let (off, size) = (be32(p, e + 4)? as usize, be32(p, e + 8)? as usize);
            p.get(off..off.checked_add(size)?)
        })
    };
    let trc = table(b"kTRC").or_else(|| table(b"gTRC"))?;
    curve_tone(trc)
}

/// A `curv` or `para` element as a tone (code → linear).
fn curve_tone(t: &[u8]) -> Option<Tone> {
    match t.get(0..4)? {
        b"curv" => {
            let n = be32(t, 8)? as usize;
            match n {
                0 => Some(Tone::Gamma(1.0)),
                1 => {
                    let g = u16::from_be_bytes(t.get(12..14)?.try_into().ok()?) as f64 / 256.0;
                    (g > 0.0).then_some(Tone::Gamma(g))
                }
                _ => {
                    let ys: Vec<f64> = (0..n)
                        .map(|k| {
                            let at = 12 + 2 * k;
                            Some(
                                u16::from_be_bytes(t.get(at..at + 2)?.try_into().ok()?) as f64
                                    / 65535.0,
                            )
                        })
                        .collect::<Option<_>>()?;
                    tabulated(|x| {
                        let pos = x * (n - 1) as f64;
                        let k = (pos.floor() as usize).min(n - 2);
                        ys[k] + (ys[k + 1] - ys[k]) * (pos - k as f64)
                    })
                }
            }
        }
        b"para" => {
            let kind = u16::from_be_bytes(t.get(8..10)?.try_into().ok()?);
            let count = [1, 3, 4, 5, 7].get(kind as usize).copied()?;
            let v: Vec<f64> = (0..count)
                .map(|k| s15f16(t, 12 + 4 * k))
                .collect::<Option<_>>()?;
            let g = v[0];
            if !(g.is_finite() && g > 0.0) {
                return None;
            }
            if kind == 0 {
                return Some(Tone::Gamma(g));
            }
            let (a, b) = (v[1], v[2]);
            if kind == 3 && is_srgb(g, a, b, v[3], v[4]) {
                return Some(Tone::Srgb);
            }
            // A pure power law written in a longer form (a = 1, no offsets, no toe).
            let zero = |k: usize| v.get(k).is_none_or(|x| x.abs() < 1e-4);
            let toe_free = match kind {
                3 => v[4].abs() < 1e-4,
                4 => v[4].abs() < 1e-4 && zero(5),
                _ => zero(3),
            };
            if (a - 1.0).abs() < 1e-4 && b.abs() < 1e-4 && toe_free {
                return Some(Tone::Gamma(g));
            }
            let pow = |x: f64| (a * x + b).max(0.0).powf(g);
            tabulated(|x| match kind {
                1 => {
                    if a * x + b >= 0.0 {
                        pow(x)
                    } else {
                        0.0
                    }
                }
                2 => {
                    if a * x + b >= 0.0 {
                        pow(x) + v[3]
                    } else {
                        v[3]
                    }
                }
                3 => {
                    if x >= v[4] {
                        pow(x)
                    } else {
                        v[3] * x
                    }
                }
                _ => {
                    if x >= v[4] {
                        pow(x) + v[5]
                    } else {
                        v[3] * x + v[6]
                    }
                }
            })
        }
        _ => None,
    }
}

/// Whether para type-3 parameters are the sRGB curve's (to their s15.16 rounding).
fn is_srgb(g: f64, a: f64, b: f64, c: f64, d: f64) -> bool {
    let close = |x: f64, y: f64| (x - y).abs() < 2e-4;
    close(g, 2.4)
        && close(a, 1.0 / 1.055)
        && close(b, 0.055 / 1.055)
        && close(c, 1.0 / 12.92)
        && close(d, 0.04045)
}

/// A curve sampled at 1025 codes as a piecewise-linear tone, when monotone and
/// spanning 0 → 1 (a file's own curve outside that is not trusted).
fn tabulated(f: impl Fn(f64) -> f64) -> Option<Tone> {
    let code: Vec<f64> = (0..=1024).map(|k| k as f64 / 1024.0).collect();
    let linear: Vec<f64> = code.iter().map(|&x| f(x).clamp(0.0, 1.0)).collect();
    let monotone = linear.windows(2).all(|w| w[1] >= w[0]);
    if !monotone || linear[1024] < 0.5 || !linear.iter().all(|v| v.is_finite()) {
        return None;
    }
    // The sRGB curve sampled (as many profiles store it) is named as such.
    if code
        .iter()
        .zip(&linear)
        .all(|(&c, &l)| (srgb_to_linear(c) - l).abs() < 2e-4)
    {
        return Some(Tone::Srgb);
    }
    Some(Tone::Curve(ToneCurve { code, linear }))
}
