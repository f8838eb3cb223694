//! The light a lens's diffraction carries into the strip from its surround,
//! found from the curve's own linear start and taken out.
//!
//! A finite aperture gives every lens's MTF a falling linear start,
//! `M(f) ≈ 1 + b·|f|` (b = −(4/π)/f_c for a circular pupil), and that cusp
//! at 0 is the far tail of its line spread, `ℓ(x) ≈ K/x²` with
//! `K = −b/(2π²)` (`∫(1 − cos 2πfx)/x² dx = 2π²|f|`). Across an edge the
//! tail carries `ΔI·K/d` at distance d from a surround ΔI brighter than the
//! strip out to infinity, `ΔI·K·(1/(d + a) − 1/(d + b))` from a ring a–b
//! beyond the edge. The strip is printed on paper (or beside other strips,
//! a card's edge, the scene) whose light differs from the strip's mean M:
//! an offset on the strip's values that does not change along the sweep,
//! so it lowers every modulation alike; the MTF (a ratio) keeps it out, but
//! the chart modulation found is the print's times `M/(M + leak)`. The
//! surround is read in rings [`RINGS_PX`] beyond each long edge (nearest
//! samples along the whole strip; the last ring read stands for everything
//! beyond it), the leak averaged over the binned band `t ∈ [m, 1 − m]`, and
//! every modulation is scaled by `1 + leak/M`. Rings beyond each end add
//! `K·ΔI/d` at a point d px from that end (since session 27): the paper
//! beyond the low end lowers the first periods more than the rest, so the
//! chart modulation is read again from the corrected points. On the independent camera's
//! plain shots (PNG, f/3.1–8, 70–108 px strips on white paper) the chart
//! modulation was found 0.12–0.50 % low, and with the paper at the strip's
//! mean 0.15 % low at most: the leak. The slope comes from the
//! chart-modulation extrapolation's linear start (none when the start is
//! even). Aberrations, defocus, the pixel and sharpening are even in f and
//! compact: they add no such tail.

use super::MtfPoint;
use super::profile::Strip;
use crate::photo::PlaneRef;

/// Ring boundaries beyond each long edge (px); the last ring read extends to infinity.
pub const RINGS_PX: [f64; 7] = [0.0, 6.0, 12.0, 24.0, 48.0, 96.0, 192.0];
/// The surround must be read at least this far (px) beyond each edge.
pub const MIN_READ_PX: f64 = 48.0;
/// Nearest distance (px) of the binned band to the strip's edge for the
/// tail's law to hold (the core of the spread stays inside it).
pub const MIN_EDGE_PX: f64 = 3.0;
/// The nearest ring is read from this far out (px): the strip's own blurred edge is nearer.
pub const NEAR_PX: f64 = 3.0;
/// Largest relative leak taken out: beyond it the slope or the surround is
/// not what the law assumes, and nothing is taken out.
pub const MAX_LEAK: f64 = 0.02;
/// The relative uncertainty claimed for the leak taken out (the slope's
/// scatter and the surround beyond the rings read).
pub const LEAK_REL_ERR: f64 = 0.3;
/// Places along the strip each side's ring is read at (× 3 depths × planes).
const ALONG: usize = 256;
/// Places across the strip each end's ring is read at (× 3 depths × planes).
const ACROSS: usize = 32;

/// The light around a strip: each ring's mean value (linear, as decoded) beyond
/// its t = 0 edge and its t = width edge, and beyond its s = 0 and s = length
/// ends, nearest ring first, as far as read.
#[derive(Debug, Clone, PartialEq)]
pub struct Surround {
    /// Ring means beyond the t = 0 edge and beyond the t = width edge.
    pub sides: [Vec<f64>; 2],
    /// Ring means beyond the s = 0 end and beyond the s = length end (empty where not read).
    pub ends: [Vec<f64>; 2],
}

/// Each ring's mean of the planes' nearest samples at `place(j, x)` for
/// `j < places` and x px into the ring (3 depths), nearest ring first; stops
/// at the first ring where fewer than half the samples tried fall in a plane.
fn read_rings(
    planes: &[PlaneRef],
    places: usize,
    place: impl Fn(usize, f64) -> Option<[f64; 2]>,
) -> Vec<f64> {
    let mut rings = Vec::new();
    for r in 0..RINGS_PX.len() - 1 {
        let (a, b) = (RINGS_PX[r].max(NEAR_PX), RINGS_PX[r + 1]);
        let (mut sum, mut n, mut tried) = (0.0, 0usize, 0usize);
        for j in 0..places {
            for k in 0..3 {
                let Some(p) = place(j, a + (b - a) * (k as f64 + 0.5) / 3.0) else {
                    continue;
                };
                for pl in planes {
                    tried += 1;
                    if let Some(v) = nearest(pl, p) {
                        sum += v;
                        n += 1;
                    }
                }
            }
        }
        if tried == 0 || 2 * n < tried {
            break;
        }
        rings.push(sum / n as f64);
    }
    rings
}

impl Surround {
    /// Reads the rings from the planes (nearest samples); None where either
    /// long side is not read out to [`MIN_READ_PX`] (the planes end: a decoded
    /// window, the frame). An end not read that far is left empty (its light
    /// is then not taken out).
    pub fn read(planes: &[PlaneRef], strip: &Strip) -> Option<Surround> {
        let sides = [0, 1].map(|side| {
            read_rings(planes, ALONG, |j, x_px| {
                let s = strip.length * (j as f64 + 0.5) / ALONG as f64;
                let per_t = strip.px_per_t(s);
                (per_t > 0.0).then(|| {
                    let x = x_px / per_t;
                    let t = if side == 0 { -x } else { strip.width + x };
                    strip.to_photo([s, t])
                })
            })
        });
        if sides.iter().any(|r| RINGS_PX[r.len()] < MIN_READ_PX) {
            return None;
        }
        let ends = [0, 1].map(|end| {
            let s_end = if end == 0 { 0.0 } else { strip.length };
            let per_s = 1.0 / strip.scale_at(s_end).s_per_px;
            let rings = read_rings(planes, ACROSS, |j, x_px| {
                let t = strip.width * (j as f64 + 0.5) / ACROSS as f64;
                let x = x_px / per_s;
                (per_s > 0.0 && per_s.is_finite())
                    .then(|| strip.to_photo([if end == 0 { -x } else { s_end + x }, t]))
            });
            if RINGS_PX[rings.len()] < MIN_READ_PX {
                Vec::new()
            } else {
                rings
            }
        });
        Some(Surround { sides, ends })
    }

    /// The relative leak `leak/M` at `s` along the strip (where it is W px
    /// wide), for a curve of relative slope `slope_rel` at 0 (per cy/px), a
    /// binned band inside `margin` (fraction of the width) of each edge, the
    /// rings' values through `to_linear` and the strip's mean `mean` (same
    /// units); None where the law does not hold or the leak is out of reason.
    pub fn leak_rel(
        &self,
        slope_rel: f64,
        strip: &Strip,
        s: f64,
        margin: f64,
        to_linear: impl Fn(f64) -> f64,
        mean: f64,
    ) -> Option<f64> {
        let w = strip.px_per_t(s) * strip.width;
        let m = margin;
        let holds = slope_rel.is_finite()
            && slope_rel < 0.0
            && w.is_finite()
            && m > 0.0
            && m < 0.5
            && m * w >= MIN_EDGE_PX
            && mean.is_finite()
            && mean > 0.0;
        if !holds {
            return None;
        }
        let k = -slope_rel / (2.0 * std::f64::consts::PI.powi(2));
        let rel = |rings: &[f64]| -> Vec<f64> {
            rings.iter().map(|&v| to_linear(v) / mean - 1.0).collect()
        };
        let sides = self.sides.each_ref().map(|r| rel(r));
        let n = 24;
        let mut sum = 0.0;
        for i in 0..n {
            let t = m + (1.0 - 2.0 * m) * (i as f64 + 0.5) / n as f64;
            for (side, rings) in sides.iter().enumerate() {
                let d = if side == 0 { t } else { 1.0 - t } * w;
                sum += ring_sum(rings, d);
            }
        }
        // Beyond each end, at the point's distance from it along the strip
        // (the corners beyond both an end and a side are left out: second order).
        let mid = |s: f64| strip.to_photo([s, 0.5 * strip.width]);
        let here = mid(s);
        for (end, rings) in self.ends.iter().enumerate() {
            let e = mid(if end == 0 { 0.0 } else { strip.length });
            let d = (here[0] - e[0]).hypot(here[1] - e[1]);
            if !rings.is_empty() && d >= MIN_EDGE_PX {
                sum += n as f64 * ring_sum(&rel(rings), d);
            }
        }
        let leak = k * sum / n as f64;
        (leak.is_finite() && leak.abs() <= MAX_LEAK).then_some(leak)
    }
}

/// The tail's sum over rings (relative light `rel` beyond an edge, nearest
/// first) at distance `d` px from that edge: Σ rel·(1/(d + a) − 1/(d + b)),
/// the last ring read out to infinity.
fn ring_sum(rel: &[f64], d: f64) -> f64 {
    rel.iter()
        .enumerate()
        .map(|(r, dv)| {
            let far = if r + 1 == rel.len() {
                0.0
            } else {
                1.0 / (d + RINGS_PX[r + 1])
            };
            dv * (1.0 / (d + RINGS_PX[r]) - far)
        })
        .sum()
}

/// Scales every point's modulation, and the low end's (the chart
/// modulation's own points, [`super::normalise::low_end_points`]), by
/// `1 + leak_at(s)` and returns the leak at the lowest point the chart
/// modulation is read from (`s ≥ s_min`), or None (nothing changed) where it
/// is not known there. The chart modulation is then read again from the
/// points: the ends' light changes along the strip.
pub(super) fn take_out(
    points: &mut [MtfPoint],
    low: &mut [MtfPoint],
    s_min: f64,
    leak_at: impl Fn(f64) -> Option<f64>,
) -> Option<f64> {
    let s_ref = points
        .iter()
        .filter(|p| p.s >= s_min)
        .map(|p| p.s)
        .fold(f64::INFINITY, f64::min);
    let leak = leak_at(s_ref)?;
    for p in points.iter_mut().chain(low.iter_mut()) {
        p.modulation *= 1.0 + leak_at(p.s).unwrap_or(leak);
    }
    Some(leak)
}

/// The chart modulation source's clause for a leak taken out.
pub fn source_note(leak: f64) -> String {
    format!(
        "; the surround's light through the lens's diffraction tail ({:+.2} % of the strip's mean) taken out",
        100.0 * leak
    )
}

/// The plane's sample nearest the photo point `p`, if it holds one there.
fn nearest(pl: &PlaneRef, p: [f64; 2]) -> Option<f64> {
    let (ox, oy, sx, sy) = pl.centres();
    let (i, j) = (((p[0] - ox) / sx).round(), ((p[1] - oy) / sy).round());
    (i >= 0.0 && j >= 0.0 && (i as usize) < pl.width && (j as usize) < pl.height)
        .then(|| pl.at(i as usize, j as usize) as f64)
        .filter(|v| v.is_finite())
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geometry::Homography;
    use crate::photo::Plane;

    /// A strip `w` px wide along x from (100, 300), 1 strip unit = 1 px.
    fn strip(len: f64, w: f64) -> Strip {
        Strip {
            to_image: Homography {
                m: [1.0, 0.0, 100.0, 0.0, 1.0, 300.0, 0.0, 0.0, 1.0],
            },
            lens: None,
            length: len,
            width: w,
        }
    }

    /// The leak a slit pupil's line spread (sinc², cut-off `fc`: MTF 1 − f/fc,
    /// so b = −1/fc) carries into the binned band from a surround `light(x)`
    /// at x px beyond either edge, integrated numerically (midpoint rule,
    /// out to 5000 px), over the strip's mean `mean`.
    fn integrated(fc: f64, w: f64, m: f64, mean: f64, light: impl Fn(f64) -> f64) -> f64 {
        let lsf = |x: f64| {
            let a = std::f64::consts::PI * fc * x;
            if a.abs() < 1e-9 {
                fc
            } else {
                fc * (a.sin() / a).powi(2)
            }
        };
        let n = 41;
        let mut leak = 0.0;
        for i in 0..n {
            let t = m + (1.0 - 2.0 * m) * (i as f64 + 0.5) / n as f64;
            let (h, mut x, mut sum) = (0.05, 0.025, 0.0);
            while x < 5_000.0 {
                let dv = light(x) - mean;
                sum += dv * (lsf(t * w + x) + lsf((1.0 - t) * w + x)) * h;
                x += h;
            }
            leak += sum / n as f64;
        }
        leak / mean
    }

    #[test]
    fn the_leak_matches_a_numerically_integrated_line_spread() {
        let (fc, w, m, mean) = (0.9, 80.0, 0.15, 0.5);
        let st = strip(1000.0, w);
        // White paper all round.
        let paper = Surround {
            sides: [vec![1.0; 6], vec![1.0; 6]],
            ends: [vec![], vec![]],
        };
        let law = paper
            .leak_rel(-1.0 / fc, &st, 500.0, m, |v| v, mean)
            .unwrap();
        let truth = integrated(fc, w, m, mean, |_| 1.0);
        assert!(
            (law - truth).abs() < 0.05 * truth,
            "law {law:.5} against {truth:.5}"
        );
        // 24 px of paper, then a dark scene (0.2): far less comes in.
        let card = Surround {
            sides: [
                vec![1.0, 1.0, 1.0, 0.2, 0.2, 0.2],
                vec![1.0, 1.0, 1.0, 0.2, 0.2, 0.2],
            ],
            ends: [vec![], vec![]],
        };
        let law2 = card
            .leak_rel(-1.0 / fc, &st, 500.0, m, |v| v, mean)
            .unwrap();
        let truth2 = integrated(fc, w, m, mean, |x| if x < 24.0 { 1.0 } else { 0.2 });
        assert!(
            (law2 - truth2).abs() < 0.05 * truth.abs(),
            "law {law2:.5} against {truth2:.5} (paper all round {truth:.5})"
        );
        assert!(truth2.abs() < 0.5 * truth);
    }

    /// The light beyond a strip's end reaches the periods next to it: at d
    /// px from the end, paper out to infinity carries `K·(R − M)/d`, within
    /// 5 % of a slit pupil's line spread integrated numerically; half-way
    /// along a 1000-px strip it is a tenth of the long edges' share.
    #[test]
    fn the_light_beyond_an_end_matches_a_numerically_integrated_line_spread() {
        let (fc, w, m, mean) = (0.9, 80.0, 0.15, 0.5);
        let st = strip(1000.0, w);
        // The sides at the strip's mean carry nothing: the end alone.
        let end_only = Surround {
            sides: [vec![mean; 6], vec![mean; 6]],
            ends: [vec![1.0; 6], vec![]],
        };
        let lsf = |x: f64| {
            let a = std::f64::consts::PI * fc * x;
            fc * (a.sin() / a).powi(2)
        };
        for d in [60.0, 150.0, 400.0] {
            let law = end_only
                .leak_rel(-1.0 / fc, &st, d, m, |v| v, mean)
                .unwrap();
            let (h, mut x, mut truth) = (0.05, 0.025, 0.0);
            while x < 20_000.0 {
                truth += (1.0 - mean) * lsf(d + x) * h;
                x += h;
            }
            truth /= mean;
            assert!(
                (law - truth).abs() < 0.05 * truth,
                "d {d}: law {law:.6} against {truth:.6}"
            );
        }
        // Paper all round: at the middle the ends add a few per cent of the sides' share.
        let sides_only = Surround {
            sides: [vec![1.0; 6], vec![1.0; 6]],
            ends: [vec![], vec![]],
        };
        let all_round = Surround {
            ends: [vec![1.0; 6], vec![1.0; 6]],
            ..sides_only.clone()
        };
        let at = |sur: &Surround, s: f64| sur.leak_rel(-1.0 / fc, &st, s, m, |v| v, mean).unwrap();
        let extra = at(&all_round, 500.0) / at(&sides_only, 500.0) - 1.0;
        assert!(extra > 0.0 && extra < 0.1, "{extra}");
        assert!(at(&all_round, 60.0) > 1.2 * at(&sides_only, 60.0));
    }

    #[test]
    fn rings_are_read_from_the_planes_as_far_as_they_reach() {
        // A 1200 × 800 frame: the strip (rows 300–380) at 0.4, 1.0 up to 24 px
        // beyond it, 0.3 beyond that.
        let (wd, ht) = (1200, 800);
        let mut data = vec![0.3f32; wd * ht];
        for y in 0..ht {
            let yc = y as f64 + 0.5;
            let v = if (300.0..380.0).contains(&yc) {
                0.4
            } else if (276.0..404.0).contains(&yc) {
                1.0
            } else {
                0.3
            };
            data[y * wd..(y + 1) * wd].fill(v);
        }
        let plane = Plane::full(wd, ht, data);
        let st = strip(1000.0, 80.0);
        let sur = Surround::read(&[PlaneRef::from(&plane)], &st).unwrap();
        for side in &sur.sides {
            assert_eq!(side.len(), 6);
            assert!(
                side[..3].iter().all(|&v| (v - 1.0).abs() < 1e-6),
                "{side:?}"
            );
            assert!((side[3] - 0.3).abs() < 1e-6, "{side:?}");
        }
        // Beyond the ends (100 px of frame each side) the rows hold 0.4.
        for end in &sur.ends {
            assert!(end.len() >= 4, "{end:?}");
            assert!(end.iter().all(|&v| (v - 0.4).abs() < 1e-6), "{end:?}");
        }
        // A window that ends 30 px beyond the strip: not read far enough.
        let cut = Plane {
            height: 410,
            data: plane.data[..wd * 410].to_vec(),
            ..plane.clone()
        };
        assert_eq!(Surround::read(&[PlaneRef::from(&cut)], &st), None);
    }

    #[test]
    fn no_leak_where_the_law_does_not_hold() {
        let st = strip(1000.0, 80.0);
        let paper = Surround {
            sides: [vec![1.0; 6], vec![1.0; 6]],
            ends: [vec![], vec![]],
        };
        let leak = |b: f64, w: f64, m: f64, mean: f64| {
            paper.leak_rel(b, &strip(1000.0, w), 500.0, m, |v| v, mean)
        };
        assert_eq!(leak(0.0, 80.0, 0.15, 0.5), None); // even start
        assert_eq!(leak(0.5, 80.0, 0.15, 0.5), None); // rising start
        assert_eq!(leak(-1.0, 10.0, 0.15, 0.5), None); // band 1.5 px from the edge
        assert_eq!(leak(-1.0, 80.0, 0.15, f64::NAN), None);
        assert_eq!(leak(-1e3, 80.0, 0.15, 0.5), None); // out of reason
        assert_eq!(leak(-1.0, 80.0, 0.0, 0.5), None);
        // A surround as bright as the strip's mean carries nothing in; a dark one takes light out.
        assert_eq!(leak(-1.0, 80.0, 0.15, 1.0), Some(0.0));
        assert!(
            paper
                .leak_rel(-1.0, &st, 500.0, 0.15, |v| 0.2 * v, 0.5)
                .unwrap()
                < 0.0
        );
        // Nothing is changed where the leak is not known at the low end.
        let mut pts = vec![];
        assert_eq!(take_out(&mut pts, &mut [], 0.0, |_| None), None);
    }
}
