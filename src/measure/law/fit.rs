//! Fits of a phase law to (s, phase, weight) samples: the plain families
//! ([`fit_law`]) and with the foreshortening along the strip that the
//! corners miss ([`fit_perspective`]).

#![allow(clippy::needless_range_loop, clippy::neg_cmp_op_on_partial_ord)]

use super::{LawKind, PhaseLaw, expm1_over};
/// Weighted least-squares fit of a law of the given family to (s, phase, weight) samples; returns it and its weighted RMS residual (cycles).
pub fn fit_law(pts: &[(f64, f64, f64)], kind: LawKind) -> Option<(PhaseLaw, f64)> {
    if pts.len() < 4 {
        return None;
    }
    match kind {
        LawKind::Linear => {
            let (c, rms) = lsq(pts, |s| [1.0, s, s * s])?;
            Some((
                PhaseLaw {
                    kind,
                    c0: c[0],
                    c1: c[1],
                    c2: c[2],
                    persp: 0.0,
                },
                rms,
            ))
        }
        LawKind::Log => {
            // Rate k by golden-section search, c0 and c1 by linear least squares.
            let (lin, _) = fit_law(pts, LawKind::Linear)?;
            let smin = pts.iter().map(|p| p.0).fold(f64::INFINITY, f64::min);
            let smax = pts.iter().map(|p| p.0).fold(f64::NEG_INFINITY, f64::max);
            let span = (smax - smin).max(1e-300);
            let (f0, f1) = (lin.freq(smin), lin.freq(smax));
            let k_guess = if f0 > 0.0 && f1 > 0.0 {
                (f1 / f0).ln() / span
            } else {
                1.0 / span
            };
            let cost = |k: f64| lsq2(pts, k).map(|(_, r)| r).unwrap_or(f64::INFINITY);
            let (mut a, mut b) = (
                -0.5 / span,
                (3.0 * k_guess.abs()).max(1.0 / span) + 10.0 / span,
            );
            let g = 0.5 * (5f64.sqrt() - 1.0);
            let mut x1 = b - g * (b - a);
            let mut x2 = a + g * (b - a);
            let (mut f1c, mut f2c) = (cost(x1), cost(x2));
            // 40 steps shrink the bracket by 4e-9: phase errors ≲ 1e-4 cycles over
            // a thousand-cycle sweep; a parabola through the last three points polishes k.
            for _ in 0..40 {
                if f1c < f2c {
                    b = x2;
                    x2 = x1;
                    f2c = f1c;
                    x1 = b - g * (b - a);
                    f1c = cost(x1);
                } else {
                    a = x1;
                    x1 = x2;
                    f1c = f2c;
                    x2 = a + g * (b - a);
                    f2c = cost(x2);
                }
            }
            let mid = 0.5 * (a + b);
            let k = parabola_min([(x1, f1c), (mid, cost(mid)), (x2, f2c)])
                .filter(|k| *k > a && *k < b && cost(*k) <= f1c.min(f2c))
                .unwrap_or(mid);
            let (c, rms) = lsq2(pts, k)?;
            Some((
                PhaseLaw {
                    kind,
                    c0: c[0],
                    c1: c[1],
                    c2: k,
                    persp: 0.0,
                },
                rms,
            ))
        }
    }
}

/// Largest foreshortening [`fit_perspective`] tries: |persp|·s_max (1/unit·unit).
const MAX_PERSP_SPAN: f64 = 0.25;

/// [`fit_law`] with the foreshortening `persp` fitted too (weighted least
/// squares over the law's three coefficients and persp, by Gauss–Newton
/// steps from the plain law, each halved until the residual falls); returns
/// it and its weighted RMS residual (cycles), never worse than the plain
/// law's. persp is kept to |persp|·s_max ≤ 0.25 with s_max the farthest of
/// the points and `reach` (strip units: where the law will be used).
pub fn fit_perspective(
    pts: &[(f64, f64, f64)],
    kind: LawKind,
    reach: f64,
) -> Option<(PhaseLaw, f64)> {
    let smax = pts.iter().map(|p| p.0.abs()).fold(reach.abs(), f64::max);
    if pts.len() < 5 || !(smax > 0.0 && smax.is_finite()) {
        return None;
    }
    let lim = MAX_PERSP_SPAN / smax;
    let wsum: f64 = pts.iter().map(|p| p.2).sum();
    let rss = |l: &PhaseLaw| -> f64 {
        pts.iter()
            .map(|&(s, y, w)| w * (y - l.phase(s)).powi(2))
            .sum()
    };
    let (mut best, _) = fit_law(pts, kind)?;
    let mut best_rss = rss(&best);
    // Levenberg–Marquardt: λ on the scaled normal equations' diagonal, cut
    // tenfold after a step that lowers the residual, raised tenfold until one does.
    let mut lambda = 1e-3;
    for _ in 0..40 {
        let mut a = [[0.0; 4]; 4];
        let mut b = [0.0; 4];
        for &(s, y, w) in pts {
            let (j, phi) = gradient(&best, s);
            let r = y - phi;
            for m in 0..4 {
                b[m] += w * j[m] * r;
                for n in 0..4 {
                    a[m][n] += w * j[m] * j[n];
                }
            }
        }
        // Columns scaled to unit diagonal.
        let sc: [f64; 4] = std::array::from_fn(|m| a[m][m].sqrt().max(1e-300));
        let b: [f64; 4] = std::array::from_fn(|m| b[m] / sc[m]);
        let mut stepped = false;
        while lambda < 1e8 {
            let a: [[f64; 4]; 4] = std::array::from_fn(|m| {
                std::array::from_fn(|n| {
                    a[m][n] / (sc[m] * sc[n]) + if m == n { lambda } else { 0.0 }
                })
            });
            let Some(d) = crate::linalg::solve(a, b, 1e-15) else {
                lambda *= 10.0;
                continue;
            };
            let l = PhaseLaw {
                c0: best.c0 + d[0] / sc[0],
                c1: best.c1 + d[1] / sc[1],
                c2: best.c2 + d[2] / sc[2],
                persp: (best.persp + d[3] / sc[3]).clamp(-lim, lim),
                ..best
            };
            let r = rss(&l);
            if r < best_rss {
                stepped = (best_rss - r) > 1e-12 * best_rss;
                best = l;
                best_rss = r;
                lambda = (lambda * 0.1).max(1e-9);
                break;
            }
            lambda *= 10.0;
        }
        if !stepped {
            break;
        }
    }
    Some((best, (best_rss / wsum.max(1e-300)).sqrt()))
}

/// The law's phase at s and its derivatives there in (c0, c1, c2, persp).
fn gradient(l: &PhaseLaw, s: f64) -> ([f64; 4], f64) {
    let q = 1.0 + l.persp * s;
    let x = s / q;
    // dx/dpersp
    let dx = -(s * s) / (q * q);
    match l.kind {
        LawKind::Linear => (
            [1.0, x, x * x, (l.c1 + 2.0 * l.c2 * x) * dx],
            l.c0 + l.c1 * x + l.c2 * x * x,
        ),
        LawKind::Log => {
            let k = l.c2;
            let e1 = expm1_over(k, x);
            // d/dk of (e^{kx} − 1)/k: (x·e^{kx} − e1)/k, or its series near k·x = 0.
            let de = if (k * x).abs() < 1e-4 {
                0.5 * x * x * (1.0 + 2.0 * k * x / 3.0)
            } else {
                (x * (k * x).exp() - e1) / k
            };
            (
                [1.0, e1, l.c1 * de, l.c1 * (k * x).exp() * dx],
                l.c0 + l.c1 * e1,
            )
        }
    }
}

/// The abscissa of the vertex of the parabola through three points (None when they are collinear).
fn parabola_min(p: [(f64, f64); 3]) -> Option<f64> {
    let [(x0, y0), (x1, y1), (x2, y2)] = p;
    let num = (x1 - x0).powi(2) * (y1 - y2) - (x1 - x2).powi(2) * (y1 - y0);
    let den = (x1 - x0) * (y1 - y2) - (x1 - x2) * (y1 - y0);
    (den.abs() > 0.0 && den.is_finite()).then(|| x1 - 0.5 * num / den)
}

fn lsq2(pts: &[(f64, f64, f64)], k: f64) -> Option<([f64; 2], f64)> {
    let (c, r) = lsq(pts, |s| [1.0, expm1_over(k, s), 0.0])?;
    Some(([c[0], c[1]], r))
}

/// Weighted least squares with up to three basis functions (a zero third column is dropped); None without weight or with a non-finite solution.
fn lsq(pts: &[(f64, f64, f64)], basis: impl Fn(f64) -> [f64; 3]) -> Option<([f64; 3], f64)> {
    // Each point's basis values once (they may cost an exponential each).
    let xs: Vec<[f64; 3]> = pts.iter().map(|p| basis(p.0)).collect();
    let third = xs.iter().any(|x| x[2] != 0.0);
    let n = if third { 3 } else { 2 };
    let mut a = [[0.0; 3]; 3];
    let mut r = [0.0; 3];
    let mut wsum = 0.0;
    for (&(_, y, w), x) in pts.iter().zip(&xs) {
        for i in 0..n {
            r[i] += w * x[i] * y;
            for j in 0..n {
                a[i][j] += w * x[i] * x[j];
            }
        }
        wsum += w;
    }
    // No weight, or a non-finite sample: no fit (rather than a NaN law).
    if !(wsum > 0.0) {
        return None;
    }
    let c = solve(&a, &r, n)?;
    if !c.iter().all(|x| x.is_finite()) {
        return None;
    }
    let rss: f64 = pts
        .iter()
        .zip(&xs)
        .map(|(&(_, y, w), x)| {
            let p: f64 = (0..n).map(|i| c[i] * x[i]).sum();
            w * (y - p) * (y - p)
        })
        .sum();
    Some((c, (rss / wsum.max(1e-300)).sqrt()))
}

/// Solves the first `n` (2 or 3) rows and columns of a small symmetric
/// system, scaled to unit diagonal for conditioning, by [`crate::linalg::solve`];
/// the unused third coefficient is 0.
fn solve(a: &[[f64; 3]; 3], r: &[f64; 3], n: usize) -> Option<[f64; 3]> {
    let scale: [f64; 3] = std::array::from_fn(|i| {
        if i < n {
            a[i][i].abs().sqrt().max(1e-300)
        } else {
            1.0
        }
    });
    let c = if n == 2 {
        let [c0, c1] = crate::linalg::solve::<2>(
            std::array::from_fn(|i| std::array::from_fn(|j| a[i][j] / (scale[i] * scale[j]))),
            std::array::from_fn(|i| r[i] / scale[i]),
            1e-13,
        )?;
        [c0, c1, 0.0]
    } else {
        crate::linalg::solve::<3>(
            std::array::from_fn(|i| std::array::from_fn(|j| a[i][j] / (scale[i] * scale[j]))),
            std::array::from_fn(|i| r[i] / scale[i]),
            1e-13,
        )?
    };
    Some(std::array::from_fn(|i| c[i] / scale[i]))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn fits_recover_both_families() {
        let lin = PhaseLaw {
            kind: LawKind::Linear,
            c0: 0.3,
            c1: 0.01,
            c2: 2e-5,
            persp: 0.0,
        };
        let log = PhaseLaw {
            kind: LawKind::Log,
            c0: -0.1,
            c1: 0.01,
            c2: 0.0025,
            persp: 0.0,
        };
        for law in [lin, log] {
            let pts: Vec<_> = (0..200)
                .map(|i| {
                    let s = i as f64 * 8.0;
                    (s, law.phase(s), 1.0)
                })
                .collect();
            let (fit, rms) = fit_law(&pts, law.kind).unwrap();
            assert!(rms < 1e-6, "{rms}");
            for s in [0.0, 500.0, 1500.0] {
                assert!((fit.freq(s) / law.freq(s) - 1.0).abs() < 1e-6);
            }
            let s = law.s_at_phase(law.phase(777.0), 0.0, 1600.0);
            assert!((s - 777.0).abs() < 1e-6);
        }
    }

    /// A sweep seen through a keystone its corners missed: the printed law in
    /// the chart's coordinate x, sampled at strip positions s with
    /// x = s/(1 + p·s), written out here by hand; the fit finds p, the
    /// frequency matches a central difference of that phase, and the phase's
    /// inverse lands back on s.
    #[test]
    fn a_foreshortening_the_corners_missed_is_found_from_the_phase() {
        let len = 1600.0;
        let linear = |x: f64| 0.3 + 0.01 * x + 2e-5 * x * x;
        let log = |x: f64| -0.1 + 0.01 * ((0.0025 * x).exp() - 1.0) / 0.0025;
        for span in [-0.2, -0.02, -0.005, 0.0, 0.004, 0.03, 0.2] {
            let p = span / len;
            let x = |s: f64| s / (1.0 + p * s);
            for (kind, phi) in [
                (LawKind::Linear, &linear as &dyn Fn(f64) -> f64),
                (LawKind::Log, &log),
            ] {
                let pts: Vec<_> = (0..=200)
                    .map(|i| {
                        let s = i as f64 * 8.0;
                        (s, phi(x(s)), 1.0)
                    })
                    .collect();
                let (fit, rms) = fit_perspective(&pts, kind, len).unwrap();
                assert!(rms < 1e-4, "{kind:?} {span}: RMS {rms}");
                assert!(
                    (fit.persp * len - span).abs() < 1e-4,
                    "{kind:?} {span}: {}",
                    fit.persp * len
                );
                for s in [0.0, 400.0, 1599.0] {
                    let h = 1e-3;
                    let want = (phi(x(s + h)) - phi(x(s - h))) / (2.0 * h);
                    let got = fit.freq(s);
                    assert!(
                        (got / want - 1.0).abs() < 1e-5,
                        "{kind:?} {span} s={s}: {got} vs {want}"
                    );
                }
                let s = fit.s_at_phase(phi(x(777.0)), 0.0, len);
                assert!((s - 777.0).abs() < 1e-3, "{kind:?} {span}: {s}");
            }
        }
    }

    /// Without foreshortening, the fit with it gives the plain law back:
    /// noise-free phases of either family, and a handful of points.
    #[test]
    fn no_foreshortening_is_read_where_there_is_none() {
        let lin = PhaseLaw {
            kind: LawKind::Linear,
            c0: 0.3,
            c1: 0.01,
            c2: 2e-5,
            persp: 0.0,
        };
        let pts: Vec<_> = (0..5)
            .map(|i| (i as f64 * 300.0, lin.phase(i as f64 * 300.0), 1.0))
            .collect();
        let (fit, rms) = fit_perspective(&pts, LawKind::Linear, 0.0).unwrap();
        assert!(
            rms < 1e-6 && (fit.persp * 1200.0).abs() < 1e-6,
            "{fit:?} {rms}"
        );
        assert!(fit_perspective(&pts[..4], LawKind::Linear, 0.0).is_none());
        assert!(fit_perspective(&[(0.0, 0.0, 1.0); 6], LawKind::Linear, 0.0).is_none());
    }

    /// Stiff and broken inputs: a log sweep rising e^40-fold, phases with
    /// jumps of whole cycles, weights from 1e-9 to 1e9, zero weights, a
    /// reach far beyond the points, non-finite phases. Each fit is either
    /// refused or finite, never worse than the plain law, and its
    /// foreshortening stays inside the bound.
    #[test]
    fn stiff_and_broken_phases_give_a_finite_law_or_none() {
        let steep = |s: f64| 0.01 * ((0.025 * s).exp() - 1.0) / 0.025;
        // (points, reach)
        type Case = (Vec<(f64, f64, f64)>, f64);
        let cases: Vec<Case> = vec![
            (
                (0..=160)
                    .map(|i| (i as f64 * 10.0, steep(i as f64 * 10.0), 1.0))
                    .collect(),
                1600.0,
            ),
            (
                (0..=160)
                    .map(|i| {
                        let s = i as f64 * 10.0;
                        (
                            s,
                            0.3 + 0.01 * s + 2e-5 * s * s + (i % 7 == 3) as u8 as f64,
                            1.0,
                        )
                    })
                    .collect(),
                1600.0,
            ),
            (
                (0..=160)
                    .map(|i| {
                        let s = i as f64 * 10.0;
                        (s, 0.01 * s + 1e-5 * s * s, 10f64.powi(i % 19 - 9))
                    })
                    .collect(),
                1e9,
            ),
            (
                (0..=20).map(|i| (i as f64, 0.1 * i as f64, 0.0)).collect(),
                20.0,
            ),
            (
                (0..=20)
                    .map(|i| {
                        (
                            i as f64,
                            if i == 7 { f64::NAN } else { 0.1 * i as f64 },
                            1.0,
                        )
                    })
                    .collect(),
                20.0,
            ),
        ];
        for (n, (pts, reach)) in cases.iter().enumerate() {
            for kind in [LawKind::Linear, LawKind::Log] {
                let Some((l, rms)) = fit_perspective(pts, kind, *reach) else {
                    continue;
                };
                let smax = pts.iter().map(|p| p.0.abs()).fold(reach.abs(), f64::max);
                assert!(
                    l.c0.is_finite() && l.c1.is_finite() && l.c2.is_finite() && l.persp.is_finite(),
                    "case {n} {kind:?}: {l:?}"
                );
                assert!(
                    (l.persp * smax).abs() <= MAX_PERSP_SPAN + 1e-12,
                    "case {n} {kind:?}: {l:?}"
                );
                if let Some((_, plain)) = fit_law(pts, kind)
                    && plain.is_finite()
                {
                    assert!(
                        rms <= plain * (1.0 + 1e-9),
                        "case {n} {kind:?}: {rms} > {plain}"
                    );
                }
            }
        }
    }
}
