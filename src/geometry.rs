//! Plane projective geometry: the homography that maps the chart's own frame
//! (millimetres, origin top-left, x right, y down) to image pixels (origin at
//! the image's top-left corner, x right, y down; the top-left pixel's centre is
//! at 0.5, 0.5), and back.

use thiserror::Error;

/// A point in a plane (units depend on the frame: mm on a chart, px in an image).
pub type Point = [f64; 2];

/// Why a homography could not be built.
#[derive(Debug, Clone, PartialEq, Error)]
pub enum GeometryError {
    /// Three of the four points lie on one line (or two coincide).
    #[error("the four corners are degenerate (three are collinear or two coincide)")]
    Degenerate,
    /// The quadrilateral's edges cross each other.
    #[error("the four corners cross over (give them in order round the region)")]
    SelfCrossing,
    /// A coordinate is not finite.
    #[error("a corner coordinate is not a finite number")]
    NotFinite,
}

/// A 3×3 projective transform, row-major, normalised so that `m[8]` = 1 when possible.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Homography {
    /// Row-major matrix entries.
    pub m: [f64; 9],
}

impl Homography {
    /// The identity transform.
    pub fn identity() -> Self {
        Homography {
            m: [1.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0],
        }
    }

    /// The homography mapping each `src[i]` to `dst[i]` (four correspondences).
    pub fn from_quads(src: &[Point; 4], dst: &[Point; 4]) -> Result<Self, GeometryError> {
        check_quad(src)?;
        check_quad(dst)?;
        // Normalise both point sets for conditioning, solve the 8x8 DLT system.
        let (ts, sn) = normalise(src);
        let (td, dn) = normalise(dst);
        let mut a = [[0.0f64; 9]; 8];
        for i in 0..4 {
            let [x, y] = sn[i];
            let [u, v] = dn[i];
            a[2 * i] = [x, y, 1.0, 0.0, 0.0, 0.0, -u * x, -u * y, u];
            a[2 * i + 1] = [0.0, 0.0, 0.0, x, y, 1.0, -v * x, -v * y, v];
        }
        let h = solve8(a).ok_or(GeometryError::Degenerate)?;
        let hn = Homography {
            m: [h[0], h[1], h[2], h[3], h[4], h[5], h[6], h[7], 1.0],
        };
        // H = Td^-1 * Hn * Ts
        let full = td
            .inverse()
            .ok_or(GeometryError::Degenerate)?
            .compose(&hn)
            .compose(&ts);
        Ok(full.normalised())
    }

    /// Maps a point; returns non-finite values on the line at infinity.
    pub fn apply(&self, p: Point) -> Point {
        let m = &self.m;
        let w = m[6] * p[0] + m[7] * p[1] + m[8];
        [
            (m[0] * p[0] + m[1] * p[1] + m[2]) / w,
            (m[3] * p[0] + m[4] * p[1] + m[5]) / w,
        ]
    }

    /// The Jacobian d(dst)/d(src) at a point: [[dx/dX, dx/dY], [dy/dX, dy/dY]].
    pub fn jacobian(&self, p: Point) -> [[f64; 2]; 2] {
        let m = &self.m;
        let w = m[6] * p[0] + m[7] * p[1] + m[8];
        let x = (m[0] * p[0] + m[1] * p[1] + m[2]) / w;
        let y = (m[3] * p[0] + m[4] * p[1] + m[5]) / w;
        [
            [(m[0] - x * m[6]) / w, (m[1] - x * m[7]) / w],
            [(m[3] - y * m[6]) / w, (m[4] - y * m[7]) / w],
        ]
    }

    /// `self ∘ other`: first `other`, then `self`.
    pub fn compose(&self, other: &Homography) -> Homography {
        let a = &self.m;
        let b = &other.m;
        let mut m = [0.0; 9];
        for r in 0..3 {
            for c in 0..3 {
                m[3 * r + c] = (0..3).map(|k| a[3 * r + k] * b[3 * k + c]).sum();
            }
        }
        Homography { m }
    }

    /// The inverse transform, if the matrix is not singular.
    pub fn inverse(&self) -> Option<Homography> {
        let m = &self.m;
        let c00 = m[4] * m[8] - m[5] * m[7];
        let c01 = m[5] * m[6] - m[3] * m[8];
        let c02 = m[3] * m[7] - m[4] * m[6];
        let det = m[0] * c00 + m[1] * c01 + m[2] * c02;
        if !det.is_finite() || det.abs() < 1e-300 {
            return None;
        }
        let inv = [
            c00 / det,
            (m[2] * m[7] - m[1] * m[8]) / det,
            (m[1] * m[5] - m[2] * m[4]) / det,
            c01 / det,
            (m[0] * m[8] - m[2] * m[6]) / det,
            (m[2] * m[3] - m[0] * m[5]) / det,
            c02 / det,
            (m[1] * m[6] - m[0] * m[7]) / det,
            (m[0] * m[4] - m[1] * m[3]) / det,
        ];
        Some(Homography { m: inv }.normalised())
    }

    fn normalised(self) -> Homography {
        let s = self.m[8];
        if s.abs() > 1e-300 && s.is_finite() {
            Homography {
                m: self.m.map(|v| v / s),
            }
        } else {
            self
        }
    }
}

/// The largest distance (pixels) between corresponding points of `a` and `b`: how far a set of corners moved.
pub fn largest_move(a: &[Point], b: &[Point]) -> f64 {
    a.iter()
        .zip(b)
        .map(|(p, q)| (p[0] - q[0]).hypot(p[1] - q[1]))
        .fold(0.0, f64::max)
}

/// The four corners of an axis-aligned rectangle, in order round it: (x0,y0), (x1,y0), (x1,y1), (x0,y1).
pub fn rect_corners(x0: f64, y0: f64, x1: f64, y1: f64) -> [Point; 4] {
    [[x0, y0], [x1, y0], [x1, y1], [x0, y1]]
}

/// Checks that four points form a simple, non-degenerate quadrilateral (convex or not).
pub fn check_quad(q: &[Point; 4]) -> Result<(), GeometryError> {
    if q.iter().flatten().any(|v| !v.is_finite()) {
        return Err(GeometryError::NotFinite);
    }
    let scale = q
        .iter()
        .flat_map(|a| q.iter().map(move |b| (a[0] - b[0]).hypot(a[1] - b[1])))
        .fold(0.0, f64::max);
    if scale <= 0.0 {
        return Err(GeometryError::Degenerate);
    }
    // Any three points collinear → degenerate.
    for i in 0..4 {
        let a = q[i];
        let b = q[(i + 1) % 4];
        let c = q[(i + 2) % 4];
        let cross = (b[0] - a[0]) * (c[1] - a[1]) - (b[1] - a[1]) * (c[0] - a[0]);
        if cross.abs() <= 1e-9 * scale * scale {
            return Err(GeometryError::Degenerate);
        }
    }
    // Opposite edges must not cross.
    if segments_cross(q[0], q[1], q[2], q[3]) || segments_cross(q[1], q[2], q[3], q[0]) {
        return Err(GeometryError::SelfCrossing);
    }
    Ok(())
}

fn segments_cross(a: Point, b: Point, c: Point, d: Point) -> bool {
    let orient = |p: Point, q: Point, r: Point| {
        (q[0] - p[0]) * (r[1] - p[1]) - (q[1] - p[1]) * (r[0] - p[0])
    };
    let d1 = orient(a, b, c);
    let d2 = orient(a, b, d);
    let d3 = orient(c, d, a);
    let d4 = orient(c, d, b);
    d1 * d2 < 0.0 && d3 * d4 < 0.0
}

fn normalise(p: &[Point; 4]) -> (Homography, [Point; 4]) {
    let cx = p.iter().map(|q| q[0]).sum::<f64>() / 4.0;
    let cy = p.iter().map(|q| q[1]).sum::<f64>() / 4.0;
    let d = p.iter().map(|q| (q[0] - cx).hypot(q[1] - cy)).sum::<f64>() / 4.0;
    let s = std::f64::consts::SQRT_2 / d;
    let t = Homography {
        m: [s, 0.0, -s * cx, 0.0, s, -s * cy, 0.0, 0.0, 1.0],
    };
    (t, p.map(|q| t.apply(q)))
}

/// Solves the 8×8 system A·h = b (b in column 8) by Gaussian elimination with partial pivoting.
fn solve8(mut a: [[f64; 9]; 8]) -> Option<[f64; 8]> {
    for col in 0..8 {
        let piv = (col..8).max_by(|&i, &j| a[i][col].abs().total_cmp(&a[j][col].abs()))?;
        if a[piv][col].abs() < 1e-12 {
            return None;
        }
        a.swap(col, piv);
        for row in 0..8 {
            if row != col {
                let f = a[row][col] / a[col][col];
                let pivot_row = a[col];
                for (x, p) in a[row][col..].iter_mut().zip(&pivot_row[col..]) {
                    *x -= f * p;
                }
            }
        }
    }
    let mut h = [0.0; 8];
    for i in 0..8 {
        h[i] = a[i][8] / a[i][i];
    }
    Some(h)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn maps_corners_exactly_and_inverts() {
        let src = rect_corners(0.0, 0.0, 297.0, 210.0);
        let dst = [
            [103.2, 88.5],
            [1800.7, 140.1],
            [1750.0, 1300.3],
            [90.0, 1250.9],
        ];
        let h = Homography::from_quads(&src, &dst).unwrap();
        for i in 0..4 {
            let p = h.apply(src[i]);
            assert!((p[0] - dst[i][0]).abs() < 1e-9 && (p[1] - dst[i][1]).abs() < 1e-9);
        }
        let inv = h.inverse().unwrap();
        let q = inv.apply(h.apply([100.0, 50.0]));
        assert!((q[0] - 100.0).abs() < 1e-9 && (q[1] - 50.0).abs() < 1e-9);
    }

    #[test]
    fn jacobian_matches_finite_differences() {
        let src = rect_corners(0.0, 0.0, 10.0, 5.0);
        let dst = [[10.0, 10.0], [200.0, 30.0], [180.0, 150.0], [5.0, 120.0]];
        let h = Homography::from_quads(&src, &dst).unwrap();
        let p = [3.0, 2.0];
        let j = h.jacobian(p);
        let e = 1e-6;
        let dx = h.apply([p[0] + e, p[1]]);
        let dx0 = h.apply([p[0] - e, p[1]]);
        assert!(((dx[0] - dx0[0]) / (2.0 * e) - j[0][0]).abs() < 1e-5);
        assert!(((dx[1] - dx0[1]) / (2.0 * e) - j[1][0]).abs() < 1e-5);
    }

    #[test]
    fn rejects_bad_quads() {
        let ok = rect_corners(0.0, 0.0, 1.0, 1.0);
        let collinear = [[0.0, 0.0], [1.0, 0.0], [2.0, 0.0], [0.0, 1.0]];
        let crossing = [[0.0, 0.0], [1.0, 1.0], [1.0, 0.0], [0.0, 1.0]];
        assert_eq!(
            Homography::from_quads(&ok, &collinear),
            Err(GeometryError::Degenerate)
        );
        assert_eq!(
            Homography::from_quads(&ok, &crossing),
            Err(GeometryError::SelfCrossing)
        );
        let nan = [[f64::NAN, 0.0], [1.0, 0.0], [1.0, 1.0], [0.0, 1.0]];
        assert_eq!(
            Homography::from_quads(&ok, &nan),
            Err(GeometryError::NotFinite)
        );
    }
}
