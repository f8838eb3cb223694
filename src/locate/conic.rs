//! Least-squares ellipse fits to edge points (a conic, with outliers
//! dropped), for the fiducial marks' centres ([`super::ellipse`]).

use crate::geometry::Point;

/// An ellipse: centre and covariance of the solid ellipse whose edge is at 2σ.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Ellipse {
    /// Centre.
    pub centre: Point,
    /// Covariance [xx, xy, yy].
    pub cov: [f64; 3],
}

/// Least-squares ellipse through points (conic with a + c = 1, outliers beyond 3 MAD dropped once).
pub fn fit_ellipse(points: &[Point]) -> Option<Ellipse> {
    let mut pts: Vec<Point> = points.to_vec();
    let mut e = fit_once(&pts)?;
    for _ in 0..2 {
        let res: Vec<f64> = pts.iter().map(|p| radial_residual(&e, *p)).collect();
        let mut abs: Vec<f64> = res.iter().map(|r| r.abs()).collect();
        abs.sort_by(f64::total_cmp);
        let mad = abs[abs.len() / 2].max(1e-3);
        let keep: Vec<Point> = pts
            .iter()
            .zip(&res)
            .filter(|(_, r)| r.abs() <= 3.0 * 1.4826 * mad)
            .map(|(p, _)| *p)
            .collect();
        if keep.len() == pts.len() || keep.len() < 8 {
            break;
        }
        pts = keep;
        e = fit_once(&pts)?;
    }
    Some(e)
}

/// Radial distance of a point from the ellipse (approximate, px).
fn radial_residual(e: &Ellipse, p: Point) -> f64 {
    let [cxx, cxy, cyy] = e.cov;
    let det = cxx * cyy - cxy * cxy;
    let (dx, dy) = (p[0] - e.centre[0], p[1] - e.centre[1]);
    let m = (dx * dx * cyy - 2.0 * dx * dy * cxy + dy * dy * cxx) / det; // (d/σ)²
    let r = dx.hypot(dy);
    if m <= 0.0 {
        return -r;
    }
    r - r * 2.0 / m.sqrt()
}

fn fit_once(points: &[Point]) -> Option<Ellipse> {
    let n = points.len();
    if n < 6 {
        return None;
    }
    let mx = points.iter().map(|p| p[0]).sum::<f64>() / n as f64;
    let my = points.iter().map(|p| p[1]).sum::<f64>() / n as f64;
    let s = (points
        .iter()
        .map(|p| (p[0] - mx).powi(2) + (p[1] - my).powi(2))
        .sum::<f64>()
        / n as f64)
        .sqrt();
    if s <= 0.0 {
        return None;
    }
    // a(x²−y²) + b·xy + d·x + e·y + f = −y²
    let mut ata = [[0.0f64; 5]; 5];
    let mut atb = [0.0f64; 5];
    for p in points {
        let (x, y) = ((p[0] - mx) / s, (p[1] - my) / s);
        let row = [x * x - y * y, x * y, x, y, 1.0];
        for i in 0..5 {
            for j in 0..5 {
                ata[i][j] += row[i] * row[j];
            }
            atb[i] += row[i] * (-y * y);
        }
    }
    let sol = crate::linalg::solve(ata, atb, 1e-14)?;
    let (a, b, d, e, f) = (sol[0], sol[1], sol[2], sol[3], sol[4]);
    let c = 1.0 - a;
    let det = 4.0 * a * c - b * b;
    if det <= 0.0 {
        return None; // not an ellipse
    }
    let x0 = (b * e - 2.0 * c * d) / det;
    let y0 = (b * d - 2.0 * a * e) / det;
    let k = a * x0 * x0 + b * x0 * y0 + c * y0 * y0 - f;
    if k <= 0.0 {
        return None;
    }
    // Σ = k/4 · A⁻¹, A = [[a, b/2], [b/2, c]], in normalised units.
    let da = a * c - b * b / 4.0;
    let q = k / 4.0 / da * s * s;
    Some(Ellipse {
        centre: [mx + x0 * s, my + y0 * s],
        cov: [q * c, -q * b / 2.0, q * a],
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn ellipse_fit_recovers_exact_ellipse() {
        // Ellipse centre (10, -3), semi-axes 5 and 2, rotated 30°.
        let (a, b, th) = (5.0f64, 2.0f64, 30f64.to_radians());
        let pts: Vec<Point> = (0..40)
            .map(|k| {
                let t = k as f64 * 0.157;
                let (x, y) = (a * t.cos(), b * t.sin());
                [
                    10.0 + x * th.cos() - y * th.sin(),
                    -3.0 + x * th.sin() + y * th.cos(),
                ]
            })
            .collect();
        let e = fit_ellipse(&pts).unwrap();
        assert!((e.centre[0] - 10.0).abs() < 1e-9 && (e.centre[1] + 3.0).abs() < 1e-9);
        // σ² along the major axis = a²/4.
        let tr = e.cov[0] + e.cov[2];
        assert!((tr - (a * a + b * b) / 4.0).abs() < 1e-9);
    }
}
