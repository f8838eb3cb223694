//! A demosaicked colour filter array's aliases in a strip: whether they are
//! there (the sine fit then models them, [`super::fit::local_fit`]).
//!
//! A Bayer sensor's demosaic passes a sine with a mean gain and adds the sine
//! times (−1)^x, (−1)^y and (−1)^(x+y), locked to the pixel grid. The
//! profile's bins count their samples' parity patterns
//! ([`Profile::parity`]); where the patterns stay in a window's bins the fit
//! holds the sine times each as two more terms, and this module decides
//! whether a strip shows those terms beyond noise at all.

use super::fit::{PhaseTable, local_fit};
use crate::measure::law::PhaseLaw;
use crate::measure::profile::Profile;
use rayon::prelude::*;

/// A local fit's pixel-parity terms, summed over them.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct AliasTerms {
    /// Σ c²/var c over the terms.
    pub chi2: f64,
    /// How many terms (0 where none entered the model).
    pub dof: usize,
    /// Each pattern's ((−1)^x, (−1)^y, (−1)^(x+y)) fitted quadratures: the
    /// alias is the pattern times (c·cos 2πφ + d·sin 2πφ), φ the law's phase
    /// (linear units, as the profile; zero where the pattern is not modelled).
    pub coef: [[f64; 2]; 3],
}

/// The parity terms' χ² per degree of freedom above which a strip shows a
/// demosaicked CFA's aliases. Without a mosaic it ran 1.4–2.3 on the
/// independent camera's JPEG and PNG shots and 1–4.6 on the simulator's q90
/// JPEGs (straight and turned 45°: the windows' residuals are not
/// independent, and JPEG's quantisation leaves grid-locked patterns of its
/// own), but 9.3 on one located shot's low-contrast sweep (tilted, 0.2
/// printed contrast); with a mosaic 23–280 within 0.4° of an axis, 6.7–63
/// at 0.5–1.2° and 1.8–7.2 at 1.4–2.6°, where the patterns average out in
/// the bins and the terms matter little. At 6 the one shot that needs them
/// most (0.55°, 6.7: RMS 0.0066 without them, 0.0027 with) keeps them, and
/// the false one costs little (RMS 0.0115 → 0.0128, 4 of 22 points left
/// out). Neither the phase of the terms against the sine (lateral CA turns
/// it) nor their power against it told the two apart better.
pub const CFA_SEEN: f64 = 6.0;

/// Whether the profile's bins show a demosaicked CFA's aliases (the sine
/// times a pixel-parity pattern): the parity terms' χ² summed over windows
/// of `window_cycles` laid end to end along the law exceeds [`CFA_SEEN`]
/// times its degrees of freedom. Where it does not (a photo without a
/// mosaic, or a strip turned so the patterns average out in the bins), the
/// terms would only cost variance: on a JPEG turned 45° without a mosaic
/// they raised the RMS error from 0.013 to 0.020 near 0.35 cy/px, where the
/// (−1)^(x+y) pattern times the sine runs at the sine's own frequency.
/// `table` is `law` tabulated over the bins of `prof` ([`PhaseTable::new`]).
pub fn cfa_aliases_seen(
    prof: &Profile,
    law: &PhaseLaw,
    table: &PhaseTable,
    window_cycles: f64,
) -> bool {
    if prof.parity.len() != prof.s.len() || prof.s.is_empty() || table.phase.len() != prof.s.len() {
        return false;
    }
    let (p0, p1) = (table.phase[0], table.phase[table.phase.len() - 1]);
    let windows = ((p1 - p0) / window_cycles).floor().max(0.0) as usize;
    let AliasTerms { chi2, dof, .. } = (0..windows)
        .into_par_iter()
        .filter_map(|k| {
            let s0 = law.s_at_phase(
                p0 + (k as f64 + 0.5) * window_cycles,
                prof.s[0],
                prof.length,
            );
            local_fit(prof, table, law, s0, 0.5 * window_cycles).map(|f| f.alias)
        })
        .filter(|t| t.dof > 0)
        .reduce(AliasTerms::default, |a, b| AliasTerms {
            chi2: a.chi2 + b.chi2,
            dof: a.dof + b.dof,
            coef: [[0.0; 2]; 3],
        });
    dof > 0 && chi2 > CFA_SEEN * dof as f64
}

/// Takes the CFA's aliases out of the profile itself, for the estimators
/// that have no terms for them (`extrema`, `envelope`) and read them as
/// modulation: the sine fit's parity terms, fitted in windows of
/// `window_cycles` a quarter window apart along the law, their quadratures
/// interpolated linearly in phase between window centres (held beyond the
/// first and last), times each bin's parity pattern and the law's
/// (bin-attenuated) cos and sin, are subtracted from its value. The parity
/// sums are then cleared: what stays is the sine common to all four pixel
/// parities. Where a window was left out (an alias running with the sine
/// itself) its neighbours' terms bridge it. `table` is `law` tabulated
/// over the bins of `prof` ([`PhaseTable::new`]; it does not depend on the values).
pub fn remove_aliases(prof: &mut Profile, law: &PhaseLaw, table: &PhaseTable, window_cycles: f64) {
    if prof.parity.len() != prof.s.len() || prof.s.is_empty() || table.phase.len() != prof.s.len() {
        return;
    }
    let (p0, p1) = (table.phase[0], table.phase[table.phase.len() - 1]);
    let step = 0.25 * window_cycles;
    let centres = ((p1 - p0) / step).floor().max(0.0) as usize + 1;
    let fits: Vec<(f64, [[f64; 2]; 3])> = (0..centres)
        .into_par_iter()
        .filter_map(|k| {
            let p = p0 + k as f64 * step;
            let s0 = law.s_at_phase(p, prof.s[0], prof.length);
            let f = local_fit(prof, table, law, s0, 0.5 * window_cycles)?;
            Some((law.phase(s0), f.alias.coef))
        })
        .collect();
    if fits.is_empty() {
        prof.parity.clear();
        return;
    }
    for k in 0..prof.y.len() {
        let ph = table.phase[k];
        let j = fits.partition_point(|&(p, _)| p < ph);
        let coef = if j == 0 {
            fits[0].1
        } else if j == fits.len() {
            fits[j - 1].1
        } else {
            let ((pa, ca), (pb, cb)) = (fits[j - 1], fits[j]);
            let t = ((ph - pa) / (pb - pa).max(1e-300)).clamp(0.0, 1.0);
            std::array::from_fn(|q| std::array::from_fn(|i| ca[q][i] + t * (cb[q][i] - ca[q][i])))
        };
        let alias: f64 = (0..3)
            .map(|q| prof.parity[k][q] * (coef[q][0] * table.cos[k] + coef[q][1] * table.sin[k]))
            .sum();
        prof.y[k] -= alias;
    }
    prof.parity.clear();
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::measure::estimate::tests_support::linear_profile;
    use std::f64::consts::PI;

    /// The test profiles' modulation at f (cycles/unit).
    fn m(f: f64) -> f64 {
        0.8 * (1.0 - 1.2 * f)
    }

    /// (−1)^x of the pixel column holding position s (one unit per pixel).
    fn sign(s: f64) -> f64 {
        if (s.floor() as i64) % 2 == 0 {
            1.0
        } else {
            -1.0
        }
    }

    /// A noise-free demosaicked sine along a pixel axis: the sine of
    /// modulation [`m`] plus the CFA's alias, the sine times (−1)^x of
    /// relative amplitude `alias` and its own phase (0.7 rad), with each
    /// bin's parity pattern recorded.
    fn aliased(alias: f64) -> (Profile, PhaseLaw) {
        let (mut prof, law) = linear_profile(0.1, 2.5e-4, 1200.0, |law, s| {
            let ph = 2.0 * PI * law.phase(s);
            0.5 * (1.0 + m(law.freq(s)) * (ph.cos() + alias * sign(s) * (ph + 0.7).cos()))
        });
        prof.parity = prof.s.iter().map(|&s| [sign(s), 0.0, 0.0]).collect();
        (prof, law)
    }

    /// A demosaicked sine along a pixel axis: each 0.25-px bin holds pixels
    /// of one column, so the CFA's alias, the sine times (−1)^x with its own
    /// amplitude (30 %) and phase, reaches the profile at ½ − f cy/px. With
    /// the bins' parity patterns the fit reads the sine common to both
    /// parities within 1e-3 from 0.15 to 0.35 cy/px (past f = ¼, where the
    /// alias coincides with it); without them it read up to 7 % off.
    #[test]
    fn a_cfa_alias_locked_to_the_pixel_grid_is_modelled_not_read_as_modulation() {
        let (mut prof, law) = aliased(0.3);
        let table = PhaseTable::new(&prof, &law);
        let worst = |prof: &Profile| {
            (0..60)
                .filter_map(|k| {
                    let s0 = 200.0 + 10.0 * k as f64;
                    let f = law.freq(s0);
                    let fit = local_fit(prof, &table, &law, s0, 2.0)?;
                    (0.15..=0.35)
                        .contains(&f)
                        .then(|| (fit.modulation() / m(law.freq(fit.s_amp)) - 1.0).abs())
                })
                .fold(0.0, f64::max)
        };
        let with = worst(&prof);
        assert!(with < 1e-3, "with the parity patterns: {with}");
        prof.parity.clear();
        let without = worst(&prof);
        assert!(without > 0.02, "without them: {without}");
    }

    /// The same alias taken out of the profile itself for the estimators
    /// without terms for it: `extrema` and `envelope` then read what they
    /// read without any alias, within 2e-3 from 0.1 to 0.4 cy/px (measured
    /// 3e-4 and 4e-5), where the alias moved them by up to 0.23 and 0.10.
    #[test]
    fn the_fits_alias_terms_take_the_alias_out_of_the_profile_for_the_other_estimators() {
        use crate::measure::estimate::Method;
        let (mut clean, law) = aliased(0.0);
        clean.parity.clear();
        let (prof, _) = aliased(0.3);
        let grid: Vec<f64> = (0..100).map(|k| 100.0 + 10.0 * k as f64).collect();
        let worst = |est: &dyn crate::measure::estimate::Estimator, prof: &Profile| {
            let truth = est.estimate(&clean, &law, &grid);
            let read = est.estimate(prof, &law, &grid);
            // Each read against what the estimator reads without the alias
            // there (interpolated between its own points).
            read.iter()
                .filter(|p| (0.1..=0.4).contains(&law.freq(p.s)))
                .filter_map(|p| {
                    let j = truth.partition_point(|t| t.s < p.s);
                    let (a, b) = (truth.get(j.checked_sub(1)?)?, truth.get(j)?);
                    let t =
                        a.modulation + (p.s - a.s) / (b.s - a.s) * (b.modulation - a.modulation);
                    Some((p.modulation - t).abs())
                })
                .fold(0.0, f64::max)
        };
        for method in [Method::Extrema, Method::Envelope] {
            let est = method.estimator(4.0);
            let before = worst(est.as_ref(), &prof);
            let mut cleaned = prof.clone();
            let table = PhaseTable::new(&cleaned, &law);
            remove_aliases(&mut cleaned, &law, &table, 4.0);
            assert!(cleaned.parity.is_empty());
            let after = worst(est.as_ref(), &cleaned);
            eprintln!("{}: {before:.4} -> {after:.4}", method.name());
            assert!(
                after < 2e-3 && before > 0.05,
                "{}: {before} -> {after}",
                method.name()
            );
        }
    }
}
