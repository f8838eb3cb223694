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
//! every modulation is scaled by `1 + leak/M`. On the independent camera's
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
/// Places along the strip each ring is read at (× 3 depths × planes).
const ALONG: usize = 256;

/// The light around a strip: each ring's mean value (linear, as decoded) beyond
/// its t = 0 edge and its t = width edge, nearest ring first, as far as read.
#[derive(Debug, Clone, PartialEq)]
pub struct Surround {
    /// Ring means beyond the t = 0 edge and beyond the t = width edge.
    pub sides: [Vec<f64>; 2],
}

impl Surround {
    /// Reads the rings from the planes (nearest samples); None where either side
    /// is not read out to [`MIN_READ_PX`] (the planes end: a decoded window, the frame).
    pub fn read(planes: &[PlaneRef], strip: &Strip) -> Option<Surround> {
        let mut sides: [Vec<f64>; 2] = [Vec::new(), Vec::new()];
        for (side, rings) in sides.iter_mut().enumerate() {
            for r in 0..RINGS_PX.len() - 1 {
                let (a, b) = (RINGS_PX[r].max(NEAR_PX), RINGS_PX[r + 1]);
                let (mut sum, mut n, mut tried) = (0.0, 0usize, 0usize);
                for j in 0..ALONG {
                    let s = strip.length * (j as f64 + 0.5) / ALONG as f64;
                    let per_t = strip.px_per_t(s);
                    if !(per_t > 0.0) {
                        continue;
                    }
                    for k in 0..3 {
                        let x = (a + (b - a) * (k as f64 + 0.5) / 3.0) / per_t;
                        let t = if side == 0 { -x } else { strip.width + x };
                        let p = strip.to_photo([s, t]);
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
            if RINGS_PX[rings.len()] < MIN_READ_PX {
                return None;
            }
        }
        Some(Surround { sides })
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
        let rel: Vec<Vec<f64>> = self
            .sides
            .iter()
            .map(|r| r.iter().map(|&v| to_linear(v) / mean - 1.0).collect())
            .collect();
        let n = 24;
        let mut sum = 0.0;
        for i in 0..n {
            let t = m + (1.0 - 2.0 * m) * (i as f64 + 0.5) / n as f64;
            for (side, rings) in rel.iter().enumerate() {
                let d = if side == 0 { t } else { 1.0 - t } * w;
                for (r, dv) in rings.iter().enumerate() {
                    let far = if r + 1 == rings.len() {
                        0.0
                    } else {
                        1.0 / (d + RINGS_PX[r + 1])
                    };
                    sum += dv * (1.0 / (d + RINGS_PX[r]) - far);
                }
            }
        }
        let leak = k * sum / n as f64;
        (leak.is_finite() && leak.abs() <= MAX_LEAK).then_some(leak)
    }
}

/// Scales every point's modulation by `1 + leak_at(s)` and the chart
/// modulation by the leak at the lowest point it was read from (`s ≥ s_min`);
/// returns that leak, or None (nothing changed) where it is not known there.
pub(super) fn take_out(
    points: &mut [MtfPoint],
    m_chart: &mut f64,
    s_min: f64,
    leak_at: impl Fn(f64) -> Option<f64>,
) -> Option<f64> {
    let s_ref = points
        .iter()
        .filter(|p| p.s >= s_min)
        .map(|p| p.s)
        .fold(f64::INFINITY, f64::min);
    let leak = leak_at(s_ref)?;
    for p in points.iter_mut() {
        p.modulation *= 1.0 + leak_at(p.s).unwrap_or(leak);
    }
    *m_chart *= 1.0 + leak;
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
        let mut cm = 0.8;
        assert_eq!(take_out(&mut pts, &mut cm, 0.0, |_| None), None);
        assert_eq!(cm, 0.8);
    }
}
