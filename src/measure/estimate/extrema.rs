//! The paper's method: local maxima and minima of the profile, one per half
//! period, located to sub-bin precision by a least-squares parabola through
//! the bins around each extremum, and M = (Amax − Amin)/(Amax + Amin) for each
//! adjacent max/min pair. Each extremum is first divided by the local mean (the
//! count-weighted mean of the bins within one period around it), so that uneven
//! light (a gradient or vignetting, which differ between a maximum and its
//! neighbouring minimum) does not bias the modulation.

#![allow(clippy::needless_range_loop, clippy::neg_cmp_op_on_partial_ord)]

use super::{Estimator, ModPoint, bin_attenuation};
use crate::measure::curve::solve3;
use crate::measure::law::PhaseLaw;
use crate::measure::profile::Profile;

/// The extrema estimator.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Extrema;

/// One located extremum: position, value and the value's uncertainty.
#[derive(Debug, Clone, Copy)]
struct Peak {
    s: f64,
    value: f64,
    var: f64,
}

fn locate(prof: &Profile, phases: &[f64], centre: f64, is_max: bool) -> Option<Peak> {
    // Search ±0.25 cycle around the expected extremum for the extreme bin.
    let a = phases.partition_point(|&p| p < centre - 0.25);
    let b = phases.partition_point(|&p| p <= centre + 0.25);
    if b < a + 3 {
        return None;
    }
    let sign = if is_max { 1.0 } else { -1.0 };
    let k = (a..b).max_by(|&i, &j| (sign * prof.y[i]).total_cmp(&(sign * prof.y[j])))?;
    if k == a || k + 1 == b {
        return None; // the extremum sits at the edge of its half period: not resolved
    }
    // Least-squares parabola over the bins within ±0.08 cycle (at least the 3 nearest).
    let pk = phases[k];
    let mut lo = phases.partition_point(|&p| p < pk - 0.08).max(a);
    let mut hi = phases.partition_point(|&p| p <= pk + 0.08).min(b);
    if hi < lo + 3 {
        lo = k - 1;
        hi = k + 2;
    }
    let x0 = prof.s[k];
    let mut m = [[0.0f64; 3]; 3];
    let mut r = [0.0f64; 3];
    for i in lo..hi {
        let x = prof.s[i] - x0;
        let row = [1.0, x, x * x];
        let w = prof.count[i];
        for p in 0..3 {
            r[p] += w * row[p] * prof.y[i];
            for q in 0..3 {
                m[p][q] += w * row[p] * row[q];
            }
        }
    }
    let c = solve3(m, r)?;
    let (value, s) = if c[2] * sign < 0.0 {
        let xv = (-c[1] / (2.0 * c[2])).clamp(prof.s[lo] - x0, prof.s[hi - 1] - x0);
        (c[0] + c[1] * xv + c[2] * xv * xv, x0 + xv)
    } else {
        (prof.y[k], x0)
    };
    let n = (hi - lo) as f64;
    let res: f64 = (lo..hi)
        .map(|i| {
            let x = prof.s[i] - x0;
            let e = prof.y[i] - (c[0] + c[1] * x + c[2] * x * x);
            prof.count[i] * e * e
        })
        .sum::<f64>();
    let wsum: f64 = prof.count[lo..hi].iter().sum();
    let var = if n > 3.0 {
        res / (n - 3.0) / wsum * 2.0
    } else {
        0.0
    };
    Some(Peak { s, value, var })
}

impl Estimator for Extrema {
    fn name(&self) -> &'static str {
        "extrema"
    }

    fn estimate(&self, prof: &Profile, law: &PhaseLaw, _grid: &[f64]) -> Vec<ModPoint> {
        if prof.s.len() < 8 {
            return Vec::new();
        }
        let phases: Vec<f64> = prof.s.iter().map(|&s| law.phase(s)).collect();
        let (p_lo, p_hi) = (phases[0], phases[phases.len() - 1]);
        // Maxima at integer phases, minima at half-integers.
        let first = (2.0 * p_lo).ceil() as i64;
        let last = (2.0 * p_hi).floor() as i64;
        let peaks: Vec<Option<Peak>> = (first..=last)
            .map(|j| locate(prof, &phases, j as f64 / 2.0, j.rem_euclid(2) == 0))
            .collect();
        // Prefix sums of count·y and count, for one-period local means.
        let mut cy = vec![0.0f64; prof.s.len() + 1];
        let mut cn = vec![0.0f64; prof.s.len() + 1];
        for k in 0..prof.s.len() {
            cy[k + 1] = cy[k] + prof.count[k] * prof.y[k];
            cn[k + 1] = cn[k] + prof.count[k];
        }
        // Bin k spans the phases between the midpoints to its neighbours; the
        // sums are interpolated linearly inside a bin, so a window of exactly
        // one period takes fractions of its end bins (a whole-bin window is
        // biased by up to a bin's share of an extremum).
        let nb = phases.len();
        let edge = |k: usize| -> f64 {
            if k == 0 {
                phases[0] - 0.5 * (phases[1] - phases[0])
            } else if k == nb {
                phases[nb - 1] + 0.5 * (phases[nb - 1] - phases[nb - 2])
            } else {
                0.5 * (phases[k - 1] + phases[k])
            }
        };
        let cum = |q: f64, c: &[f64]| -> f64 {
            // The last edge at or below q.
            let k = phases.partition_point(|&x| x < q).clamp(1, nb) - 1;
            let k = if edge(k + 1) <= q { k + 1 } else { k };
            let k = k.min(nb - 1);
            let (e0, e1) = (edge(k), edge(k + 1));
            let t = ((q - e0) / (e1 - e0)).clamp(0.0, 1.0);
            c[k] + t * (c[k + 1] - c[k])
        };
        let local_mean = |s: f64| -> Option<f64> {
            let p = law.phase(s);
            // A full period must lie inside the strip.
            if !(p - 0.5 >= p_lo && p + 0.5 <= p_hi) {
                return None;
            }
            let n = cum(p + 0.5, &cn) - cum(p - 0.5, &cn);
            (n > 0.0).then(|| (cum(p + 0.5, &cy) - cum(p - 0.5, &cy)) / n)
        };
        let mut out = Vec::new();
        for (i, w) in peaks.windows(2).enumerate() {
            let (Some(p), Some(q)) = (w[0], w[1]) else {
                continue;
            };
            let j = first + i as i64;
            let (mut mx, mut mn) = if j.rem_euclid(2) == 0 { (p, q) } else { (q, p) };
            // Relative to the local mean at each extremum: uneven light cancels.
            let (Some(mu_x), Some(mu_n)) = (local_mean(mx.s), local_mean(mn.s)) else {
                continue;
            };
            if !(mu_x > 0.0 && mu_n > 0.0) {
                continue;
            }
            mx.value /= mu_x;
            mx.var /= mu_x * mu_x;
            mn.value /= mu_n;
            mn.var /= mu_n * mu_n;
            let sum = mx.value + mn.value;
            if sum <= 0.0 || mx.value <= mn.value {
                continue;
            }
            let s = 0.5 * (p.s + q.s);
            let var_s = prof.var_s[prof.s.partition_point(|&x| x < s).min(prof.s.len() - 1)];
            let att = bin_attenuation(law.freq(s), var_s);
            let m = (mx.value - mn.value) / sum / att;
            let err = 2.0 * (mn.value.powi(2) * mx.var + mx.value.powi(2) * mn.var).sqrt()
                / (sum * sum)
                / att;
            out.push(ModPoint {
                s,
                modulation: m,
                err,
            });
        }
        out
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::measure::estimate::tests_support::chirp;

    #[test]
    fn noiseless_chirp_gives_the_known_modulation() {
        let (prof, law, truth) = chirp(0.0, 1);
        let pts = Extrema.estimate(&prof, &law, &[]);
        assert!(pts.len() > 500);
        for p in &pts {
            assert!(
                (p.modulation - truth(p.s)).abs() < 0.01,
                "{} {} {}",
                p.s,
                p.modulation,
                truth(p.s)
            );
        }
    }
}
