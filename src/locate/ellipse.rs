//! Sub-pixel fiducial centres at full resolution. The dark→white edge of each
//! mark is found on 64 rays (threshold halfway between the ray's own dark and
//! white levels, so a light gradient across the mark does not bias it), an
//! ellipse is fitted to the edge points (with outlier rejection), and its
//! centre is taken. Under perspective the centre of the imaged ellipse is not
//! the image of the disk's centre; the shift is predicted by projecting the
//! disk's circle through the current homography as a conic and removed
//! (two iterations). Then the homography and the frame corners follow.

use super::assign::{Pick, affine3};
pub use super::conic::{Ellipse, fit_ellipse};
use super::sample::Gray;
use super::source::Source;
use super::{Candidate, Located};
use crate::geometry::{Homography, Point, rect_corners};
use crate::photo::linearise::Crop;
use crate::target::Target;
use rayon::prelude::*;

/// Rays used for the full-resolution edge fit.
pub const RAYS: usize = 64;

/// Edge points of a dark mark on `RAYS` rays from `e.centre` (grid units).
pub fn edge_points(g: &Gray<'_>, e: &Ellipse) -> Vec<Point> {
    edge_points_within(
        g,
        e,
        &mut [
            f64::INFINITY,
            f64::INFINITY,
            f64::NEG_INFINITY,
            f64::NEG_INFINITY,
        ],
    )
}

/// [`edge_points`], widening `reach` (grid box [x0, y0, x1, y1]) to every place the rays may read.
fn edge_points_within(g: &Gray<'_>, e: &Ellipse, reach: &mut [f64; 4]) -> Vec<Point> {
    let [cxx, cxy, cyy] = e.cov;
    let det = cxx * cyy - cxy * cxy;
    let mut out = Vec::with_capacity(RAYS);
    if det <= 0.0 {
        return out;
    }
    let (ixx, ixy, iyy) = (cyy / det, -cxy / det, cxx / det);
    let mut prof = Vec::with_capacity(1024);
    'rays: for k in 0..RAYS {
        let a = 2.0 * std::f64::consts::PI * (k as f64 + 0.5) / RAYS as f64;
        let (ux, uy) = (a.cos(), a.sin());
        let rho = 2.0 / (ux * ux * ixx + 2.0 * ux * uy * ixy + uy * uy * iyy).sqrt();
        let step = (rho / 40.0).min(0.2);
        let m = (1.75 * rho / step).ceil() as usize + 1;
        for t in [0.0, (m - 1) as f64 * step] {
            let (x, y) = (e.centre[0] + t * ux, e.centre[1] + t * uy);
            *reach = [
                reach[0].min(x),
                reach[1].min(y),
                reach[2].max(x),
                reach[3].max(y),
            ];
        }
        prof.clear();
        for i in 0..m {
            let t = i as f64 * step;
            match g.bilinear([e.centre[0] + t * ux, e.centre[1] + t * uy]) {
                Some(v) => prof.push(v),
                None => continue 'rays,
            }
        }
        let idx = |t: f64| ((t / step).round() as usize).min(m - 1);
        let (w0, w1) = (idx(1.4 * rho), idx(1.75 * rho));
        let white = prof[w0..=w1].iter().sum::<f64>() / (w1 - w0 + 1) as f64;
        // Dark level: mean of the darkest part of the mark on this ray.
        let (d0, d1) = (idx(0.55 * rho), idx(0.85 * rho));
        let dark = prof[d0..=d1].iter().sum::<f64>() / (d1 - d0 + 1) as f64;
        if white - dark <= 0.0 {
            continue;
        }
        let thr = 0.5 * (dark + white);
        for i in (0..idx(1.35 * rho)).rev() {
            if prof[i] < thr {
                let (p0, p1) = (prof[i], prof[i + 1]);
                let f = if p1 > p0 { (thr - p0) / (p1 - p0) } else { 0.5 };
                let t = (i as f64 + f.clamp(0.0, 1.0)) * step;
                out.push([e.centre[0] + t * ux, e.centre[1] + t * uy]);
                break;
            }
        }
    }
    out
}

/// Refines a mark's ellipse at full resolution (image px in, image px out).
pub fn refine_mark(full: &Gray<'_>, centre_px: Point, cov_px2: [f64; 3]) -> Option<Ellipse> {
    refine_mark_within(full, centre_px, cov_px2, &mut [0.0; 4])
}

/// [`refine_mark`], setting `reach` to the grid box of every place it may read.
fn refine_mark_within(
    full: &Gray<'_>,
    centre_px: Point,
    cov_px2: [f64; 3],
    reach: &mut [f64; 4],
) -> Option<Ellipse> {
    *reach = [
        f64::INFINITY,
        f64::INFINITY,
        f64::NEG_INFINITY,
        f64::NEG_INFINITY,
    ];
    let s = full.scale;
    let mut e = Ellipse {
        centre: full.to_grid(centre_px),
        cov: [
            cov_px2[0] / (s[0] * s[0]),
            cov_px2[1] / (s[0] * s[1]),
            cov_px2[2] / (s[1] * s[1]),
        ],
    };
    for _ in 0..3 {
        let pts = edge_points_within(full, &e, reach);
        if pts.len() < RAYS / 2 {
            return None;
        }
        let next = fit_ellipse(&pts)?;
        let moved = (next.centre[0] - e.centre[0]).hypot(next.centre[1] - e.centre[1]);
        e = next;
        if moved < 0.01 {
            break;
        }
    }
    Some(Ellipse {
        centre: full.to_img(e.centre),
        cov: [
            e.cov[0] * s[0] * s[0],
            e.cov[1] * s[0] * s[1],
            e.cov[2] * s[1] * s[1],
        ],
    })
}

type M3 = [[f64; 3]; 3];

fn m3(h: &Homography) -> M3 {
    let m = &h.m;
    [[m[0], m[1], m[2]], [m[3], m[4], m[5]], [m[6], m[7], m[8]]]
}

fn mul(a: &M3, b: &M3) -> M3 {
    let mut c = [[0.0; 3]; 3];
    for i in 0..3 {
        for j in 0..3 {
            c[i][j] = (0..3).map(|k| a[i][k] * b[k][j]).sum();
        }
    }
    c
}

fn transpose(a: &M3) -> M3 {
    let mut c = [[0.0; 3]; 3];
    for i in 0..3 {
        for j in 0..3 {
            c[i][j] = a[j][i];
        }
    }
    c
}

/// Image position of the centre of the ellipse that a circle (centre, radius; mm) projects to.
pub fn projected_circle_centre(h: &Homography, centre: Point, radius: f64) -> Option<Point> {
    let inv = m3(&h.inverse()?);
    let (x, y) = (centre[0], centre[1]);
    let c: M3 = [
        [1.0, 0.0, -x],
        [0.0, 1.0, -y],
        [-x, -y, x * x + y * y - radius * radius],
    ];
    let cp = mul(&transpose(&inv), &mul(&c, &inv));
    let (a, b, cc, d, e) = (cp[0][0], cp[0][1], cp[1][1], cp[0][2], cp[1][2]);
    let det = a * cc - b * b;
    if det.abs() < 1e-300 {
        return None;
    }
    Some([(-d * cc + e * b) / det, (-e * a + d * b) / det])
}

/// Measured centres corrected for the perspective shift, and the homography through them.
fn solve_with_correction(
    target: &Target,
    marks: &[(usize, Point)],
    mut h: Homography,
) -> Option<Homography> {
    // Go round the marks in the target's turning order (a quad must not cross itself).
    let mut marks = marks.to_vec();
    let pos = |fi: usize| [target.fiducials[fi].x_mm, target.fiducials[fi].y_mm];
    let n = marks.len() as f64;
    let cx = marks.iter().map(|m| pos(m.0)[0]).sum::<f64>() / n;
    let cy = marks.iter().map(|m| pos(m.0)[1]).sum::<f64>() / n;
    marks.sort_by(|a, b| {
        let (pa, pb) = (pos(a.0), pos(b.0));
        (pa[1] - cy)
            .atan2(pa[0] - cx)
            .total_cmp(&(pb[1] - cy).atan2(pb[0] - cx))
    });
    for _ in 0..3 {
        let mut src = Vec::new();
        let mut dst = Vec::new();
        for &(fi, p) in &marks {
            let f = &target.fiducials[fi];
            let c = [f.x_mm, f.y_mm];
            let shift = match projected_circle_centre(&h, c, f.diameter_mm / 2.0) {
                Some(e) => {
                    let hc = h.apply(c);
                    [e[0] - hc[0], e[1] - hc[1]]
                }
                None => [0.0, 0.0],
            };
            src.push(c);
            dst.push([p[0] - shift[0], p[1] - shift[1]]);
        }
        h = if marks.len() >= 4 {
            Homography::from_quads(
                &[src[0], src[1], src[2], src[3]],
                &[dst[0], dst[1], dst[2], dst[3]],
            )
            .ok()?
        } else {
            affine3(&src, &dst)?
        };
    }
    Some(h)
}

/// Looks for fiducial `fi` where `h` predicts it; its refined image centre when a mark
/// of the predicted size and shape is there.
fn recover_mark(
    full: &Gray<'_>,
    target: &Target,
    h: &Homography,
    fi: usize,
    start: Option<Point>,
) -> Option<Point> {
    let f = &target.fiducials[fi];
    let c = [f.x_mm, f.y_mm];
    let p = start.unwrap_or_else(|| h.apply(c));
    let j = h.jacobian(c);
    let r2 = (f.diameter_mm / 2.0).powi(2) / 4.0;
    let pred = [
        r2 * (j[0][0] * j[0][0] + j[0][1] * j[0][1]),
        r2 * (j[0][0] * j[1][0] + j[0][1] * j[1][1]),
        r2 * (j[1][0] * j[1][0] + j[1][1] * j[1][1]),
    ];
    let s = full.scale;
    let grid_cov = [
        pred[0] / (s[0] * s[0]),
        pred[1] / (s[0] * s[1]),
        pred[2] / (s[1] * s[1]),
    ];
    // Where the mark must be, a dark blob of the right size with clear contrast will do
    // (small rings often fail the blind disk test).
    let t = super::blobs::ray_test(full, full.to_grid(p), grid_cov)?;
    if t.contrast < 0.3 {
        return None;
    }
    let e = refine_mark(full, p, pred)?;
    let radius = (pred[0] + pred[2]).sqrt(); // ≈ the imaged radius
    let moved = (e.centre[0] - p[0]).hypot(e.centre[1] - p[1]);
    let size = ((e.cov[0] * e.cov[2] - e.cov[1] * e.cov[1])
        / (pred[0] * pred[2] - pred[1] * pred[1]))
        .sqrt();
    // Seeded from a blob near an affine guess (perhaps a fragment of a ring): the fit may
    // move further from the seed, and the guessed size is less certain.
    let (max_move, sizes) = if start.is_some() {
        (1.5 * radius + 1.0, 0.4..=2.5)
    } else {
        (0.6 * radius + 1.0, 0.6..=1.6)
    };
    if !(moved < max_move && sizes.contains(&size)) {
        return None;
    }
    if start.is_some() {
        // Far from a trusted prediction: the refined ellipse must pass the disk test itself.
        let g = [
            e.cov[0] / (s[0] * s[0]),
            e.cov[1] / (s[0] * s[1]),
            e.cov[2] / (s[1] * s[1]),
        ];
        let t = super::blobs::ray_test(full, full.to_grid(e.centre), g)?;
        if !t.disk_like {
            return None;
        }
    }
    Some(e.centre)
}

/// Looks for the hidden mark at blobs near where an (affine) guess puts it, nearest first.
fn recover_near(
    full: &Gray<'_>,
    target: &Target,
    h: &Homography,
    fi: usize,
    cands: &[Candidate],
    used: &[usize],
) -> Option<Point> {
    let f = &target.fiducials[fi];
    let p = h.apply([f.x_mm, f.y_mm]);
    let span = {
        let c = rect_corners(0.0, 0.0, target.width_mm, target.height_mm).map(|q| h.apply(q));
        (c[2][0] - c[0][0]).hypot(c[2][1] - c[0][1])
    };
    let mut near: Vec<(f64, usize)> = cands
        .iter()
        .enumerate()
        .filter(|(i, _)| !used.contains(i))
        .map(|(i, c)| ((c.centre_px[0] - p[0]).hypot(c.centre_px[1] - p[1]), i))
        .filter(|&(d, _)| d <= 0.1 * span)
        .collect();
    near.sort_by(|a, b| a.0.total_cmp(&b.0));
    near.iter()
        .take(6)
        .find_map(|&(_, i)| recover_mark(full, target, h, fi, Some(cands[i].centre_px)))
}

/// [`refine_mark`] reading `src` only in a window around the mark: the
/// window is widened until every read the fit made lies inside it, so the
/// result is the one the whole image gives.
fn refine_in_window<S: Source + ?Sized>(
    src: &S,
    centre_px: Point,
    cov_px2: [f64; 3],
) -> Option<Ellipse> {
    // The rays reach 3.5 σ along the mark's long axis; the fit may move and grow it.
    let (a, c, b) = (cov_px2[0], cov_px2[2], cov_px2[1]);
    let long = (0.5 * (a + c) + (0.25 * (a - c).powi(2) + b * b).sqrt()).max(0.0);
    let mut half = 6.0 * long.sqrt() + 16.0;
    let (w, h) = src.size();
    for _ in 0..4 {
        let lo = |v: f64| (v - half).floor().max(0.0) as usize;
        let hi = |v: f64| (v + half).ceil().max(0.0) as usize;
        let win = src.window(Crop {
            x0: lo(centre_px[0]),
            y0: lo(centre_px[1]),
            x1: hi(centre_px[0]).min(w),
            y1: hi(centre_px[1]).min(h),
        });
        let mut reach = [0.0; 4];
        let e = refine_mark_within(&win.gray, centre_px, cov_px2, &mut reach);
        if win.holds(reach) {
            return e;
        }
        half *= 2.0;
    }
    refine_mark(&src.window(whole(src)).gray, centre_px, cov_px2)
}

/// The whole image of `src` as a crop.
fn whole<S: Source + ?Sized>(src: &S) -> Crop {
    let (w, h) = src.size();
    Crop {
        x0: 0,
        y0: 0,
        x1: w,
        y1: h,
    }
}

/// Full-resolution refinement of a pick; `None` when the marks cannot be measured.
///
/// The marks of a full quad are read in windows around them; a hidden mark's
/// recovery (which follows the target's edges) reads the whole image.
pub fn finish<S: Source + ?Sized>(
    src: &S,
    target: &Target,
    pick: &Pick,
    cands: &[Candidate],
) -> Option<Located> {
    let mut warnings = Vec::new();
    let mut marks: Vec<(usize, Point)> = Vec::new();
    // The marks are refined independently (in parallel), then taken in order.
    let fits: Vec<Option<Ellipse>> = pick
        .cand_idx
        .par_iter()
        .map(|&ci| refine_in_window(src, cands[ci].centre_px, cands[ci].cov_px2))
        .collect();
    for ((&ci, &fi), fit) in pick.cand_idx.iter().zip(&pick.fid_idx).zip(fits) {
        let c = &cands[ci];
        match fit {
            Some(e) => marks.push((fi, e.centre)),
            None => {
                warnings.push(format!(
                    "fiducial '{}': edge fit failed, using its blob centre",
                    target.fiducials[fi].id
                ));
                marks.push((fi, c.centre_px));
            }
        }
    }
    let mut h = solve_with_correction(target, &marks, pick.homography)?;
    let mut hidden = None;
    if let Some(missing) = pick.hidden {
        let window = src.window(whole(src));
        let full = window.gray;
        let id = target.fiducials[missing].id.clone();
        let fixed: Vec<(Point, Point)> = marks
            .iter()
            .map(|&(fi, p)| {
                let f = &target.fiducials[fi];
                ([f.x_mm, f.y_mm], p)
            })
            .collect();
        // The mark may be there but too small or faint for the blob search: look at
        // blobs near where the affine guess puts it, then where the edge-refined
        // solution predicts it.
        let mut edges = None;
        let mut found = recover_near(&full, target, &h, missing, cands, &pick.cand_idx);
        if found.is_none() {
            edges = super::refine::fit_target_edges(&full, target, h, &fixed);
            if let Some((h2, _)) = edges {
                h = h2;
            }
            found = recover_mark(&full, target, &h, missing, None);
        }
        if let Some(p) = found {
            marks.push((missing, p));
            h = solve_with_correction(target, &marks, h)?;
        } else {
            match edges {
                Some((_, n)) => warnings.push(format!(
                    "fiducial '{id}' not seen (hidden or outside the frame): solved from the other {} marks and {n} edge points of the target",
                    marks.len()
                )),
                None => warnings.push(format!(
                    "fiducial '{id}' not seen (hidden or outside the frame): solved from the other {} marks assuming no perspective (affine); corners may be off under tilt",
                    marks.len()
                )),
            }
            hidden = Some(id);
        }
    }
    let corners = rect_corners(0.0, 0.0, target.width_mm, target.height_mm).map(|c| h.apply(c));
    if corners.iter().flatten().any(|v| !v.is_finite()) {
        return None;
    }
    Some(Located {
        homography: h,
        corners_px: corners,
        fiducials: marks
            .iter()
            .map(|&(fi, _)| {
                let f = &target.fiducials[fi];
                (f.id.clone(), h.apply([f.x_mm, f.y_mm]))
            })
            .collect(),
        hidden,
        warnings,
        score: pick.score,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn projected_circle_centre_matches_sampled_ellipse() {
        let src = rect_corners(0.0, 0.0, 100.0, 60.0);
        let dst = [[50.0, 40.0], [600.0, 90.0], [520.0, 420.0], [80.0, 330.0]];
        let h = Homography::from_quads(&src, &dst).unwrap();
        let (c, r) = ([12.0, 9.0], 4.0);
        let pts: Vec<Point> = (0..200)
            .map(|k| {
                let t = k as f64 * std::f64::consts::TAU / 200.0;
                h.apply([c[0] + r * t.cos(), c[1] + r * t.sin()])
            })
            .collect();
        let fit = fit_ellipse(&pts).unwrap();
        let pc = projected_circle_centre(&h, c, r).unwrap();
        assert!((fit.centre[0] - pc[0]).abs() < 1e-6 && (fit.centre[1] - pc[1]).abs() < 1e-6);
        // and it differs from the image of the centre under this perspective
        let hc = h.apply(c);
        assert!((pc[0] - hc[0]).hypot(pc[1] - hc[1]) > 1e-3);
    }
}
