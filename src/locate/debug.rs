//! The picture of what the search saw (`STEM.roi.png`): the photo, reduced to
//! at most 1200 px across and shown with an sRGB-like tone curve, with every
//! examined blob outlined (green: used as a fiducial; yellow: disk-like but
//! unused; red: rejected; a cyan dot marks a bright, ring-like centre) and
//! every chart found drawn as its frame (blue) and fiducials (magenta).

use super::downscale::box_reduce;
use super::sample::Gray;
use super::{Candidate, Located};
use crate::geometry::Point;
use crate::photo::Plane;
use image::{Rgb, RgbImage};

/// Longest side of the debug picture (px).
pub const MAX_SIDE: usize = 1200;

/// Draws the candidates and charts over a reduced copy of the plane.
pub fn debug_image(plane: &Plane, candidates: &[Candidate], charts: &[Located]) -> RgbImage {
    let full = Gray::of_plane(plane);
    let k = plane.width.max(plane.height).div_ceil(MAX_SIDE).max(1);
    let g = if k > 1 { box_reduce(&full, k) } else { full };
    let mut img = RgbImage::new(g.w.max(1) as u32, g.h.max(1) as u32);
    for j in 0..g.h {
        for i in 0..g.w {
            let v = (g.at(i, j).clamp(0.0, 1.0) as f64).powf(1.0 / 2.2);
            let b = (v * 255.0).round() as u8;
            img.put_pixel(i as u32, j as u32, Rgb([b, b, b]));
        }
    }
    let to = |p: Point| g.to_grid(p);
    for c in candidates {
        let colour = if c.used {
            Rgb([0, 220, 0])
        } else if c.disk_like {
            Rgb([255, 220, 0])
        } else {
            Rgb([230, 30, 30])
        };
        // The 2σ ellipse, drawn in grid units.
        let [cxx, cxy, cyy] = c.cov_px2;
        let tr = cxx + cyy;
        let disc = ((cxx - cyy).powi(2) / 4.0 + cxy * cxy).sqrt();
        let (l1, l2) = (tr / 2.0 + disc, (tr / 2.0 - disc).max(0.0));
        let th = 0.5 * (2.0 * cxy).atan2(cxx - cyy);
        let (a, b) = (2.0 * l1.sqrt(), 2.0 * l2.sqrt());
        let n = 48;
        let pts: Vec<Point> = (0..=n)
            .map(|q| {
                let t = q as f64 * std::f64::consts::TAU / n as f64;
                let (x, y) = (a * t.cos(), b * t.sin());
                to([
                    c.centre_px[0] + x * th.cos() - y * th.sin(),
                    c.centre_px[1] + x * th.sin() + y * th.cos(),
                ])
            })
            .collect();
        for w in pts.windows(2) {
            line(&mut img, w[0], w[1], colour);
        }
        if c.ring_score > 0.3 {
            dot(&mut img, to(c.centre_px), 1, Rgb([0, 220, 255]));
        }
    }
    for ch in charts {
        for i in 0..4 {
            line(
                &mut img,
                to(ch.corners_px[i]),
                to(ch.corners_px[(i + 1) % 4]),
                Rgb([40, 90, 255]),
            );
        }
        dot(&mut img, to(ch.corners_px[0]), 3, Rgb([40, 90, 255]));
        for (_, p) in &ch.fiducials {
            dot(&mut img, to(*p), 2, Rgb([255, 0, 255]));
        }
    }
    img
}

fn put(img: &mut RgbImage, x: f64, y: f64, c: Rgb<u8>) {
    if x >= 0.0 && y >= 0.0 && (x as u32) < img.width() && (y as u32) < img.height() {
        img.put_pixel(x as u32, y as u32, c);
    }
}

fn line(img: &mut RgbImage, a: Point, b: Point, c: Rgb<u8>) {
    let n = ((b[0] - a[0]).abs().max((b[1] - a[1]).abs()).ceil() as usize).clamp(1, 10_000);
    for i in 0..=n {
        let f = i as f64 / n as f64;
        put(img, a[0] + f * (b[0] - a[0]), a[1] + f * (b[1] - a[1]), c);
    }
}

fn dot(img: &mut RgbImage, p: Point, r: i64, c: Rgb<u8>) {
    for dy in -r..=r {
        for dx in -r..=r {
            put(img, p[0] + dx as f64, p[1] + dy as f64, c);
        }
    }
}
