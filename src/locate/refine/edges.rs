//! Edge points for the refinement: the target's straight segments and, along
//! each, the image position of its strongest gradient of the right polarity.

use super::super::sample::AtImage;
use crate::geometry::{Homography, Point};
use crate::target::Target;
use rayon::prelude::*;

/// One observed edge point: the target segment it belongs to and where it is in the image.
#[derive(Debug, Clone, Copy)]
pub struct EdgeObs {
    /// Segment start (target units).
    pub a: Point,
    /// Segment end (target units).
    pub b: Point,
    /// Observed image position (px).
    pub p: Point,
}

/// A straight edge of the target (or of a strip) to look for in the image.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Segment {
    /// Start (target units).
    pub a: Point,
    /// End (target units).
    pub b: Point,
    /// Whether the outside (the left of a → b in a y-down frame, i.e. outward of a
    /// clockwise rectangle) is brighter than the inside; `None` when not known.
    pub outside_brighter: Option<bool>,
}

/// Target segments worth fitting: sides of every region with contrast across them,
/// each with the side that is brighter.
pub fn target_segments(t: &Target) -> Vec<Segment> {
    let mut rects: Vec<crate::target::Rect> = t.sweeps.iter().map(|s| s.rect).collect();
    rects.extend(t.patches.iter().map(|p| p.rect));
    rects.extend(t.greys.iter().map(|g| g.rect));
    let mut out = Vec::new();
    for r in rects {
        let c = r.corners();
        for i in 0..4 {
            let (a, b) = (c[i], c[(i + 1) % 4]);
            // Mean reflectance just inside and just outside, along the side.
            let (dx, dy) = (b[0] - a[0], b[1] - a[1]);
            let len = dx.hypot(dy);
            let n = [dy / len, -dx / len]; // outward for a clockwise (y-down) rectangle
            let off = 0.02 * r.width_mm.min(r.height_mm);
            let (mut inside, mut outside) = (0.0, 0.0);
            let k = 50;
            for j in 0..k {
                let f = (j as f64 + 0.5) / k as f64;
                let p = [a[0] + f * dx, a[1] + f * dy];
                inside += t.reflectance(p[0] - off * n[0], p[1] - off * n[1]);
                outside += t.reflectance(p[0] + off * n[0], p[1] + off * n[1]);
            }
            if ((inside - outside) / k as f64).abs() >= 0.15 {
                out.push(Segment {
                    a,
                    b,
                    outside_brighter: Some(outside > inside),
                });
            }
        }
    }
    out
}

/// The strongest gradient extremum of sign `sign` (+1 or −1) in `grad`, sub-sample
/// by a parabola, or `None` when it is at the window's end, weak against the
/// window's median, or ambiguous (another extremum of that sign at least 0.7 as
/// strong more than `apart` samples away).
pub(super) fn pick_peak(grad: &[f64], sign: f64, apart: usize) -> Option<f64> {
    let (imax, gmax) = grad
        .iter()
        .map(|v| v * sign)
        .enumerate()
        .max_by(|x, y| x.1.total_cmp(&y.1))?;
    if gmax <= 1e-6 || imax == 0 || imax + 1 == grad.len() {
        return None;
    }
    let mut abs: Vec<f64> = grad.iter().map(|v| v.abs()).collect();
    abs.sort_by(f64::total_cmp);
    if gmax < 3.0 * abs[abs.len() / 2] {
        return None;
    }
    let rival = (1..grad.len() - 1).any(|i| {
        let v = grad[i] * sign;
        i.abs_diff(imax) > apart
            && v >= 0.7 * gmax
            && v >= grad[i - 1] * sign
            && v >= grad[i + 1] * sign
    });
    if rival {
        return None;
    }
    let (g0, g1, g2) = (grad[imax - 1] * sign, gmax, grad[imax + 1] * sign);
    let den = g0 - 2.0 * g1 + g2;
    let sub = if den < 0.0 {
        0.5 * (g0 - g2) / den
    } else {
        0.0
    };
    Some(imax as f64 + sub.clamp(-0.5, 0.5))
}

/// The first gradient extremum met going outward from the inside end of the window
/// (`from_start`: the inside is at index 0) that is at least half the window's
/// strongest and 3× its median, sub-sample by a parabola: the region's own edge
/// when the polarity is not known and another edge may lie beyond it.
pub(super) fn pick_first(grad: &[f64], from_start: bool) -> Option<f64> {
    let abs: Vec<f64> = grad.iter().map(|v| v.abs()).collect();
    let mut sorted = abs.clone();
    sorted.sort_by(f64::total_cmp);
    let thr = (0.5 * sorted[sorted.len() - 1]).max(3.0 * sorted[sorted.len() / 2]);
    if thr <= 1e-6 {
        return None;
    }
    let n = abs.len();
    let order: Box<dyn Iterator<Item = usize>> = if from_start {
        Box::new(1..n - 1)
    } else {
        Box::new((1..n - 1).rev())
    };
    for i in order {
        if abs[i] >= thr && abs[i] >= abs[i - 1] && abs[i] >= abs[i + 1] {
            let den = abs[i - 1] - 2.0 * abs[i] + abs[i + 1];
            let sub = if den < 0.0 {
                0.5 * (abs[i - 1] - abs[i + 1]) / den
            } else {
                0.0
            };
            return Some(i as f64 + sub.clamp(-0.5, 0.5));
        }
    }
    None
}

/// Searches every segment for its edge in the image around its predicted place
/// (±`search_px` along the normal): the strongest gradient of the segment's
/// polarity when the target gives it (with `skip_ambiguous`, samples with a rival
/// edge of that polarity in the window are skipped), else the first strong edge
/// going outward from the inside.
pub fn collect_edges<S: AtImage + ?Sized>(
    g: &S,
    segments: &[Segment],
    h: &Homography,
    search_px: f64,
    skip_ambiguous: bool,
) -> Vec<EdgeObs> {
    let step = 0.5;
    let m = (search_px / step).ceil() as i64;
    // Segments are searched in parallel; their points are kept in segment order.
    let one = |seg: &Segment| -> Vec<EdgeObs> {
        let mut out = Vec::new();
        let (a, b) = (seg.a, seg.b);
        let (ia, ib) = (h.apply(a), h.apply(b));
        let len = (ib[0] - ia[0]).hypot(ib[1] - ia[1]);
        if !len.is_finite() || len < 8.0 {
            return out;
        }
        let n = [-(ib[1] - ia[1]) / len, (ib[0] - ia[0]) / len];
        // Which way along n is outward in the image (a mirror flips it).
        let outward = {
            let (dx, dy) = (b[0] - a[0], b[1] - a[1]);
            let mid = [a[0] + 0.5 * dx, a[1] + 0.5 * dy];
            let o = [mid[0] + 1e-3 * dy, mid[1] - 1e-3 * dx];
            let (pm, po) = (h.apply(mid), h.apply(o));
            if (po[0] - pm[0]) * n[0] + (po[1] - pm[1]) * n[1] >= 0.0 {
                1.0
            } else {
                -1.0
            }
        };
        let count = ((len / 3.0) as usize).clamp(4, 200);
        let mut profiles: Vec<(Point, Vec<f64>)> = Vec::with_capacity(count);
        for j in 0..count {
            let f = 0.08 + 0.84 * (j as f64 + 0.5) / count as f64;
            // Along the segment in target units, mapped (straight lines stay straight).
            let tp = [a[0] + f * (b[0] - a[0]), a[1] + f * (b[1] - a[1])];
            let q = h.apply(tp);
            let prof: Option<Vec<f64>> = (-m - 2..=m + 2)
                .map(|i| {
                    let t = i as f64 * step;
                    g.at_img([q[0] + t * n[0], q[1] + t * n[1]])
                })
                .collect();
            if let Some(prof) = prof {
                let grad: Vec<f64> = (1..prof.len() - 1)
                    .map(|i| (prof[i + 1] - prof[i - 1]) / (2.0 * step))
                    .collect();
                profiles.push((q, grad));
            }
        }
        let sign = match seg.outside_brighter {
            Some(brighter) => outward * if brighter { 1.0 } else { -1.0 },
            None => 0.0,
        };
        let apart = if skip_ambiguous {
            (2.5 / step) as usize
        } else {
            usize::MAX
        };
        for (q, grad) in &profiles {
            let found = if sign == 0.0 {
                pick_first(grad, outward > 0.0)
            } else {
                pick_peak(grad, sign, apart)
            };
            if let Some(i) = found {
                // grad index i ↔ profile index i+1 ↔ t = (i + 1 − m − 2)·step
                let t = (i + 1.0 - (m + 2) as f64) * step;
                out.push(EdgeObs {
                    a,
                    b,
                    p: [q[0] + t * n[0], q[1] + t * n[1]],
                });
            }
        }
        out
    };
    segments.par_iter().map(one).collect::<Vec<_>>().concat()
}
