//! Judging one assignment of candidates to marks: the frame in front of the
//! camera, each mark's predicted size and shape, then the pattern's correlation.

use super::{Pattern, Pick};
use crate::geometry::Homography;
use crate::locate::Candidate;
use crate::locate::sample::Gray;
use crate::target::Target;

/// Size/shape prediction check, then pattern verification.
#[allow(clippy::too_many_arguments)]
pub(super) fn judge(
    g: &Gray<'_>,
    pat: &Pattern,
    target: &Target,
    cands: &[Candidate],
    assign: &[(usize, usize)],
    h: Homography,
    hidden: Option<usize>,
    min_score: f64,
) -> Option<Pick> {
    // The frame must stay in front of the camera (w of one sign at every corner).
    let corners = crate::geometry::rect_corners(0.0, 0.0, target.width_mm, target.height_mm);
    let ws: Vec<f64> = corners
        .iter()
        .map(|c| h.m[6] * c[0] + h.m[7] * c[1] + h.m[8])
        .collect();
    if ws.iter().any(|&w| w * ws[0] <= 0.0) {
        return None;
    }
    for &(ci, fi) in assign {
        let f = &target.fiducials[fi];
        let j = h.jacobian([f.x_mm, f.y_mm]);
        let r2 = (f.diameter_mm / 2.0).powi(2) / 4.0;
        // predicted covariance = r²/4 · J Jᵀ
        let pxx = r2 * (j[0][0] * j[0][0] + j[0][1] * j[0][1]);
        let pxy = r2 * (j[0][0] * j[1][0] + j[0][1] * j[1][1]);
        let pyy = r2 * (j[1][0] * j[1][0] + j[1][1] * j[1][1]);
        // An affine guess (one mark hidden) cannot follow the perspective change of size.
        let (lo, hi) = if hidden.is_some() {
            (0.2, 5.0)
        } else {
            (0.4, 2.5)
        };
        if !shape_matches([pxx, pxy, pyy], cands[ci].cov_px2, lo, hi) {
            return None;
        }
    }
    let score = pat.verify(g, &h, min_score - 0.2)?;
    if score < min_score {
        return None;
    }
    Some(Pick {
        cand_idx: assign.iter().map(|x| x.0).collect(),
        fid_idx: assign.iter().map(|x| x.1).collect(),
        hidden,
        homography: h,
        score,
    })
}

/// Whether a measured covariance matches a predicted one: eigenvalues of P⁻¹M in [lo, hi].
pub(super) fn shape_matches(p: [f64; 3], m: [f64; 3], lo: f64, hi: f64) -> bool {
    let det = p[0] * p[2] - p[1] * p[1];
    if det <= 0.0 || !det.is_finite() {
        return false;
    }
    let (ixx, ixy, iyy) = (p[2] / det, -p[1] / det, p[0] / det);
    // A = P⁻¹ M
    let a00 = ixx * m[0] + ixy * m[1];
    let a01 = ixx * m[1] + ixy * m[2];
    let a10 = ixy * m[0] + iyy * m[1];
    let a11 = ixy * m[1] + iyy * m[2];
    let tr = a00 + a11;
    let dt = a00 * a11 - a01 * a10;
    let disc = (tr * tr / 4.0 - dt).max(0.0).sqrt();
    let (l1, l2) = (tr / 2.0 + disc, tr / 2.0 - disc);
    l2 >= lo && l1 <= hi
}
