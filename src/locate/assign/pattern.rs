//! The target's pattern sampled for verification ([`Pattern`]) and its
//! correlation with the image under a homography.

use crate::geometry::{Homography, Point};
use crate::locate::sample::Gray;
use crate::target::Target;
use rayon::prelude::*;

/// The target's pattern sampled once for verification: points around the fiducials
/// first, then a 40×30 grid, each with its reflectance and how far (mm) the pattern
/// stays flat around it (within 0.08).
#[derive(Debug, Clone)]
pub struct Pattern {
    pub(super) pts: Vec<(Point, f64, f64)>,
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
