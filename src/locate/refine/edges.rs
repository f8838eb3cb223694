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
    Some(lobe_centroid(grad, sign, imax))
}

/// The sub-sample place of the peak of `sign·g` at its local maximum `i`
/// (`0 < i < g.len() − 1`, as both callers ensure): the
/// centroid of the samples around it above [`LOBE_LEVEL`] of the peak,
/// weighted by their excess over that level, where they end inside `g`;
/// else (a soft edge whose lobe the search window cuts) a parabola through
/// the peak and its neighbours. A parabola locks onto the pixel grid where
/// the lobe is narrow: on an edge along a pixel axis the bilinear profile's
/// gradient is piecewise linear between pixel centres, and the vertex sits
/// where the grid puts it, up to 0.25 px from the edge (unit test; session
/// 33: a strip 0.02° off the pixel columns had its long edges read 0.9 px
/// out of parallel, and the homography took that for a keystone). The
/// thresholded centroid is unbiased for a symmetric lobe and follows the
/// edge within 0.021 px there.
fn lobe_centroid(g: &[f64], sign: f64, i: usize) -> f64 {
    let at = |k: usize| g[k] * sign;
    let floor = LOBE_LEVEL * at(i);
    let mut lo = i;
    while lo > 0 && at(lo - 1) > floor {
        lo -= 1;
    }
    let mut hi = i;
    while hi + 1 < g.len() && at(hi + 1) > floor {
        hi += 1;
    }
    if lo == 0 || hi + 1 == g.len() {
        return parabola_vertex([at(i - 1), at(i), at(i + 1)], i);
    }
    let (mut sum, mut moment) = (0.0, 0.0);
    for k in lo..=hi {
        let excess = at(k) - floor;
        sum += excess;
        moment += excess * k as f64;
    }
    if sum > 0.0 { moment / sum } else { i as f64 }
}

/// The lobe's samples count above this fraction of its peak, by their
/// excess over it. At 0.5 the unit test's sharp edge is read within
/// 0.047 px; at 0.3 noise at the soft shot's wide lobe moved its edges
/// enough that the ends' bars were no longer followed (integration test).
const LOBE_LEVEL: f64 = 0.4;

/// The vertex of the parabola through `[g0, g1, g2]` at `i − 1`, `i`, `i + 1` (within ±½ of `i`).
fn parabola_vertex([g0, g1, g2]: [f64; 3], i: usize) -> f64 {
    let den = g0 - 2.0 * g1 + g2;
    let sub = if den < 0.0 {
        0.5 * (g0 - g2) / den
    } else {
        0.0
    };
    i as f64 + sub.clamp(-0.5, 0.5)
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
            // The lobe of the gradient's own sign (a lobe of |g| could run
            // on into the next edge's).
            return Some(lobe_centroid(grad, grad[i].signum(), i));
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

#[cfg(test)]
mod tests {
    use super::*;
    use crate::locate::sample::ConvertedCrop;
    use crate::photo::linearise::Crop;

    /// Image pixel (i, j)'s value for a near-vertical edge, dark to its
    /// left, at x = `x0 + drift·y/400`: a logistic edge of scale `s` px
    /// integrated exactly over the pixel's width (its row at its centre).
    fn edge_pixel(i: usize, j: usize, x0: f64, drift: f64, s: f64) -> f32 {
        let e = x0 + drift * (j as f64 + 0.5) / 400.0;
        let softplus = |u: f64| if u > 30.0 { u } else { u.exp().ln_1p() };
        let x = i as f64;
        (0.1 + 0.8 * s * (softplus((x + 1.0 - e) / s) - softplus((x - e) / s))) as f32
    }

    #[test]
    fn an_edge_along_a_pixel_axis_is_found_at_its_sub_pixel_place() {
        // The edge drifts one pixel over 400 rows: every sub-pixel place is met.
        let (x0, drift) = (30.2, 1.0);
        for s in [0.35, 0.8] {
            let img = ConvertedCrop {
                crop: Crop {
                    x0: 0,
                    y0: 0,
                    x1: 64,
                    y1: 420,
                },
                at: move |i: usize, j: usize| edge_pixel(i, j, x0, drift, s),
            };
            let identity = Homography {
                m: [1.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0],
            };
            let seg = Segment {
                a: [x0, 10.0],
                b: [x0 + drift, 410.0],
                outside_brighter: None,
            };
            let obs = collect_edges(&img, &[seg], &identity, 4.0, true);
            assert!(obs.len() > 100, "{} points", obs.len());
            let worst = obs
                .iter()
                .map(|o| (o.p[0] - (x0 + drift * o.p[1] / 400.0)).abs())
                .fold(0.0, f64::max);
            // A parabola through the gradient's peak read these up to 0.25 px
            // off (s 0.35), following the pixel grid; the lobe's centroid
            // within 0.021 px (s 0.35) and 0.007 px (s 0.8).
            assert!(worst < 0.03, "scale {s}: worst {worst:.3} px");
        }
    }
}
