//! Where the printed sweep stops inside the region. Corners clicked by hand
//! may put a strip's end a few pixels beyond the printed sweep: the bins
//! there hold the paper (or whatever surrounds the sweep), the estimator's
//! last windows fit a sine through them, and their modulation falls (the
//! independent study's `varied` seed 12 #3, corners ±4 px: the high end 2.2 px
//! beyond the print read its last point 0.257 against 0.356 and the three
//! before it 0.011–0.014 low).
//!
//! The end is found as a change point: near each end of the profile, the
//! bins are fitted once by the sweep's model (mean and amplitude each
//! linear in s, the phase from the law) and once split at a candidate end,
//! the sweep's model inside and a straight line (no oscillation) beyond
//! (one level where the sweep's cycle is long, as at a log sweep's low end:
//! a line there stands in for part of a cycle).
//! Where the best split explains the bins better than the sweep alone by
//! far more than noise allows, the bins beyond it are left out. Whatever the
//! surround is (paper brighter than the sweep's mean, a dark frame, or a
//! grey equal to it, where only the oscillation stops) the split finds it;
//! an end inside the print (the sweep oscillates to the last bin) keeps
//! every bin. Each search covers the last [`SEARCH_PX`] of the bins, and an
//! end found there is searched again from just inside it, so an end clicked
//! up to about 24 px beyond the print is found (tested to 22 px). Farther,
//! the first search sees no sweep at all: at the high end, a surround whose
//! level steps to the sweep's mean (paper or a dark frame), or that shows no
//! oscillation where the print beyond it starts whole (a grey equal to the
//! sweep's mean), is then walked over to where it meets the print
//! ([`surround_end`], up to a quarter of the strip), and the search starts
//! there. The walk also starts where the searches stopped inside the
//! surround (a JPEG's block edge in a grey, taken for an end).

use super::law::PhaseLaw;
use super::profile::Profile;
use std::f64::consts::TAU;

/// How far inside the region's end the printed end is searched in one
/// round (image px): a hand's click, not a misplaced region.
const SEARCH_PX: f64 = 16.0;

/// Longest cycle (image px) at an end for the surround beyond a candidate
/// end to be fitted by a straight line; beyond it, by one level (see
/// [`find_end`]).
const LONGEST_CYCLE_PX: f64 = 10.0;

/// Searches in turn at most.
const ROUNDS: usize = 4;

/// How far inside an end found the next search starts (image px): clear of
/// the print's blurred edge.
const RESTART_PX: f64 = 2.0;

/// The stretch a surround beyond the high end is walked in (image px; see
/// [`surround_end`]).
const SURROUND_STEP_PX: f64 = 8.0;

/// Farthest a surround is followed inwards, as a fraction of the strip.
const MAX_SURROUND_FRACTION: f64 = 0.25;

/// How far (relative) a surround's level may wander from one stretch to
/// the next: light changes slowly along a strip.
const SURROUND_TOLERANCE: f64 = 0.1;

/// The least step in level (relative to the larger) from the surround to
/// the sweep's mean for a surround to be stepped over: paper (about twice
/// the mean of a sweep printed about mid-grey) or a dark frame; a grey equal
/// to the sweep's mean is not.
const MIN_STEP: f64 = 0.2;

/// Fewest image px beyond a candidate end for the split to be tried.
const MIN_BEYOND_PX: f64 = 1.0;

/// Cycles of the sweep fitted inside a candidate end (at least [`MIN_INSIDE_PX`]).
const INSIDE_CYCLES: f64 = 3.0;

/// Fewest image px fitted inside a candidate end.
const MIN_INSIDE_PX: f64 = 8.0;

/// Fewest filled bins fitted inside a candidate end beyond the search (those
/// of [`MIN_INSIDE_PX`] at the default 0.25 px bins): a strip along the pixel
/// rows fills one bin per pixel, and 8 px inside a grey's edge at 0.4 cy/px
/// then held 8 bins against the sweep model's 6 parameters (q75, turned
/// 0.01°: gain 32 against [`MIN_GAIN`], the grey kept, RMS 0.058).
const MIN_INSIDE_BINS: usize = 32;

/// The improvement in weighted squared residual, in units of the noise
/// variance, the split must bring to be taken: the best of some 60 candidate
/// ends, each with 2 more parameters than the sweep alone, reached 19.5 at
/// most by chance over 234 ends of noisy sweeps (`noise_alone_moves_no_end`);
/// a grey surround 2 px beyond a sweep of modulation 0.3 brings 117.
const MIN_GAIN: f64 = 50.0;

/// A printed end found inside the region.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(super) struct PrintedEnd {
    /// Where the sweep stops (strip units).
    pub s: f64,
    /// How far inside the region's end that is (image px).
    pub inside_px: f64,
}

/// The printed ends found inside the profile's low and high ends (None where
/// the sweep runs to the end).
pub(super) fn find(
    prof: &Profile,
    law: &PhaseLaw,
    s_per_px: &dyn Fn(f64) -> f64,
) -> [Option<PrintedEnd>; 2] {
    let n = prof.s.len();
    if n < 20 || prof.y.len() != n || prof.count.len() != n {
        return [None, None];
    }
    // Bins where the law's frequency is not positive (a linear sweep's law
    // over a surround clicked before the print's low end) are no print.
    let rise = prof.s.partition_point(|&s| !(law.freq(s) > 0.0));
    if rise >= n / 2 {
        return [None, None];
    }
    let ends = [false, true].map(|high| {
        let edge = if high { prof.s[n - 1] } else { prof.s[0] };
        let mut bins = if high { 0..n } else { rise..n };
        let mut found = (!high && rise > 0).then(|| PrintedEnd {
            s: prof.s[rise],
            inside_px: (prof.s[rise] - edge).abs() / s_per_px(prof.s[rise]),
        });
        // An end clicked farther out than one search is followed inwards,
        // each search starting clear of the last one's blurred edge.
        let mut walked = false;
        for _ in 0..ROUNDS {
            let Some(s) = find_end(prof, law, s_per_px, high, bins.clone()) else {
                // Nothing more at the high end: a surround reaching farther
                // than the searches is stepped over, once, to where it meets
                // the sweep. (A search may have stopped inside the surround,
                // at a JPEG's block edge in a grey: the walk starts there.)
                if !high || walked {
                    break;
                }
                walked = true;
                match surround_end(prof, law, s_per_px, bins.end) {
                    Some(z) if z < bins.end => {
                        bins = bins.start..z;
                        continue;
                    }
                    _ => break,
                }
            };
            let px = s_per_px(s);
            found = Some(PrintedEnd {
                s,
                inside_px: (s - edge).abs() / px,
            });
            bins = if high {
                let z = prof.s.partition_point(|&v| v < s - RESTART_PX * px);
                bins.start..z
            } else {
                prof.s.partition_point(|&v| v <= s + RESTART_PX * px)..bins.end
            };
        }
        found
    });
    // Ends that would leave less than half the strip are no click's few
    // pixels but a sweep the law does not follow: nothing is cut.
    let (first, last) = (prof.s[0], prof.s[n - 1]);
    let kept = ends[1].map_or(last, |e| e.s) - ends[0].map_or(first, |e| e.s);
    if kept < 0.5 * (last - first) {
        return [None, None];
    }
    ends
}

/// Leaves out the bins beyond each printed end found, and `margin_px` more
/// (the blur of the print's own edge), so the profile holds only the sweep.
pub(super) fn cut(
    prof: &mut Profile,
    parity: &mut Vec<[f64; 3]>,
    ends: &[Option<PrintedEnd>; 2],
    margin_px: f64,
    s_per_px: &dyn Fn(f64) -> f64,
) {
    let n = prof.s.len();
    let lo = ends[0].map_or(0, |e| {
        prof.s
            .partition_point(|&s| s < e.s + margin_px * s_per_px(e.s))
    });
    let hi = ends[1].map_or(n, |e| {
        prof.s
            .partition_point(|&s| s < e.s - margin_px * s_per_px(e.s))
    });
    if lo >= hi {
        return;
    }
    keep(&mut prof.s, lo, hi);
    keep(&mut prof.y, lo, hi);
    keep(&mut prof.count, lo, hi);
    keep(&mut prof.var_s, lo, hi);
    // Per-bin flags and parities, where the profile has them.
    if prof.clipped.len() == n {
        keep(&mut prof.clipped, lo, hi);
    }
    if parity.len() == n {
        keep(parity, lo, hi);
    }
}

/// Keeps the entries `lo..hi` of `v`.
fn keep<T>(v: &mut Vec<T>, lo: usize, hi: usize) {
    v.truncate(hi);
    v.drain(..lo);
}

/// An end found closer than this to the region's end (image px) is named in
/// no note: exact corners find the print's own blurred edge there (the
/// simulator's strips: 1.1 px at the low end).
const NOTED_PX: f64 = 1.5;

/// The note naming the printed ends found inside the region, if any.
pub(super) fn note(inside_px: &[Option<f64>; 2]) -> Option<String> {
    let said: Vec<String> = inside_px
        .iter()
        .zip(["low", "high"])
        .filter_map(|(d, which)| {
            d.filter(|&d| d >= NOTED_PX)
                .map(|d| format!("{d:.1} px inside its {which}-frequency end"))
        })
        .collect();
    (!said.is_empty()).then(|| {
        format!(
            "the printed sweep stops {} of the region (corners beyond the print); \
             the bins beyond were left out",
            said.join(" and ")
        )
    })
}

/// Weighted least squares by normal equations over rows of `P` regressors.
#[derive(Clone, Copy)]
struct Normal<const P: usize> {
    ata: [[f64; P]; P],
    aty: [f64; P],
    yy: f64,
    w: f64,
}

impl<const P: usize> Normal<P> {
    fn new() -> Self {
        Normal {
            ata: [[0.0; P]; P],
            aty: [0.0; P],
            yy: 0.0,
            w: 0.0,
        }
    }

    fn add(&mut self, x: &[f64; P], y: f64, w: f64) {
        for i in 0..P {
            self.aty[i] += w * x[i] * y;
            for j in 0..P {
                self.ata[i][j] += w * x[i] * x[j];
            }
        }
        self.yy += w * y * y;
        self.w += w;
    }

    /// The fitted coefficients; None when the system is singular.
    fn solve(&self) -> Option<[f64; P]> {
        crate::linalg::solve(self.ata, self.aty, 1e-12 * self.w.max(1e-300))
    }

    /// The weighted squared residual of the fit; None when it is singular.
    fn rss(&self) -> Option<f64> {
        let beta = crate::linalg::solve(self.ata, self.aty, 1e-12 * self.w.max(1e-300))?;
        let fitted: f64 = beta.iter().zip(&self.aty).map(|(b, a)| b * a).sum();
        let r = self.yy - fitted;
        r.is_finite().then_some(r.max(0.0))
    }
}

/// One end's search over the bins `bins` (`high`: the high-frequency end, at
/// the largest s): where the sweep stops (strip units), if it does.
fn find_end(
    prof: &Profile,
    law: &PhaseLaw,
    s_per_px: &dyn Fn(f64) -> f64,
    high: bool,
    bins: std::ops::Range<usize>,
) -> Option<f64> {
    if bins.len() < 20 || bins.end > prof.s.len() {
        return None;
    }
    let (first, last) = (prof.s[bins.start], prof.s[bins.end - 1]);
    let edge = if high { last } else { first };
    let px = s_per_px(edge);
    let f = law.freq(edge);
    if !(px > 0.0 && px.is_finite() && f > 0.0 && f.is_finite()) {
        return None;
    }
    // Where a cycle is longer than [`LONGEST_CYCLE_PX`], a straight line
    // beyond a candidate end stands in for part of a cycle (a log sweep's
    // low end, 58 px a cycle, read an end 6.4 px inside exact corners): the
    // surround beyond is then one level, a constant.
    let level_beyond = f * px * LONGEST_CYCLE_PX < 1.0;
    let span = last - first;
    let search = (SEARCH_PX * px).min(0.2 * span);
    let inside = (INSIDE_CYCLES / law.freq(if high { edge - search } else { edge + search }))
        .max(MIN_INSIDE_PX * px)
        .min(0.3 * span);
    if !(inside.is_finite() && search > MIN_BEYOND_PX * px) {
        return None;
    }
    // Farther in where the bins there are sparse, up to the same bound.
    let inside =
        inside.max(filled_depth(prof, high, edge, search, MIN_INSIDE_BINS).min(0.3 * span));
    // Bins ordered from the inside outwards; x counts strip units from the
    // region's end, positive inwards.
    let idx: Vec<usize> = if high {
        let a = prof.s.partition_point(|&s| s < edge - search - inside);
        (a.max(bins.start)..bins.end).collect()
    } else {
        let b = prof.s.partition_point(|&s| s <= edge + search + inside);
        (bins.start..b.min(bins.end)).rev().collect()
    };
    let scale = search + inside;
    let rows: Vec<([f64; 6], f64, f64, f64)> = idx
        .iter()
        .filter(|&&k| !prof.is_clipped(k) && prof.count[k] > 0.0 && prof.y[k].is_finite())
        .map(|&k| {
            let x = (prof.s[k] - edge).abs() / scale;
            let (sn, cs) = (TAU * law.phase(prof.s[k])).sin_cos();
            (
                [1.0, x, cs, sn, x * cs, x * sn],
                prof.y[k],
                prof.count[k],
                (prof.s[k] - edge).abs(),
            )
        })
        .collect();
    // rows run from the inside (large depth) to the end (depth 0)
    if rows.len() < 24 || rows.iter().any(|r| r.0.iter().any(|v| !v.is_finite())) {
        return None;
    }
    let mut whole = Normal::<6>::new();
    for r in &rows {
        whole.add(&r.0, r.1, r.2);
    }
    let null = whole.rss()?;
    // Prefix sums from the inside: the sweep's model over rows[..i], the
    // straight line over rows[i..] (suffix, built from the end backwards).
    let m = rows.len();
    let mut suffix: Vec<Normal<2>> = Vec::with_capacity(m + 1);
    let mut acc = Normal::<2>::new();
    suffix.push(Normal::<2>::new());
    for r in rows.iter().rev() {
        acc.add(&[1.0, r.0[1]], r.1, r.2);
        suffix.push(acc);
    }
    suffix.reverse(); // suffix[i]: rows[i..]
    let mut prefix = Normal::<6>::new();
    let mut best: Option<(f64, f64, usize)> = None; // (split rss, end depth, rows inside)
    for i in 0..m {
        prefix.add(&rows[i].0, rows[i].1, rows[i].2);
        let depth = rows[i].3;
        let next = rows.get(i + 1).map_or(0.0, |r| r.3);
        // The end between rows i and i+1: the sweep inside, a line beyond.
        let end = 0.5 * (depth + next);
        if end > search || end < MIN_BEYOND_PX * px || i + 1 < 12 {
            continue;
        }
        let beyond = &suffix[i + 1];
        let b = if level_beyond {
            level_rss(beyond)
        } else {
            line_rss(beyond)
        };
        let (Some(a), Some(b)) = (prefix.rss(), b) else {
            continue;
        };
        if best.is_none_or(|(r, _, _)| a + b < r) {
            best = Some((a + b, end, i + 1));
        }
    }
    let (split, depth, _) = best?;
    let dof = (m as f64 - 8.0).max(1.0);
    // Noise variance per unit weight from the split's own residual.
    let var = split / dof;
    let gain = null - split;
    (var > 0.0 && gain > MIN_GAIN * var).then_some(if high { edge - depth } else { edge + depth })
}

/// How far inwards (strip units) from `search` beyond the region's end
/// (`edge`) the `want`-th filled bin lies; 0 where there are fewer.
fn filled_depth(prof: &Profile, high: bool, edge: f64, search: f64, want: usize) -> f64 {
    let filled = |&k: &usize| prof.count[k] > 0.0 && prof.y[k].is_finite();
    let depth = |k: usize| (prof.s[k] - edge).abs() - search;
    let nth = if high {
        let z = prof.s.partition_point(|&v| v <= edge - search);
        (0..z).rev().filter(filled).nth(want - 1)
    } else {
        let a = prof.s.partition_point(|&v| v < edge + search);
        (a..prof.s.len()).filter(filled).nth(want - 1)
    };
    nth.map_or(0.0, depth)
}

/// Where a surround beyond the high end, too long for one search to see the
/// sweep, meets it: the bins are walked inwards in stretches of
/// [`SURROUND_STEP_PX`], each fitted by a level and the sweep's cosine and
/// sine (so part of a cycle does not move the level), while the level stays
/// the surround's. Where it leaves it, the level one stretch farther in must
/// differ from the surround's by [`MIN_STEP`] (a step, not the light's slow
/// change, nor a sweep whose modulation has faded: its level stays its
/// mean). Where the region's end shows no oscillation and one appears at
/// the surround's level (a grey equal to the sweep's mean), the two
/// stretches farther in must both show it clearly ([`SWEEP_GAIN`]) and at
/// one amplitude (within [`SAME_AMPLITUDE`]): the print's edge, where the
/// sweep starts whole, not a modulation growing back from a fade or from a
/// zero of the MTF (defocus), which grows from stretch to stretch. Returns
/// the end (exclusive bin index) for the next search: one stretch of
/// surround beyond the stretch where the level or the oscillation changed.
/// The walk starts at the bins before `end` (exclusive bin index).
/// None where the cycle there is long (one stretch would not hold one), the
/// surround is not followed to such a change within
/// [`MAX_SURROUND_FRACTION`] of the strip, or the bins cannot be fitted.
fn surround_end(
    prof: &Profile,
    law: &PhaseLaw,
    s_per_px: &dyn Fn(f64) -> f64,
    end: usize,
) -> Option<usize> {
    let n = end.min(prof.s.len());
    let (first, edge) = (*prof.s.first()?, *prof.s[..n].last()?);
    let px = s_per_px(edge);
    let f = law.freq(edge);
    if !(px > 0.0 && px.is_finite() && f > 0.0 && f * px * LONGEST_CYCLE_PX >= 1.0) {
        return None;
    }
    let step = SURROUND_STEP_PX * px;
    let reach = MAX_SURROUND_FRACTION * (edge - first);
    if !(reach > step && reach.is_finite()) {
        return None;
    }
    let fit = |b: f64| stretch_fit(prof, law, b - step, b);
    let end_fit = fit(edge)?;
    // The region's end shows no oscillation: the surround may be a grey.
    let quiet = end_fit.gain < no_sweep_gain(end_fit.dof);
    let mut prev = end_fit.level;
    // Two levels alike: within the light's slow change.
    let kept = |a: f64, b: f64| (a - b).abs() <= SURROUND_TOLERANCE * a.abs().max(b.abs());
    let mut k = 1.0;
    loop {
        let b = edge - k * step;
        if edge - (b - step) > reach {
            return None;
        }
        let here = fit(b)?;
        if kept(here.level, prev) {
            // At the surround's level: the oscillation starts here (a grey),
            // the sweep whole one stretch in and the next alike? (Where the
            // level steps one stretch in, the walk goes on to the step.)
            if quiet && here.gain >= no_sweep_gain(here.dof) {
                let in1 = fit(b - step)?;
                if kept(in1.level, here.level) {
                    let in2 = fit(b - 2.0 * step)?;
                    let ratio = in1.amp / in2.amp;
                    let whole = in1.gain >= SWEEP_GAIN
                        && in2.gain >= SWEEP_GAIN
                        && (1.0 / SAME_AMPLITUDE..=SAME_AMPLITUDE).contains(&ratio);
                    return whole.then(|| prof.s.partition_point(|&v| v <= b + step).min(n));
                }
            }
            prev = here.level;
            k += 1.0;
            continue;
        }
        // The level changed in (b − step, b]: a step to the sweep's mean?
        let inside = fit(b - step)?.level;
        let big = prev.abs().max(inside.abs());
        return ((inside - prev).abs() > MIN_STEP * big && big > 0.0)
            .then(|| prof.s.partition_point(|&v| v <= b + step).min(n));
    }
}

/// Below this gain (the oscillation's share of a stretch's squared
/// residual, in units of its noise variance: χ² with 2 degrees of freedom
/// for noise alone, above 16 once in 3000) a stretch shows no oscillation;
/// the bound for a stretch of few bins is [`no_sweep_gain`].
const NO_SWEEP_GAIN: f64 = 16.0;

/// [`NO_SWEEP_GAIN`] for a stretch whose noise variance comes from `dof`
/// degrees of freedom: the gain is then 2·F(2, dof) for noise alone, whose
/// tail P(F > x) = (1 + 2x/dof)^(−dof/2) reaches the same 1 in 3000
/// (e^−8) at 2x = dof·(e^(16/dof) − 1): 118 for the 8 bins of a strip along
/// the pixel rows (one filled bin per pixel; 16 there read 23 on noise),
/// 16 as dof grows.
fn no_sweep_gain(dof: f64) -> f64 {
    if dof <= 1.0 {
        return f64::INFINITY;
    }
    (dof * (NO_SWEEP_GAIN / dof).exp_m1()).max(NO_SWEEP_GAIN)
}

/// The gain of a stretch that shows the sweep clearly: its amplitude known
/// to 7 % (1/√gain), so the ratio of two such is known to 10 % and
/// [`SAME_AMPLITUDE`] lies 4 σ out for one amplitude. (It was 400 until
/// session 38: a q75 strip along the pixel rows under defocus, whose print
/// ends on a modulation of 0.13, showed its sweep at 250 and 390 and kept
/// its grey, RMS 0.042. The unit tests' fades and MTF zeros are refused
/// down to 100 and taken at 50.)
const SWEEP_GAIN: f64 = 200.0;

/// Most the amplitudes of the two stretches inside a grey surround may
/// differ (ratio): a modulation growing back from 0 at a zero of the MTF
/// grows as the distance from it, 2:3 (or 1:2) in the first stretches that
/// [`SWEEP_GAIN`] lets through after one under [`NO_SWEEP_GAIN`]; the
/// sweep's own, over 16 px, by more than 1.25× where a short log sweep
/// ends on a steep MTF (the independent study's 403-px log strip, seed 40
/// `varied` #6: 1.25 refused it).
/// The walk only says where to search: the change-point search after it
/// must still find the end.
const SAME_AMPLITUDE: f64 = 1.4;

/// A stretch of bins fitted by a level and the sweep's cosine and sine.
struct StretchFit {
    /// The level (the profile's units).
    level: f64,
    /// The oscillation's amplitude (the profile's units).
    amp: f64,
    /// The oscillation's reduction of the weighted squared residual, in
    /// units of the residual's noise variance per unit weight.
    gain: f64,
    /// Degrees of freedom of that noise variance (bins less 3).
    dof: f64,
}

/// Fits the bins with s in (a, b] by a level and the law's cosine and sine;
/// None with fewer than 8 bins or a singular fit.
fn stretch_fit(prof: &Profile, law: &PhaseLaw, a: f64, b: f64) -> Option<StretchFit> {
    let lo = prof.s.partition_point(|&v| v <= a);
    let hi = prof.s.partition_point(|&v| v <= b);
    let mut nrm = Normal::<3>::new();
    let mut rows = 0;
    for k in lo..hi {
        if prof.is_clipped(k) || !(prof.count[k] > 0.0) || !prof.y[k].is_finite() {
            continue;
        }
        let (sn, cs) = (TAU * law.phase(prof.s[k])).sin_cos();
        nrm.add(&[1.0, cs, sn], prof.y[k], prof.count[k]);
        rows += 1;
    }
    if rows < 8 {
        return None;
    }
    let beta = nrm.solve()?;
    let full = nrm.rss()?;
    let flat = level_rss(&nrm)?;
    // A noise-free stretch: its variance floored far below any noise.
    let floor = 1e-12 * nrm.yy / nrm.w;
    let var = (full / (rows - 3) as f64).max(floor);
    let gain = (flat - full).max(0.0) / var;
    (beta.iter().all(|v| v.is_finite()) && gain.is_finite()).then(|| StretchFit {
        level: beta[0],
        amp: beta[1].hypot(beta[2]),
        gain,
        dof: (rows - 3) as f64,
    })
}

/// The constant's weighted squared residual (the first regressor being 1).
fn level_rss<const P: usize>(n: &Normal<P>) -> Option<f64> {
    (n.w > 0.0).then(|| (n.yy - n.aty[0] * n.aty[0] / n.w).max(0.0))
}

/// The straight line's weighted squared residual (a constant where the rows
/// cannot fix a slope).
fn line_rss(n: &Normal<2>) -> Option<f64> {
    if n.w <= 0.0 {
        return None;
    }
    n.rss().or_else(|| {
        let mean = n.aty[0] / n.w;
        Some((n.yy - mean * n.aty[0]).max(0.0))
    })
}

#[cfg(test)]
mod tests;
