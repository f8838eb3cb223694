//! The least-squares system of the strip-tone fit: the low-frequency
//! windows' bins, the correction's directions, each window's parameters
//! profiled out, and one pass's solution with or without a sharpening of the
//! code beside the tone (see [`super`]).

use super::{
    CODE_HIGH, CODE_LOW, MAX_FREQ_CY_PX, MAX_FREQ_STRETCH_CY_PX, MIN_SHARPENING_SIGNIFICANCE,
    MIN_WINDOWS, NF, NP, NS, NX, Pass, TERMS, WINDOW_CYCLES, code_of, effect_at_half, functions,
    slope,
};
use crate::measure::PhaseLaw;
use crate::measure::profile::Profile;
use crate::photo::linearise::Tone;
use rayon::prelude::*;

/// One bin read for the shape: code, linear value, samples, weight, window design row.
#[derive(Clone)]
pub(super) struct Row {
    c: f64,
    pub(super) v: f64,
    n: f64,
    w: f64,
    x: [f64; NX],
    /// (f / [`MAX_FREQ_CY_PX`])² at the row's local frequency f: the scale of
    /// a sharpening of the code, which bends a period's shape as a tone
    /// curve does but vanishes as f → 0.
    q: f64,
}

impl Row {
    /// The row with its value `v` (decoded with `base`) replaced.
    pub(super) fn with_value(&self, base: &Tone, v: f64) -> Row {
        let c = code_of(base, v);
        Row {
            c,
            v,
            w: self.n / slope(base, c).powi(2).max(1e-300),
            ..self.clone()
        }
    }
}

/// The bins of each window at the strip's low end (from one cycle past its
/// start), up to [`MAX_FREQ_CY_PX`] (or [`MAX_FREQ_STRETCH_CY_PX`] when that
/// gives fewer than [`MIN_WINDOWS`]); windows with a clipped code are left
/// out. Weights: samples over D'(c)², so residuals count in code units.
pub(super) fn windows(
    prof: &Profile,
    law: &PhaseLaw,
    s_per_px: &(dyn Fn(f64) -> f64 + Sync),
    base: &Tone,
) -> Vec<Vec<Row>> {
    let (Some(&s0), Some(&s1)) = (prof.s.first(), prof.s.last()) else {
        return Vec::new();
    };
    let p0 = law.phase(s0) + 1.0;
    // The windows' places first (each stops the reading where it would pass
    // the strip's end or `f_max`), then their rows, read in parallel and
    // kept in order.
    let read = |f_max: f64| -> Vec<Vec<Row>> {
        let mut spans = Vec::new();
        let mut k = 0.0;
        loop {
            let (a, b) = (p0 + k * WINDOW_CYCLES, p0 + (k + 1.0) * WINDOW_CYCLES);
            k += 1.0;
            if b > law.phase(s1) - 0.5 {
                break;
            }
            let (sa, sb) = (law.s_at_phase(a, s0, s1), law.s_at_phase(b, s0, s1));
            if law.freq(sb) * s_per_px(sb) > f_max {
                break;
            }
            spans.push((sa, sb));
        }
        let rows_of = |&(sa, sb): &(f64, f64)| -> Option<Vec<Row>> {
            let (mid, half) = (0.5 * (sa + sb), 0.5 * (sb - sa));
            let bins = prof.bins_within(sa, sb);
            let mut rows = Vec::with_capacity(bins.len());
            let mut clipped = false;
            for i in bins {
                let (v, c) = (prof.y[i], code_of(base, prof.y[i]));
                clipped |= !(CODE_LOW..CODE_HIGH).contains(&c);
                let f = law.freq(prof.s[i]) * s_per_px(prof.s[i]);
                rows.push(Row {
                    c,
                    v,
                    n: prof.count[i],
                    w: prof.count[i] / slope(base, c).powi(2).max(1e-300),
                    x: window_row(law, prof.s[i], mid, half),
                    q: (f / MAX_FREQ_CY_PX).powi(2),
                });
            }
            (!clipped && rows.len() >= 4 * NX).then_some(rows)
        };
        let read: Vec<Option<Vec<Row>>> = spans.par_iter().map(rows_of).collect();
        read.into_iter().flatten().collect()
    };
    let w = read(MAX_FREQ_CY_PX);
    if w.len() >= MIN_WINDOWS {
        w
    } else {
        read(MAX_FREQ_STRETCH_CY_PX)
    }
}

/// A window's design row at `s` (window middle `mid`, half-width `half`):
/// a mean, a sine and a cosine at the law's phase, and each times the
/// position d ∈ [−1, 1] (the light's trend).
pub(in crate::measure) fn window_row(law: &PhaseLaw, s: f64, mid: f64, half: f64) -> [f64; NX] {
    let d = (s - mid) / half;
    let (sn, cs) = (std::f64::consts::TAU * law.phase(s)).sin_cos();
    [1.0, d, sn, cs, d * sn, d * cs]
}

/// The correction's directions: the functions D'(c)·uᵏ made orthonormal to
/// 1, v and each other over the rows (weighted Gram–Schmidt; `vals`: each
/// row's functions), as coefficient vectors over the functions; a function
/// (nearly) inside the span of those before it is dropped.
fn directions(rows: &[&Row], vals: &[[f64; NF]]) -> Vec<[f64; NF]> {
    let dot = |a: &[f64; NF], b: &[f64; NF]| -> f64 {
        rows.iter()
            .zip(vals)
            .map(|(r, f)| {
                let x: f64 = a.iter().zip(f).map(|(p, q)| p * q).sum();
                let y: f64 = b.iter().zip(f).map(|(p, q)| p * q).sum();
                r.w * x * y
            })
            .sum()
    };
    let mut basis: Vec<[f64; NF]> = Vec::new();
    let mut out = Vec::new();
    for j in 0..NF {
        let mut e = [0.0; NF];
        e[j] = 1.0;
        let norm0 = dot(&e, &e).sqrt();
        for q in &basis {
            let p = dot(&e, q);
            for m in 0..NF {
                e[m] -= p * q[m];
            }
        }
        let norm = dot(&e, &e).sqrt();
        if !(norm > 1e-5 * norm0) {
            continue;
        }
        e.iter_mut().for_each(|x| *x /= norm);
        basis.push(e);
        if j >= 2 {
            out.push(e);
        }
    }
    out
}

/// Per window, the Schur complement of the window parameters in the
/// weighted Gram matrix of [X | Ψ | v]: adds the profiled normal matrix to
/// `a` and the profiled right side to `b` (unused directions stay 0), and
/// returns the window's residual sum of squares with no correction
/// (`vals`: each row's functions).
fn profiled(
    rows: &[Row],
    vals: &[[f64; NF]],
    dirs: &[[f64; NF]],
    a: &mut [[f64; NP]; NP],
    b: &mut [f64; NP],
) -> Option<f64> {
    const M: usize = NX + NP + 1;
    let k = dirs.len();
    let mut g = [[0.0; M]; M];
    for (r, f) in rows.iter().zip(vals) {
        let mut z = [0.0; M];
        z[..NX].copy_from_slice(&r.x);
        for (j, d) in dirs.iter().enumerate() {
            let psi: f64 = d.iter().zip(f).map(|(p, q)| p * q).sum();
            z[NX + j] = psi;
            let mut qm = 1.0;
            for m in 1..=NS {
                qm *= r.q;
                z[NX + m * TERMS + j] = qm * psi;
            }
        }
        z[M - 1] = r.v;
        for i in 0..M {
            for j in i..M {
                g[i][j] += r.w * z[i] * z[j];
            }
        }
    }
    for i in 0..M {
        for j in 0..i {
            g[i][j] = g[j][i];
        }
    }
    let mut gxx = [[0.0; NX]; NX];
    for i in 0..NX {
        gxx[i].copy_from_slice(&g[i][..NX]);
    }
    let scale = (0..NX).map(|i| gxx[i][i]).fold(0.0, f64::max);
    // G_XX⁻¹ times each of the other columns (directions, their
    // sharpening twins, then v).
    let params: Vec<usize> = (0..=NS).flat_map(|m| m * TERMS..m * TERMS + k).collect();
    let cols: Vec<usize> = params.iter().map(|p| NX + p).chain([M - 1]).collect();
    let mut y = Vec::with_capacity(cols.len());
    for &col in &cols {
        let rhs: [f64; NX] = std::array::from_fn(|i| g[i][col]);
        y.push(crate::linalg::solve(gxx, rhs, 1e-12 * scale.max(1e-300))?);
    }
    let schur = |p: usize, q: usize, yq: &[f64; NX]| -> f64 {
        g[p][q] - (0..NX).map(|i| g[i][p] * yq[i]).sum::<f64>()
    };
    for &i in &params {
        for (yj, &j) in params.iter().enumerate() {
            a[i][j] += schur(NX + i, NX + j, &y[yj]);
        }
        b[i] += schur(NX + i, M - 1, &y[params.len()]);
    }
    Some(schur(M - 1, M - 1, &y[params.len()]).max(0.0))
}

/// One window's share of the normal system over the tone's parameters (its
/// matrix, right-hand side and residual with none), boxed: 2.7 kB.
type Share = Box<([[f64; NP]; NP], [f64; NP], f64)>;

/// One pass of the fit: the correction, its Wald distance from none (σ), the
/// change of the MTF at 0.5 it makes, the code range and windows read.
pub(super) struct PassFit {
    pub(super) pass: Pass,
    pub(super) significance: f64,
    /// Whether a sharpening of the code was fitted beside the tone.
    pub(super) sharpening_seen: bool,
    pub(super) effect: f64,
    pub(super) code_range: (f64, f64),
    pub(super) windows: usize,
}

/// One pass: the first-order correction of the values in the windows' rows
/// (see the module text).
pub(super) fn fit_pass(wins: &[Vec<Row>], base: &Tone) -> Option<PassFit> {
    let all: Vec<&Row> = wins.iter().flatten().collect();
    let (lo, hi) = all
        .iter()
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(l, h), r| {
            (l.min(r.c), h.max(r.c))
        });
    if !(hi > lo) {
        return None;
    }
    let mh = (0.5 * (lo + hi), 0.5 * (hi - lo));
    // Each row's functions, once per pass (the directions and the fit read them).
    let vals: Vec<[f64; NF]> = all
        .par_iter()
        .map(|r| functions(base, r.c, r.v, mh))
        .collect();
    let dirs = directions(&all, &vals);
    if dirs.is_empty() {
        return None;
    }
    // Each window's share of the normal system, in parallel, then summed in
    // the windows' order (the sums a sequential pass makes, bit for bit).
    let mut starts = Vec::with_capacity(wins.len());
    let mut at = 0;
    for w in wins {
        starts.push(at);
        at += w.len();
    }
    let shares: Vec<Option<Share>> = wins
        .par_iter()
        .zip(&starts)
        .map(|(w, &at)| {
            let mut share: Share = Box::new(([[0.0; NP]; NP], [0.0; NP], 0.0));
            let (a, b, rss) = &mut *share;
            *rss = profiled(w, &vals[at..at + w.len()], &dirs, a, b)?;
            Some(share)
        })
        .collect();
    let (mut a, mut b) = ([[0.0; NP]; NP], [0.0; NP]);
    let mut rss0 = 0.0;
    for share in shares {
        let (aw, bw, rss) = *share?;
        for (row, roww) in a.iter_mut().zip(&aw) {
            for (x, y) in row.iter_mut().zip(roww) {
                *x += y;
            }
        }
        for (x, y) in b.iter_mut().zip(&bw) {
            *x += y;
        }
        rss0 += rss;
    }
    // Unused directions: identity rows, so the padded system stays regular.
    for j in (0..=NS).flat_map(|m| m * TERMS + dirs.len()..(m + 1) * TERMS) {
        a[j][j] = 1.0;
    }
    let n = all.len();
    let k = dirs.len();
    // The tone alone: the least squares over its block, and the fall in the
    // residual it gives (βᵀAβ = −βᵀb).
    let (tone, explained_tone) = {
        let mut at = [[0.0; TERMS]; TERMS];
        for (row, full) in at.iter_mut().zip(&a) {
            row.copy_from_slice(&full[..TERMS]);
        }
        let bt: [f64; TERMS] = std::array::from_fn(|i| b[i]);
        let tiny = 1e-12 * (0..TERMS).map(|i| at[i][i]).fold(0.0, f64::max);
        let beta = crate::linalg::solve(at, bt.map(|x| -x), tiny.max(1e-300))?;
        let explained = -(0..TERMS).map(|j| beta[j] * bt[j]).sum::<f64>();
        (beta, explained)
    };
    let dof_tone = n.checked_sub(NX * wins.len() + k)?.max(1) as f64;
    let s2_tone = ((rss0 - explained_tone) / dof_tone).max(1e-300);
    // With a sharpening of the code beside it (each direction again times q
    // and q²): used where it explains significantly more. Where that larger
    // system cannot be solved, the tone alone stands.
    let with_sharpening = sharpened_fit(
        &a,
        &b,
        rss0,
        explained_tone,
        n,
        NX * wins.len() + k * (1 + NS),
    );
    let (beta, significance, sharpening_seen) = match with_sharpening {
        Some((beta, significance)) => (beta, significance, true),
        None => (tone, (explained_tone.max(0.0) / s2_tone).sqrt(), false),
    };
    let mut coef = [0.0; NF];
    for (j, d) in dirs.iter().enumerate() {
        for m in 0..NF {
            coef[m] += beta[j] * d[m];
        }
    }
    let pass = Pass {
        coef,
        code_mid_half: mh,
    };
    let (vlo, vhi) = (base.apply(lo), base.apply(hi));
    let one = |v: f64| pass.apply(base, v);
    Some(PassFit {
        pass,
        significance,
        sharpening_seen,
        effect: effect_at_half(&one, 0.5 * (vlo + vhi), 0.5 * (vhi - vlo)),
        code_range: (lo, hi),
        windows: wins.len(),
    })
}

/// The tone's coefficients and Wald distance (σ) fitted with a sharpening of
/// the code beside it (the normal system `a`, `b` over the tone's directions
/// and their q, q² twins; `rss0` the residual with none, `explained_tone` the
/// fall the tone alone gives, `n` rows and `used` parameters with the
/// windows'): None where the sharpening does not explain the shapes beyond
/// [`MIN_SHARPENING_SIGNIFICANCE`] more than the tone alone, or the system
/// is singular.
fn sharpened_fit(
    a: &[[f64; NP]; NP],
    b: &[f64; NP],
    rss0: f64,
    explained_tone: f64,
    n: usize,
    used: usize,
) -> Option<([f64; TERMS], f64)> {
    let tiny = 1e-12 * (0..NP).map(|i| a[i][i]).fold(0.0, f64::max);
    let both = crate::linalg::solve(*a, b.map(|x| -x), tiny.max(1e-300))?;
    let explained = -(0..NP).map(|j| both[j] * b[j]).sum::<f64>();
    let s2 = ((rss0 - explained) / n.checked_sub(used)?.max(1) as f64).max(1e-300);
    if !(((explained - explained_tone).max(0.0) / s2).sqrt() > MIN_SHARPENING_SIGNIFICANCE) {
        return None;
    }
    // The tone's Wald distance with the sharpening profiled out: the fall
    // beyond what the sharpening alone explains.
    let (mut a2, mut b2) = (*a, *b);
    for i in 0..NP {
        for j in 0..NP {
            if i < TERMS || j < TERMS {
                a2[i][j] = if i == j { 1.0 } else { 0.0 };
            }
        }
        if i < TERMS {
            b2[i] = 0.0;
        }
    }
    let g = crate::linalg::solve(a2, b2.map(|x| -x), tiny.max(1e-300))?;
    let sharp_only = -(0..NP).map(|j| g[j] * b2[j]).sum::<f64>();
    Some((
        std::array::from_fn(|i| both[i]),
        ((explained - sharp_only).max(0.0) / s2).sqrt(),
    ))
}
