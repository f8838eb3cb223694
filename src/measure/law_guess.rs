//! The first guess of a sweep's phase law, from the profile itself: the
//! profile resampled onto its uniform bin grid, smoothed, its zero crossings
//! about the local mean and the local half period they give, and the noise
//! level; [`initial_laws`] fits each family of [`super::law`] to the
//! crossings' phases.

#![allow(clippy::needless_range_loop, clippy::neg_cmp_op_on_partial_ord)]

use super::law::{LawKind, PhaseLaw, fit_law};
use super::profile::Profile;

/// The profile resampled onto its uniform bin grid (empty bins filled linearly): (s of bin 0 centre, step, values).
pub fn uniform(prof: &Profile) -> (f64, f64, Vec<f64>) {
    let bin = prof.bin;
    let n = ((prof.length / bin).ceil() as usize).max(1);
    let mut v = vec![f64::NAN; n];
    for k in 0..prof.s.len() {
        let b = ((prof.s[k] / bin) as usize).min(n - 1);
        v[b] = prof.y[k];
    }
    fill_gaps(&mut v);
    (0.5 * bin, bin, v)
}

/// Like [`uniform`], but on the finest grid (a whole multiple of the bin width, at most 8)
/// on which at most 5 % of the cells are empty, so that little needs filling in.
/// Each cell is the count-weighted mean of the bins that fall in it. Also returns the
/// mean variance of sample positions within a cell (strip units²).
pub fn uniform_dense(prof: &Profile) -> (f64, f64, Vec<f64>, f64) {
    let mut best = None;
    for k in 1..=8usize {
        let step = prof.bin * k as f64;
        let n = ((prof.length / step).ceil() as usize).max(1);
        let mut sum = vec![0.0f64; n];
        let mut cnt = vec![0.0f64; n];
        let mut ss = vec![0.0f64; n];
        let mut ss2 = vec![0.0f64; n];
        for i in 0..prof.s.len() {
            let b = ((prof.s[i] / step) as usize).min(n - 1);
            let c = prof.count[i];
            sum[b] += prof.y[i] * c;
            cnt[b] += c;
            ss[b] += prof.s[i] * c;
            ss2[b] += (prof.s[i] * prof.s[i] + prof.var_s[i]) * c;
        }
        let (mut vsum, mut vn) = (0.0f64, 0.0f64);
        for b in 0..n {
            if cnt[b] > 0.0 {
                let m = ss[b] / cnt[b];
                vsum += (ss2[b] / cnt[b] - m * m).max(0.0);
                vn += 1.0;
            }
        }
        let avg_var = vsum / vn.max(1.0);
        // Only the span between the first and last filled cells matters.
        let first = cnt.iter().position(|&c| c > 0.0).unwrap_or(0);
        let last = cnt.iter().rposition(|&c| c > 0.0).unwrap_or(0);
        let empty = cnt[first..=last].iter().filter(|&&c| c == 0.0).count();
        let mut v: Vec<f64> = (0..n)
            .map(|b| {
                if cnt[b] > 0.0 {
                    sum[b] / cnt[b]
                } else {
                    f64::NAN
                }
            })
            .collect();
        let ok = (empty as f64) <= 0.05 * (last + 1 - first) as f64;
        if ok || k == 8 {
            fill_gaps(&mut v);
            best = Some((0.5 * step, step, v, avg_var));
            break;
        }
    }
    best.unwrap_or_else(|| {
        let (a, b, v) = uniform(prof);
        (a, b, v, 0.0)
    })
}

fn fill_gaps(v: &mut [f64]) {
    let known: Vec<usize> = (0..v.len()).filter(|&i| v[i].is_finite()).collect();
    if known.is_empty() {
        v.iter_mut().for_each(|x| *x = 0.0);
        return;
    }
    let (first, last) = (known[0], *known.last().unwrap_or(&0));
    let (vf, vl) = (v[first], v[last]);
    v[..first].iter_mut().for_each(|x| *x = vf);
    v[last + 1..].iter_mut().for_each(|x| *x = vl);
    for w in known.windows(2) {
        let (a, b) = (w[0], w[1]);
        for i in a + 1..b {
            v[i] = v[a] + (v[b] - v[a]) * (i - a) as f64 / (b - a) as f64;
        }
    }
}

/// Moving average with a per-sample window half-width (in samples), by cumulative sums.
pub fn moving_mean(v: &[f64], half: impl Fn(usize) -> usize) -> Vec<f64> {
    let mut cum = Vec::with_capacity(v.len() + 1);
    cum.push(0.0);
    let mut acc = 0.0;
    for &x in v {
        acc += x;
        cum.push(acc);
    }
    (0..v.len())
        .map(|i| {
            let h = half(i);
            let a = i.saturating_sub(h);
            let b = (i + h + 1).min(v.len());
            (cum[b] - cum[a]) / (b - a) as f64
        })
        .collect()
}

/// Moving average over ±`half(i)` samples (fractional), treating samples as unit cells; by cumulative sums.
pub fn moving_mean_frac(v: &[f64], half: impl Fn(usize) -> f64) -> Vec<f64> {
    let n = v.len();
    let mut cum = Vec::with_capacity(n + 1);
    cum.push(0.0);
    let mut acc = 0.0;
    for &x in v {
        acc += x;
        cum.push(acc);
    }
    // Integral of the piecewise-constant signal from cell edge 0 to x.
    let integral = |x: f64| -> f64 {
        let x = x.clamp(0.0, n as f64);
        let k = (x.floor() as usize).min(n - 1);
        cum[k] + (x - k as f64) * v[k]
    };
    (0..n)
        .map(|i| {
            let h = half(i).max(0.5);
            let c = i as f64 + 0.5;
            let (a, b) = ((c - h).max(0.0), (c + h).min(n as f64));
            (integral(b) - integral(a)) / (b - a)
        })
        .collect()
}

/// Zero crossings of `d` with hysteresis `h[i]`: (position in samples, rising?).
fn crossings(d: &[f64], h: &[f64]) -> Vec<(f64, bool)> {
    let mut out = Vec::new();
    let mut state = 0i8;
    let mut last_zero = 0.0;
    for i in 0..d.len() {
        if i > 0 && (d[i - 1] < 0.0) != (d[i] < 0.0) {
            let t = d[i - 1] / (d[i - 1] - d[i]);
            last_zero = (i - 1) as f64 + t;
        }
        if d[i] > h[i] && state != 1 {
            if state == -1 {
                out.push((last_zero, true));
            }
            state = 1;
        } else if d[i] < -h[i] && state != -1 {
            if state == 1 {
                out.push((last_zero, false));
            }
            state = -1;
        }
    }
    out
}

/// How many leading zero crossings the law's first guess may skip (an end's step into the surround).
const LEADING_CROSSINGS: usize = 4;

/// (s, phase in cycles, weight) samples of a phase law.
pub type PhasePoints = Vec<(f64, f64, f64)>;

/// The profile's zero crossings as (s, phase) points over the well-resolved
/// low-frequency part (stops where the half-periods become irregular, the
/// oscillation fades, or `max_cy_px` is reached). `s_per_px` gives strip
/// units per pixel at s.
fn crossing_points(
    prof: &Profile,
    s_per_px: impl Fn(f64) -> f64,
    max_cy_px: f64,
) -> Option<PhasePoints> {
    let (s0, ds, v) = uniform(prof);
    let n = v.len();
    if n < 16 {
        return None;
    }
    // Pass 1: wide moving mean; pass 2: one local period.
    let mut trend = moving_mean(&v, |_| n / 16);
    let mut cross = Vec::new();
    for pass in 0..2 {
        let d: Vec<f64> = v.iter().zip(&trend).map(|(a, b)| a - b).collect();
        let sq: Vec<f64> = d.iter().map(|x| x * x).collect();
        let half_env = if pass == 0 {
            vec![n / 16; n]
        } else {
            local_half_period(&cross, n)
        };
        let rms = moving_mean(&sq, |i| half_env[i].max(2));
        let noise = noise_sigma(&v);
        let h: Vec<f64> = rms
            .iter()
            .map(|r| (0.35 * r.sqrt()).max(2.5 * noise))
            .collect();
        cross = crossings(&d, &h);
        if cross.len() < 4 {
            return None;
        }
        let hp = local_half_period(&cross, n);
        trend = moving_mean(&v, |i| hp[i]);
    }
    // Accept crossings while the half-periods shrink smoothly, from the
    // first crossing or, where the strip's end holds a step (an end given a
    // few px beyond the printed strip, into its surround: two crossings a
    // pixel or two apart), from one of the next few: the longest such run.
    let run = |k0: usize| {
        let mut pts = Vec::new();
        let first_phase = if cross[k0].1 { -0.25 } else { 0.25 };
        for k in k0..cross.len() {
            let s = s0 + cross[k].0 * ds;
            if k >= k0 + 2 {
                let p1 = cross[k].0 - cross[k - 1].0;
                let p0 = cross[k - 1].0 - cross[k - 2].0;
                if !(p1 > 0.45 * p0 && p1 < 1.8 * p0) {
                    break;
                }
                // Frequency in cycles/pixel from the half-period.
                let f_px = s_per_px(s) / (2.0 * p1 * ds);
                if f_px > max_cy_px {
                    break;
                }
            }
            pts.push((s, first_phase + 0.5 * (k - k0) as f64, 1.0));
        }
        pts
    };
    let mut pts = run(0);
    for k0 in 1..cross.len().min(LEADING_CROSSINGS + 1) {
        let other = run(k0);
        if other.len() > pts.len() {
            pts = other;
        }
    }
    if pts.len() < 8 {
        return None;
    }
    Some(pts)
}

/// A first phase law from the profile's zero crossings: the best-fitting
/// family (or `kind`) over the regularly spaced crossings, with those
/// crossings as (s, phase, weight) points.
pub fn initial_law(
    prof: &Profile,
    kind: Option<LawKind>,
    s_per_px: impl Fn(f64) -> f64,
    max_cy_px: f64,
) -> Option<(PhaseLaw, PhasePoints)> {
    let kinds: &[LawKind] = match &kind {
        Some(k) => std::slice::from_ref(k),
        None => &[LawKind::Linear, LawKind::Log],
    };
    let (laws, pts) = initial_laws(prof, kinds, s_per_px, max_cy_px)?;
    let best = laws.into_iter().min_by(|a, b| a.1.total_cmp(&b.1))?;
    Some((best.0, pts))
}

/// First phase laws of each family in `kinds` (with their RMS residuals,
/// cycles) from one search for the profile's zero crossings.
pub fn initial_laws(
    prof: &Profile,
    kinds: &[LawKind],
    s_per_px: impl Fn(f64) -> f64,
    max_cy_px: f64,
) -> Option<(Vec<(PhaseLaw, f64)>, PhasePoints)> {
    let pts = crossing_points(prof, s_per_px, max_cy_px)?;
    let laws: Vec<_> = kinds.iter().filter_map(|&k| fit_law(&pts, k)).collect();
    (!laws.is_empty()).then_some((laws, pts))
}

/// Half a local period (in samples) at every sample, from crossings (which are half a period apart).
fn local_half_period(cross: &[(f64, bool)], n: usize) -> Vec<usize> {
    let mut out = vec![n / 16; n];
    if cross.len() < 2 {
        return out;
    }
    let mut k = 0;
    for (i, o) in out.iter_mut().enumerate() {
        let x = i as f64;
        while k + 2 < cross.len() && cross[k + 1].0 < x {
            k += 1;
        }
        let hp = cross[k + 1].0 - cross[k].0;
        *o = (hp.round() as usize).max(1);
    }
    out
}

/// Robust noise estimate of a uniformly sampled profile (from second differences).
pub fn noise_sigma(v: &[f64]) -> f64 {
    if v.len() < 3 {
        return 0.0;
    }
    let mut d: Vec<f64> = v
        .windows(3)
        .map(|w| (w[0] - 2.0 * w[1] + w[2]).abs())
        .collect();
    let mid = d.len() / 2;
    d.select_nth_unstable_by(mid, |a, b| a.total_cmp(b));
    d[mid] * 1.4826 / 6f64.sqrt()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn finds_a_chirp_from_crossings() {
        let law = PhaseLaw {
            kind: LawKind::Linear,
            c0: 0.1,
            c1: 0.01,
            c2: 0.4 / 4000.0 / 2.0,
            persp: 0.0,
        };
        let n = 4000 * 4;
        let prof = Profile {
            s: (0..n).map(|i| (i as f64 + 0.5) * 0.25).collect(),
            y: (0..n)
                .map(|i| {
                    let s = (i as f64 + 0.5) * 0.25;
                    0.4 + 0.00002 * s + 0.2 * (2.0 * std::f64::consts::PI * law.phase(s)).cos()
                })
                .collect(),
            count: vec![1.0; n],
            var_s: vec![0.0; n],
            bin: 0.25,
            length: 4000.0,
            ..Profile::default()
        };
        let (fit, pts) = initial_law(&prof, None, |_| 1.0, 0.3).unwrap();
        assert!(pts.len() > 100);
        assert_eq!(fit.kind, LawKind::Linear);
        for s in [100.0, 1000.0, 2000.0] {
            assert!((fit.freq(s) / law.freq(s) - 1.0).abs() < 0.01, "{s}");
        }
    }

    /// A log sweep whose first 2 px are the strip's white surround (an end
    /// given just beyond the printed strip): the step's two crossings, a
    /// pixel or two apart, used to end the run of regular half-periods
    /// before it began ("fewer than 5 regular cycles").
    #[test]
    fn a_step_into_the_surround_at_the_start_is_skipped() {
        let (f0, k) = (0.008, (0.6f64 / 0.008).ln() / 1400.0);
        let n = 1400 * 4;
        let y: Vec<f64> = (0..n)
            .map(|i| {
                let x = (i as f64 + 0.5) * 0.25 - 2.0;
                if x < 0.0 {
                    1.0
                } else {
                    let phase = f0 / k * ((k * x).exp() - 1.0);
                    0.5 + 0.4 * (2.0 * std::f64::consts::PI * phase).sin()
                }
            })
            .collect();
        let prof = Profile {
            s: (0..n).map(|i| (i as f64 + 0.5) * 0.25).collect(),
            y,
            count: vec![1.0; n],
            var_s: vec![0.0; n],
            bin: 0.25,
            length: 1400.0,
            ..Profile::default()
        };
        let (fit, pts) = initial_law(&prof, Some(LawKind::Log), |_| 1.0, 0.3).unwrap();
        assert!(pts.len() > 100, "{} crossings", pts.len());
        for s in [200.0, 600.0, 1000.0] {
            let want = f0 * (k * (s - 2.0)).exp();
            assert!(
                (fit.freq(s) / want - 1.0).abs() < 0.02,
                "{s}: {} against {want}",
                fit.freq(s)
            );
        }
    }
}
