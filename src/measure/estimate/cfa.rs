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
pub fn cfa_aliases_seen(prof: &Profile, law: &PhaseLaw, window_cycles: f64) -> bool {
    if prof.parity.len() != prof.s.len() || prof.s.is_empty() {
        return false;
    }
    let table = PhaseTable::new(prof, law);
    let (p0, p1) = (table.phase[0], table.phase[table.phase.len() - 1]);
    let windows = ((p1 - p0) / window_cycles).floor().max(0.0) as usize;
    let AliasTerms { chi2, dof } = (0..windows)
        .into_par_iter()
        .filter_map(|k| {
            let s0 = law.s_at_phase(
                p0 + (k as f64 + 0.5) * window_cycles,
                prof.s[0],
                prof.length,
            );
            local_fit(prof, &table, law, s0, 0.5 * window_cycles).map(|f| f.alias)
        })
        .filter(|t| t.dof > 0)
        .reduce(AliasTerms::default, |a, b| AliasTerms {
            chi2: a.chi2 + b.chi2,
            dof: a.dof + b.dof,
        });
    dof > 0 && chi2 > CFA_SEEN * dof as f64
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::measure::estimate::tests_support::linear_profile;
    use std::f64::consts::PI;

    /// A demosaicked sine along a pixel axis: each 0.25-px bin holds pixels
    /// of one column, so the CFA's alias, the sine times (−1)^x with its own
    /// amplitude (30 %) and phase, reaches the profile at ½ − f cy/px. With
    /// the bins' parity patterns the fit reads the sine common to both
    /// parities within 1e-3 from 0.15 to 0.35 cy/px (past f = ¼, where the
    /// alias coincides with it); without them it read up to 7 % off.
    #[test]
    fn a_cfa_alias_locked_to_the_pixel_grid_is_modelled_not_read_as_modulation() {
        let m = |f: f64| 0.8 * (1.0 - 1.2 * f);
        let sign = |s: f64| {
            if (s.floor() as i64) % 2 == 0 {
                1.0
            } else {
                -1.0
            }
        };
        let (mut prof, law) = linear_profile(0.1, 2.5e-4, 1200.0, |law, s| {
            let ph = 2.0 * PI * law.phase(s);
            let alias = 0.3 * sign(s) * (ph + 0.7).cos();
            0.5 * (1.0 + m(law.freq(s)) * (ph.cos() + alias))
        });
        prof.parity = prof.s.iter().map(|&s| [sign(s), 0.0, 0.0]).collect();
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
}
