//! Homography refinement on straight edges. Points along known straight
//! edges (a strip's four sides, or every side of a target's sweeps, patches
//! and grey patches that has contrast) are searched along the edge normal in
//! the image for the strongest gradient of the edge's polarity (sub-pixel by
//! a parabola through the peak); the homography is then fitted to all of
//! them (plus any fixed point correspondences, e.g. seen fiducials) by robust
//! Gauss–Newton on the point-to-line distances in pixels.

use super::LocateError;
use super::sample::Gray;
use crate::geometry::{Homography, Point, check_quad, rect_corners};
use crate::photo::Plane;
use crate::target::Target;

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

/// Target segments worth fitting: sides of every region, with the contrast across them.
pub fn target_segments(t: &Target) -> Vec<(Point, Point)> {
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
                out.push((a, b));
            }
        }
    }
    out
}

/// Searches every segment for its edge in the image around its predicted place.
pub fn collect_edges(
    g: &Gray<'_>,
    segments: &[(Point, Point)],
    h: &Homography,
    search_px: f64,
) -> Vec<EdgeObs> {
    let mut out = Vec::new();
    let step = 0.5;
    let m = (search_px / step).ceil() as i64;
    for &(a, b) in segments {
        let (ia, ib) = (h.apply(a), h.apply(b));
        let len = (ib[0] - ia[0]).hypot(ib[1] - ia[1]);
        if !len.is_finite() || len < 8.0 {
            continue;
        }
        let n = [-(ib[1] - ia[1]) / len, (ib[0] - ia[0]) / len];
        let count = ((len / 3.0) as usize).clamp(4, 200);
        let mut found: Vec<(f64, Point, f64)> = Vec::new(); // (signed grad, point, sharpness)
        for j in 0..count {
            let f = 0.08 + 0.84 * (j as f64 + 0.5) / count as f64;
            // Along the segment in target units, mapped (straight lines stay straight).
            let tp = [a[0] + f * (b[0] - a[0]), a[1] + f * (b[1] - a[1])];
            let q = h.apply(tp);
            let mut prof = Vec::with_capacity((2 * m + 5) as usize);
            let mut ok = true;
            for i in -m - 2..=m + 2 {
                let t = i as f64 * step;
                match g.at_img([q[0] + t * n[0], q[1] + t * n[1]]) {
                    Some(v) => prof.push(v),
                    None => {
                        ok = false;
                        break;
                    }
                }
            }
            if !ok {
                continue;
            }
            let grad: Vec<f64> = (1..prof.len() - 1)
                .map(|i| (prof[i + 1] - prof[i - 1]) / (2.0 * step))
                .collect();
            let (imax, gmax) = grad
                .iter()
                .enumerate()
                .max_by(|x, y| x.1.abs().total_cmp(&y.1.abs()))
                .map(|(i, v)| (i, *v))
                .unwrap();
            if imax == 0 || imax + 1 == grad.len() {
                continue;
            }
            let mut abs: Vec<f64> = grad.iter().map(|v| v.abs()).collect();
            abs.sort_by(f64::total_cmp);
            let med = abs[abs.len() / 2];
            if gmax.abs() < 3.0 * med || gmax.abs() < 1e-6 {
                continue;
            }
            let (g0, g1, g2) = (grad[imax - 1].abs(), gmax.abs(), grad[imax + 1].abs());
            let den = g0 - 2.0 * g1 + g2;
            let sub = if den < 0.0 {
                0.5 * (g0 - g2) / den
            } else {
                0.0
            };
            // grad index i ↔ profile index i+1 ↔ t = (i + 1 − m − 2)·step
            let t = (imax as f64 + 1.0 + sub.clamp(-0.5, 0.5) - (m + 2) as f64) * step;
            found.push((
                gmax,
                [q[0] + t * n[0], q[1] + t * n[1]],
                gmax.abs() / med.max(1e-9),
            ));
        }
        // Keep the majority polarity.
        let pos = found.iter().filter(|x| x.0 > 0.0).count();
        let want_pos = 2 * pos >= found.len();
        for (gv, p, _) in found {
            if (gv > 0.0) == want_pos {
                out.push(EdgeObs { a, b, p });
            }
        }
    }
    out
}

/// Signed distance (px) of an observed point from its segment's image line.
fn line_residual(h: &Homography, o: &EdgeObs) -> f64 {
    let (ia, ib) = (h.apply(o.a), h.apply(o.b));
    let (dx, dy) = (ib[0] - ia[0], ib[1] - ia[1]);
    let len = dx.hypot(dy);
    ((o.p[0] - ia[0]) * dy - (o.p[1] - ia[1]) * dx) / len
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
    let residuals = |h: &Homography| -> Vec<f64> {
        let mut r: Vec<f64> = edges.iter().map(|o| line_residual(h, o)).collect();
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
        let Some(dx) = solve8(ata, atb) else {
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

fn solve8(mut a: [[f64; 8]; 8], mut b: [f64; 8]) -> Option<[f64; 8]> {
    for col in 0..8 {
        let piv = (col..8).max_by(|&i, &j| a[i][col].abs().total_cmp(&a[j][col].abs()))?;
        if a[piv][col].abs() < 1e-300 {
            return None;
        }
        a.swap(col, piv);
        b.swap(col, piv);
        for r in 0..8 {
            if r != col {
                let f = a[r][col] / a[col][col];
                let prow = a[col];
                for (x, p) in a[r].iter_mut().zip(prow) {
                    *x -= f * p;
                }
                b[r] -= f * b[col];
            }
        }
    }
    Some([0, 1, 2, 3, 4, 5, 6, 7].map(|i| b[i] / a[i][i]))
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
        let edges = collect_edges(full, &segs, &h, search.max(3.0));
        let edges = prune(&h, edges, search.max(3.0));
        if edges.len() < 12 {
            return None;
        }
        h = fit_homography(h, &edges, fixed);
    }
    let edges = prune(&h, collect_edges(full, &segs, &h, 3.0), 1.5);
    if edges.len() < 12 {
        return None;
    }
    h = fit_homography(h, &edges, fixed);
    Some((h, edges.len()))
}

/// See [`super::refine_roi`].
pub fn refine_roi(
    plane: &Plane,
    corners: [Point; 4],
    target: Option<&Target>,
    search_px: f64,
) -> Result<[Point; 4], LocateError> {
    check_quad(&corners).map_err(|e| LocateError::Refine(e.to_string()))?;
    let full = Gray::of_plane(plane);
    let (src, segs) = match target {
        Some(t) => (
            rect_corners(0.0, 0.0, t.width_mm, t.height_mm),
            target_segments(t),
        ),
        None => {
            let s = rect_corners(0.0, 0.0, 1.0, 1.0);
            (s, (0..4).map(|i| (s[i], s[(i + 1) % 4])).collect())
        }
    };
    if segs.len() < 4 && target.is_some() {
        return Err(LocateError::Refine(
            "the target has too few straight edges with contrast".into(),
        ));
    }
    let mut h =
        Homography::from_quads(&src, &corners).map_err(|e| LocateError::Refine(e.to_string()))?;
    let search = search_px.max(2.0) + 2.0;
    for s in [search, 3.0, 2.0] {
        let mut edges = prune(&h, collect_edges(&full, &segs, &h, s), s);
        if target.is_none() {
            // A side whose edge is not clearly seen (e.g. a sweep's low-frequency end, which
            // starts at a bright peak) keeps the user's line.
            let mut seen = 0;
            for (i, &(a, b)) in segs.iter().enumerate() {
                let pts: Vec<Point> = edges
                    .iter()
                    .filter(|o| o.a == a && o.b == b)
                    .map(|o| o.p)
                    .collect();
                if pts.len() >= 6 && line_rms(&pts) <= 1.0 {
                    seen += 1;
                    continue;
                }
                edges.retain(|o| !(o.a == a && o.b == b));
                let (ca, cb) = (corners[i], corners[(i + 1) % 4]);
                for k in 0..10 {
                    let f = (k as f64 + 0.5) / 10.0;
                    edges.push(EdgeObs {
                        a,
                        b,
                        p: [ca[0] + f * (cb[0] - ca[0]), ca[1] + f * (cb[1] - ca[1])],
                    });
                }
            }
            if seen < 2 {
                return Err(LocateError::Refine(format!(
                    "edges not found near the given corners ({seen} of 4 sides seen)"
                )));
            }
        } else if edges.len() < 12 {
            return Err(LocateError::Refine(format!(
                "edges not found near the given corners (saw {} edge points)",
                edges.len()
            )));
        }
        h = fit_homography(h, &edges, &[]);
    }
    let out = src.map(|p| h.apply(p));
    check_quad(&out).map_err(|e| LocateError::Refine(e.to_string()))?;
    let moved = out
        .iter()
        .zip(&corners)
        .map(|(a, b)| (a[0] - b[0]).hypot(a[1] - b[1]))
        .fold(0.0, f64::max);
    if moved > 3.0 * search {
        return Err(LocateError::Refine(format!(
            "refined corners moved {moved:.1} px, more than the search range allows"
        )));
    }
    Ok(out)
}
