//! The optical renderer: linear irradiance at every pixel centre of the chart
//! seen through the system's OTF and the pixel aperture.
//!
//! Method (per tile, tiles overlapping by `margin_px`): sample the chart's
//! reflectance at `k = oversample` points per pixel and axis in image space
//! (each fine point undistorted by the camera's lens model, when it has one,
//! and mapped to the chart through the inverse homography; the
//! fine grid contains every pixel centre), take the 2-D real FFT, multiply by
//! the presampling OTF — system factors × pixel aperture — at the fine grid's
//! frequencies (cycles/pixel → cycles/mm through the pitch; image y points
//! down, the model's v up, so v = −f_y/pitch), inverse-transform, and keep the
//! values at pixel centres inside the tile's core. Band-limited content below
//! `k/2` cy/px (the sines) is transferred exactly. Fine cells crossed by a hard
//! edge (fiducials, patch borders: the region id differs between the cell's
//! corners) are area-sampled with `edge_subsamples`² N-rooks sub-samples; what
//! remains is the fine grid's aliasing of the edge (≈ 1.5 % of the step at
//! k = 2, 0.3 % at k = 4: see the README's table).
//! Memory is bounded by the tile size: a few MB per worker thread.

use super::{Camera, PixelAperture, SimError};
use crate::geometry::Homography;
use crate::model::System;
use crate::target::Target;
use num_complex::Complex64;
use rayon::prelude::*;
use realfft::{ComplexToReal, RealFftPlanner, RealToComplex};
use rustfft::{Fft, FftPlanner};
use std::f64::consts::PI;
use std::sync::Arc;

/// sin(πx)/(πx), with its limit 1 at x = 0.
pub fn sinc(x: f64) -> f64 {
    if x.abs() < 1e-8 {
        1.0 - (PI * x).powi(2) / 6.0
    } else {
        (PI * x).sin() / (PI * x)
    }
}

/// The presampling OTF the simulator applies: the system's non-sampling
/// factors, and the square pixel aperture when it applies.
#[derive(Debug)]
pub struct Optics<'a> {
    system: &'a System,
    /// Which factors are applied (sampling-grid factors are not: the simulator samples for real).
    used: Vec<bool>,
    /// Whether the 100 % fill-factor square pixel aperture is applied.
    pub square_pixel: bool,
    /// Pixel pitch, mm.
    pub pitch_mm: f64,
}

impl<'a> Optics<'a> {
    /// Decides which factors apply: a factor defining a sampling pitch (`nyquist()`)
    /// and not named as an aperture is the sampling-grid MTF, skipped because the
    /// simulator really samples; the square pixel aperture applies per `camera.pixel_aperture`.
    pub fn new(system: &'a System, camera: &Camera) -> Optics<'a> {
        let is_aperture = |name: &str| name.to_ascii_lowercase().contains("aperture");
        let used: Vec<bool> = system
            .factors
            .iter()
            .map(|f| is_aperture(&f.name()) || f.nyquist().is_none())
            .collect();
        let has_aperture = system
            .factors
            .iter()
            .zip(&used)
            .any(|(f, u)| *u && is_aperture(&f.name()));
        let square_pixel = match camera.pixel_aperture {
            PixelAperture::Auto => !has_aperture,
            PixelAperture::Square => true,
            PixelAperture::None => false,
        };
        Optics {
            system,
            used,
            square_pixel,
            pitch_mm: camera.pitch_mm(),
        }
    }

    /// Names of the factors applied (plus "pixel" for the square pixel aperture).
    pub fn applied(&self) -> Vec<String> {
        let mut v: Vec<String> = self
            .system
            .factors
            .iter()
            .zip(&self.used)
            .filter(|(_, u)| **u)
            .map(|(f, _)| f.name())
            .collect();
        if self.square_pixel {
            v.push("pixel".into());
        }
        v
    }

    /// Names of the factors skipped (sampling-grid factors).
    pub fn skipped(&self) -> Vec<String> {
        self.system
            .factors
            .iter()
            .zip(&self.used)
            .filter(|(_, u)| !**u)
            .map(|(f, _)| f.name())
            .collect()
    }

    /// Presampling OTF at image frequency (fx right, fy down), cycles/pixel.
    pub fn otf_cy_px(&self, fx: f64, fy: f64) -> Complex64 {
        let (u, v) = (fx / self.pitch_mm, -fy / self.pitch_mm);
        let mut h = self
            .system
            .factors
            .iter()
            .zip(&self.used)
            .filter(|(_, u)| **u)
            .fold(Complex64::new(1.0, 0.0), |acc, (f, _)| acc * f.otf(u, v));
        if self.square_pixel {
            h *= sinc(fx) * sinc(fy);
        }
        h
    }
}

/// FFT plans and the OTF on the fine grid, shared by all tiles.
struct Plan {
    n: usize,
    nc: usize,
    k: usize,
    margin: usize,
    tile: usize,
    r2c: Arc<dyn RealToComplex<f64>>,
    c2r: Arc<dyn ComplexToReal<f64>>,
    fwd: Arc<dyn Fft<f64>>,
    inv: Arc<dyn Fft<f64>>,
    /// OTF × 1/n², row-major n rows (fy) × nc columns (fx ≥ 0).
    otf: Vec<Complex64>,
}

/// One worker's buffers.
struct Scratch {
    real: Vec<f64>,
    spec: Vec<Complex64>,
    col: Vec<Complex64>,
    row: Vec<f64>,
    fft_scratch: Vec<Complex64>,
    /// Region ids on the fine-cell corners above and below the current row (n + 1 each).
    ids: Vec<u32>,
    ids_below: Vec<u32>,
}

impl Plan {
    fn new(optics: &Optics, camera: &Camera) -> Plan {
        let r = camera.render;
        let n = r.fft_size + r.fft_size % 2;
        let nc = n / 2 + 1;
        let k = r.oversample;
        let mut rp = RealFftPlanner::<f64>::new();
        let mut cp = FftPlanner::<f64>::new();
        let df = k as f64 / n as f64; // fine-grid frequency step, cy/px
        let norm = 1.0 / (n * n) as f64;
        let mut otf = vec![Complex64::new(0.0, 0.0); n * nc];
        for j in 0..n {
            let fy = if j <= n / 2 {
                j as f64
            } else {
                j as f64 - n as f64
            } * df;
            for i in 0..nc {
                otf[j * nc + i] = optics.otf_cy_px(i as f64 * df, fy) * norm;
            }
        }
        Plan {
            n,
            nc,
            k,
            margin: r.margin_px,
            tile: (n / k).saturating_sub(2 * r.margin_px).max(1),
            r2c: rp.plan_fft_forward(n),
            c2r: rp.plan_fft_inverse(n),
            fwd: cp.plan_fft_forward(n),
            inv: cp.plan_fft_inverse(n),
            otf,
        }
    }

    fn scratch(&self) -> Scratch {
        let len = self
            .r2c
            .get_scratch_len()
            .max(self.c2r.get_scratch_len())
            .max(self.fwd.get_inplace_scratch_len())
            .max(self.inv.get_inplace_scratch_len());
        Scratch {
            real: vec![0.0; self.n * self.n],
            spec: vec![Complex64::new(0.0, 0.0); self.n * self.nc],
            col: vec![Complex64::new(0.0, 0.0); self.n],
            row: vec![0.0; self.n],
            fft_scratch: vec![Complex64::new(0.0, 0.0); len],
            ids: vec![0; self.n + 1],
            ids_below: vec![0; self.n + 1],
        }
    }
}

/// What the renderer samples: the chart's reflectance at image points.
struct Scene<'a> {
    target: &'a Target,
    image_to_chart: Homography,
    /// Lens distortion: photo points are undistorted before the homography.
    lens: Option<crate::distortion::Lens>,
    surround: f64,
    /// Sub-samples per fine-cell side where a cell straddles a region boundary.
    edge_subsamples: usize,
    /// The print's own MTF applied to the chart's sines (`None`: a perfect print).
    print: Option<crate::print_mtf::PrintMtf>,
}

impl Scene<'_> {
    #[inline]
    fn chart(&self, x: f64, y: f64) -> (f64, f64) {
        let (x, y) = match &self.lens {
            Some(l) => {
                let p = l.undistort([x, y]);
                (p[0], p[1])
            }
            None => (x, y),
        };
        let m = &self.image_to_chart.m;
        let w = m[6] * x + m[7] * y + m[8];
        (
            (m[0] * x + m[1] * y + m[2]) / w,
            (m[3] * x + m[4] * y + m[5]) / w,
        )
    }

    #[inline]
    fn inside(&self, cx: f64, cy: f64) -> bool {
        cx >= 0.0 && cy >= 0.0 && cx < self.target.width_mm && cy < self.target.height_mm
    }

    /// Reflectance at image point (x, y): the target (as printed) inside its frame, the surround outside.
    #[inline]
    fn at(&self, x: f64, y: f64) -> f64 {
        let (cx, cy) = self.chart(x, y);
        if !self.inside(cx, cy) {
            self.surround
        } else if let Some(p) = &self.print {
            self.target.reflectance_printed(cx, cy, |f| p.transfer(f))
        } else {
            self.target.reflectance(cx, cy)
        }
    }

    /// Which piece of the chart's layout holds image point (x, y), in the
    /// painting order of `Target::reflectance`: equal ids on a cell's four
    /// corners mean no hard edge crosses it (regions are far wider than a cell).
    fn region(&self, x: f64, y: f64) -> u32 {
        let (cx, cy) = self.chart(x, y);
        if !self.inside(cx, cy) {
            return 0;
        }
        let t = self.target;
        for (i, f) in t.fiducials.iter().enumerate() {
            if let Some(v) = f.reflectance_at(cx, cy) {
                return 1_000 + 2 * i as u32 + (v > 0.5) as u32;
            }
        }
        if let Some(i) = t.sweeps.iter().position(|s| s.rect.contains(cx, cy)) {
            return 2_000 + i as u32;
        }
        if let Some(i) = t.patches.iter().position(|p| p.rect.contains(cx, cy)) {
            return 3_000 + i as u32;
        }
        if let Some(i) = t.greys.iter().position(|g| g.rect.contains(cx, cy)) {
            return 4_000 + i as u32;
        }
        1
    }

    /// Mean reflectance over the fine cell of side `h` centred on (x, y), by
    /// s² sub-samples on an N-rooks pattern (every sample in its own column and
    /// row stratum of s², so an axis-near edge's coverage is resolved to 1/s² of the cell).
    fn cell_mean(&self, x: f64, y: f64, h: f64) -> f64 {
        let s = self.edge_subsamples;
        let n2 = (s * s) as f64;
        let mut acc = 0.0;
        for b in 0..s {
            for a in 0..s {
                let u = (a * s + b) as f64 + 0.5;
                let v = (b * s + a) as f64 + 0.5;
                acc += self.at(x + h * (u / n2 - 0.5), y + h * (v / n2 - 0.5));
            }
        }
        acc / n2
    }
}

/// Renders one tile whose core starts at pixel (tx0, ty0) and is tw×th pixels.
fn render_tile(
    plan: &Plan,
    scene: &Scene,
    s: &mut Scratch,
    (tx0, ty0, tw, th): (usize, usize, usize, usize),
) -> Result<Vec<f32>, SimError> {
    let (n, nc, k, m) = (plan.n, plan.nc, plan.k, plan.margin);
    let step = 1.0 / k as f64;
    let x0 = tx0 as f64 - m as f64 + 0.5;
    let y0 = ty0 as f64 - m as f64 + 0.5;
    let fft_err = |e: realfft::FftError| SimError::Internal(format!("FFT failed: {e}"));
    for (j, (row, spec_row)) in s
        .real
        .chunks_exact_mut(n)
        .zip(s.spec.chunks_exact_mut(nc))
        .enumerate()
    {
        let y = y0 + j as f64 * step;
        if scene.edge_subsamples > 1 {
            // Region ids on the cell corners of this row: above (`s.ids`) and below.
            let corner_y = y + 0.5 * step;
            if j == 0 {
                for (i, id) in s.ids.iter_mut().enumerate() {
                    *id = scene.region(x0 + (i as f64 - 0.5) * step, y - 0.5 * step);
                }
            }
            for (i, id) in s.ids_below.iter_mut().enumerate() {
                *id = scene.region(x0 + (i as f64 - 0.5) * step, corner_y);
            }
            for (i, v) in row.iter_mut().enumerate() {
                let x = x0 + i as f64 * step;
                let a = s.ids[i];
                let edge = s.ids[i + 1] != a || s.ids_below[i] != a || s.ids_below[i + 1] != a;
                *v = if edge {
                    scene.cell_mean(x, y, step)
                } else {
                    scene.at(x, y)
                };
            }
            std::mem::swap(&mut s.ids, &mut s.ids_below);
        } else {
            for (i, v) in row.iter_mut().enumerate() {
                *v = scene.at(x0 + i as f64 * step, y);
            }
        }
        plan.r2c
            .process_with_scratch(row, spec_row, &mut s.fft_scratch)
            .map_err(fft_err)?;
    }
    // Rows of the fine grid holding pixel centres of the tile's core.
    let wanted = |r: usize| (m + r) * k;
    for i in 0..nc {
        for (j, c) in s.col.iter_mut().enumerate() {
            *c = s.spec[j * nc + i];
        }
        plan.fwd
            .process_with_scratch(&mut s.col, &mut s.fft_scratch);
        for (j, c) in s.col.iter_mut().enumerate() {
            *c *= plan.otf[j * nc + i];
        }
        plan.inv
            .process_with_scratch(&mut s.col, &mut s.fft_scratch);
        for r in 0..th {
            let j = wanted(r);
            s.spec[j * nc + i] = s.col[j];
        }
    }
    let mut out = vec![0f32; tw * th];
    for r in 0..th {
        let j = wanted(r);
        let spec_row = &mut s.spec[j * nc..(j + 1) * nc];
        spec_row[0].im = 0.0;
        if n % 2 == 0 {
            spec_row[nc - 1].im = 0.0;
        }
        plan.c2r
            .process_with_scratch(spec_row, &mut s.row, &mut s.fft_scratch)
            .map_err(fft_err)?;
        for (c, o) in out[r * tw..(r + 1) * tw].iter_mut().enumerate() {
            *o = s.row[wanted(c)] as f32;
        }
    }
    Ok(out)
}

/// The chart's reflectance blurred by `optics`, at every pixel centre (row-major, width × height).
pub fn render_reflectance(
    target: &Target,
    image_to_chart: Homography,
    optics: &Optics,
    camera: &Camera,
) -> Result<Vec<f32>, SimError> {
    let plan = Plan::new(optics, camera);
    let scene = Scene {
        target,
        image_to_chart,
        lens: camera.lens(),
        surround: camera.surround,
        edge_subsamples: camera.render.edge_subsamples,
        print: camera.print_blur,
    };
    let (w, h) = (camera.width_px, camera.height_px);
    let t = plan.tile;
    let tiles: Vec<(usize, usize, usize, usize)> = (0..h)
        .step_by(t)
        .flat_map(|ty| {
            (0..w)
                .step_by(t)
                .map(move |tx| (tx, ty, t.min(w - tx), t.min(h - ty)))
        })
        .collect();
    let blocks: Vec<Vec<f32>> = tiles
        .par_iter()
        .map_init(
            || plan.scratch(),
            |s, &tile| render_tile(&plan, &scene, s, tile),
        )
        .collect::<Result<_, _>>()?;
    let mut img = vec![0f32; w * h];
    for (&(tx, ty, tw, th), block) in tiles.iter().zip(&blocks) {
        for r in 0..th {
            img[(ty + r) * w + tx..(ty + r) * w + tx + tw]
                .copy_from_slice(&block[r * tw..(r + 1) * tw]);
        }
    }
    Ok(img)
}
