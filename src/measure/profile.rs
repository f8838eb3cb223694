//! The sweep profile: every sample centre of a strip, mapped through the
//! homography to the strip's own coordinate `s` (along the sweep) and binned
//! in sub-pixel bins, with a robust (3σ-clipped) mean per bin. No image
//! resampling: each bin's value is an average of real samples, and each bin
//! also records the mean and variance of its samples' `s` so the estimators
//! can work at the true sample positions and correct the tiny box blur of
//! binning exactly.

#![allow(clippy::needless_range_loop, clippy::neg_cmp_op_on_partial_ord)]

use crate::geometry::{Homography, Point};
use crate::photo::Plane;

/// A strip on the chart: its own frame `(s, t)` (s along the sweep from the
/// low-frequency edge, t across) and where that frame lies in the image.
#[derive(Debug, Clone)]
pub struct Strip {
    /// Maps strip coordinates (s, t) to image pixel coordinates.
    pub to_image: Homography,
    /// Length along the sweep (strip units: mm with a target, else 1).
    pub length: f64,
    /// Width across the sweep (strip units).
    pub width: f64,
}

/// Local scale of a strip in the image.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct LocalScale {
    /// |∇s| in strip units per image pixel (multiply a frequency in cycles per strip unit by this to get cycles/pixel).
    pub s_per_px: f64,
    /// Direction of increasing s in the image (radians from +x towards +y).
    pub angle_rad: f64,
}

impl Strip {
    /// The four image corners of the strip region t ∈ [t0, t1] over its whole length.
    pub fn image_quad(&self, t0: f64, t1: f64) -> [Point; 4] {
        let l = self.length;
        [[0.0, t0], [l, t0], [l, t1], [0.0, t1]].map(|p| self.to_image.apply(p))
    }

    /// Scale and direction of the sweep in the image at distance `s` along the strip's centre line.
    pub fn scale_at(&self, s: f64) -> LocalScale {
        let j = self.to_image.jacobian([s, 0.5 * self.width]);
        // Inverse Jacobian: d(s,t)/d(x,y); its first row is ∇s.
        let det = j[0][0] * j[1][1] - j[0][1] * j[1][0];
        let gx = j[1][1] / det;
        let gy = -j[0][1] / det;
        LocalScale {
            s_per_px: gx.hypot(gy),
            angle_rad: gy.atan2(gx),
        }
    }
}

/// How the strip is binned.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct BinOptions {
    /// Bin width in image pixels (at the strip's most magnified end).
    pub bin_px: f64,
    /// Fraction of the strip width left out along each long edge (0–0.45).
    pub margin: f64,
    /// Pixels left out at each short end of the strip.
    pub end_px: f64,
    /// Linear value at or above which a sample counts as clipped.
    pub clip_level: f32,
}

impl Default for BinOptions {
    fn default() -> Self {
        BinOptions {
            bin_px: 0.25,
            margin: 0.15,
            end_px: 1.0,
            clip_level: 0.999,
        }
    }
}

/// A binned profile along a strip (only non-empty bins, in increasing `s`).
#[derive(Debug, Clone, Default)]
pub struct Profile {
    /// Mean `s` of each bin's samples (strip units).
    pub s: Vec<f64>,
    /// Robust mean linear value of each bin.
    pub y: Vec<f64>,
    /// Samples averaged in each bin.
    pub count: Vec<f64>,
    /// Variance of the samples' `s` within each bin (strip units²).
    pub var_s: Vec<f64>,
    /// Bin width (strip units).
    pub bin: f64,
    /// Strip length (strip units).
    pub length: f64,
    /// Samples that fell inside the region.
    pub samples: usize,
    /// Samples at or above the clipping level.
    pub clipped_high: usize,
    /// Samples at or below zero (black clipping).
    pub clipped_low: usize,
}

impl Profile {
    /// Fraction of the region's samples that are clipped (white or black).
    pub fn clipped_fraction(&self) -> f64 {
        if self.samples == 0 {
            0.0
        } else {
            (self.clipped_high + self.clipped_low) as f64 / self.samples as f64
        }
    }
}

/// Bins one plane along a strip. Returns an empty profile when no sample falls inside.
pub fn bin_plane(plane: &Plane, strip: &Strip, opts: &BinOptions) -> Profile {
    bin_planes(&[plane], strip, opts)
}

/// Bins several planes of one colour (e.g. the two green sites of a Bayer
/// mosaic) together along a strip.
pub fn bin_planes(planes: &[&Plane], strip: &Strip, opts: &BinOptions) -> Profile {
    let Some(inv) = strip.to_image.inverse() else {
        return Profile::default();
    };
    let margin = opts.margin.clamp(0.0, 0.45);
    let (t0, t1) = (margin * strip.width, (1.0 - margin) * strip.width);
    let max_px_per_s = [0.0, 0.5, 1.0]
        .iter()
        .map(|f| 1.0 / strip.scale_at(f * strip.length).s_per_px)
        .fold(0.0, f64::max);
    let bin = opts.bin_px / max_px_per_s;
    let end = opts.end_px / max_px_per_s;
    let (s_lo, s_hi) = (end, strip.length - end);
    if !(bin > 0.0 && bin.is_finite() && s_hi > s_lo) {
        return Profile::default();
    }
    let nbins = ((strip.length / bin).ceil() as usize).max(1);
    let quad = strip.image_quad(t0, t1);
    let ymin = quad.iter().map(|p| p[1]).fold(f64::INFINITY, f64::min);
    let ymax = quad.iter().map(|p| p[1]).fold(f64::NEG_INFINITY, f64::max);
    let mut sum = vec![0.0f64; nbins];
    let mut sum2 = vec![0.0f64; nbins];
    let mut n = vec![0u32; nbins];
    let mut ssum = vec![0.0f64; nbins];
    let mut ssum2 = vec![0.0f64; nbins];
    let mut prof = Profile {
        bin,
        length: strip.length,
        ..Profile::default()
    };
    let m = inv.m;
    // Visits every sample inside the region: f(bin, s, value).
    let visit = |f: &mut dyn FnMut(usize, f64, f32)| {
        for plane in planes {
            let (sx, sy) = (plane.step.0 as f64, plane.step.1 as f64);
            let (ox, oy) = (plane.offset.0 as f64 + 0.5, plane.offset.1 as f64 + 0.5);
            // Sample rows whose centres lie within the quad's vertical extent.
            let j0 = ((ymin - oy) / sy).ceil().max(0.0) as usize;
            let j1 = (((ymax - oy) / sy).floor() + 1.0).clamp(0.0, plane.height as f64) as usize;
            for j in j0..j1 {
                let y = oy + j as f64 * sy;
                let Some((xa, xb)) = row_span(&quad, y) else {
                    continue;
                };
                let i0 = ((xa - ox) / sx).ceil().max(0.0) as usize;
                let i1 = (((xb - ox) / sx).floor() + 1.0).clamp(0.0, plane.width as f64) as usize;
                let row = &plane.data[j * plane.width..(j + 1) * plane.width];
                // Along a row the homography's numerators and denominator are linear in x.
                let (ns0, nt0, w0) = (m[1] * y + m[2], m[4] * y + m[5], m[7] * y + m[8]);
                for (i, &v) in row.iter().enumerate().take(i1).skip(i0) {
                    let x = ox + i as f64 * sx;
                    let rw = 1.0 / (m[6] * x + w0);
                    let s = (m[0] * x + ns0) * rw;
                    let t = (m[3] * x + nt0) * rw;
                    if !(t >= t0 && t <= t1 && s >= s_lo && s <= s_hi) {
                        continue;
                    }
                    f(((s / bin) as usize).min(nbins - 1), s, v);
                }
            }
        }
    };
    visit(&mut |b, s, v| {
        prof.samples += 1;
        if v >= opts.clip_level {
            prof.clipped_high += 1;
        } else if v <= 0.0 {
            prof.clipped_low += 1;
        }
        let vd = v as f64;
        sum[b] += vd;
        sum2[b] += vd * vd;
        n[b] += 1;
        ssum[b] += s;
        ssum2[b] += s * s;
    });
    // Robust mean: drop samples more than 3σ (and more than a small floor) from the bin mean.
    let mut lim = vec![f64::INFINITY; nbins];
    let mut any_limit = false;
    for b in 0..nbins {
        if n[b] >= 4 {
            let c = n[b] as f64;
            let mu = sum[b] / c;
            let var = (sum2[b] / c - mu * mu).max(0.0);
            lim[b] = 3.0 * var.sqrt() + 1e-6;
            any_limit = true;
        }
    }
    let mean: Vec<f64> = (0..nbins)
        .map(|b| if n[b] > 0 { sum[b] / n[b] as f64 } else { 0.0 })
        .collect();
    let mut rsum = vec![0.0f64; nbins];
    let mut rn = vec![0u32; nbins];
    if any_limit {
        visit(&mut |b, _, v| {
            if (v as f64 - mean[b]).abs() <= lim[b] {
                rsum[b] += v as f64;
                rn[b] += 1;
            }
        });
    } else {
        rsum.copy_from_slice(&sum);
        rn.copy_from_slice(&n);
    }
    for b in 0..nbins {
        if n[b] == 0 {
            continue;
        }
        let c = n[b] as f64;
        let ms = ssum[b] / c;
        prof.s.push(ms);
        prof.var_s.push((ssum2[b] / c - ms * ms).max(0.0));
        if rn[b] > 0 {
            prof.y.push(rsum[b] / rn[b] as f64);
            prof.count.push(rn[b] as f64);
        } else {
            prof.y.push(mean[b]);
            prof.count.push(c);
        }
    }
    prof
}

/// The x-interval where the horizontal line at `y` crosses a convex quadrilateral.
pub fn row_span(q: &[Point; 4], y: f64) -> Option<(f64, f64)> {
    let mut lo = f64::INFINITY;
    let mut hi = f64::NEG_INFINITY;
    for k in 0..4 {
        let (a, b) = (q[k], q[(k + 1) % 4]);
        let (ya, yb) = (a[1].min(b[1]), a[1].max(b[1]));
        if y < ya || y > yb {
            continue;
        }
        if (b[1] - a[1]).abs() < 1e-12 {
            lo = lo.min(a[0].min(b[0]));
            hi = hi.max(a[0].max(b[0]));
        } else {
            let x = a[0] + (b[0] - a[0]) * (y - a[1]) / (b[1] - a[1]);
            lo = lo.min(x);
            hi = hi.max(x);
        }
    }
    (lo <= hi).then_some((lo, hi))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn strip_for(quad: [Point; 4], len: f64, wid: f64) -> Strip {
        let src = crate::geometry::rect_corners(0.0, 0.0, len, wid);
        Strip {
            to_image: Homography::from_quads(&src, &quad).unwrap(),
            length: len,
            width: wid,
        }
    }

    #[test]
    fn bins_a_linear_ramp_exactly_under_rotation() {
        // Image value = 0.001·s for a strip rotated by 30°: every bin mean must
        // equal 0.001 × the bin's mean s (brute force: linear data, no blur).
        let (w, h) = (300, 200);
        let a = 30f64.to_radians();
        let (c, sn) = (a.cos(), a.sin());
        let o = [40.0, 30.0];
        let len = 200.0;
        let wid = 40.0;
        let quad = [
            o,
            [o[0] + len * c, o[1] + len * sn],
            [o[0] + len * c - wid * sn, o[1] + len * sn + wid * c],
            [o[0] - wid * sn, o[1] + wid * c],
        ];
        let strip = strip_for(quad, len, wid);
        let mut data = vec![0f32; w * h];
        for j in 0..h {
            for i in 0..w {
                let (x, y) = (i as f64 + 0.5 - o[0], j as f64 + 0.5 - o[1]);
                data[j * w + i] = (0.001 * (x * c + y * sn)) as f32;
            }
        }
        let plane = Plane::full(w, h, data);
        let p = bin_plane(&plane, &strip, &BinOptions::default());
        assert!(p.s.len() > 600, "{}", p.s.len());
        for k in 0..p.s.len() {
            assert!((p.y[k] - 0.001 * p.s[k]).abs() < 1e-6, "{k}");
            assert!(p.var_s[k].sqrt() <= p.bin);
        }
        // Samples inside: 70% of the strip area (margins 15% + 15%) minus the end pixels.
        let area = len * wid * 0.7;
        assert!(
            (p.samples as f64 - area).abs() < 0.03 * area,
            "{}",
            p.samples
        );
        let sc = strip.scale_at(100.0);
        assert!((sc.s_per_px - 1.0).abs() < 1e-9);
        assert!((sc.angle_rad - a).abs() < 1e-9);
    }

    #[test]
    fn sparse_plane_uses_its_own_sites() {
        // A Bayer-like plane with step 2 and offset (1, 0): site x = 2i + 1.5.
        let plane = Plane {
            width: 50,
            height: 20,
            step: (2, 2),
            offset: (1, 0),
            data: (0..1000).map(|k| (2 * (k % 50) + 1) as f32 + 0.5).collect(),
        };
        let strip = strip_for(
            crate::geometry::rect_corners(0.0, 0.0, 100.0, 40.0),
            100.0,
            40.0,
        );
        let p = bin_plane(&plane, &strip, &BinOptions::default());
        for k in 0..p.s.len() {
            assert!((p.y[k] - p.s[k]).abs() < 1e-9);
        }
    }
}
