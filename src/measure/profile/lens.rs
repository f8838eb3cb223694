//! Binning through a lens model: the photo's iso-phase lines are curves, so
//! every sample centre is undistorted before the inverse homography.

use super::acc::BinAcc;
use super::{Profile, Strip};
use crate::distortion::Lens;
use crate::geometry::Point;
use crate::photo::PlaneRef;
use rayon::prelude::*;

/// Binning through a lens model (the photo's iso-phase lines are curves):
/// every sample centre inside the region's photo outline is undistorted, then
/// mapped by the inverse homography `m` (denominator positive) to (s, t); bins take the plain
/// two-pass robust mean (3σ about the bin's mean, as the fast path). The rows
/// are read in parallel, the bins filled in row order (results do not depend
/// on threads).
#[allow(clippy::too_many_arguments)]
pub(super) fn bin_through_lens(
    planes: &[PlaneRef],
    strip: &Strip,
    lens: &Lens,
    m: [f64; 9],
    (t0, t1, s_lo, s_hi): (f64, f64, f64, f64),
    bin: f64,
    nbins: usize,
    clip_level: f32,
) -> Profile {
    let outline = photo_outline(strip, t0, t1);
    let ymin = outline.iter().map(|p| p[1]).fold(f64::INFINITY, f64::min) - 1.0;
    let ymax = outline
        .iter()
        .map(|p| p[1])
        .fold(f64::NEG_INFINITY, f64::max)
        + 1.0;
    let last = nbins - 1;
    let inv_bin = 1.0 / bin;
    // (bin, s, value) of every sample inside, row by row.
    let mut rows: Vec<(usize, usize)> = Vec::new();
    for (p, plane) in planes.iter().enumerate() {
        let oy = plane.offset.1 as f64 + 0.5;
        let sy = plane.step.1 as f64;
        let j0 = ((ymin - oy) / sy).ceil().max(0.0) as usize;
        let j1 = (((ymax - oy) / sy).floor() + 1.0).clamp(0.0, plane.height as f64) as usize;
        rows.extend((j0..j1).map(|j| (p, j)));
    }
    let samples: Vec<Vec<(u32, f64, f32)>> = rows
        .par_iter()
        .map(|&(p, j)| {
            let plane = planes[p];
            let (sx, sy) = (plane.step.0 as f64, plane.step.1 as f64);
            let (ox, oy) = (plane.offset.0 as f64 + 0.5, plane.offset.1 as f64 + 0.5);
            let y = oy + j as f64 * sy;
            let mut out = Vec::new();
            let Some((xa, xb)) = super::row_span(&outline, y) else {
                return out;
            };
            let i0 = (((xa - 1.5 - ox) / sx).floor().max(0.0) as usize).min(plane.width);
            let i1 = (((xb + 1.5 - ox) / sx).ceil().max(0.0) as usize + 1).min(plane.width);
            let mut buf = vec![0.0f32; i1.saturating_sub(i0)];
            let row = plane.values(j, i0, &mut buf);
            for (i, &v) in (i0..i1).zip(row) {
                let x = ox + i as f64 * sx;
                let [xu, yu] = lens.undistort([x, y]);
                let w = m[6] * xu + m[7] * yu + m[8];
                if !(w > 0.0) {
                    continue;
                }
                let s = (m[0] * xu + m[1] * yu + m[2]) / w;
                let t = (m[3] * xu + m[4] * yu + m[5]) / w;
                if t >= t0 && t <= t1 && s >= s_lo && s <= s_hi {
                    out.push((((s * inv_bin) as usize).min(last) as u32, s, v));
                }
            }
            out
        })
        .collect();
    let mut acc = vec![BinAcc::default(); nbins];
    let mut prof = Profile::default();
    for &(b, s, v) in samples.iter().flatten() {
        acc[b as usize].add(s, v);
        prof.samples += 1;
        prof.clipped_high += (v >= clip_level) as usize;
        prof.clipped_low += (v <= 0.0) as usize;
    }
    let lims: Vec<(f64, f64)> = acc.iter().map(BinAcc::clip_limits).collect();
    for &(b, _, v) in samples.iter().flatten() {
        let (mu, lim) = lims[b as usize];
        if (v as f64 - mu).abs() <= lim {
            acc[b as usize].rsum += v as f64;
            acc[b as usize].rn += 1;
        }
    }
    super::acc::finish(&acc, &mut prof);
    prof
}

/// The outline in the photo of the strip's part between t0 and t1, densely
/// sampled (under a lens its edges are curves): a closed polygon, image px.
pub(crate) fn photo_outline(strip: &Strip, t0: f64, t1: f64) -> Vec<Point> {
    let l = strip.length;
    let mut outline = Vec::new();
    let n_long = 128;
    for i in 0..n_long {
        outline.push(strip.to_photo([l * i as f64 / n_long as f64, t0]));
    }
    for i in 0..8 {
        outline.push(strip.to_photo([l, t0 + (t1 - t0) * i as f64 / 8.0]));
    }
    for i in 0..n_long {
        outline.push(strip.to_photo([l * (1.0 - i as f64 / n_long as f64), t1]));
    }
    for i in 0..8 {
        outline.push(strip.to_photo([0.0, t1 - (t1 - t0) * i as f64 / 8.0]));
    }
    outline
}
