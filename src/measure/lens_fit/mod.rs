//! Lens distortion of a shot: the one the user gave (`--distortion`), or one
//! estimated from the strip's two long printed edges, which are straight on
//! the chart and so straight again once the photo is undistorted.
//!
//! Estimate: along each long edge, at evenly spaced places (the ends left
//! out), the profile across the edge is read (bilinear, averaged over ±2 px
//! along the edge) and the edge put where it crosses the mean of the levels
//! inside and outside (exact for any symmetric blur: inside the strip the
//! pattern varies along the edge only). A radial model about the image centre
//! is fitted so that the undistorted points of each edge lie on a line (least
//! squares of the perpendicular residuals, two rounds with outliers beyond 4
//! robust σ dropped; `model_fit`): the classic cubic PTLens b (a = c = 0,
//! r_d = r_u·(1 − b + b·r_u²)), then a with it and c too where the edges
//! determine them ([`MIN_RICHER_GAIN`]). With a model used, `snap` puts the
//! user's corners on the long edges as seen through it. Only steps of the majority sign count (a
//! printed edge is darker or lighter than its surround all along; a pattern
//! without a printed edge flips sign with its phase). The model is used only
//! when the evidence is clear: the edges found at ≥ [`MIN_EDGE_COVERAGE`] of
//! the places searched on each edge, their points within [`MAX_EDGE_RMS_PX`]
//! RMS of the undistorted lines, b more than [`MIN_SIGNIFICANCE`] standard
//! errors from 0, a bow of at least [`MIN_BOW_PX`], and the edges' RMS about
//! straight lines lowered [`MIN_STRAIGHTENING`]× by the model; otherwise the
//! shot is measured as without distortion and the note says why.
//!
//! What the edges cannot see: a strip through the image centre has radial
//! edges, straight under any radial distortion; its local frequency still
//! follows the distortion (give the lens's model with `--distortion` then).

use crate::distortion::{Lens, MAX_CORNER_PERCENT, Ptlens};
use crate::geometry::Point;
use rayon::prelude::*;
use serde::Serialize;

mod edges;
mod model_fit;
mod snap;
use edges::edge_points;
pub use edges::{Converted, Sampler};
use model_fit::fit_edges;
pub use snap::snap_to_edges;

/// Smallest bow (px) of the strip's edges for which an estimated distortion is used.
pub const MIN_BOW_PX: f64 = 0.1;
/// Least fraction of the places searched along each long edge where the edge must be found.
pub const MIN_EDGE_COVERAGE: f64 = 0.6;
/// Largest RMS (px) of the edge points about their undistorted lines for the edges to count as printed edges.
pub const MAX_EDGE_RMS_PX: f64 = 0.5;
/// Least |b| in standard errors of the edge fit for an estimated distortion to be used.
pub const MIN_SIGNIFICANCE: f64 = 5.0;
/// Least factor by which the model must lower the edges' RMS about straight lines.
pub const MIN_STRAIGHTENING: f64 = 1.5;
/// Least factor by which a richer model (a with b; then c too) must lower the edges' RMS about their lines beyond the simpler one for it to be kept.
pub const MIN_RICHER_GAIN: f64 = 1.2;

/// Where the distortion used came from.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(rename_all = "lowercase")]
pub enum DistortionSource {
    /// Given by the user (`--distortion`).
    Given,
    /// Estimated from the strip's long edges and used.
    Estimated,
    /// Estimated, but too small or too uncertain to matter: not used.
    Negligible,
}

/// The lens distortion of a measurement, as reported in the summary.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct DistortionFound {
    /// The model (PTLens a, b, c; radius 1 = half the image's smaller side).
    pub model: Ptlens,
    /// Its distortion at the frame corner, percent (+ pincushion, − barrel).
    pub corner_percent: f64,
    /// Where it came from.
    pub source: DistortionSource,
    /// Standard uncertainty of the estimated b (None when given).
    pub b_sigma: Option<f64>,
    /// Standard uncertainty of the estimated a (None when given or not fitted).
    pub a_sigma: Option<f64>,
    /// Standard uncertainty of the estimated c (None when given or not fitted).
    pub c_sigma: Option<f64>,
    /// How far the estimated model is from none, in standard errors of the edge fit (None when given).
    pub significance: Option<f64>,
    /// RMS distance of the undistorted edge points from their lines, px (None when given).
    pub edge_rms_px: Option<f64>,
    /// RMS distance of the same edge points from straight lines without any model, px (None when given).
    pub straight_rms_px: Option<f64>,
    /// Smaller of the two long edges' fractions of places where the edge was found (None when given).
    pub edge_coverage: Option<f64>,
    /// Edge points the estimate used (0 when given).
    pub edge_points: usize,
    /// Largest bow of the strip's long edges in the photo under this model, px.
    pub bow_px: f64,
    /// Why an estimated model is not used (None when used or given).
    pub why_not: Option<&'static str>,
    /// The long edges seen, undistorted by the model: for corners 1→2 and
    /// 4→3, a point on the line and its unit direction (px; None when given).
    #[serde(skip)]
    pub edge_lines: Option<[[Point; 2]; 2]>,
    /// The strip corners with their long edges put on the edges seen through
    /// the model ([`snap_to_edges`]) and the largest move (px), when done.
    #[serde(skip)]
    pub snapped: Option<([Point; 4], f64)>,
}

impl DistortionFound {
    /// The model when it is used for the measurement.
    pub fn used(&self) -> Option<Ptlens> {
        (self.source != DistortionSource::Negligible).then_some(self.model)
    }

    /// The lens the measurement bins through in a `width`×`height` px image, when used.
    pub fn lens(&self, width: usize, height: usize) -> Option<crate::distortion::Lens> {
        self.used()
            .map(|m| crate::distortion::Lens::new(m, width, height))
    }

    /// One line for the notes.
    pub fn note(&self) -> String {
        let m = &self.model;
        match self.source {
            DistortionSource::Given => format!(
                "lens distortion as given: {m} ({:+.2} % at the frame corner)",
                self.corner_percent
            ),
            DistortionSource::Estimated => format!(
                "lens distortion estimated from the strip's edges: ptlens:{}b={:.5} ± {:.5} ({:+.2} % at the frame corner, edges bowed {:.2} px, {} edge points, RMS {:.3} px straight → {:.3} px with it); iso-phase lines and frequencies follow it (--no-estimate-distortion to measure without)",
                self.a_sigma
                    .map_or(String::new(), |s| format!("a={:.5} ± {s:.5},", m.a)),
                m.b,
                self.b_sigma.unwrap_or(0.0),
                self.corner_percent,
                self.bow_px,
                self.edge_points,
                self.straight_rms_px.unwrap_or(0.0),
                self.edge_rms_px.unwrap_or(0.0)
            ) + &self.snapped.map_or(String::new(), |(_, m)| format!(
                "; the region's corners as given put on the long edges seen through it instead (moved up to {m:.2} px)"
            )),
            DistortionSource::Negligible if self.edge_points == 0 => format!(
                "lens distortion: none applied ({})",
                self.why_not.unwrap_or("not found")
            ),
            DistortionSource::Negligible => format!(
                "lens distortion: none applied (from the strip's edges b = {:.5} ± {:.5}, edges bowed {:.2} px, RMS {:.3} px straight, {:.3} px with it, {:.0} % of the edges found: {})",
                m.b,
                self.b_sigma.unwrap_or(0.0),
                self.bow_px,
                self.straight_rms_px.unwrap_or(0.0),
                self.edge_rms_px.unwrap_or(0.0),
                100.0 * self.edge_coverage.unwrap_or(0.0),
                self.why_not.unwrap_or("negligible")
            ),
        }
    }
}

/// The report for a model the user gave, on a `width`×`height` image whose strip corners are `roi`.
pub fn given(model: Ptlens, roi: &[Point; 4], width: usize, height: usize) -> DistortionFound {
    let lens = Lens::new(model, width, height);
    DistortionFound {
        model,
        corner_percent: lens.corner_percent(),
        source: DistortionSource::Given,
        b_sigma: None,
        a_sigma: None,
        c_sigma: None,
        significance: None,
        edge_rms_px: None,
        straight_rms_px: None,
        edge_coverage: None,
        edge_points: 0,
        bow_px: long_edge_bow(&lens, roi),
        why_not: None,
        edge_lines: None,
        snapped: None,
    }
}

/// How far (px) the strip's long edges bow in the photo under `lens`: the
/// straight chart edges through the undistorted corners, distorted, against
/// their photo chords.
pub fn long_edge_bow(lens: &Lens, roi: &[Point; 4]) -> f64 {
    let mut worst = 0.0f64;
    for (a, b) in [(roi[0], roi[1]), (roi[3], roi[2])] {
        let (ua, ub) = (lens.undistort(a), lens.undistort(b));
        let len = (b[0] - a[0]).hypot(b[1] - a[1]).max(1e-9);
        for i in 1..32 {
            let u = i as f64 / 32.0;
            let p = lens.distort([ua[0] + u * (ub[0] - ua[0]), ua[1] + u * (ub[1] - ua[1])]);
            let d = ((b[0] - a[0]) * (p[1] - a[1]) - (b[1] - a[1]) * (p[0] - a[0])) / len;
            worst = worst.max(d.abs());
        }
    }
    worst
}

/// How far (px) beyond the strip's bounding box the plane given to [`estimate`]
/// must reach: the search margin plus the largest bow of the long edges
/// under the strongest allowed distortion of either sign.
pub fn search_pad_px(roi: &[Point; 4], width: usize, height: usize) -> f64 {
    let b_max = b_max(width, height);
    let bow = [-b_max, b_max]
        .map(|b| long_edge_bow(&Lens::new(Ptlens { a: 0.0, b, c: 0.0 }, width, height), roi));
    20.0 + bow[0].max(bow[1])
}

/// The photo columns [x0, x1) of row `y` (pixel centre y + 0.5) that
/// [`estimate`] may read: those within `pad` px of either long edge's chord
/// (corners 1→2 and 4→3), where every edge search stays (the largest allowed
/// bow plus the search depth is below [`search_pad_px`]); (0, 0) for rows
/// that meet neither band. One interval per row: the hull of both bands.
pub fn edge_band_span(roi: &[Point; 4], pad: f64, y: usize) -> (usize, usize) {
    let yc = y as f64 + 0.5;
    let (mut lo, mut hi) = (f64::INFINITY, f64::NEG_INFINITY);
    for (p, q) in [(roi[0], roi[1]), (roi[3], roi[2])] {
        let (dx, dy) = (q[0] - p[0], q[1] - p[1]);
        // The part of the chord within `pad` of this row, as t ∈ [0, 1].
        let (t0, t1) = if dy.abs() < 1e-12 {
            if (p[1] - yc).abs() > pad {
                continue;
            }
            (0.0, 1.0)
        } else {
            let (a, b) = ((yc - pad - p[1]) / dy, (yc + pad - p[1]) / dy);
            (a.min(b).max(0.0), a.max(b).min(1.0))
        };
        if t0 > t1 {
            continue;
        }
        let (xa, xb) = (p[0] + t0 * dx, p[0] + t1 * dx);
        lo = lo.min(xa.min(xb) - pad);
        hi = hi.max(xa.max(xb) + pad);
    }
    if lo > hi {
        return (0, 0);
    }
    (
        lo.floor().max(0.0) as usize,
        hi.ceil().max(0.0) as usize + 1,
    )
}

/// The largest |b| (a = c = 0) allowed in a `width`×`height` image ([`MAX_CORNER_PERCENT`] at the corner).
fn b_max(width: usize, height: usize) -> f64 {
    let rc2 = (width as f64 / 2.0).hypot(height as f64 / 2.0).powi(2)
        / (width.min(height) as f64 / 2.0).powi(2);
    MAX_CORNER_PERCENT / 100.0 / (rc2 - 1.0).max(0.05)
}

/// Estimates the distortion from the long edges of the strip with photo corners
/// `roi` (corners 1→2 and 4→3 are the long edges) in `plane` (luminance, linear;
/// it must reach [`search_pad_px`] beyond the strip's bounding box). The result says whether the model
/// is used ([`DistortionSource::Estimated`]) or not, and why not.
pub fn estimate(
    plane: &dyn Sampler,
    roi: &[Point; 4],
    width: usize,
    height: usize,
) -> DistortionFound {
    let mid = |a: Point, b: Point| [0.5 * (a[0] + b[0]), 0.5 * (a[1] + b[1])];
    let (m0, m1) = (mid(roi[0], roi[1]), mid(roi[3], roi[2]));
    let depth = (m1[0] - m0[0]).hypot(m1[1] - m0[1]);
    let b_max = b_max(width, height);
    let follow = |start: Option<Lens>| follow(plane, roi, depth, start, (width, height), b_max);
    // About the chords first; when the edges are found along too little of
    // them (a strong distortion bends them off their chords by more than the
    // search reaches), about the curves of the best of a ladder of models up
    // to the largest allowed.
    let mut result = follow(None);
    let covered = |r: &Option<DistortionFound>| {
        r.as_ref()
            .and_then(|d| d.edge_coverage)
            .is_some_and(|c| c >= MIN_EDGE_COVERAGE)
    };
    if !covered(&result) {
        // A quick probe (48 places per edge) about each model's curves picks
        // the one along which most of both edges is found; only that one is followed.
        let b_step = b_max / 5.0;
        let models: Vec<i32> = (-5..=5).filter(|&k| k != 0).collect();
        let probed: Vec<Option<(f64, Lens)>> = models
            .par_iter()
            .map(|&k| {
                let start = Lens::new(
                    Ptlens {
                        a: 0.0,
                        b: k as f64 * b_step * 0.975,
                        c: 0.0,
                    },
                    width,
                    height,
                );
                if start.check().is_err() {
                    return None;
                }
                let probe = |a: Point, b: Point, oa: Point, ob: Point| {
                    let (e, n) = edge_points(plane, (a, b), (oa, ob), depth, Some(&start), 48);
                    e.len() as f64 / n.max(1) as f64
                };
                let found = probe(roi[0], roi[1], roi[3], roi[2])
                    .min(probe(roi[3], roi[2], roi[0], roi[1]));
                Some((found, start))
            })
            .collect();
        // The first of the best (in the ladder's order, as a sequential search would pick).
        let mut best: Option<(f64, Lens)> = None;
        for (found, start) in probed.into_iter().flatten() {
            if best.as_ref().is_none_or(|b| found > b.0) {
                best = Some((found, start));
            }
        }
        if let Some((found, start)) = best
            && found >= MIN_EDGE_COVERAGE
            && let Some(r) = follow(Some(start))
            && r.source == DistortionSource::Estimated
        {
            result = Some(r);
        }
    }
    result.unwrap_or(DistortionFound {
        model: Ptlens {
            a: 0.0,
            b: 0.0,
            c: 0.0,
        },
        corner_percent: 0.0,
        source: DistortionSource::Negligible,
        b_sigma: None,
        a_sigma: None,
        c_sigma: None,
        significance: None,
        edge_rms_px: None,
        straight_rms_px: None,
        edge_coverage: Some(0.0),
        edge_points: 0,
        bow_px: 0.0,
        why_not: Some(
            "the strip's long edges were not found (no printed edge against its surround)",
        ),
        edge_lines: None,
        snapped: None,
    })
}

/// Edge points about the curves `start` predicts (the chords without one),
/// fitted; then (when the fit moves the edges by 2 px or more) again about
/// the curves the fit predicts, up to three rounds.
fn follow(
    plane: &dyn Sampler,
    roi: &[Point; 4],
    depth: f64,
    start: Option<Lens>,
    (width, height): (usize, usize),
    b_max: f64,
) -> Option<DistortionFound> {
    let mut lens = start;
    let mut result: Option<DistortionFound> = None;
    for _ in 0..3 {
        // Each long edge searched from its own side, the two side by side.
        let side = |ab: (Point, Point), other: (Point, Point)| {
            edge_points(plane, ab, other, depth, lens.as_ref(), usize::MAX)
        };
        let ((e0, n0), (e1, n1)) = rayon::join(
            || side((roi[0], roi[1]), (roi[3], roi[2])),
            || side((roi[3], roi[2]), (roi[0], roi[1])),
        );
        let Some(found) = fit_edges(
            [e0, e1],
            [n0, n1],
            roi,
            width,
            height,
            b_max,
            lens.map_or(0.0, |l| l.model.b),
        ) else {
            break;
        };
        let bow = found.bow_px;
        let moved = lens.map_or(bow, |l: Lens| {
            let change = Ptlens {
                a: found.model.a - l.model.a,
                b: found.model.b - l.model.b,
                c: found.model.c - l.model.c,
            };
            long_edge_bow(&Lens::new(change, width, height), roi)
        });
        let next = Lens::new(found.model, width, height);
        // Search about the predicted curves only when this fit is a real one.
        let credible = found.edge_rms_px.is_some_and(|r| r <= MAX_EDGE_RMS_PX)
            && found.significance.is_some_and(|s| s > MIN_SIGNIFICANCE)
            && next.check().is_ok();
        result = Some(found);
        if moved < 2.0 || !credible {
            break;
        }
        lens = Some(next);
    }
    result
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Every point within `pad` − 1 px of a long edge's chord lies in its row's
    /// span (checked densely, for a turned and a steep strip); rows far from
    /// both edges get none.
    #[test]
    fn edge_bands_hold_every_point_near_the_long_edges() {
        let turned: [Point; 4] = [
            [415.2, 1104.7],
            [5614.4, 1195.5],
            [5584.7, 2895.2],
            [385.5, 2804.5],
        ];
        let steep: [Point; 4] = [
            [800.0, 100.0],
            [1300.0, 3900.0],
            [1000.0, 3950.0],
            [500.0, 150.0],
        ];
        let pad = 40.0;
        for roi in [turned, steep] {
            for (p, q) in [(roi[0], roi[1]), (roi[3], roi[2])] {
                let len = (q[0] - p[0]).hypot(q[1] - p[1]);
                let (ux, uy) = ((q[0] - p[0]) / len, (q[1] - p[1]) / len);
                for k in 0..=400 {
                    let t = k as f64 / 400.0;
                    for d in [-(pad - 1.0), -10.0, 0.0, 10.0, pad - 1.0] {
                        let x = p[0] + t * (q[0] - p[0]) - d * uy;
                        let y = p[1] + t * (q[1] - p[1]) + d * ux;
                        let row = (y - 0.5).round().max(0.0) as usize;
                        let (a, b) = edge_band_span(&roi, pad, row);
                        assert!(
                            a as f64 <= x && x < b as f64,
                            "({x:.1}, {y:.1}) outside row {row}'s span {a}..{b}"
                        );
                    }
                }
            }
        }
        // The turned strip's middle rows (edges at y ≈ 1105–1196 and 2804–2895) read nothing.
        assert_eq!(edge_band_span(&turned, pad, 2000), (0, 0));
        assert_ne!(edge_band_span(&turned, pad, 1150), (0, 0));
    }
}
