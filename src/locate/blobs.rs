//! Dark-blob detection on the search image: pixels darker than 60 % of their
//! neighbourhood's mean (a box window about the size of the largest expected
//! fiducial, so vignetting and gradients cancel) are grouped into connected
//! components; those of plausible size and aspect are tested along 32 rays:
//! the dark→white edge must lie on one ellipse (the image of a disk) and the
//! surround must be uniformly white (the fiducial's white square). Each test
//! result is kept as a [`Candidate`] for the debug picture.

use super::Candidate;
use super::masks;
use super::sample::Gray;
use crate::geometry::Point;
use rayon::prelude::*;

/// Number of rays used to test a blob's outline.
pub const RAYS: usize = 32;
/// A pixel is dark when below this fraction of its neighbourhood's mean.
pub const DARK_FRACTION: f32 = 0.6;
/// Smallest blob considered (search-image samples).
pub const MIN_AREA: usize = 7;

/// A component's raw statistics (grid coordinates of the search image).
#[derive(Debug, Clone, Copy, PartialEq, Default)]
struct Comp {
    n: usize,
    sx: f64,
    sy: f64,
    sxx: f64,
    syy: f64,
    sxy: f64,
    touches_border: bool,
}

/// The blobs of the search image (under two dark masks: relative to the local mean
/// and to the local white level) and of a 2× coarser copy (where small rings fill in
/// to solid blobs), each tested for being a fiducial (image px), without duplicates.
pub fn find_candidates(g: &Gray<'_>) -> Vec<Candidate> {
    // The three searches are independent (run in parallel); merged in a fixed order.
    let ((mut out, white), coarse) = rayon::join(
        || {
            rayon::join(
                || find_candidates_one(g, &masks::dark_mask(g)),
                || find_candidates_one(g, &masks::dark_mask_white(g)),
            )
        },
        || {
            (g.w.min(g.h) >= 200).then(|| {
                let coarse = super::downscale::box_reduce(g, 2);
                find_candidates_one(&coarse, &masks::dark_mask(&coarse))
            })
        },
    );
    merge(&mut out, white);
    if let Some(coarse) = coarse {
        merge(&mut out, coarse);
    }
    mark_crowded(&mut out);
    out
}

/// Adds new candidates unless one is already there (a disk-like one is preferred).
fn merge(out: &mut Vec<Candidate>, more: Vec<Candidate>) {
    for c in more {
        let r = 2.0 * (c.cov_px2[0] + c.cov_px2[2]).sqrt();
        let near = |f: &Candidate| {
            (f.centre_px[0] - c.centre_px[0]).hypot(f.centre_px[1] - c.centre_px[1]) < r
        };
        let dup = out.iter().any(|f| near(f) && (f.disk_like || !c.disk_like));
        if !dup {
            out.retain(|f| !near(f));
            out.push(c);
        }
    }
}

/// A fiducial sits alone on its white square (side two diameters): a disk-like blob with
/// another disk-like blob of similar size reaching into that square is rejected (dense
/// dot grids).
fn mark_crowded(cands: &mut [Candidate]) {
    let radius_towards = |c: &Candidate, u: Point| {
        let [cxx, cxy, cyy] = c.cov_px2;
        let det = cxx * cyy - cxy * cxy;
        let q = (u[0] * u[0] * cyy - 2.0 * u[0] * u[1] * cxy + u[1] * u[1] * cxx) / det;
        2.0 / q.sqrt()
    };
    let mean_radius = |c: &Candidate| {
        let [cxx, cxy, cyy] = c.cov_px2;
        2.0 * (cxx * cyy - cxy * cxy).max(0.0).sqrt().sqrt()
    };
    let crowded: Vec<bool> = cands
        .iter()
        .enumerate()
        .map(|(i, a)| {
            a.disk_like
                && cands.iter().enumerate().any(|(j, b)| {
                    // Only another disk-like blob of comparable size counts (a dot grid);
                    // fragments of a dark surround next to the chart do not.
                    let ratio = mean_radius(b) / mean_radius(a);
                    if i == j || !b.disk_like || !(0.5..=2.0).contains(&ratio) {
                        return false;
                    }
                    let d = [
                        b.centre_px[0] - a.centre_px[0],
                        b.centre_px[1] - a.centre_px[1],
                    ];
                    let dist = d[0].hypot(d[1]);
                    if dist <= 0.0 {
                        return false;
                    }
                    let u = [d[0] / dist, d[1] / dist];
                    dist - mean_radius(b) < 1.9 * radius_towards(a, u)
                })
        })
        .collect();
    for (c, crowd) in cands.iter_mut().zip(crowded) {
        if crowd {
            c.disk_like = false;
            c.why = "another blob inside its white square";
        }
    }
}

fn find_candidates_one(g: &Gray<'_>, dark: &[bool]) -> Vec<Candidate> {
    let comps = components(dark, g.w, g.h);
    let short = g.w.min(g.h) as f64;
    let max_area = (0.25 * short).powi(2);
    comps
        .par_iter()
        .filter(|c| c.n >= MIN_AREA && (c.n as f64) <= max_area && !c.touches_border)
        .filter_map(|c| test_blob(g, c))
        .collect()
}

/// 8-connected components of the mask, in the order of their first pixel
/// (row-major). Run-based: each row's runs of set pixels are joined to the
/// runs of the row above that touch them (union-find), and a component's
/// moments are summed a run at a time in closed form. Every moment is a sum of
/// multiples of ¼, so the sums are exact and equal to a pixel-by-pixel fill's.
fn components(mask: &[bool], w: usize, h: usize) -> Vec<Comp> {
    // Runs (row, first column, end column), row-major; `row_start[j]` = first run of row j.
    let mut runs: Vec<(usize, usize, usize)> = Vec::new();
    let mut row_start = Vec::with_capacity(h + 1);
    for j in 0..h {
        row_start.push(runs.len());
        let row = &mask[j * w..(j + 1) * w];
        let mut i = 0;
        while i < w {
            if !row[i] {
                i += 1;
                continue;
            }
            let a = i;
            while i < w && row[i] {
                i += 1;
            }
            runs.push((j, a, i));
        }
    }
    row_start.push(runs.len());
    // Union-find over runs; the root is always the component's first run.
    let mut parent: Vec<usize> = (0..runs.len()).collect();
    fn find(parent: &mut [usize], mut r: usize) -> usize {
        while parent[r] != r {
            parent[r] = parent[parent[r]];
            r = parent[r];
        }
        r
    }
    for j in 1..h {
        let (above, here) = (
            row_start[j - 1]..row_start[j],
            row_start[j]..row_start[j + 1],
        );
        let mut k = above.start;
        for r in here {
            let (_, a, b) = runs[r];
            // Runs above ending before column a − 1 touch neither this run nor later ones.
            while k < above.end && runs[k].2 < a {
                k += 1;
            }
            // 8-connected: a run above touches [a − 1, b] (end exclusive b + 1).
            let mut q = k;
            while q < above.end && runs[q].1 <= b {
                let (x, y) = (find(&mut parent, q), find(&mut parent, r));
                if x != y {
                    let (lo, hi) = (x.min(y), x.max(y));
                    parent[hi] = lo;
                }
                q += 1;
            }
        }
    }
    let mut index = vec![usize::MAX; runs.len()];
    let mut out: Vec<Comp> = Vec::new();
    for (r, &(j, a, b)) in runs.iter().enumerate() {
        let root = find(&mut parent, r);
        if index[root] == usize::MAX {
            index[root] = out.len();
            out.push(Comp::default());
        }
        let c = &mut out[index[root]];
        let len = (b - a) as f64;
        let y = j as f64 + 0.5;
        // Σ (i + ½) and Σ (i + ½)² over i in [a, b).
        let (af, bf) = (a as f64, b as f64);
        let sx = 0.5 * len * (af + bf);
        let sum_sq = |m: f64| (m - 1.0) * m * (2.0 * m - 1.0) / 6.0;
        let sum_i = |m: f64| m * (m - 1.0) / 2.0;
        let sxx = (sum_sq(bf) - sum_sq(af)) + (sum_i(bf) - sum_i(af)) + 0.25 * len;
        c.n += b - a;
        c.sx += sx;
        c.sy += len * y;
        c.sxx += sxx;
        c.syy += len * y * y;
        c.sxy += y * sx;
        c.touches_border |= j == 0 || j + 1 == h || a == 0 || b == w;
    }
    out
}

/// The ray test of one blob; `None` when its statistics already rule it out.
fn test_blob(g: &Gray<'_>, c: &Comp) -> Option<Candidate> {
    let n = c.n as f64;
    let (mx, my) = (c.sx / n, c.sy / n);
    // Pixel-area moments (+1/12 for the extent of each square sample).
    let cxx = c.sxx / n - mx * mx + 1.0 / 12.0;
    let cyy = c.syy / n - my * my + 1.0 / 12.0;
    let cxy = c.sxy / n - mx * my;
    let det = cxx * cyy - cxy * cxy;
    if det <= 0.0 {
        return None;
    }
    let tr = cxx + cyy;
    let disc = ((cxx - cyy).powi(2) / 4.0 + cxy * cxy).sqrt();
    let (l1, l2) = (tr / 2.0 + disc, tr / 2.0 - disc);
    if l2 <= 0.0 || (l2 / l1).sqrt() < 0.3 {
        return None;
    }
    let fill = n / (4.0 * std::f64::consts::PI * det.sqrt());
    if !(0.45..=1.3).contains(&fill) {
        return None;
    }
    let t = ray_test(g, [mx, my], [cxx, cxy, cyy])?;
    let s = g.scale;
    let cov_img = [
        t.cov[0] * s[0] * s[0],
        t.cov[1] * s[0] * s[1],
        t.cov[2] * s[1] * s[1],
    ];
    Some(Candidate {
        centre_px: g.to_img([mx, my]),
        cov_px2: cov_img,
        ring_score: t.ring_score,
        contrast: t.contrast,
        disk_like: t.disk_like,
        why: t.why,
        used: false,
    })
}

/// What the rays saw around a blob.
#[derive(Debug, Clone, Copy)]
pub struct RayTest {
    /// Covariance of the equivalent solid ellipse whose edge is at the measured edge (grid units²).
    pub cov: [f64; 3],
    /// Centre brightness between dark (0) and white (1).
    pub ring_score: f64,
    /// (white − dark)/white.
    pub contrast: f64,
    /// Median dark and white levels.
    pub dark: f64,
    /// Median white level of the surround.
    pub white: f64,
    /// Passed: round outline and uniform white surround.
    pub disk_like: bool,
    /// Why it failed ("" when it passed).
    pub why: &'static str,
}

/// Casts [`RAYS`] rays from `centre` (grid units) across an ellipse of covariance `cov`
/// (edge at 2σ) and tests whether the dark→white edge is elliptical with a white surround.
pub fn ray_test(g: &Gray<'_>, centre: Point, cov: [f64; 3]) -> Option<RayTest> {
    let [cxx, cxy, cyy] = cov;
    let det = cxx * cyy - cxy * cxy;
    let (ixx, ixy, iyy) = (cyy / det, -cxy / det, cxx / det);
    // Pass 1: profiles, and the edge on each ray (white level just outside the blob).
    struct Ray {
        rho: f64,
        step: f64,
        prof: Vec<f64>,
        dark: f64,
        q: f64,
    }
    let mut rays: Vec<Ray> = Vec::with_capacity(RAYS);
    let mut rho_sum = 0.0;
    for k in 0..RAYS {
        let a = 2.0 * std::f64::consts::PI * k as f64 / RAYS as f64;
        let (ux, uy) = (a.cos(), a.sin());
        let rho = 2.0 / (ux * ux * ixx + 2.0 * ux * uy * ixy + uy * uy * iyy).sqrt();
        rho_sum += rho;
        let step = (rho / 24.0).min(0.25);
        let m = (1.95 * rho / step).ceil() as usize + 1;
        let mut prof = Vec::with_capacity(m);
        for i in 0..m {
            let t = i as f64 * step;
            match g.bilinear([centre[0] + t * ux, centre[1] + t * uy]) {
                Some(v) => prof.push(v),
                None => break,
            }
        }
        if prof.len() < m {
            continue; // leaves the image (a mark near the border): judge on the other rays
        }
        let idx = |t: f64| ((t / step).round() as usize).min(m - 1);
        let (w0, w1) = (idx(1.3 * rho), idx(1.6 * rho));
        let white = prof[w0..=w1].iter().sum::<f64>() / (w1 - w0 + 1) as f64;
        let dark = prof[..=idx(rho)]
            .iter()
            .cloned()
            .fold(f64::INFINITY, f64::min);
        let thr = 0.5 * (dark + white);
        let mut e = None;
        for i in (0..idx(1.3 * rho)).rev() {
            if prof[i] < thr {
                let (p0, p1) = (prof[i], prof[i + 1]);
                let f = if p1 > p0 { (thr - p0) / (p1 - p0) } else { 0.5 };
                e = Some((i as f64 + f.clamp(0.0, 1.0)) * step);
                break;
            }
        }
        if let Some(e) = e {
            rays.push(Ray {
                rho,
                step,
                prof,
                dark,
                q: e / rho,
            });
        }
    }
    if rays.len() < RAYS * 2 / 3 {
        return None;
    }
    let med = |mut v: Vec<f64>| {
        v.sort_by(f64::total_cmp);
        v[v.len() / 2]
    };
    let nq = rays.len() as f64;
    let qm = rays.iter().map(|r| r.q).sum::<f64>() / nq;
    let qsd = (rays.iter().map(|r| (r.q - qm).powi(2)).sum::<f64>() / nq).sqrt();
    let qmed = med(rays.iter().map(|r| r.q).collect());
    // Pass 2: the surround, 1.3–1.7 edge radii out (inside a fiducial's white square).
    let whites: Vec<f64> = rays
        .iter()
        .map(|r| {
            let m = r.prof.len();
            let idx = |t: f64| ((t / r.step).round() as usize).min(m - 1);
            let (w0, w1) = (idx(1.3 * qmed * r.rho), idx(1.7 * qmed * r.rho));
            r.prof[w0..=w1].iter().sum::<f64>() / (w1 - w0 + 1) as f64
        })
        .collect();
    let white = med(whites.clone());
    let dark = med(rays.iter().map(|r| r.dark).collect());
    let span = white - dark;
    if span <= 0.0 || white <= 0.0 {
        return None;
    }
    let (mut cv, mut cn) = (0.0, 0.0);
    for r in &rays {
        for (i, &v) in r.prof.iter().enumerate() {
            if i as f64 * r.step <= 0.15 * qmed * r.rho {
                cv += v;
                cn += 1.0;
            }
        }
    }
    let contrast = span / white;
    let rho_mean = rho_sum / RAYS as f64 * qm;
    let round = qsd / qm <= 0.05 + 0.35 / rho_mean.max(1.0);
    // At least 3/4 of the rays see white: the white square is only one mark diameter
    // from the centre at the frame's edges, so a few rays may reach the surroundings.
    let white_rays = whites.iter().filter(|&&w| w >= dark + 0.6 * span).count();
    let uniform = 4 * white_rays >= 3 * whites.len();
    let ring_score = (cv / f64::max(cn, 1.0) - dark) / span;
    Some(RayTest {
        cov: [cxx * qm * qm, cxy * qm * qm, cyy * qm * qm],
        ring_score,
        contrast,
        dark,
        white,
        disk_like: round && uniform && contrast >= 0.35,
        why: if !round {
            "outline not elliptical"
        } else if !uniform {
            "surround not uniformly white"
        } else if contrast < 0.35 {
            "low contrast"
        } else {
            ""
        },
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The pixel-by-pixel flood fill the run-based labelling replaced (the oracle).
    fn components_flood(mask: &[bool], w: usize, h: usize) -> Vec<Comp> {
        let mut seen = vec![false; w * h];
        let mut out = Vec::new();
        let mut stack = Vec::new();
        for start in 0..w * h {
            if !mask[start] || seen[start] {
                continue;
            }
            seen[start] = true;
            stack.push(start);
            let mut c = Comp::default();
            while let Some(p) = stack.pop() {
                let (i, j) = (p % w, p / w);
                let (x, y) = (i as f64 + 0.5, j as f64 + 0.5);
                c.n += 1;
                c.sx += x;
                c.sy += y;
                c.sxx += x * x;
                c.syy += y * y;
                c.sxy += x * y;
                if i == 0 || j == 0 || i + 1 == w || j + 1 == h {
                    c.touches_border = true;
                }
                for dj in -1i64..=1 {
                    for di in -1i64..=1 {
                        let (ni, nj) = (i as i64 + di, j as i64 + dj);
                        if ni < 0 || nj < 0 || ni >= w as i64 || nj >= h as i64 {
                            continue;
                        }
                        let q = nj as usize * w + ni as usize;
                        if mask[q] && !seen[q] {
                            seen[q] = true;
                            stack.push(q);
                        }
                    }
                }
            }
            out.push(c);
        }
        out
    }

    #[test]
    fn run_labelling_equals_a_flood_fill() {
        // Random masks of several densities (8-connected diagonals, rings,
        // U shapes joined late), plus empty and full ones.
        let mut state = 0x2545_f491_4f6c_dd1du64;
        let mut next = || {
            state ^= state << 13;
            state ^= state >> 7;
            state ^= state << 17;
            state
        };
        for (w, h, p) in [
            (1, 1, 50),
            (7, 5, 0),
            (7, 5, 100),
            (40, 30, 20),
            (40, 30, 45),
            (64, 48, 60),
            (33, 1, 50),
            (1, 33, 50),
        ] {
            for _ in 0..8 {
                let mask: Vec<bool> = (0..w * h).map(|_| next() % 100 < p).collect();
                let got = components(&mask, w, h);
                let want = components_flood(&mask, w, h);
                assert_eq!(got, want, "{w}×{h} at {p} %");
            }
        }
    }
}
