//! Homography refinement on straight edges. Points along known straight
//! edges (a strip's four sides, or every side of a target's sweeps, patches
//! and grey patches that has contrast) are searched along the edge normal in
//! the image for the strongest gradient of the edge's polarity (sub-pixel by
//! a parabola through the peak); the homography is then fitted to all of
//! them (plus any fixed point correspondences, e.g. seen fiducials) by robust
//! Gauss–Newton on the point-to-line distances in pixels. A single strip's ends
//! have no reliable edge; they are turned along the printed bars afterwards
//! ([`super::strip_ends`]).

mod edges;

pub use edges::{EdgeObs, Segment, collect_edges, target_segments};

use super::LocateError;
use super::sample::{AtImage, Gray};
use crate::geometry::{Homography, Point, check_quad, rect_corners};
use crate::target::Target;

/// A target segment's line in the image under a homography.
struct ImageLine {
    /// Image of the segment's start (px).
    ia: Point,
    /// Image of the segment's end minus its start (px).
    d: Point,
    /// Length of `d` (px).
    len: f64,
}

impl ImageLine {
    /// The image line of the segment `a`–`b` (target units) under `h`.
    fn of(h: &Homography, a: Point, b: Point) -> ImageLine {
        let (ia, ib) = (h.apply(a), h.apply(b));
        let d = [ib[0] - ia[0], ib[1] - ia[1]];
        ImageLine {
            ia,
            d,
            len: d[0].hypot(d[1]),
        }
    }

    /// Signed distance (px) of the image point `p` from the line.
    fn residual(&self, p: Point) -> f64 {
        ((p[0] - self.ia[0]) * self.d[1] - (p[1] - self.ia[1]) * self.d[0]) / self.len
    }
}

/// Signed distance (px) of an observed point from its segment's image line.
fn line_residual(h: &Homography, o: &EdgeObs) -> f64 {
    ImageLine::of(h, o.a, o.b).residual(o.p)
}

/// Robust (Huber, 1 px) Gauss–Newton fit of the homography to edge points and fixed points.
///
/// The update is parametrised in the target's own frame scaled to about unit size,
/// `H = H₀ · S⁻¹ · (I + Δ) · S`, so the 8 unknowns are comparably scaled.
pub fn fit_homography(h0: Homography, edges: &[EdgeObs], fixed: &[(Point, Point)]) -> Homography {
    let src_pts = edges
        .iter()
        .flat_map(|o| [o.a, o.b])
        .chain(fixed.iter().map(|f| f.0));
    let l = src_pts
        .map(|p| p[0].abs().max(p[1].abs()))
        .fold(0.0f64, f64::max)
        .max(1e-9);
    let s = Homography {
        m: [1.0 / l, 0.0, 0.0, 0.0, 1.0 / l, 0.0, 0.0, 0.0, 1.0],
    };
    let s_inv = Homography {
        m: [l, 0.0, 0.0, 0.0, l, 0.0, 0.0, 0.0, 1.0],
    };
    let with = |base: &Homography, d: &[f64; 8]| -> Homography {
        let t = Homography {
            m: [
                1.0 + d[0],
                d[1],
                d[2],
                d[3],
                1.0 + d[4],
                d[5],
                d[6],
                d[7],
                1.0,
            ],
        };
        base.compose(&s_inv).compose(&t).compose(&s)
    };
    // Edge points come in runs on one segment: each run's line is mapped once.
    let mut runs: Vec<(Point, Point, usize)> = Vec::new();
    for o in edges {
        match runs.last_mut() {
            Some((a, b, k)) if *a == o.a && *b == o.b => *k += 1,
            _ => runs.push((o.a, o.b, 1)),
        }
    }
    let residuals = |h: &Homography| -> Vec<f64> {
        let mut r: Vec<f64> = Vec::with_capacity(edges.len() + 2 * fixed.len());
        let mut rest = edges;
        for &(a, b, k) in &runs {
            let line = ImageLine::of(h, a, b);
            let (run, tail) = rest.split_at(k);
            r.extend(run.iter().map(|o| line.residual(o.p)));
            rest = tail;
        }
        for &(sp, d) in fixed {
            let p = h.apply(sp);
            // a fixed point weighs as much as 5 edge points in each coordinate
            r.push(5.0 * (p[0] - d[0]));
            r.push(5.0 * (p[1] - d[1]));
        }
        r
    };
    let cost = |r: &[f64]| -> f64 {
        r.iter()
            .map(|v| {
                if v.abs() <= 1.0 {
                    0.5 * v * v
                } else {
                    v.abs() - 0.5
                }
            })
            .sum()
    };
    let mut h = h0;
    for _ in 0..10 {
        let r0 = residuals(&h);
        let n = r0.len();
        if n < 8 {
            return h;
        }
        let w: Vec<f64> = r0
            .iter()
            .map(|r| if r.abs() <= 1.0 { 1.0 } else { 1.0 / r.abs() })
            .collect();
        let mut jac = vec![[0.0f64; 8]; n];
        let eps = 1e-7;
        for k in 0..8 {
            let mut d = [0.0; 8];
            d[k] = eps;
            let rp = residuals(&with(&h, &d));
            for i in 0..n {
                jac[i][k] = (rp[i] - r0[i]) / eps;
            }
        }
        let mut ata = [[0.0f64; 8]; 8];
        let mut atb = [0.0f64; 8];
        for i in 0..n {
            for a in 0..8 {
                atb[a] -= w[i] * jac[i][a] * r0[i];
                for b in 0..8 {
                    ata[a][b] += w[i] * jac[i][a] * jac[i][b];
                }
            }
        }
        for (a, row) in ata.iter_mut().enumerate() {
            row[a] *= 1.0 + 1e-9;
        }
        let Some(dx) = crate::linalg::solve(ata, atb, 1e-300) else {
            return h;
        };
        let hn = with(&h, &dx);
        if cost(&residuals(&hn)) > cost(&r0) {
            return h;
        }
        h = hn;
        if dx.iter().all(|d| d.abs() < 1e-9) {
            break;
        }
    }
    h
}

/// RMS distance of points from their total-least-squares line (px).
fn line_rms(pts: &[Point]) -> f64 {
    let n = pts.len() as f64;
    let mx = pts.iter().map(|p| p[0]).sum::<f64>() / n;
    let my = pts.iter().map(|p| p[1]).sum::<f64>() / n;
    let (mut sxx, mut syy, mut sxy) = (0.0, 0.0, 0.0);
    for p in pts {
        let (dx, dy) = (p[0] - mx, p[1] - my);
        sxx += dx * dx;
        syy += dy * dy;
        sxy += dx * dy;
    }
    // smallest eigenvalue of the scatter matrix = sum of squared normal distances
    let tr = sxx + syy;
    let disc = ((sxx - syy).powi(2) / 4.0 + sxy * sxy).sqrt();
    ((tr / 2.0 - disc).max(0.0) / n).sqrt()
}

/// Drops edge points more than `max_px` from their predicted line.
fn prune(h: &Homography, edges: Vec<EdgeObs>, max_px: f64) -> Vec<EdgeObs> {
    edges
        .into_iter()
        .filter(|o| line_residual(h, o).abs() <= max_px)
        .collect()
}

/// Refines a target homography on the target's own edges, keeping `fixed` correspondences;
/// returns the homography and the number of edge points used, or `None` when too few.
pub fn fit_target_edges(
    full: &Gray<'_>,
    target: &Target,
    h0: Homography,
    fixed: &[(Point, Point)],
) -> Option<(Homography, usize)> {
    let segs = target_segments(target);
    if segs.len() < 2 {
        return None;
    }
    // A hidden mark leaves the affine guess off by up to a few % of the chart: search wide.
    let span = {
        let c = rect_corners(0.0, 0.0, target.width_mm, target.height_mm).map(|p| h0.apply(p));
        (c[2][0] - c[0][0]).hypot(c[2][1] - c[0][1])
    };
    let mut h = h0;
    for search in [0.04 * span, 0.01 * span + 2.0, 3.0] {
        let edges = collect_edges(full, &segs, &h, search.max(3.0), false);
        let edges = prune(&h, edges, search.max(3.0));
        if edges.len() < 12 {
            return None;
        }
        h = fit_homography(h, &edges, fixed);
    }
    let edges = prune(&h, collect_edges(full, &segs, &h, 3.0, false), 1.5);
    if edges.len() < 12 {
        return None;
    }
    h = fit_homography(h, &edges, fixed);
    Some((h, edges.len()))
}

/// Keeps the points of segments seen as straight lines: at least `min_pts`
/// points lying within 1 px RMS of their own line.
fn keep_straight(edges: Vec<EdgeObs>, min_pts: usize) -> Vec<EdgeObs> {
    let mut keep = vec![false; edges.len()];
    for i in 0..edges.len() {
        if keep[i] {
            continue;
        }
        let same: Vec<usize> = (i..edges.len())
            .filter(|&j| edges[j].a == edges[i].a && edges[j].b == edges[i].b)
            .collect();
        let pts: Vec<Point> = same.iter().map(|&j| edges[j].p).collect();
        if pts.len() >= min_pts && line_rms(&pts) <= 1.0 {
            for j in same {
                keep[j] = true;
            }
        }
    }
    edges
        .into_iter()
        .zip(keep)
        .filter_map(|(e, k)| k.then_some(e))
        .collect()
}

/// Like [`keep_straight`], but a segment whose points are not within 1 px RMS of
/// one line first loses its farthest points (down to half of them, at least
/// `min_pts`): a strip's long edge has weak stretches where its bright bars meet a
/// bright surround, and an edge point there may lock onto something else.
fn keep_straight_trimmed(edges: Vec<EdgeObs>, min_pts: usize) -> Vec<EdgeObs> {
    let mut out = Vec::new();
    let mut done = vec![false; edges.len()];
    for i in 0..edges.len() {
        if done[i] {
            continue;
        }
        let mut same: Vec<EdgeObs> = Vec::new();
        for j in i..edges.len() {
            if edges[j].a == edges[i].a && edges[j].b == edges[i].b {
                done[j] = true;
                same.push(edges[j]);
            }
        }
        let floor = min_pts.max(same.len() / 2);
        while same.len() >= floor.max(2) {
            let pts: Vec<Point> = same.iter().map(|o| o.p).collect();
            if line_rms(&pts) <= 1.0 {
                if same.len() >= min_pts {
                    out.extend(same.iter().copied());
                }
                break;
            }
            // Drop the point farthest from the total-least-squares line.
            let n = pts.len() as f64;
            let (mx, my) = (
                pts.iter().map(|p| p[0]).sum::<f64>() / n,
                pts.iter().map(|p| p[1]).sum::<f64>() / n,
            );
            let (mut sxx, mut syy, mut sxy) = (0.0, 0.0, 0.0);
            for p in &pts {
                let (dx, dy) = (p[0] - mx, p[1] - my);
                sxx += dx * dx;
                syy += dy * dy;
                sxy += dx * dy;
            }
            // Direction of the line: the scatter matrix's major axis.
            let ang = 0.5 * (2.0 * sxy).atan2(sxx - syy);
            let nrm = [-ang.sin(), ang.cos()];
            let worst = (0..pts.len())
                .max_by(|&a, &b| {
                    let d = |p: Point| ((p[0] - mx) * nrm[0] + (p[1] - my) * nrm[1]).abs();
                    d(pts[a]).total_cmp(&d(pts[b]))
                })
                .expect("non-empty");
            same.swap_remove(worst);
        }
    }
    out
}

/// How many of `edges` lie on each of `segs`.
fn per_segment(segs: &[Segment], edges: &[EdgeObs]) -> Vec<usize> {
    segs.iter()
        .map(|g| edges.iter().filter(|o| o.a == g.a && o.b == g.b).count())
        .collect()
}

/// Whether a side that held at least [`MIN_SIDE_POINTS`] edge points in the
/// pass `before` holds fewer than half as many `now`.
///
/// A blurred edge (a lens defocused by a 1.5 px disc) spreads its gradient
/// over ±3 px: the last pass's ±4 px window then finds a local peak on 6–7
/// of 200 places per side, where the pass before found 195, and the lines
/// fitted through those few moved an exact corner 1.05 px (a keystoned
/// linear sweep on the independent camera: chart modulation −3.5 %, MTF50
/// +2.7 %; with the pass before standing, −0.4 % and +0.3 %).
fn lost_an_edge(before: &[usize], now: &[usize]) -> bool {
    before
        .iter()
        .zip(now)
        .any(|(&b, &n)| b >= MIN_SIDE_POINTS && 2 * n < b)
}

/// Most an end's slant across the strip may be turned (px): corners off by
/// up to `search_px` slant an end by up to about twice that.
fn max_end_slant(search_px: f64) -> f64 {
    2.0 * search_px + 4.0
}

/// The strip `h`'s (unit square → image) corners with its ends turned along
/// the printed bars ([`super::strip_ends`]), its long edges as they are.
fn turn_ends<S: AtImage + ?Sized>(
    full: &S,
    h: &Homography,
    search_px: f64,
) -> Result<[Point; 4], LocateError> {
    let max_slant = max_end_slant(search_px);
    let fit = super::strip_ends::align_ends_settled(full, h, max_slant).map_err(|e| match e {
        super::strip_ends::EndsError::Slanted(px, max) => {
            LocateError::EndsSlanted(px[0], px[1], max)
        }
        e => LocateError::Refine(format!("strip ends: {e}")),
    })?;
    check_quad(&fit.corners).map_err(|e| LocateError::Refine(e.to_string()))?;
    Ok(fit.corners)
}

/// See [`super::turn_strip_ends`].
pub fn turn_strip_ends<S: AtImage + ?Sized>(
    full: &S,
    corners: [Point; 4],
    search_px: f64,
) -> Result<[Point; 4], LocateError> {
    check_quad(&corners).map_err(|e| LocateError::Refine(e.to_string()))?;
    let h = Homography::from_quads(&rect_corners(0.0, 0.0, 1.0, 1.0), &corners)
        .map_err(|e| LocateError::Refine(e.to_string()))?;
    turn_ends(full, &h, search_px)
}

/// Edge points a side must have held for its loss to stop the refinement.
const MIN_SIDE_POINTS: usize = 12;

/// See [`super::refine_roi`].
pub fn refine_roi<S: AtImage + ?Sized>(
    full: &S,
    corners: [Point; 4],
    target: Option<&Target>,
    search_px: f64,
) -> Result<[Point; 4], LocateError> {
    let fail = |m: String| Err(LocateError::Refine(m));
    check_quad(&corners).map_err(|e| LocateError::Refine(e.to_string()))?;
    let (src, segs) = match target {
        Some(t) => (
            rect_corners(0.0, 0.0, t.width_mm, t.height_mm),
            target_segments(t),
        ),
        None => {
            let s = rect_corners(0.0, 0.0, 1.0, 1.0);
            let segs = (0..4)
                .step_by(2)
                .map(|i| Segment {
                    a: s[i],
                    b: s[(i + 1) % 4],
                    outside_brighter: None,
                })
                .collect();
            (s, segs)
        }
    };
    if segs.len() < 4 && target.is_some() {
        return fail("the target has too few straight edges with contrast".into());
    }
    let mut h =
        Homography::from_quads(&src, &corners).map_err(|e| LocateError::Refine(e.to_string()))?;
    let search = search_px.max(2.0) + 2.0;
    let mut seen_edges = Vec::new();
    // Edge points each segment held in the pass before (none before the first).
    let mut before: Option<Vec<usize>> = None;
    for s in [search, 3.0, 2.0] {
        let mut edges = prune(&h, collect_edges(full, &segs, &h, s, true), s);
        edges = if target.is_some() {
            keep_straight(edges, 4)
        } else {
            keep_straight_trimmed(edges, 6)
        };
        // A narrower window that loses most of a long edge's points sees less
        // of that edge, not more precisely: the pass before stands. (A
        // target's many short edges are each fitted with the others.)
        let counts = per_segment(&segs, &edges);
        if target.is_none() && before.as_ref().is_some_and(|b| lost_an_edge(b, &counts)) {
            break;
        }
        if let Some(t) = target {
            // Both directions of the target's edges must be seen to fix the homography.
            let mut dirs = [0usize; 2];
            for (seg, _) in segs.iter().zip(&counts).filter(|(_, n)| **n > 0) {
                let horizontal = (seg.b[0] - seg.a[0]).abs() >= (seg.b[1] - seg.a[1]).abs();
                dirs[usize::from(horizontal)] += 1;
            }
            if edges.len() < 12 || dirs[0] < 2 || dirs[1] < 2 {
                return fail(format!(
                    "the edges of '{}' are not clearly seen near the given corners \
                     ({} edge points on {} vertical and {} horizontal sides)",
                    t.name,
                    edges.len(),
                    dirs[0],
                    dirs[1]
                ));
            }
            seen_edges = edges.clone();
        } else {
            seen_edges = edges.clone();
            // A side whose edge is not clearly seen keeps the user's line. The ends
            // are not searched (a sweep's low-frequency end starts at a bright peak, its
            // high-frequency end fades to grey, and the target's border may lie just
            // beyond): they keep the user's lines, so exact corners stay exact along
            // the strip, and are only turned along the printed bars at the end
            // (`strip_ends`). The estimator leaves out the periods next to each end,
            // so a little surround inside a loosely given end costs nothing.
            let mut seen = 0;
            for i in 0..4 {
                let (sa, sb) = (src[i], src[(i + 1) % 4]);
                if edges.iter().any(|o| o.a == sa && o.b == sb) {
                    seen += 1;
                    continue;
                }
                let (ca, cb) = (corners[i], corners[(i + 1) % 4]);
                for k in 0..10 {
                    let f = (k as f64 + 0.5) / 10.0;
                    edges.push(EdgeObs {
                        a: sa,
                        b: sb,
                        p: [ca[0] + f * (cb[0] - ca[0]), ca[1] + f * (cb[1] - ca[1])],
                    });
                }
            }
            if seen == 0 {
                return fail(
                    "the strip's long edges are not clearly seen near the given corners".into(),
                );
            }
        }
        h = fit_homography(h, &edges, &[]);
        before = Some(counts);
    }
    let mut out = src.map(|p| h.apply(p));
    let max_slant = max_end_slant(search_px);
    if target.is_none() {
        // The ends kept the user's (slanted) lines: turn them along the printed bars.
        out = turn_ends(full, &h, search_px)?;
    }
    check_quad(&out).map_err(|e| LocateError::Refine(e.to_string()))?;
    // The seen edges must lie on the refined lines; else they were not one clear edge each.
    let rms = (seen_edges
        .iter()
        .map(|o| line_residual(&h, o).powi(2))
        .sum::<f64>()
        / seen_edges.len().max(1) as f64)
        .sqrt();
    if rms > 0.75 {
        return fail(format!(
            "the edges near the given corners are ambiguous (RMS {rms:.2} px off the refined lines)"
        ));
    }
    let moved = crate::geometry::largest_move(&out, &corners);
    // (A strip's ends are turned along the bars about their centres: each end
    // corner slides along its long edge by up to half the largest slant.)
    let trim = if target.is_none() {
        0.5 * max_slant
    } else {
        0.0
    };
    let limit = std::f64::consts::SQRT_2 * search_px + 2.0 + trim;
    if moved > limit {
        return fail(format!(
            "refined corners would move {moved:.1} px, more than the corners' ±{search_px} px allow"
        ));
    }
    Ok(out)
}
