//! Tests of the printed ends' search, on chirps blurred by a Gaussian edge.

use super::*;
use crate::measure::estimate::tests_support::{lcg_normal, linear_profile};

/// A chirp from 0.05 to 0.35 cy/unit over 600 units (unit = px), mean 0.5,
/// modulation 0.3, printed up to `end` and `beyond` (its level) after,
/// blurred by a Gaussian of σ 0.8 px, with noise.
fn sweep(end: f64, beyond: f64, noise: f64, seed: u64) -> (Profile, PhaseLaw) {
    sweep_from(0.05, f64::NEG_INFINITY, end, beyond, noise, seed)
}

/// [`sweep`] starting at `f0` cy/unit, printed from `start` to `end`.
fn sweep_from(
    f0: f64,
    start: f64,
    end: f64,
    beyond: f64,
    noise: f64,
    seed: u64,
) -> (Profile, PhaseLaw) {
    let sig = 0.8;
    let (mut prof, law) = linear_profile(f0, 0.3 / 600.0, 600.0, |_, _| 0.0);
    let mut st = seed;
    let r2 = sig * std::f64::consts::SQRT_2;
    for k in 0..prof.s.len() {
        let s = prof.s[k];
        // The blurred steps: the sweep's share at s.
        let share = 0.5 * erfc_approx((s - end) / r2) - 0.5 * erfc_approx((s - start) / r2);
        let f = law.freq(s);
        let att = (-2.0 * (std::f64::consts::PI * f * sig).powi(2)).exp();
        let sweep = 0.5 * (1.0 + 0.3 * att * (TAU * law.phase(s)).cos());
        prof.y[k] = share * sweep + (1.0 - share) * beyond + noise * lcg_normal(&mut st);
    }
    (prof, law)
}

/// erfc to ~1e-7 (Numerical Recipes' Chebyshev form).
fn erfc_approx(x: f64) -> f64 {
    let z = x.abs();
    let t = 1.0 / (1.0 + 0.5 * z);
    let r = t
        * (-z * z - 1.26551223
            + t * (1.00002368
                + t * (0.37409196
                    + t * (0.09678418
                        + t * (-0.18628806
                            + t * (0.27886807
                                + t * (-1.13520398
                                    + t * (1.48851587 + t * (-0.82215223 + t * 0.17087277)))))))))
            .exp();
    if x >= 0.0 { r } else { 2.0 - r }
}

#[test]
fn a_printed_end_inside_the_region_is_found_whatever_lies_beyond() {
    let one = |_: f64| 1.0;
    for (beyond, what) in [(1.0, "paper"), (0.05, "black"), (0.5, "grey")] {
        for end in [592.0, 595.5, 598.0] {
            let (prof, law) = sweep(end, beyond, 0.004, 3);
            let got = find(&prof, &law, &one);
            let hi = got[1].unwrap_or_else(|| panic!("{what} end {end}: none found"));
            assert!(
                // The blurred step's ramp, when little of it lies
                // inside the region, reads the end up to 1.5 px early.
                (-1.6..0.5).contains(&(hi.s - end)),
                "{what}: end {end} found at {}",
                hi.s
            );
            assert!(got[0].is_none(), "{what}: a low end found {got:?}");
        }
    }
}

#[test]
fn a_surround_longer_than_one_search_is_stepped_over_to_the_print() {
    let one = |_: f64| 1.0;
    for (beyond, what) in [(1.0, "paper"), (0.05, "black")] {
        for inside in [30.0, 60.0, 100.0, 140.0] {
            let end = 600.0 - inside;
            let (prof, law) = sweep(end, beyond, 0.004, 7);
            let got = find(&prof, &law, &one);
            let hi = got[1].unwrap_or_else(|| panic!("{what} {inside} px: none found"));
            assert!(
                (-1.6..0.5).contains(&(hi.s - end)),
                "{what} {inside} px: end {end} found at {}",
                hi.s
            );
            assert!(got[0].is_none(), "{what}: a low end found {got:?}");
        }
    }
    // Beyond a quarter of the strip: not followed (a misplaced region).
    let (prof, law) = sweep(400.0, 1.0, 0.004, 7);
    assert_eq!(find(&prof, &law, &one)[1], None);
}

#[test]
fn a_grey_surround_at_the_sweeps_mean_is_walked_over_to_the_print() {
    let one = |_: f64| 1.0;
    // Only the oscillation stops there: no step in level. (Per-bin noise
    // 0.004 against a modulation of 0.037 at the print's end; at 0.008 the
    // sweep's stretches are told from the grey with a gain of 320–770, over
    // `SWEEP_GAIN`, but the change-point search after the walk then finds
    // the end on some seeds only (its gain 13 against `MIN_GAIN` on one 60 px
    // in), and the grey is kept there, as before.)
    for inside in [30.0, 60.0, 100.0, 140.0] {
        for (noise, seed) in [(0.004, 7), (0.004, 8), (0.004, 9), (0.0, 1)] {
            let end = 600.0 - inside;
            let (prof, law) = sweep(end, 0.5, noise, seed);
            let got = find(&prof, &law, &one);
            let hi = got[1].unwrap_or_else(|| panic!("grey {inside} px, noise {noise}: none"));
            // The oscillation's blurred stop (no step in level) reads up to
            // 1 px beyond it (the cut leaves out 1 px more; the measured
            // curve: `tests/it/sweep_end_clicked.rs`).
            assert!(
                (-1.6..1.5).contains(&(hi.s - end)),
                "grey {inside} px, noise {noise}: end {end} found at {}",
                hi.s
            );
            assert!(got[0].is_none(), "a low end found {got:?}");
        }
    }
    // Beyond a quarter of the strip: not followed.
    let (prof, law) = sweep(400.0, 0.5, 0.004, 7);
    assert_eq!(find(&prof, &law, &one)[1], None);
    // A step of 2 % in the grey 5 px inside the region's end (a JPEG's
    // block edge) is taken for an end by the first search; the walk then
    // starts there and goes on to the print.
    for inside in [40.0, 75.0] {
        let end = 600.0 - inside;
        let (mut prof, law) = sweep(end, 0.5, 0.002, 5);
        for (s, y) in prof.s.iter().zip(prof.y.iter_mut()) {
            if *s > 595.0 {
                *y += 0.01;
            }
        }
        let first = find_end(&prof, &law, &one, true, 0..prof.s.len());
        assert!(
            first.is_some_and(|s| s > 590.0),
            "{inside}: first search {first:?}"
        );
        let hi = find(&prof, &law, &one)[1].unwrap_or_else(|| panic!("{inside}: none"));
        assert!(
            (-1.6..1.5).contains(&(hi.s - end)),
            "block edge, grey {inside} px: end {end} found at {}",
            hi.s
        );
    }
}

/// A strip along the pixel rows fills one bin in four (the 0.25 px bins at
/// whole pixels; each then holds four times the pixels, so half the noise):
/// the change-point search reaches inside over as many filled bins as the
/// default bins give it, and a stretch's few bins are judged quiet by their
/// own few degrees of freedom, so a grey beyond is still found.
#[test]
fn a_grey_beyond_sparse_bins_is_found_too() {
    let one = |_: f64| 1.0;
    for inside in [30.0, 40.0, 75.0] {
        for seed in [7, 8, 9] {
            let end = 600.0 - inside;
            let (mut prof, law) = sweep(end, 0.5, 0.002, seed);
            for k in (0..prof.s.len()).filter(|k| k % 4 != 0) {
                prof.count[k] = 0.0;
                prof.y[k] = f64::NAN;
            }
            let hi = find(&prof, &law, &one)[1]
                .unwrap_or_else(|| panic!("sparse, grey {inside} px, seed {seed}: none"));
            assert!(
                (-1.6..1.5).contains(&(hi.s - end)),
                "sparse, grey {inside} px, seed {seed}: end {end} found at {}",
                hi.s
            );
        }
    }
}

/// The chirp of [`sweep`] printed to its end, its modulation at s scaled by
/// `mtf(f)` (f in cy/unit), under light falling `light`:1 along the strip.
fn sweep_with_mtf(
    mtf: impl Fn(f64) -> f64,
    light: f64,
    noise: f64,
    seed: u64,
) -> (Profile, PhaseLaw) {
    let (mut prof, law) = linear_profile(0.05, 0.3 / 600.0, 600.0, |_, _| 0.0);
    let mut st = seed;
    for k in 0..prof.s.len() {
        let s = prof.s[k];
        let light = light.powf(-s / 600.0);
        let m = mtf(law.freq(s));
        prof.y[k] = light * 0.5 * (1.0 + 0.3 * m * (TAU * law.phase(s)).cos())
            + noise * lcg_normal(&mut st);
    }
    (prof, law)
}

#[test]
fn a_modulation_that_fades_or_grows_back_from_zero_is_no_surround() {
    let one = |_: f64| 1.0;
    let gauss = |sig: f64| move |f: f64| (-2.0 * (std::f64::consts::PI * f * sig).powi(2)).exp();
    for seed in [11, 12, 13] {
        // Faded to nothing long before the end (a soft lens: σ 3 px).
        let (prof, law) = sweep_with_mtf(gauss(3.0), 3.0, 0.004, seed);
        assert_eq!(find(&prof, &law, &one), [None, None], "σ 3, seed {seed}");
        // Faded to the noise within the walk's reach (σ 1.6 px: below 3 %
        // of the print's modulation over the last 60 px).
        let (prof, law) = sweep_with_mtf(gauss(1.6), 3.0, 0.004, seed);
        assert_eq!(
            surround_end(&prof, &law, &one, prof.s.len()),
            None,
            "σ 1.6, seed {seed}"
        );
        assert_eq!(find(&prof, &law, &one), [None, None], "σ 1.6, seed {seed}");
        // A zero of the MTF 60 or 100 px inside the end (defocus), nothing
        // after it, the modulation growing back from it inwards: |1 − f/f0|.
        for zero_at in [540.0, 500.0] {
            let (_, law) = linear_profile(0.05, 0.3 / 600.0, 600.0, |_, _| 0.0);
            let f0 = law.freq(zero_at);
            let ramp = move |f: f64| (1.0 - f / f0).max(0.0);
            for (light, noise) in [(3.0, 0.004), (1.0, 0.004), (1.0, 0.0005), (1.0, 0.0001)] {
                let (prof, law) = sweep_with_mtf(ramp, light, noise, seed);
                let what = format!("zero at {zero_at}, light {light}, noise {noise}, seed {seed}");
                // The walk itself takes no such growth for an edge (the
                // change-point search after it would not find one either).
                assert_eq!(
                    surround_end(&prof, &law, &one, prof.s.len()),
                    None,
                    "{what}"
                );
                assert_eq!(find(&prof, &law, &one)[1], None, "{what}");
            }
        }
    }
}

#[test]
fn a_low_end_is_found_whatever_its_cycle() {
    let one = |_: f64| 1.0;
    // 0.15 cy/px at the start (a 6.7 px cycle: a line beyond), 0.05 and
    // 0.009 (20 and 111 px: one level beyond); paper or black before s = 5.
    for f0 in [0.15, 0.05, 0.009] {
        for beyond in [1.0, 0.05] {
            let (prof, law) = sweep_from(f0, 5.0, 1e9, beyond, 0.004, 5);
            let got = find(&prof, &law, &one);
            let lo = got[0].unwrap_or_else(|| panic!("{f0} {beyond}: no low end"));
            assert!((-0.5..1.6).contains(&(lo.s - 5.0)), "{f0} {beyond}: {lo:?}");
            assert!(got[1].is_none(), "{got:?}");
            // Printed from the first bin: none.
            let (prof, law) = sweep_from(f0, f64::NEG_INFINITY, 1e9, beyond, 0.004, 5);
            assert_eq!(find(&prof, &law, &one), [None, None], "{f0} {beyond}");
        }
    }
}

#[test]
fn bins_where_a_linear_law_falls_to_zero_are_no_print() {
    let one = |_: f64| 1.0;
    // A linear law from −0.01 cy/unit at s = 0 (0 at s = 20): a low end
    // clicked beyond the print, whose law extrapolates below 0 there; the
    // print (0.0025 cy/unit and up) starts at s = 25, paper or black before.
    for beyond in [1.0, 0.05] {
        let (prof, law) = sweep_from(-0.01, 25.0, 1e9, beyond, 0.004, 9);
        assert!(law.freq(0.0) < 0.0 && law.freq(30.0) > 0.0);
        let got = find(&prof, &law, &one);
        let lo = got[0].unwrap_or_else(|| panic!("{beyond}: no low end"));
        assert!(lo.s >= 20.0 && lo.s <= 26.6, "{beyond}: {lo:?}");
        assert!(got[1].is_none(), "{got:?}");
    }
}

#[test]
fn noise_alone_moves_no_end() {
    let one = |_: f64| 1.0;
    for seed in 1..40 {
        for noise in [0.002, 0.02, 0.1] {
            let (prof, law) = sweep(1e9, 1.0, noise, seed);
            let got = find(&prof, &law, &one);
            assert!(got == [None, None], "seed {seed} noise {noise}: {got:?}");
        }
    }
}

#[test]
fn broken_profiles_give_no_end() {
    let one = |_: f64| 1.0;
    let (mut prof, law) = sweep(595.0, 1.0, 0.0, 1);
    let nan = |_: f64| f64::NAN;
    assert_eq!(find(&prof, &law, &nan), [None, None]);
    prof.y.iter_mut().for_each(|y| *y = 0.5);
    assert_eq!(find(&prof, &law, &one), [None, None], "flat");
    prof.y[100] = f64::NAN;
    let _ = find(&prof, &law, &one);
    prof.s.truncate(10);
    assert_eq!(find(&prof, &law, &one), [None, None], "short");
}
