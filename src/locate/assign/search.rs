//! The search over candidate sets: every convex quad of candidates in each
//! turn, and every triple (one mark hidden) in each order, with the ring
//! checks that prune them; each surviving assignment is judged.

use super::judge::judge;
use super::{MIN_SCORE_QUAD, MIN_SCORE_TRIPLE_AFFINE, Pattern, Pick, RING_RESOLVED_RADIUS};
use crate::geometry::{Homography, Point};
use crate::locate::Candidate;
use crate::locate::sample::Gray;
use crate::target::{FiducialKind, Target};

/// Target fiducial indices 0..4 in turning order around their centroid.
fn turning_order(pts: &[Point]) -> Vec<usize> {
    let n = pts.len() as f64;
    let cx = pts.iter().map(|p| p[0]).sum::<f64>() / n;
    let cy = pts.iter().map(|p| p[1]).sum::<f64>() / n;
    let mut o: Vec<usize> = (0..pts.len()).collect();
    o.sort_by(|&a, &b| {
        let aa = (pts[a][1] - cy).atan2(pts[a][0] - cx);
        let ab = (pts[b][1] - cy).atan2(pts[b][0] - cx);
        aa.total_cmp(&ab)
    });
    o
}

fn convex(p: &[Point; 4]) -> bool {
    let mut sign = 0.0;
    for i in 0..4 {
        let (a, b, c) = (p[i], p[(i + 1) % 4], p[(i + 2) % 4]);
        let cr = (b[0] - a[0]) * (c[1] - b[1]) - (b[1] - a[1]) * (c[0] - b[0]);
        if cr == 0.0 || (sign != 0.0 && cr * sign < 0.0) {
            return false;
        }
        sign = cr;
    }
    true
}

pub(super) fn quads(
    g: &Gray<'_>,
    target: &Target,
    pat: &Pattern,
    cands: &[Candidate],
    idx: &[usize],
) -> Vec<Pick> {
    let fpos: Vec<Point> = target.fiducials[..4]
        .iter()
        .map(|f| [f.x_mm, f.y_mm])
        .collect();
    let t_order = turning_order(&fpos);
    let ring: Option<usize> = (0..4).find(|&i| target.fiducials[i].kind == FiducialKind::Ring);
    let n = idx.len();
    let mut out = Vec::new();
    for a in 0..n {
        for b in a + 1..n {
            for c in b + 1..n {
                for d in c + 1..n {
                    let set = [idx[a], idx[b], idx[c], idx[d]];
                    let pts: Vec<Point> = set.iter().map(|&i| cands[i].centre_px).collect();
                    let p_order = turning_order(&pts);
                    let quad = [0, 1, 2, 3].map(|m| pts[p_order[m]]);
                    if !convex(&quad) {
                        continue;
                    }
                    let big = set.iter().all(|&c| {
                        let v = cands[c].cov_px2;
                        let r = 2.0 * (v[0] * v[2] - v[1] * v[1]).max(0.0).sqrt().sqrt();
                        r / g.scale[0].max(g.scale[1]) >= RING_RESOLVED_RADIUS
                    });
                    for shift in 0..4 {
                        // candidate set[p_order[(m+shift)%4]] ↔ fiducial t_order[m]
                        let assign: Vec<(usize, usize)> = (0..4)
                            .map(|m| (set[p_order[(m + shift) % 4]], t_order[m]))
                            .collect();
                        if let Some(r) = ring {
                            if ring_resolved(cands, &set) {
                                if !ring_ok(cands, &assign, Some(r)) {
                                    continue;
                                }
                            } else if big {
                                break; // large marks, none with a white centre: not our quad
                            }
                        }
                        let src = [0, 1, 2, 3].map(|m| fpos[assign[m].1]);
                        let dst = [0, 1, 2, 3].map(|m| cands[assign[m].0].centre_px);
                        let Ok(h) = Homography::from_quads(&src, &dst) else {
                            continue;
                        };
                        if let Some(p) =
                            judge(g, pat, target, cands, &assign, h, None, MIN_SCORE_QUAD)
                        {
                            out.push(p);
                        }
                    }
                }
            }
        }
    }
    out
}

/// Whether one of four candidates clearly has a bright centre (the ring is resolved);
/// when none has (tiny or blurred marks), every turn is tried and the pattern decides.
fn ring_resolved(cands: &[Candidate], set: &[usize]) -> bool {
    let mut rs: Vec<f64> = set.iter().map(|&c| cands[c].ring_score).collect();
    rs.sort_by(|a, b| b.total_cmp(a));
    rs[0] >= 0.2 && rs[0] >= rs[1] + 0.1
}

/// The ring mark (if any, and if assigned) must be the brightest-centred candidate, clearly.
fn ring_ok(cands: &[Candidate], assign: &[(usize, usize)], ring: Option<usize>) -> bool {
    let Some(r) = ring else { return true };
    let rs: Vec<(f64, bool)> = assign
        .iter()
        .map(|&(c, f)| (cands[c].ring_score, f == r))
        .collect();
    match rs.iter().find(|x| x.1) {
        Some(&(score, _)) => {
            let other = rs
                .iter()
                .filter(|x| !x.1)
                .map(|x| x.0)
                .fold(f64::NEG_INFINITY, f64::max);
            score >= 0.2 && score >= other + 0.1
        }
        // Ring hidden: every seen mark must look solid.
        None => rs.iter().all(|x| x.0 < 0.35),
    }
}

pub(super) fn triples(
    g: &Gray<'_>,
    target: &Target,
    pat: &Pattern,
    cands: &[Candidate],
    idx: &[usize],
    fids: &[usize],
) -> Vec<Pick> {
    let ring: Option<usize> = fids
        .iter()
        .copied()
        .find(|&i| target.fiducials[i].kind == FiducialKind::Ring);
    let fpos: Vec<Point> = target.fiducials.iter().map(|f| [f.x_mm, f.y_mm]).collect();
    let n = idx.len();
    let mut out = Vec::new();
    const PERMS: [[usize; 3]; 6] = [
        [0, 1, 2],
        [0, 2, 1],
        [1, 0, 2],
        [1, 2, 0],
        [2, 0, 1],
        [2, 1, 0],
    ];
    for a in 0..n {
        for b in a + 1..n {
            for c in b + 1..n {
                let set = [idx[a], idx[b], idx[c]];
                for &missing in fids {
                    let seen: Vec<usize> = fids.iter().copied().filter(|&f| f != missing).collect();
                    if seen.len() != 3 {
                        continue;
                    }
                    for perm in PERMS {
                        let assign: Vec<(usize, usize)> =
                            (0..3).map(|m| (set[perm[m]], seen[m])).collect();
                        if !ring_ok(cands, &assign, ring) {
                            continue;
                        }
                        let src: Vec<Point> = assign.iter().map(|x| fpos[x.1]).collect();
                        let dst: Vec<Point> = assign.iter().map(|x| cands[x.0].centre_px).collect();
                        let Some(h) = affine3(&src, &dst) else {
                            continue;
                        };
                        let m = &h.m;
                        if m[0] * m[4] - m[1] * m[3] <= 0.0 {
                            continue; // mirrored
                        }
                        if let Some(p) = judge(
                            g,
                            pat,
                            target,
                            cands,
                            &assign,
                            h,
                            Some(missing),
                            MIN_SCORE_TRIPLE_AFFINE,
                        ) {
                            out.push(p);
                        }
                    }
                }
            }
        }
    }
    out
}

/// The affine homography through three correspondences.
pub fn affine3(src: &[Point], dst: &[Point]) -> Option<Homography> {
    let s4 = [
        src[0],
        src[1],
        src[2],
        [
            src[0][0] + src[2][0] - src[1][0],
            src[0][1] + src[2][1] - src[1][1],
        ],
    ];
    let d4 = [
        dst[0],
        dst[1],
        dst[2],
        [
            dst[0][0] + dst[2][0] - dst[1][0],
            dst[0][1] + dst[2][1] - dst[1][1],
        ],
    ];
    // 0, 1, 2 and the parallelogram's fourth vertex (opposite 1) go round in order.
    Homography::from_quads(&s4, &d4).ok()
}
