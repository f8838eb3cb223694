//! Choosing which blobs are the target's fiducials. Every four disk-like
//! candidates that form a convex quad are matched to the target's four marks
//! in the same turning order (a photo is not mirrored), the `Ring` mark going
//! to the candidate with the brightest centre; the homography they give must
//! predict each mark's imaged size and shape, and the image must correlate
//! with the target's own pattern (fiducials, patches, sweeps) sampled through
//! it. Without a full quad, triples are tried with an affine map (one mark
//! hidden). Several charts in one frame give several non-overlapping picks.

mod judge;
mod pattern;
mod search;
#[cfg(test)]
mod tests;

use super::Candidate;
use super::sample::Gray;
use crate::geometry::Homography;
use crate::target::Target;
use search::{quads, triples};

pub use pattern::{Pattern, verify};
pub use search::affine3;

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
