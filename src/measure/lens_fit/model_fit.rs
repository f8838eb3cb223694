//! The least-squares fit of the radial model to the edge points of the
//! strip's two long edges: the cubic b, then a and c where the edges
//! determine them (see the module above).

use super::*;

/// The model a fit keeps: its coefficients' uncertainties (a, b, c; None
/// where not fitted), its distance from no model in σ and its cost.
struct Chosen {
    model: Ptlens,
    sigma: [Option<f64>; 3],
    significance: f64,
    cost: f64,
}

/// The total-least-squares line through `pts`: its centroid and unit direction.
pub(super) fn tls_line(pts: &[Point]) -> [Point; 2] {
    let n = pts.len().max(1) as f64;
    let mx = pts.iter().map(|p| p[0]).sum::<f64>() / n;
    let my = pts.iter().map(|p| p[1]).sum::<f64>() / n;
    let (mut sxx, mut sxy, mut syy) = (0.0, 0.0, 0.0);
    for p in pts {
        let (dx, dy) = (p[0] - mx, p[1] - my);
        sxx += dx * dx;
        sxy += dx * dy;
        syy += dy * dy;
    }
    let th = 0.5 * (2.0 * sxy).atan2(sxx - syy);
    [[mx, my], [th.cos(), th.sin()]]
}

/// Perpendicular residuals of points about their total-least-squares line.
fn line_residuals(pts: &[Point]) -> Vec<f64> {
    let [[mx, my], [cx, cy]] = tls_line(pts);
    let (nx, ny) = (-cy, cx);
    pts.iter()
        .map(|p| (p[0] - mx) * nx + (p[1] - my) * ny)
        .collect()
}

/// Cost of a model: the squared residuals of both edges' undistorted points about their lines.
fn cost(edges: &[Vec<Point>; 2], m: Ptlens, width: usize, height: usize) -> f64 {
    let lens = Lens::new(m, width, height);
    edges
        .iter()
        .map(|e| {
            let u: Vec<Point> = e.iter().map(|&p| lens.undistort(p)).collect();
            line_residuals(&u).iter().map(|r| r * r).sum::<f64>()
        })
        .sum()
}

/// The cubic model b (a = c = 0).
fn cubic(b: f64) -> Ptlens {
    Ptlens { a: 0.0, b, c: 0.0 }
}

/// Minimum of the parabola through the cost at b0 − h, b0, b0 + h (a = c = 0): (b, curvature κ, cost there).
fn parabola(edges: &[Vec<Point>; 2], b0: f64, h: f64, w: usize, ht: usize) -> (f64, f64, f64) {
    let (cm, c0, cp) = (
        cost(edges, cubic(b0 - h), w, ht),
        cost(edges, cubic(b0), w, ht),
        cost(edges, cubic(b0 + h), w, ht),
    );
    let kappa = (cp - 2.0 * c0 + cm) / (2.0 * h * h);
    if !(kappa > 0.0) {
        return (b0, kappa, c0);
    }
    let b = b0 - (cp - cm) / (4.0 * kappa * h);
    (b, kappa, c0 - kappa * (b - b0).powi(2))
}

/// The model `base` with its coefficients `free` (0 = a, 1 = b, 2 = c) set to `p`.
fn with_terms<const N: usize>(base: Ptlens, free: [usize; N], p: [f64; N]) -> Ptlens {
    let mut k = [base.a, base.b, base.c];
    for (i, v) in free.into_iter().zip(p) {
        k[i] = v;
    }
    Ptlens {
        a: k[0],
        b: k[1],
        c: k[2],
    }
}

/// K⁻¹ for a symmetric positive definite K (columns solved one by one, scaled to unit diagonal).
fn inverse<const N: usize>(k: [[f64; N]; N]) -> Option<[[f64; N]; N]> {
    let d: [f64; N] = std::array::from_fn(|i| k[i][i].sqrt());
    if d.iter().any(|v| !(*v > 0.0)) {
        return None;
    }
    let ks: [[f64; N]; N] =
        std::array::from_fn(|i| std::array::from_fn(|j| k[i][j] / (d[i] * d[j])));
    let mut inv = [[0.0; N]; N];
    for c in 0..N {
        let e: [f64; N] = std::array::from_fn(|i| if i == c { 1.0 } else { 0.0 });
        let x = crate::linalg::solve(ks, e, 1e-12)?;
        for r in 0..N {
            inv[r][c] = x[r] / (d[r] * d[c]);
        }
    }
    Some(inv)
}

/// A fit of N coefficients: the model, K, K⁻¹ and the least cost ([`fit_terms`]).
type TermsFit<const N: usize> = (Ptlens, [[f64; N]; N], [[f64; N]; N], f64);

/// Least squares of the coefficients `free` (0 = a, 1 = b, 2 = c; the others
/// as in `start`) by Newton steps on the quadratic through the cost at a
/// central-difference stencil, shrinking: the model, K (half the cost's
/// Hessian, the normal matrix), K⁻¹ (σ²·K⁻¹ is the covariance) and the least cost;
/// `None` where the cost is not convex or the model leaves what a lens can have.
fn fit_terms<const N: usize>(
    edges: &[Vec<Point>; 2],
    start: Ptlens,
    free: [usize; N],
    w: usize,
    ht: usize,
) -> Option<TermsFit<N>> {
    let k0 = [start.a, start.b, start.c];
    let mut p: [f64; N] = std::array::from_fn(|i| k0[free[i]]);
    let mut normal = None;
    let mut h = 0.002;
    for _ in 0..3 {
        let c = |d: &[(usize, f64)]| {
            let mut q = p;
            for &(i, s) in d {
                q[i] += s * h;
            }
            cost(edges, with_terms(start, free, q), w, ht)
        };
        let c0 = c(&[]);
        let plus: [f64; N] = std::array::from_fn(|i| c(&[(i, 1.0)]));
        let minus: [f64; N] = std::array::from_fn(|i| c(&[(i, -1.0)]));
        let g: [f64; N] = std::array::from_fn(|i| (plus[i] - minus[i]) / (2.0 * h));
        let mut k = [[0.0; N]; N];
        for i in 0..N {
            k[i][i] = (plus[i] - 2.0 * c0 + minus[i]) / (2.0 * h * h);
            for j in 0..i {
                let cross = c(&[(i, 1.0), (j, 1.0)])
                    - c(&[(i, 1.0), (j, -1.0)])
                    - c(&[(i, -1.0), (j, 1.0)])
                    + c(&[(i, -1.0), (j, -1.0)]);
                k[i][j] = cross / (8.0 * h * h);
                k[j][i] = k[i][j];
            }
        }
        let inv = inverse(k)?;
        // Minimum of c0 + g·d + dᵀKd: d = −½ K⁻¹ g.
        for (i, row) in inv.iter().enumerate() {
            p[i] -= 0.5 * row.iter().zip(g).map(|(a, b)| a * b).sum::<f64>();
        }
        normal = Some((k, inv));
        h = (h * 0.25).max(1e-5);
    }
    let m = with_terms(start, free, p);
    let lens = Lens::new(m, w, ht);
    (p.iter().all(|v| v.is_finite())
        && lens.check().is_ok()
        && lens.corner_percent().abs() <= MAX_CORNER_PERCENT)
        .then(|| {
            let (k, kinv) = normal.unwrap_or(([[0.0; N]; N], [[0.0; N]; N]));
            (m, k, kinv, cost(edges, m, w, ht))
        })
}

/// RMS of the points of both edges about their own lines once undistorted by `m`.
fn rms_about_lines(edges: &[Vec<Point>; 2], m: Ptlens, width: usize, height: usize) -> f64 {
    let n: usize = edges.iter().map(|e| e.len()).sum();
    (cost(edges, m, width, height) / n.max(1) as f64).sqrt()
}

/// The richer model `fit` (from [`fit_terms`] over the coefficients
/// `free`, `n` edge points) where it beats `chosen`: its Δχ² over it passes
/// MIN_SIGNIFICANCE² and it lowers the edges' RMS MIN_RICHER_GAIN×.
fn richer<const N: usize>(
    chosen: &Chosen,
    (m, k, kinv, c): TermsFit<N>,
    free: [usize; N],
    n: usize,
) -> Option<Chosen> {
    let s2 = c / (n as f64 - 4.0 - N as f64).max(1.0);
    let gain = (
        (chosen.cost / c.max(1e-300)).sqrt(),
        (chosen.cost - c) / s2.max(1e-300),
    );
    if !(gain.0 >= MIN_RICHER_GAIN && gain.1 > MIN_SIGNIFICANCE * MIN_SIGNIFICANCE) {
        return None;
    }
    let mut sigma = [None; 3];
    for (r, &i) in free.iter().enumerate() {
        sigma[i] = Some((s2 * kinv[r][r]).max(0.0).sqrt());
    }
    // Distance from no model: χ² of the coefficients against their covariance σ²·K⁻¹.
    let all = [m.a, m.b, m.c];
    let v: [f64; N] = std::array::from_fn(|i| all[free[i]]);
    let chi2 = (0..N)
        .map(|i| (0..N).map(|j| v[i] * k[i][j] * v[j]).sum::<f64>())
        .sum::<f64>()
        / s2.max(1e-300);
    Some(Chosen {
        model: m,
        sigma,
        significance: chi2.max(0.0).sqrt(),
        cost: c,
    })
}

/// Fits the model to the edge points of both long edges (see the module's
/// text); `places` is how many places along each edge were searched.
pub(super) fn fit_edges(
    mut edges: [Vec<Point>; 2],
    places: [usize; 2],
    roi: &[Point; 4],
    width: usize,
    height: usize,
    b_max: f64,
    b_start: f64,
) -> Option<DistortionFound> {
    if edges.iter().any(|e| e.len() < 8) {
        return None;
    }
    let mut fit = (0.0, 0.0, 0.0);
    for round in 0..2 {
        let mut b = b_start;
        let mut h = 0.004;
        for _ in 0..3 {
            let f = parabola(&edges, b, h, width, height);
            fit = f;
            b = f.0.clamp(-b_max, b_max);
            h = (h * 0.25).max(1e-5);
        }
        fit.0 = b;
        if round == 1 {
            break;
        }
        // Drop edge points beyond 4 robust σ of their line, then fit again.
        let lens = Lens::new(cubic(b), width, height);
        for e in edges.iter_mut() {
            let u: Vec<Point> = e.iter().map(|&p| lens.undistort(p)).collect();
            let r = line_residuals(&u);
            let mut abs: Vec<f64> = r.iter().map(|v| v.abs()).collect();
            abs.sort_by(f64::total_cmp);
            let mad = abs[abs.len() / 2].max(1e-3);
            let keep: Vec<Point> = e
                .iter()
                .zip(&r)
                .filter(|(_, r)| r.abs() <= 4.0 * 1.4826 * mad)
                .map(|(p, _)| *p)
                .collect();
            *e = keep;
        }
        if edges.iter().any(|e| e.len() < 8) {
            return None;
        }
    }
    let (b, kappa, c_min) = fit;
    let n: usize = edges.iter().map(|e| e.len()).sum();
    let rms0 = rms_about_lines(&edges, cubic(0.0), width, height);
    // The cubic alone: its uncertainty and its distance from no model in σ.
    let sigma2 = c_min.max(0.0) / (n as f64 - 5.0).max(1.0);
    let b_sigma = if kappa > 0.0 {
        (sigma2 / kappa).sqrt()
    } else {
        f64::INFINITY
    };
    // Richer models where the edges determine them: the quartic term a
    // (a Brown–Conrady k2's r⁵, a moustache), then c as well. Each is kept
    // only when its Δχ² over the model before it passes MIN_SIGNIFICANCE²
    // and it lowers the edges' RMS MIN_RICHER_GAIN× (a misfit below that
    // does not move the MTF).
    let mut chosen = Chosen {
        model: cubic(b),
        sigma: [None, Some(b_sigma), None],
        significance: (b / b_sigma).abs(),
        cost: c_min.max(0.0),
    };
    if let Some(fit) = fit_terms(&edges, cubic(b), [0, 1], width, height)
        && let Some(next) = richer(&chosen, fit, [0, 1], n)
    {
        chosen = next;
        if let Some(fit) = fit_terms(&edges, chosen.model, [0, 1, 2], width, height)
            && let Some(next) = richer(&chosen, fit, [0, 1, 2], n)
        {
            chosen = next;
        }
    }
    let Chosen {
        model,
        sigma,
        significance,
        ..
    } = chosen;
    let coverage = edges
        .iter()
        .zip(places)
        .map(|(e, n)| e.len() as f64 / n.max(1) as f64)
        .fold(1.0, f64::min);
    let rms_m = rms_about_lines(&edges, model, width, height);
    let lens = Lens::new(model, width, height);
    let bow = long_edge_bow(&lens, roi);
    let why_not = if coverage < MIN_EDGE_COVERAGE {
        Some("the long edges were found along too little of the strip")
    } else if rms_m > MAX_EDGE_RMS_PX {
        Some("the edge points scatter too much to be printed edges")
    } else if !(significance > MIN_SIGNIFICANCE) {
        Some("the model is within the edge fit's noise")
    } else if bow < MIN_BOW_PX {
        Some("it bends the strip's edges too little to matter")
    } else if !(rms0 >= MIN_STRAIGHTENING * rms_m) {
        Some("it does not straighten the edges clearly")
    } else if lens.check().is_err() {
        Some("the fitted model is outside what a lens can have")
    } else {
        None
    };
    Some(DistortionFound {
        model,
        corner_percent: lens.corner_percent(),
        source: if why_not.is_none() {
            DistortionSource::Estimated
        } else {
            DistortionSource::Negligible
        },
        b_sigma: sigma[1],
        a_sigma: sigma[0],
        c_sigma: sigma[2],
        significance: Some(significance),
        edge_rms_px: Some(rms_m),
        straight_rms_px: Some(rms0),
        edge_coverage: Some(coverage),
        edge_points: n,
        bow_px: bow,
        why_not,
        snapped: None,
        edge_lines: Some([0, 1].map(|i| {
            let u: Vec<Point> = edges[i].iter().map(|&p| lens.undistort(p)).collect();
            tls_line(&u)
        })),
    })
}
