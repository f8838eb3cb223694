//! Test-only shot renderer for the locate tests and bench: a target seen
//! through a known homography, supersampled, with vignetting, a light
//! gradient, Gaussian defocus and shot/read noise from a seeded RNG, plus
//! dark distractor shapes around the chart. Independent of the code under test
//! (uses only `Target::reflectance` and `Homography`).
#![allow(dead_code)]

pub mod sweep;

use sweepmtf::geometry::{Homography, Point, rect_corners};
use sweepmtf::photo::Plane;
use sweepmtf::target::{
    Direction, Fiducial, FiducialKind, GreyPatch, Rect, Sweep, SweepLaw, Target,
};

/// SplitMix64 with Box–Muller normals.
pub struct Rng(pub u64);

impl Rng {
    pub fn next_u64(&mut self) -> u64 {
        self.0 = self.0.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        z ^ (z >> 31)
    }
    pub fn uniform(&mut self) -> f64 {
        (self.next_u64() >> 11) as f64 / (1u64 << 53) as f64
    }
    pub fn range(&mut self, a: f64, b: f64) -> f64 {
        a + (b - a) * self.uniform()
    }
    pub fn normal(&mut self) -> f64 {
        let u1 = self.uniform().max(1e-300);
        let u2 = self.uniform();
        (-2.0 * u1.ln()).sqrt() * (std::f64::consts::TAU * u2).cos()
    }
}

/// A target following the fiducial convention: d = 4 % of the short side, centred d in.
pub fn test_target(w: f64, h: f64) -> Target {
    let d = 0.04 * w.min(h);
    let fid = |id: &str, x: f64, y: f64, kind| Fiducial {
        id: id.into(),
        x_mm: x,
        y_mm: y,
        diameter_mm: d,
        kind,
    };
    let sweep = |id: &str, y: f64, law, f1| Sweep {
        id: id.into(),
        rect: Rect {
            x_mm: 0.1 * w,
            y_mm: y,
            width_mm: 0.8 * w,
            height_mm: 0.2 * h,
        },
        direction: Direction::X,
        law,
        f_min_cy_mm: 0.2,
        f_max_cy_mm: f1,
        mean: 0.5,
        contrast: 0.8,
    };
    let refl = [0.02, 0.1, 0.2, 0.35, 0.55, 0.8];
    let pw = 0.8 * w / refl.len() as f64;
    Target {
        name: "locate-test".into(),
        width_mm: w,
        height_mm: h,
        background: 1.0,
        sweeps: vec![
            sweep("log", 0.14 * h, SweepLaw::Log, 10.0),
            sweep("lin", 0.38 * h, SweepLaw::Linear, 5.0),
        ],
        patches: vec![],
        greys: refl
            .iter()
            .enumerate()
            .map(|(i, &r)| GreyPatch {
                id: format!("g{i}"),
                rect: Rect {
                    x_mm: 0.1 * w + i as f64 * pw,
                    y_mm: 0.64 * h,
                    width_mm: pw,
                    height_mm: 0.2 * h,
                },
                reflectance: r,
                density: None,
            })
            .collect(),
        fiducials: vec![
            fid("tl", d, d, FiducialKind::Ring),
            fid("tr", w - d, d, FiducialKind::Disk),
            fid("br", w - d, h - d, FiducialKind::Disk),
            fid("bl", d, h - d, FiducialKind::Disk),
        ],
    }
}

/// How a shot is rendered.
#[derive(Debug, Clone)]
pub struct Look {
    /// Gaussian blur σ (px); 0 = none.
    pub blur_px: f64,
    /// Vignetting: relative fall-off at the frame corner.
    pub vignette: f64,
    /// Linear light gradient across the frame (x, y), relative.
    pub gradient: [f64; 2],
    /// White level (linear).
    pub gain: f64,
    /// Read noise σ and shot-noise factor (σ = read + shot·√v).
    pub noise: [f64; 2],
    /// Scene reflectance outside the target frame.
    pub surround: f64,
    /// Dark distractor shapes (centre px, radius px, square?).
    pub distractors: Vec<(Point, f64, bool)>,
    /// Chart regions painted over with surround (occluders, target mm rect).
    pub occluders: Vec<[f64; 4]>,
    /// Supersampling per axis.
    pub supersample: usize,
}

impl Default for Look {
    fn default() -> Self {
        Look {
            blur_px: 0.7,
            vignette: 0.0,
            gradient: [0.0, 0.0],
            gain: 0.9,
            noise: [0.0, 0.0],
            surround: 0.3,
            distractors: vec![],
            occluders: vec![],
            supersample: 2,
        }
    }
}

/// Renders targets (each with its target→image homography) into a w×h linear plane.
pub fn render(
    targets: &[(&Target, Homography)],
    w: usize,
    h: usize,
    look: &Look,
    rng: &mut Rng,
) -> Plane {
    let invs: Vec<(&Target, Homography)> = targets
        .iter()
        .map(|(t, hh)| (*t, hh.inverse().unwrap()))
        .collect();
    let n = look.supersample.max(1);
    let mut img = vec![0.0f64; w * h];
    for j in 0..h {
        for i in 0..w {
            let mut acc = 0.0;
            for b in 0..n {
                for a in 0..n {
                    let p = [
                        i as f64 + (a as f64 + 0.5) / n as f64,
                        j as f64 + (b as f64 + 0.5) / n as f64,
                    ];
                    acc += scene(&invs, look, p);
                }
            }
            img[j * w + i] = acc / (n * n) as f64;
        }
    }
    if look.blur_px > 0.0 {
        img = blur(&img, w, h, look.blur_px);
    }
    let (cx, cy) = (w as f64 / 2.0, h as f64 / 2.0);
    let r2 = cx * cx + cy * cy;
    let data = img
        .iter()
        .enumerate()
        .map(|(k, &v)| {
            let (x, y) = ((k % w) as f64 + 0.5, (k / w) as f64 + 0.5);
            let rr = ((x - cx).powi(2) + (y - cy).powi(2)) / r2;
            let illum = look.gain
                * (1.0 - look.vignette * rr)
                * (1.0
                    + look.gradient[0] * (x / w as f64 - 0.5)
                    + look.gradient[1] * (y / h as f64 - 0.5));
            let s = v * illum;
            let sd = look.noise[0] + look.noise[1] * s.max(0.0).sqrt();
            (s + sd * rng.normal()).clamp(0.0, 1.0) as f32
        })
        .collect();
    Plane::full(w, h, data)
}

fn scene(invs: &[(&Target, Homography)], look: &Look, p: Point) -> f64 {
    for &(t, inv) in invs {
        let q = inv.apply(p);
        if q[0] >= 0.0 && q[1] >= 0.0 && q[0] < t.width_mm && q[1] < t.height_mm {
            if look
                .occluders
                .iter()
                .any(|o| q[0] >= o[0] && q[1] >= o[1] && q[0] < o[0] + o[2] && q[1] < o[1] + o[3])
            {
                return look.surround;
            }
            return t.reflectance(q[0], q[1]);
        }
    }
    for &(c, r, square) in &look.distractors {
        let (dx, dy) = ((p[0] - c[0]).abs(), (p[1] - c[1]).abs());
        let inside = if square {
            dx < r && dy < r
        } else {
            dx.hypot(dy) < r
        };
        if inside {
            return 0.03;
        }
    }
    look.surround
}

fn blur(img: &[f64], w: usize, h: usize, sigma: f64) -> Vec<f64> {
    let r = (3.0 * sigma).ceil() as i64;
    let k: Vec<f64> = (-r..=r)
        .map(|i| (-(i * i) as f64 / (2.0 * sigma * sigma)).exp())
        .collect();
    let ks: f64 = k.iter().sum();
    let k: Vec<f64> = k.iter().map(|v| v / ks).collect();
    let mut tmp = vec![0.0; w * h];
    for j in 0..h {
        for i in 0..w {
            let mut a = 0.0;
            for (t, kv) in k.iter().enumerate() {
                let ii = (i as i64 + t as i64 - r).clamp(0, w as i64 - 1) as usize;
                a += kv * img[j * w + ii];
            }
            tmp[j * w + i] = a;
        }
    }
    let mut out = vec![0.0; w * h];
    for j in 0..h {
        for i in 0..w {
            let mut a = 0.0;
            for (t, kv) in k.iter().enumerate() {
                let jj = (j as i64 + t as i64 - r).clamp(0, h as i64 - 1) as usize;
                a += kv * tmp[jj * w + i];
            }
            out[j * w + i] = a;
        }
    }
    out
}

/// A random camera pose: roll any, tilt up to `max_tilt_deg` about a random in-plane
/// axis, camera 1–3 chart diagonals away; the projected chart is scaled so its area is
/// `coverage` of the frame's (or as large as fits) and placed at random.
pub fn random_pose(
    t: &Target,
    w: usize,
    h: usize,
    max_tilt_deg: f64,
    coverage: f64,
    rng: &mut Rng,
) -> Homography {
    let (cw, ch) = (t.width_mm, t.height_mm);
    let diag = cw.hypot(ch);
    let tilt = rng.range(0.0, max_tilt_deg).to_radians();
    let phi = rng.range(0.0, std::f64::consts::TAU);
    let roll = rng.range(0.0, std::f64::consts::TAU);
    let dist = diag * rng.range(1.0, 3.0);
    // Rotation about the in-plane axis (cos φ, sin φ, 0) by tilt (Rodrigues), then roll about z.
    let (ax, ay) = (phi.cos(), phi.sin());
    let (c, s) = (tilt.cos(), tilt.sin());
    let rot = |p: [f64; 3]| -> [f64; 3] {
        // v cosθ + (k×v) sinθ + k(k·v)(1−cosθ), k = (ax, ay, 0)
        let kv = ax * p[0] + ay * p[1];
        let cross = [ay * p[2], -ax * p[2], ax * p[1] - ay * p[0]];
        let v = [
            p[0] * c + cross[0] * s + ax * kv * (1.0 - c),
            p[1] * c + cross[1] * s + ay * kv * (1.0 - c),
            p[2] * c + cross[2] * s,
        ];
        let (cr, sr) = (roll.cos(), roll.sin());
        [cr * v[0] - sr * v[1], sr * v[0] + cr * v[1], v[2]]
    };
    let src = rect_corners(0.0, 0.0, cw, ch);
    let proj: Vec<Point> = src
        .iter()
        .map(|p| {
            let q = rot([p[0] - cw / 2.0, p[1] - ch / 2.0, 0.0]);
            let z = q[2] + dist;
            [q[0] / z, q[1] / z]
        })
        .collect();
    let (minx, maxx) = minmax(proj.iter().map(|p| p[0]));
    let (miny, maxy) = minmax(proj.iter().map(|p| p[1]));
    // `coverage` is the chart's area as a fraction of the frame's, capped where it fits.
    let area: f64 = (0..4)
        .map(|i| {
            let (a, b) = (proj[i], proj[(i + 1) % 4]);
            a[0] * b[1] - a[1] * b[0]
        })
        .sum::<f64>()
        .abs()
        / 2.0;
    let fit = 0.98 * (w as f64 / (maxx - minx)).min(h as f64 / (maxy - miny));
    let scale = (coverage * (w * h) as f64 / area).sqrt().min(fit);
    let bw = (maxx - minx) * scale;
    let bh = (maxy - miny) * scale;
    let ox = rng.range(0.0, (w as f64 - bw).max(0.0));
    let oy = rng.range(0.0, (h as f64 - bh).max(0.0));
    let dst: Vec<Point> = proj
        .iter()
        .map(|p| [ox + (p[0] - minx) * scale, oy + (p[1] - miny) * scale])
        .collect();
    Homography::from_quads(&src, &[dst[0], dst[1], dst[2], dst[3]]).unwrap()
}

fn minmax(it: impl Iterator<Item = f64>) -> (f64, f64) {
    it.fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), v| {
        (a.min(v), b.max(v))
    })
}

/// The target frame's corners in the image under `h`.
pub fn true_corners(t: &Target, h: &Homography) -> [Point; 4] {
    rect_corners(0.0, 0.0, t.width_mm, t.height_mm).map(|p| h.apply(p))
}

/// Decodes an 8-bit sRGB photo to a linear luminance plane.
pub fn load_linear_luma(path: &str) -> Plane {
    let img = image::open(path).expect("decode").to_rgb8();
    let lin = |v: u8| {
        let c = v as f64 / 255.0;
        if c <= 0.04045 {
            c / 12.92
        } else {
            ((c + 0.055) / 1.055).powf(2.4)
        }
    };
    let data = img
        .pixels()
        .map(|p| (0.2126 * lin(p[0]) + 0.7152 * lin(p[1]) + 0.0722 * lin(p[2])) as f32)
        .collect();
    Plane::full(img.width() as usize, img.height() as usize, data)
}

/// Writes a linear plane as an sRGB-ish PNG (for looking at).
pub fn save_plane(p: &Plane, path: &std::path::Path) {
    let img = image::GrayImage::from_fn(p.width as u32, p.height as u32, |i, j| {
        image::Luma([
            ((p.get(i as usize, j as usize).clamp(0.0, 1.0) as f64).powf(1.0 / 2.2) * 255.0) as u8,
        ])
    });
    img.save(path).unwrap();
}
