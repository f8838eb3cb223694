//! Choosing which blobs are the target's fiducials. Every four disk-like
//! candidates that form a convex quad are matched to the target's four marks
//! in the same turning order (a photo is not mirrored), the `Ring` mark going
//! to the candidate with the brightest centre; the homography they give must
//! predict each mark's imaged size and shape, and the image must correlate
//! with the target's own pattern (fiducials, patches, sweeps) sampled through
//! it. Without a full quad, triples are tried with an affine map (one mark
//! hidden). Several charts in one frame give several non-overlapping picks.

use super::Candidate;
use super::sample::Gray;
use crate::geometry::{Homography, Point};
use crate::target::{FiducialKind, Target};
use rayon::prelude::*;

/// Most disk-like candidates considered (by contrast).
pub const MAX_CANDIDATES: usize = 30;
/// Most candidates tried in threes (one mark hidden).
pub const MAX_CANDIDATES_TRIPLES: usize = 16;
/// Marks at least this large (radius, search-image samples) must show the ring's white centre.
pub const RING_RESOLVED_RADIUS: f64 = 3.0;
/// Least correlation between image and target pattern for a quad of four marks.
pub const MIN_SCORE_QUAD: f64 = 0.6;
/// Least correlation for a solution from three marks (one hidden), after edge refinement.
pub const MIN_SCORE_TRIPLE: f64 = 0.7;
/// Least correlation for three marks under the first, affine guess.
pub const MIN_SCORE_TRIPLE_AFFINE: f64 = 0.5;

/// A choice of candidates for one chart.
#[derive(Debug, Clone)]
pub struct Pick {
    /// Candidate indices (into the candidate list), one per used fiducial.
    pub cand_idx: Vec<usize>,
    /// Target fiducial index matched to each candidate.
    pub fid_idx: Vec<usize>,
    /// Target fiducial index not seen, if any.
    pub hidden: Option<usize>,
    /// The approximate homography target mm → image px.
    pub homography: Homography,
    /// Image/target pattern correlation.
    pub score: f64,
}

/// All accepted picks, best first, non-overlapping.
pub fn choose(g: &Gray<'_>, target: &Target, pat: &Pattern, cands: &[Candidate]) -> Vec<Pick> {
    let mut idx: Vec<usize> = (0..cands.len()).filter(|&i| cands[i].disk_like).collect();
    idx.sort_by(|&a, &b| cands[b].contrast.total_cmp(&cands[a].contrast));
    idx.truncate(MAX_CANDIDATES);
    let fids: Vec<usize> = (0..target.fiducials.len().min(4)).collect();
    let mut picks = Vec::new();
    if fids.len() == 4 {
        picks = quads(g, target, pat, cands, &idx);
    }
    let mut chosen = select(picks);
    // Triples among candidates not used by a chart (one mark hidden).
    let used: Vec<usize> = chosen.iter().flat_map(|p| p.cand_idx.clone()).collect();
    let rest: Vec<usize> = idx
        .iter()
        .copied()
        .filter(|i| !used.contains(i))
        .take(MAX_CANDIDATES_TRIPLES)
        .collect();
    if rest.len() >= 3 {
        let triples = triples(g, target, pat, cands, &rest, &fids);
        let mut all = chosen.clone();
        for t in select(triples) {
            if !all.iter().any(|p| overlaps(p, &t, target)) {
                all.push(t);
            }
        }
        chosen = all;
    }
    chosen
}

/// Greedy: best score first, dropping picks that share a candidate with a better one.
fn select(mut picks: Vec<Pick>) -> Vec<Pick> {
    picks.sort_by(|a, b| b.score.total_cmp(&a.score));
    let mut out: Vec<Pick> = Vec::new();
    for p in picks {
        if out
            .iter()
            .any(|q| q.cand_idx.iter().any(|c| p.cand_idx.contains(c)))
        {
            continue;
        }
        out.push(p);
    }
    out
}

/// Whether two picks' target frames overlap in the image (centre of one inside the other).
fn overlaps(a: &Pick, b: &Pick, t: &Target) -> bool {
    let centre = [t.width_mm / 2.0, t.height_mm / 2.0];
    let inside = |p: &Pick, q: &Pick| {
        let c = q.homography.apply(centre);
        match p.homography.inverse() {
            Some(inv) => {
                let x = inv.apply(c);
                x[0] >= 0.0 && x[1] >= 0.0 && x[0] <= t.width_mm && x[1] <= t.height_mm
            }
            None => false,
        }
    };
    inside(a, b) || inside(b, a)
}

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

fn quads(
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

fn triples(
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

/// Size/shape prediction check, then pattern verification.
#[allow(clippy::too_many_arguments)]
fn judge(
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
fn shape_matches(p: [f64; 3], m: [f64; 3], lo: f64, hi: f64) -> bool {
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

/// The target's pattern sampled once for verification: points around the fiducials
/// first, then a 40×30 grid, each with its reflectance and how far (mm) the pattern
/// stays flat around it (within 0.08).
#[derive(Debug, Clone)]
pub struct Pattern {
    pts: Vec<(Point, f64, f64)>,
    n_fid: usize,
}

impl Pattern {
    /// Samples the target's pattern.
    pub fn new(target: &Target) -> Pattern {
        let mut pts: Vec<Point> = Vec::new();
        for f in &target.fiducials {
            let d = f.diameter_mm;
            pts.push([f.x_mm, f.y_mm]);
            for k in 0..8 {
                let a = k as f64 * std::f64::consts::FRAC_PI_4;
                for r in [0.375 * d, 0.8 * d] {
                    pts.push([f.x_mm + r * a.cos(), f.y_mm + r * a.sin()]);
                }
            }
        }
        let n_fid = pts.len();
        const NX: usize = 40;
        const NY: usize = 30;
        for j in 0..NY {
            for i in 0..NX {
                pts.push([
                    (i as f64 + 0.5) / NX as f64 * target.width_mm,
                    (j as f64 + 0.5) / NY as f64 * target.height_mm,
                ]);
            }
        }
        let max_eps = 0.25 * target.width_mm.min(target.height_mm);
        // Each point's flat radius on its own (in parallel, kept in order).
        let pts = pts
            .into_par_iter()
            .map(|p| {
                let e = target.reflectance(p[0], p[1]);
                // Offsets within this of a background point are background
                // too (a hair less, for rounding): no need to look.
                let clear = if e == target.background {
                    target.background_clearance(p[0], p[1]) * (1.0 - 1e-9) - 1e-9
                } else {
                    0.0
                };
                let mut flat = 0.0;
                let mut eps = 0.01;
                while eps <= max_eps {
                    let ok = eps < clear
                        || [
                            [eps, 0.0],
                            [-eps, 0.0],
                            [0.0, eps],
                            [0.0, -eps],
                            [eps, eps],
                            [-eps, -eps],
                            [eps, -eps],
                            [-eps, eps],
                        ]
                        .iter()
                        .all(|o| (target.reflectance(p[0] + o[0], p[1] + o[1]) - e).abs() < 0.08);
                    if !ok {
                        break;
                    }
                    flat = eps;
                    eps *= std::f64::consts::SQRT_2;
                }
                (p, e, flat)
            })
            .collect();
        Pattern { pts, n_fid }
    }

    /// Correlation between the pattern and the image (search image `g`) under `h`, over
    /// points whose neighbourhood of 1.5 search-image samples is flat; `None` when too
    /// little of the target is in the image. Gives up early (returning the low value)
    /// when the points around the fiducials alone correlate below `early_min`.
    pub fn verify(&self, g: &Gray<'_>, h: &Homography, early_min: f64) -> Option<f64> {
        let mut acc = Corr::default();
        let px = 1.5 * g.scale[0].max(g.scale[1]);
        for (k, &(p, e, flat)) in self.pts.iter().enumerate() {
            if k == self.n_fid
                && acc.n >= 0.5 * self.n_fid as f64
                && let Some(r) = acc.value()
                && r < early_min
            {
                return Some(r);
            }
            let ip = h.apply(p);
            if !ip[0].is_finite() || !ip[1].is_finite() {
                continue;
            }
            let j = h.jacobian(p);
            let det = (j[0][0] * j[1][1] - j[0][1] * j[1][0]).abs();
            if det <= 0.0 || px / det.sqrt() > flat {
                continue;
            }
            if let Some(v) = g.at_img(ip) {
                acc.add(e, v);
            }
        }
        if acc.n < 0.3 * self.pts.len() as f64 || acc.n < 20.0 {
            return None;
        }
        Some(acc.value().unwrap_or(0.0))
    }
}

/// Correlation between the target's reflectance and the image (see [`Pattern::verify`]).
pub fn verify(g: &Gray<'_>, target: &Target, h: &Homography) -> Option<f64> {
    Pattern::new(target).verify(g, h, f64::NEG_INFINITY)
}

/// Running sums for a Pearson correlation of expected reflectance and image value.
#[derive(Default)]
struct Corr {
    n: f64,
    sx: f64,
    sy: f64,
    sxx: f64,
    syy: f64,
    sxy: f64,
}

impl Corr {
    fn add(&mut self, e: f64, v: f64) {
        self.n += 1.0;
        self.sx += e;
        self.sy += v;
        self.sxx += e * e;
        self.syy += v * v;
        self.sxy += e * v;
    }

    fn value(&self) -> Option<f64> {
        let n = self.n;
        if n < 2.0 {
            return None;
        }
        let cov = self.sxy / n - self.sx * self.sy / (n * n);
        let vx = self.sxx / n - (self.sx / n).powi(2);
        let vy = self.syy / n - (self.sy / n).powi(2);
        if vx <= 0.0 || vy <= 0.0 {
            return Some(0.0);
        }
        Some(cov / (vx * vy).sqrt())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn affine_from_three_points_is_exact() {
        let src = [[0.0, 0.0], [10.0, 0.0], [10.0, 5.0]];
        let f = |p: Point| [3.0 + 2.0 * p[0] - 0.5 * p[1], 7.0 + 0.3 * p[0] + 1.7 * p[1]];
        let dst: Vec<Point> = src.iter().map(|&p| f(p)).collect();
        let h = affine3(&src, &dst).unwrap();
        for p in [[0.0, 5.0], [4.0, 3.0], [-2.0, 8.0]] {
            let (a, b) = (h.apply(p), f(p));
            assert!((a[0] - b[0]).abs() < 1e-9 && (a[1] - b[1]).abs() < 1e-9);
        }
        assert!(h.m[6].abs() < 1e-12 && h.m[7].abs() < 1e-12);
    }

    /// The flat radius by its plain definition: the ladder of offsets, each
    /// of the 8 points evaluated, for every point.
    fn plain_flat(target: &Target, p: Point, e: f64) -> f64 {
        let max_eps = 0.25 * target.width_mm.min(target.height_mm);
        let (mut flat, mut eps) = (0.0, 0.01);
        while eps <= max_eps {
            let offsets = [-eps, 0.0, eps];
            let ok = offsets
                .iter()
                .flat_map(|&a| offsets.iter().map(move |&b| [a, b]))
                .filter(|o| {
                    *o != [0.0, 0.0]
                        && (o[0] == 0.0 || o[1] == 0.0 || o[0] == o[1] || o[0] == -o[1])
                })
                .all(|o| (target.reflectance(p[0] + o[0], p[1] + o[1]) - e).abs() < 0.08);
            if !ok {
                break;
            }
            flat = eps;
            eps *= std::f64::consts::SQRT_2;
        }
        flat
    }

    #[test]
    fn pattern_flat_radii_equal_the_plain_ladder() {
        // Every shipped target (fiducials, sweeps, sine and grey patches):
        // the background shortcut changes no radius, and points near the
        // regions' edges (where a rounding error would show) are included.
        for name in ["a4_log", "a4_linear", "a4_patches", "a3_log"] {
            let path = format!("{}/targets/{name}.toml", env!("CARGO_MANIFEST_DIR"));
            let target = Target::load(std::path::Path::new(&path)).unwrap();
            let pat = Pattern::new(&target);
            assert!(pat.pts.len() > 1200);
            for &(p, e, flat) in &pat.pts {
                assert_eq!(e, target.reflectance(p[0], p[1]));
                assert_eq!(flat, plain_flat(&target, p, e), "{name} at {p:?}");
            }
        }
    }

    #[test]
    fn background_clearance_leaves_every_region_out() {
        // Random points: every point within the clearance (Chebyshev) of a
        // background point reads the background.
        let path = format!("{}/targets/a4_patches.toml", env!("CARGO_MANIFEST_DIR"));
        let target = Target::load(std::path::Path::new(&path)).unwrap();
        let mut st = 7u64;
        let mut u = || {
            st = st
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            (st >> 11) as f64 / (1u64 << 53) as f64
        };
        let mut checked = 0;
        for _ in 0..20_000 {
            let (x, y) = (u() * 320.0 - 10.0, u() * 230.0 - 10.0);
            let c = target.background_clearance(x, y);
            if target.reflectance(x, y) != target.background || c == 0.0 {
                continue;
            }
            for _ in 0..8 {
                let (dx, dy) = ((2.0 * u() - 1.0) * c, (2.0 * u() - 1.0) * c);
                assert_eq!(
                    target.reflectance(x + dx * 0.999, y + dy * 0.999),
                    target.background
                );
            }
            // Just beyond it, some region begins (the clearance is tight).
            let hit = (0..64).any(|k| {
                let a = k as f64 / 64.0 * std::f64::consts::TAU;
                let r = 1.001 * c * 1.5;
                target.reflectance(x + r * a.cos(), y + r * a.sin()) != target.background
            });
            checked += hit as usize;
        }
        assert!(checked > 1000, "{checked}");
    }

    #[test]
    fn shape_check_accepts_rotated_equal_and_rejects_double_size() {
        assert!(shape_matches([4.0, 1.0, 2.0], [4.0, 1.0, 2.0], 0.4, 2.5));
        assert!(!shape_matches([4.0, 1.0, 2.0], [12.0, 3.0, 6.0], 0.4, 2.5));
    }
}
