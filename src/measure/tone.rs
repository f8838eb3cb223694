//! Tone: how a photo's codes become linear light — the target's grey or
//! density patches (`--tone chart`), a power law (`--gamma`), or the default
//! for the bit depth (sRGB for 8 bits, linear for 16) — and the line the
//! summary gives for it. Raw data is linear and needs none.

use super::profile::{BinOptions, bin_plane};
use super::region::{rect_strip, target_homography};
use super::{Failure, MeasureOptions};
use crate::geometry::Point;
use crate::photo::Plane;
use crate::photo::decode::Decoded;
use crate::photo::linearise::{Crop, Tone, ToneCurve, file_tone, planes};
use crate::target::{Direction, Target};

/// The tone that makes the photo's codes linear, and the summary's line for
/// it; the default tone's assumption goes to `notes`. `crop` (image px) holds
/// the region `roi`, read for `--tone chart`.
pub(super) fn photo_tone(
    dec: &Decoded,
    target: Option<&Target>,
    opts: &MeasureOptions,
    crop: Crop,
    roi: &[Point; 4],
    notes: &mut Vec<String>,
) -> Result<(Tone, String), Failure> {
    if opts.tone_chart {
        let t = target.ok_or_else(|| {
            Failure::Options("--tone chart needs --target with grey or density patches".into())
        })?;
        let raw = planes(dec, crop, &Tone::Gamma(1.0), opts.channel);
        let curve = chart_tone(&raw[0], t, roi)?;
        let n = curve.code.len();
        Ok((
            Tone::Curve(curve),
            format!("tone curve from {n} grey levels of the target"),
        ))
    } else if let Some(g) = opts.gamma {
        Ok((Tone::Gamma(g), format!("power law, gamma {g}")))
    } else {
        let (t, notice) = file_tone(dec);
        notes.extend(notice);
        let d = match (&dec.declared_tone, &t) {
            (Some(d), Tone::Srgb) => format!("sRGB curve (from {})", d.source),
            (Some(d), Tone::Gamma(g)) => format!("power law, gamma {g:.4} (from {})", d.source),
            (Some(d), _) => format!("tabulated curve (from {})", d.source),
            (None, Tone::Srgb) => "sRGB curve (8-bit default)".to_string(),
            (None, _) => "linear (16-bit default)".to_string(),
        };
        Ok((t, d))
    }
}

/// The tone curve from the target's grey or density patches, read in the
/// linear-coded plane `raw` whose target corners are `roi` (image px).
fn chart_tone(raw: &Plane, t: &Target, roi: &[Point; 4]) -> Result<ToneCurve, Failure> {
    if t.greys.len() < 2 {
        return Err(Failure::Options(
            "--tone chart needs at least two grey or density patches in the target".into(),
        ));
    }
    let h = target_homography(t, roi)?;
    let opts = BinOptions {
        bin_px: 2.0,
        margin: 0.2,
        end_px: 0.0,
        clip_level: f32::INFINITY,
        max_across: 0,
    };
    let mut pairs = Vec::new();
    for g in &t.greys {
        // Inner 60 % of the patch, away from its edges' blur.
        let strip = rect_strip(&h, &g.rect, Direction::X);
        let end = 0.2 * strip.length / strip.scale_at(0.0).s_per_px;
        let prof = bin_plane(
            raw,
            &strip,
            &BinOptions {
                end_px: end,
                ..opts
            },
        );
        let n: f64 = prof.count.iter().sum();
        if n > 0.0 {
            let mean = prof
                .y
                .iter()
                .zip(&prof.count)
                .map(|(y, c)| y * c)
                .sum::<f64>()
                / n;
            pairs.push((mean, g.reflectance));
        }
    }
    ToneCurve::from_patches(&pairs).map_err(Failure::Options)
}
