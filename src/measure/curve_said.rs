//! What a measurement says of each curve it measured: the notes (what was
//! done or found) and warnings (what may be wrong) of its sweep law, print
//! ends, clipping, tone correction and black level, light, JPEG coding and
//! chart modulation, in the order they are read.

use super::options::MeasureOptions;
use super::result::Curve;
use super::{block_ripple, frequency, jpeg_deadzone, sine_tone, strip, sweep_end};

/// Adds to `notes` and `warnings` what curve `c` of channel `name` says, and
/// to `square` its name and bars' drift (px) where a coarse JPEG's blocks
/// lie square to them ([`square_to_blocks`]).
pub(super) fn of_curve(
    name: &str,
    c: &Curve,
    opts: &MeasureOptions,
    coding: strip::Coding,
    notes: &mut Vec<String>,
    warnings: &mut Vec<String>,
    square: &mut Vec<(String, f64)>,
) {
    if let Some(line) = frequency::foreshortening_note(c, opts.margin) {
        notes.push(format!("{name}/{}: {line}", c.sweep_id));
    }
    if let Some(line) = sweep_end::note(&c.print_ends_inside_px) {
        notes.push(format!("{name}/{}: {line}", c.sweep_id));
    }
    if c.clipped_fraction > 0.0 {
        warnings.push(format!(
            "{name}/{}: {:.2} % of the region's samples are clipped",
            c.sweep_id,
            100.0 * c.clipped_fraction
        ));
    }
    // A used correction is needed; one needed but unused is a warning.
    if let Some(f) = &c.tone_fix
        && f.needed()
    {
        let line = format!("{name}/{}: {}", c.sweep_id, f.describe());
        if f.used {
            notes.push(line);
        } else {
            warnings.push(line);
        }
        if let Some(b) = &f.black
            && (b.used || f.light_ratio > sine_tone::MAX_EVEN_LIGHT)
        {
            notes.push(format!("{name}/{}: {}", c.sweep_id, b.describe()));
        }
        if f.uneven_light() {
            warnings.push(format!(
                "{name}/{}: {}",
                c.sweep_id,
                f.uneven_light_warning()
            ));
        }
    }
    if coding.block_ripple {
        let drift = block_ripple::bar_drift_px(c);
        if drift < block_ripple::SQUARE_DRIFT_PX {
            square.push((format!("{name}/{}", c.sweep_id), drift));
        }
    }
    if let Some(f) = c.rounded_away_from_cy_px {
        warnings.push(jpeg_deadzone::rounded_away_warning(
            &format!("{name}/{}", c.sweep_id),
            f,
        ));
    }
    if c.chart_modulation_source.starts_with("extrapolated") {
        warnings.push(format!(
            "{name}/{}: chart modulation {:.4} {}",
            c.sweep_id, c.chart_modulation, c.chart_modulation_source
        ));
    }
}

/// The warning for strips of a coarse JPEG whose bars lie square to its
/// 8×8 blocks: `square` holds each one's name and its bars' drift across
/// the strip at an end (px); None where there is none.
pub(super) fn square_to_blocks(square: &[(String, f64)]) -> Option<String> {
    if square.is_empty() {
        return None;
    }
    let names: Vec<&str> = square.iter().map(|s| s.0.as_str()).collect();
    let drift = square.iter().map(|s| s.1).fold(0.0, f64::max);
    Some(format!(
        "{}: the bars lie square to the JPEG's 8×8 blocks (they drift ≤ {drift:.2} px across \
         the strip at an end), so its quantisation error is not averaged along them (simulated q75: \
         MTF50 off by up to ±2.5 % and the chart modulation by up to +1.1 %, against ±1.1 % \
         and 0.45 % turned 0.1–5°); turn the chart by 1–5°",
        names.join(", ")
    ))
}
