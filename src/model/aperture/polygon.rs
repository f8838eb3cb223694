//! Any simple polygon as a detector aperture: the exact Fourier transform of
//! its indicator, evaluated stably everywhere (after J. Wuttke, J. Appl. Cryst.
//! 54 (2021) 580–587).
//!
//! With q = 2π(u, v), vertices rⱼ taken relative to the bounding-box centre c
//! and R = max |rⱼ|:
//! - |q|R ≤ 4: the moment series F = Σₙ (−i)ⁿ·2/(n+2)!·Σⱼ Aⱼ·hₙ(q·rⱼ, q·rⱼ₊₁),
//!   Aⱼ = (rⱼ × rⱼ₊₁)/2 the signed fan triangles and hₙ(x, y) = Σₐ xᵃyⁿ⁻ᵃ;
//!   no division by q, so nothing cancels as q → 0;
//! - otherwise the edge sum F = i/(2π|f|) Σⱼ (f̂ × eⱼ)·e^(−i2πf·mⱼ)·sinc(f·eⱼ)
//!   with eⱼ the edge vector and mⱼ its midpoint, sinc stable where f·eⱼ → 0.
//!
//! The result is multiplied by e^(−i2πf·c) and divided by the area.

use super::guard::{FAR, LENGTH_RANGE_MM};
use crate::model::special::{sinc, sincospi};
use crate::model::{Factor, ModelError};
use num_complex::Complex64;
use std::f64::consts::PI;

const NAME: &str = "aperture polygon";
/// |q|·R up to which the moment series is used.
const SERIES_QR: f64 = 4.0;
/// Highest moment order kept (enough for 1e-18 at |q|R = 4).
const SERIES_N: usize = 44;

/// A simple polygon (mm), stored counter-clockwise relative to its bounding-box centre.
#[derive(Debug, Clone)]
pub struct Polygon {
    verts: Vec<[f64; 2]>,
    centre: [f64; 2],
    area: f64,
    r_max: f64,
    size: f64,
}

fn err(message: String) -> ModelError {
    ModelError::Parameter {
        factor: NAME.into(),
        message,
    }
}

fn cross(a: [f64; 2], b: [f64; 2]) -> f64 {
    a[0] * b[1] - a[1] * b[0]
}

fn sub(a: [f64; 2], b: [f64; 2]) -> [f64; 2] {
    [a[0] - b[0], a[1] - b[1]]
}

/// Orientation of c relative to the line a→b: +1 left, −1 right, 0 collinear.
fn orient(a: [f64; 2], b: [f64; 2], c: [f64; 2]) -> i8 {
    let x = cross(sub(b, a), sub(c, a));
    if x > 0.0 {
        1
    } else if x < 0.0 {
        -1
    } else {
        0
    }
}

/// Whether c (collinear with a–b) lies on the closed segment a–b.
fn on_segment(a: [f64; 2], b: [f64; 2], c: [f64; 2]) -> bool {
    c[0] >= a[0].min(b[0])
        && c[0] <= a[0].max(b[0])
        && c[1] >= a[1].min(b[1])
        && c[1] <= a[1].max(b[1])
}

/// Whether the closed segments p1–p2 and p3–p4 share a point.
fn segments_touch(p1: [f64; 2], p2: [f64; 2], p3: [f64; 2], p4: [f64; 2]) -> bool {
    let d1 = orient(p3, p4, p1);
    let d2 = orient(p3, p4, p2);
    let d3 = orient(p1, p2, p3);
    let d4 = orient(p1, p2, p4);
    if d1 * d2 < 0 && d3 * d4 < 0 {
        return true;
    }
    (d1 == 0 && on_segment(p3, p4, p1))
        || (d2 == 0 && on_segment(p3, p4, p2))
        || (d3 == 0 && on_segment(p1, p2, p3))
        || (d4 == 0 && on_segment(p1, p2, p4))
}

impl Polygon {
    /// A simple polygon from its vertices (mm) in either orientation; a closing
    /// vertex equal to the first is dropped. Rejects fewer than 3 vertices,
    /// non-finite or out-of-range coordinates, repeated vertices, zero area and
    /// self-intersection (including edges that touch or fold back).
    pub fn new(vertices_mm: Vec<[f64; 2]>) -> Result<Polygon, ModelError> {
        let mut v = vertices_mm;
        if v.len() > 1 && v.first() == v.last() {
            v.pop();
        }
        let n = v.len();
        if n < 3 {
            return Err(err(format!("needs at least 3 vertices, got {n}")));
        }
        let hi = LENGTH_RANGE_MM.1;
        if let Some((i, p)) = v.iter().enumerate().find(|(_, p)| {
            !(p[0].is_finite() && p[1].is_finite() && p[0].abs() <= hi && p[1].abs() <= hi)
        }) {
            return Err(err(format!(
                "vertex {} ({} mm, {} mm) is not a finite coordinate within ±1 km",
                i + 1,
                p[0],
                p[1]
            )));
        }
        for i in 0..n {
            for j in i + 1..n {
                if v[i] == v[j] {
                    return Err(err(format!(
                        "vertices {} and {} are the same point ({} mm, {} mm)",
                        i + 1,
                        j + 1,
                        v[i][0],
                        v[i][1]
                    )));
                }
            }
        }
        // self-intersection: non-adjacent edges must not touch, adjacent ones
        // must meet only at their shared vertex
        for i in 0..n {
            let (a, b) = (v[i], v[(i + 1) % n]);
            for j in i + 1..n {
                let (c, d) = (v[j], v[(j + 1) % n]);
                let adjacent = j == i + 1 || (i == 0 && j == n - 1);
                if adjacent {
                    // shared vertex s, other ends p (edge i) and q (edge j)
                    let (s, p, q) = if j == i + 1 { (b, a, d) } else { (a, b, c) };
                    let e1 = sub(p, s);
                    let e2 = sub(q, s);
                    if cross(e1, e2) == 0.0 && e1[0] * e2[0] + e1[1] * e2[1] > 0.0 {
                        return Err(err(format!(
                            "self-intersecting: edges {} and {} fold back onto each other",
                            i + 1,
                            j + 1
                        )));
                    }
                } else if segments_touch(a, b, c, d) {
                    return Err(err(format!(
                        "self-intersecting: edge {} ({} {} → {} {} mm) meets edge {} ({} {} → {} {} mm)",
                        i + 1,
                        a[0],
                        a[1],
                        b[0],
                        b[1],
                        j + 1,
                        c[0],
                        c[1],
                        d[0],
                        d[1]
                    )));
                }
            }
        }
        let (mut x0, mut x1, mut y0, mut y1) = (f64::MAX, f64::MIN, f64::MAX, f64::MIN);
        for p in &v {
            x0 = x0.min(p[0]);
            x1 = x1.max(p[0]);
            y0 = y0.min(p[1]);
            y1 = y1.max(p[1]);
        }
        let centre = [0.5 * (x0 + x1), 0.5 * (y0 + y1)];
        let mut verts: Vec<[f64; 2]> = v.iter().map(|p| sub(*p, centre)).collect();
        let twice: f64 = (0..n).map(|i| cross(verts[i], verts[(i + 1) % n])).sum();
        let box_area = (x1 - x0) * (y1 - y0);
        if twice.abs() <= 1e-12 * box_area || twice.abs() * 0.5 < LENGTH_RANGE_MM.0.powi(2) {
            return Err(err(format!(
                "has (near) zero area ({} mm²)",
                0.5 * twice.abs()
            )));
        }
        if twice < 0.0 {
            verts.reverse();
        }
        let area = 0.5 * twice.abs();
        let perimeter: f64 = (0..n)
            .map(|i| {
                let e = sub(verts[(i + 1) % n], verts[i]);
                e[0].hypot(e[1])
            })
            .sum();
        let r_max = verts.iter().map(|p| p[0].hypot(p[1])).fold(0.0, f64::max);
        Ok(Polygon {
            verts,
            centre,
            area,
            r_max,
            size: area / perimeter,
        })
    }

    /// The area, mm².
    pub fn area(&self) -> f64 {
        self.area
    }

    /// The vertices (mm), counter-clockwise, in the frame given to [`Polygon::new`].
    pub fn vertices_mm(&self) -> Vec<[f64; 2]> {
        self.verts
            .iter()
            .map(|p| [p[0] + self.centre[0], p[1] + self.centre[1]])
            .collect()
    }

    /// ∬ exp(−i q·r) over the centred polygon by the moment series (|q|R ≤ 4).
    fn series(&self, u: f64, v: f64) -> Complex64 {
        let qx = 2.0 * PI * u;
        let qy = 2.0 * PI * v;
        let n = self.verts.len();
        let mut s = [0.0f64; SERIES_N + 1];
        let qr = qx.hypot(qy) * self.r_max;
        // terms fall like (qR)^n·2(n+1)/(n+2)!; stop once below 1e-19
        let mut n_max = SERIES_N;
        let mut t = 2.0;
        for k in 1..=SERIES_N {
            t *= qr / (k as f64 + 2.0);
            if t * (k as f64 + 1.0) < 1e-19 {
                n_max = k;
                break;
            }
        }
        // edges in chunks of LANES so the hₙ recurrences of different edges
        // run side by side instead of one long dependency chain
        const LANES: usize = 8;
        let mut j0 = 0;
        while j0 < n {
            let m = LANES.min(n - j0);
            let mut tri = [0.0f64; LANES];
            let mut x = [0.0f64; LANES];
            let mut y = [0.0f64; LANES];
            for l in 0..m {
                let a = self.verts[j0 + l];
                let b = self.verts[(j0 + l + 1) % n];
                tri[l] = 0.5 * cross(a, b);
                x[l] = qx * a[0] + qy * a[1];
                y[l] = qx * b[0] + qy * b[1];
            }
            let mut h = [1.0f64; LANES];
            let mut ypow = [1.0f64; LANES];
            s[0] += tri.iter().sum::<f64>();
            for sk in s.iter_mut().take(n_max + 1).skip(1) {
                let mut acc = 0.0;
                for l in 0..LANES {
                    ypow[l] *= y[l];
                    h[l] = x[l] * h[l] + ypow[l];
                    acc += tri[l] * h[l];
                }
                *sk += acc;
            }
            j0 += m;
        }
        // Σ (−i)^n · 2/(n+2)! · S_n
        let mut re = 0.0;
        let mut im = 0.0;
        let mut c = 1.0; // 2/(n+2)!
        for (k, sk) in s.iter().enumerate().take(n_max + 1) {
            if k > 0 {
                c /= k as f64 + 2.0;
            }
            let term = c * sk;
            match k % 4 {
                0 => re += term,
                1 => im -= term,
                2 => re -= term,
                _ => im += term,
            }
        }
        Complex64::new(re, im)
    }

    /// ∬ exp(−i2π f·r) over the centred polygon by the edge sum (|q|R > 4), f = |(u, v)|.
    fn edges(&self, u: f64, v: f64, f: f64) -> Complex64 {
        let (fx, fy) = (u / f, v / f);
        let n = self.verts.len();
        // zⱼ = e^(iπ f·rⱼ), one sincospi per vertex; the edge phase
        // e^(−i2π f·m) = conj(zₐ·z_b) and, where |f·e| ≥ 1/4, the sinc numerator
        // sin(π f·e) = Im(z_b·conj zₐ) come from products (no cancellation there)
        let phase = |p: [f64; 2]| u * p[0] + v * p[1];
        let p0 = phase(self.verts[0]);
        let (s0, c0) = sincospi(p0);
        let (mut pa, mut sa, mut ca) = (p0, s0, c0);
        let mut re = 0.0;
        let mut im = 0.0;
        for j in 0..n {
            let a = self.verts[j];
            let (pb, sb, cb) = if j + 1 == n {
                (p0, s0, c0)
            } else {
                let pb = phase(self.verts[j + 1]);
                let (sb, cb) = sincospi(pb);
                (pb, sb, cb)
            };
            let b = self.verts[(j + 1) % n];
            let e = sub(b, a);
            let t = pb - pa;
            let sinc_fe = if t.abs() >= 0.25 {
                (sb * ca - cb * sa) / (PI * t)
            } else {
                sinc(u * e[0] + v * e[1])
            };
            let w = (fx * e[1] - fy * e[0]) * sinc_fe;
            // e^(−iπ(pₐ+p_b)) = conj(zₐ z_b)
            let c = ca * cb - sa * sb;
            let s = sa * cb + ca * sb;
            re += w * c;
            im -= w * s;
            (pa, sa, ca) = (pb, sb, cb);
        }
        // multiply by i/(2π f)
        let k = 1.0 / (2.0 * PI * f);
        Complex64::new(-im * k, re * k)
    }
}

impl Factor for Polygon {
    fn name(&self) -> String {
        "aperture_polygon".into()
    }

    fn otf(&self, u: f64, v: f64) -> Complex64 {
        let f = u.hypot(v);
        if f * self.size > FAR || f * self.r_max > FAR {
            return Complex64::new(0.0, 0.0);
        }
        let raw = if 2.0 * PI * f * self.r_max <= SERIES_QR {
            self.series(u, v)
        } else {
            self.edges(u, v, f)
        };
        let phase = 2.0 * (u * self.centre[0] + v * self.centre[1]);
        let (s, c) = sincospi(phase);
        let shift = Complex64::new(c, -s);
        raw * shift / self.area
    }
}

/// Reads one coordinate: a bare number is µm, otherwise a length with a unit. Returns mm.
fn coordinate(text: &str, what: &str) -> Result<f64, ModelError> {
    let t = text.trim();
    if let Ok(x) = t.parse::<f64>()
        && x.is_finite()
    {
        return Ok(x * 1e-3);
    }
    crate::units::parse_length_mm(t).map_err(|e| err(format!("{what}: {e}")))
}

/// Parses `x1 y1;x2 y2;…` (µm, or with units) or `@file.csv` (columns x_um,y_um, header optional).
pub fn parse_vertices(text: &str) -> Result<Polygon, ModelError> {
    let text = text.trim();
    if let Some(path) = text.strip_prefix('@') {
        return Polygon::new(read_csv(path.trim())?);
    }
    let mut verts = Vec::new();
    for (i, item) in text.split(';').map(str::trim).enumerate() {
        if item.is_empty() {
            continue;
        }
        let parts: Vec<&str> = item
            .split(|c: char| c.is_whitespace() || c == ',')
            .filter(|s| !s.is_empty())
            .collect();
        if parts.len() != 2 {
            return Err(err(format!(
                "vertex {} '{item}' is not 'x y' (µm, e.g. polygon:0 0;5 0;0 5)",
                i + 1
            )));
        }
        let what = format!("vertex {}", i + 1);
        verts.push([coordinate(parts[0], &what)?, coordinate(parts[1], &what)?]);
    }
    Polygon::new(verts)
}

/// Reads vertices (µm) from a CSV file with columns x_um,y_um; returns mm.
fn read_csv(path: &str) -> Result<Vec<[f64; 2]>, ModelError> {
    let file_err = |cause: String| ModelError::File {
        path: path.to_string(),
        cause,
    };
    let mut reader = csv::ReaderBuilder::new()
        .has_headers(false)
        .trim(csv::Trim::All)
        .comment(Some(b'#'))
        .flexible(true)
        .from_path(path)
        .map_err(|e| file_err(e.to_string()))?;
    let mut verts = Vec::new();
    let mut cols = (0usize, 1usize);
    for (line, rec) in reader.records().enumerate() {
        let rec = rec.map_err(|e| file_err(e.to_string()))?;
        if rec.iter().all(|f| f.is_empty()) {
            continue;
        }
        if line == 0 && rec.get(0).is_some_and(|f| f.parse::<f64>().is_err()) {
            let find = |name: &str| rec.iter().position(|f| f == name);
            cols = match (find("x_um"), find("y_um")) {
                (Some(x), Some(y)) => (x, y),
                _ => {
                    return Err(file_err(format!(
                        "header must name the columns x_um,y_um, got '{}'",
                        rec.iter().collect::<Vec<_>>().join(",")
                    )));
                }
            };
            continue;
        }
        let get = |c: usize| -> Result<f64, ModelError> {
            let f = rec.get(c).unwrap_or("");
            match f.parse::<f64>() {
                Ok(x) if x.is_finite() => Ok(x * 1e-3),
                _ => Err(file_err(format!(
                    "line {}: '{f}' is not a number (µm)",
                    line + 1
                ))),
            }
        };
        verts.push([get(cols.0)?, get(cols.1)?]);
    }
    Ok(verts)
}
