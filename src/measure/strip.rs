//! Strip: one sweep strip of one channel measured — binned along the sweep
//! ([`super::profile`]), its phase law found from crossings ([`super::law`])
//! or taken from the target and refined ([`super::frequency`]), modulation
//! estimated on the output grid ([`super::estimate`]), points flagged where
//! they alias, and normalised by the chart modulation ([`super::normalise`])
//! into a [`Curve`].

use super::estimate::Method;
use super::estimate::fit::{LocalFit, PhaseTable, SineFit, local_fit};
use super::frequency::{
    DEV_HALF_CYCLES, dev_at, deviation_from_fits, local_freq_deviation, output_grid, refine_law,
};
use super::profile::{BinOptions, Strip, bin_planes};
use super::{Curve, Failure, LawKind, MeasureOptions, MtfPoint, PhaseLaw, SweepChoice};
use super::{
    block_ripple, curve, jpeg_deadzone, law_guess, normalise, sine_tone, surround_leak, sweep_end,
    tone_black, tone_unseen,
};
use crate::geometry::Point;
use crate::photo::PlaneRef;
use crate::photo::linearise::Tone;
use rayon::prelude::*;

/// Refuse when more than this fraction of the region is clipped.
const CLIP_REFUSE: f64 = 0.02;

/// How a strip's planes were coded, for what the strip may take out of them.
#[derive(Debug, Clone, Copy, Default)]
pub(super) struct Coding<'a> {
    /// A coarse JPEG's luma, whose block quantisation ripples the curve (smoothed).
    pub block_ripple: bool,
    /// The tone the planes were decoded with, where a camera's own tone
    /// curve on top of it may be found from the strip's shape and taken out.
    pub tone: Option<&'a Tone>,
    /// An 8-bit JPEG's luma quantisation table (natural order, DCT units)
    /// and the tone its codes were decoded with: the quantiser's error on
    /// weak sines joins each point's uncertainty ([`jpeg_deadzone`]).
    pub jpeg_luma: Option<(&'a [u16; 64], &'a Tone)>,
}

/// A value of the strip's planes (linear light through the decode's tone)
/// as the strip reads it: through the camera tone curve and black level
/// found from it, where they are taken out.
fn fixed_value(tone_fix: Option<&sine_tone::ToneFix>, v: f64) -> f64 {
    match tone_fix.filter(|f| f.used) {
        Some(f) => {
            f.linear(v)
                - f.black
                    .as_ref()
                    .filter(|b| b.used)
                    .map_or(0.0, |b| b.offset)
        }
        None => v,
    }
}

/// Measures one strip of one plane; without a target law, `seed` (another
/// channel's law of the same strip), when given, is refined instead of a law
/// found from this plane's own crossings.
#[allow(clippy::too_many_arguments)]
pub(super) fn measure_strip(
    planes: &[PlaneRef],
    channel: &str,
    id: &str,
    strip: &Strip,
    target_law: Option<PhaseLaw>,
    seed: Option<PhaseLaw>,
    contrast: Option<f64>,
    opts: &MeasureOptions,
    bin_opts: &BinOptions,
    coding: Coding,
) -> Result<Curve, Failure> {
    let scale_mid = strip.scale_at(0.5 * strip.length);
    let len_px = strip.length / scale_mid.s_per_px;
    let wid_px = strip.width * (1.0 - 2.0 * opts.margin) / scale_mid.s_per_px;
    if len_px < 20.0 || wid_px < 1.0 {
        return Err(Failure::TooSmall(format!(
            "the strip is {len_px:.0}×{wid_px:.1} px inside its margins; it cannot hold 5 cycles"
        )));
    }
    let mut prof = bin_planes(planes, strip, bin_opts);
    // The bins' pixel-parity patterns, set aside until the law is found
    // (its fits do without them, as before) and then used by the modulation
    // fits only where the strip shows a CFA's aliases. A single colour's
    // curve keeps its aliases: they are the colour moiré `moire` reads from
    // red and blue apart.
    let parity = std::mem::take(&mut prof.parity);
    if prof.s.len() < 20 {
        return Err(Failure::TooSmall(format!(
            "only {} bins fall inside the region",
            prof.s.len()
        )));
    }
    let clipped = prof.clipped_fraction();
    if clipped > CLIP_REFUSE {
        return Err(Failure::Clipped {
            percent: 100.0 * clipped,
        });
    }
    let s_per_px = |s: f64| strip.scale_at(s).s_per_px;
    let lattice = curve::Lattice::of(planes);
    // Highest frequency (cy/px) at s that stays inside the lattice's band in the sweep's direction.
    let band_limit = |s: f64| lattice.band_limit(strip.scale_at(s).angle_rad);
    let ymax = prof.y.iter().cloned().fold(f64::NEG_INFINITY, f64::max);
    let ymin = prof.y.iter().cloned().fold(f64::INFINITY, f64::min);
    if !(ymax > 0.0) || (ymax - ymin) < 1e-4 * ymax.abs().max(1e-6) {
        return Err(Failure::NoOscillation(format!(
            "{channel}/{id}: the region is blank (no variation)"
        )));
    }
    // Phase law: from the target (then refined) or from zero crossings.
    let kind = match (target_law, opts.sweep) {
        (Some(l), _) => Some(l.kind),
        (None, SweepChoice::Linear) => Some(LawKind::Linear),
        (None, SweepChoice::Log) => Some(LawKind::Log),
        (None, SweepChoice::Auto) => None,
    };
    let mut laws: Vec<PhaseLaw> = Vec::new();
    if let Some(l) = target_law.or(seed) {
        laws.push(l);
    } else {
        let kinds: &[LawKind] = match &kind {
            Some(k) => std::slice::from_ref(k),
            None => &[LawKind::Linear, LawKind::Log],
        };
        if let Some((found, _)) = law_guess::initial_laws(&prof, kinds, s_per_px, 0.3) {
            // A family that fits the crossings 4× worse than the best is not refined.
            let best = found.iter().map(|f| f.1).fold(f64::INFINITY, f64::min);
            laws.extend(
                found
                    .into_iter()
                    .filter(|(_, rms)| *rms <= 4.0 * best.max(1e-3))
                    .map(|(l, _)| l),
            );
        }
    }
    if laws.is_empty() {
        return Err(Failure::NoOscillation(format!(
            "{channel}/{id}: fewer than 5 regular cycles found along the strip"
        )));
    }
    // Refine each candidate; keep the one explaining the most phase with the least residual.
    let mut best: Option<(PhaseLaw, f64, usize)> = None;
    let refined: Vec<_> = laws
        .par_iter()
        .filter_map(|&l| refine_law(&prof, l, &s_per_px, &band_limit))
        .collect();
    for r in refined {
        let better = match &best {
            None => true,
            Some(b) => r.2 > b.2 + b.2 / 10 || (r.2 + r.2 / 10 >= b.2 && r.1 < b.1),
        };
        if better {
            best = Some(r);
        }
    }
    let Some((law, law_rms, n_resolved)) = best else {
        return Err(Failure::NoOscillation(format!(
            "{channel}/{id}: the oscillation is too weak or irregular to follow"
        )));
    };
    // Quality gate: a strip too thin to average across, or a phase law that the
    // local fits do not follow, gives a curve that only looks confident.
    if wid_px < super::MIN_ACROSS_PX {
        return Err(Failure::Unreliable(format!(
            "{channel}/{id}: the strip is {wid_px:.1} px across inside its margins; \
             at least {} px are needed to average the sweep across it",
            super::MIN_ACROSS_PX
        )));
    }
    if law_rms > super::MAX_LAW_RMS_CYCLES {
        return Err(Failure::Unreliable(format!(
            "{channel}/{id}: the sweep's phase law fits poorly (RMS {law_rms:.3} cycles, \
             at most {})",
            super::MAX_LAW_RMS_CYCLES
        )));
    }
    // Where the law's frequency is positive: from the region's start, or,
    // where a linear sweep's low end was clicked beyond the print, from
    // inside it (`sweep_end` cuts the bins before).
    let s_rise = super::frequency::positive_from(&law, 0.0f64.min(prof.s[0]), prof.length);
    let s_from = s_rise.unwrap_or(0.0);
    let total_cycles = law.phase(prof.length) - law.phase(s_from);
    if total_cycles < 5.0 || n_resolved < 5 {
        return Err(Failure::TooSmall(format!(
            "{channel}/{id}: the strip holds {total_cycles:.1} cycles; at least 5 are needed"
        )));
    }
    if s_rise.is_none() || law.freq(prof.length) <= law.freq(s_from) {
        return Err(Failure::NoOscillation(format!(
            "{channel}/{id}: the frequency does not rise along the strip (corners 1 and 4 must be on the low-frequency edge)"
        )));
    }
    // Ends clicked beyond the printed sweep: the bins beyond it left out.
    let ends = if opts.find_print_ends {
        sweep_end::find(&prof, &law, &s_per_px)
    } else {
        [None, None]
    };
    let mut parity = parity;
    sweep_end::cut(&mut prof, &mut parity, &ends, bin_opts.end_px, &s_per_px);
    // A camera's own tone curve, found from the low end's shape and taken out.
    let mut paper_bands_px = Vec::new();
    let mut tone_fix = coding
        .tone
        .and_then(|t| sine_tone::fit(&prof, &law, &s_per_px, t));
    if let Some(f) = &mut tone_fix
        && f.used
    {
        sine_tone::apply(f, &mut prof);
        // Its black level, from the paper beside the strip where the light changes.
        let bands = tone_black::bands(strip);
        paper_bands_px = bands.iter().map(outline).collect();
        let paper: Vec<_> = bands
            .iter()
            .map(|b| {
                let o = BinOptions {
                    margin: 0.0,
                    ..*bin_opts
                };
                bin_planes(planes, b, &o)
            })
            .collect();
        f.black = tone_black::find(&prof, &paper, &law, f);
        if let Some(b) = &f.black {
            tone_black::apply(b, &mut prof);
        }
    }
    // The law tabulated over the bins (it depends on their positions, not
    // their values): once, shared by the CFA check, the aliases' removal,
    // the estimator and the aliasing check (the image's local frequency
    // versus the law).
    let table = PhaseTable::new(&prof, &law);
    if !matches!(channel, "r" | "g" | "b") && parity.len() == prof.s.len() {
        prof.parity = parity;
        if !super::estimate::cfa::cfa_aliases_seen(&prof, &law, &table, opts.window_cycles) {
            prof.parity.clear();
        } else if opts.method != Method::Fit {
            // Estimators without terms for the aliases read them as
            // modulation: the fit's terms take them out of the profile.
            super::estimate::cfa::remove_aliases(&mut prof, &law, &table, opts.window_cycles);
        }
    }
    let grid = output_grid(&law, prof.s[0], prof.s[prof.s.len() - 1]);
    let est = opts.method.estimator(opts.window_cycles);
    let (mods, dev) = if opts.method == Method::Fit && 0.5 * opts.window_cycles == DEV_HALF_CYCLES {
        // The default estimator's fits are the check's own (same positions,
        // same half-width): made once, read by both.
        let fits: Vec<Option<LocalFit>> = grid
            .par_iter()
            .map(|&s| local_fit(&prof, &table, &law, s, DEV_HALF_CYCLES))
            .collect();
        let sine = SineFit {
            window_cycles: opts.window_cycles,
        };
        let mods = fits
            .iter()
            .filter_map(|f| sine.point(f.as_ref()?))
            .collect();
        (mods, deviation_from_fits(&law, &grid, &fits))
    } else {
        rayon::join(
            || est.estimate_tabulated(&prof, &law, &table, &grid),
            || local_freq_deviation(&prof, &table, &law, &grid),
        )
    };
    // The low end's own short windows, for the chart modulation (the fit's model).
    let mut low = if contrast.is_none() && opts.method == Method::Fit {
        normalise::low_end_points(&prof, &table, &law, &s_per_px, opts.window_cycles)
    } else {
        Vec::new()
    };
    drop(table);
    let mut points: Vec<MtfPoint> = mods
        .iter()
        .map(|m| {
            let f_chart = law.freq(m.s);
            let f_px = f_chart * s_per_px(m.s);
            let d = dev_at(&dev, m.s);
            MtfPoint {
                s: m.s,
                freq_cy_px: f_px,
                freq_chart: f_chart,
                modulation: m.modulation,
                mtf: m.modulation,
                mtf_err: m.err,
                aliased: f_px > band_limit(m.s) || d.is_some_and(|d| d.abs() > 0.05),
                jpeg_limited: false,
            }
        })
        .filter(|p| p.modulation.is_finite() && p.freq_cy_px.is_finite())
        .collect();
    points.sort_by(|a, b| a.freq_cy_px.total_cmp(&b.freq_cy_px));
    // Once aliased, everything above is aliased too (a sweep only rises).
    if let Some(i) = points
        .iter()
        .position(|p| p.aliased && p.freq_cy_px > 0.25 * band_limit(p.s))
    {
        points[i..].iter_mut().for_each(|p| p.aliased = true);
    }
    points
        .iter_mut()
        .filter(|p| p.freq_cy_px <= 0.25 * band_limit(p.s))
        .for_each(|p| p.aliased = false);
    if points.iter().filter(|p| !p.aliased).count() < 5 {
        return Err(Failure::NoOscillation(format!(
            "{channel}/{id}: fewer than 5 usable modulation points"
        )));
    }
    // Leave out the periods whose estimator window runs past the strip's low
    // end (the estimator keeps points whose window holds ≥ 80 % of its cycles):
    // with them, low-end corners 6 px off moved the chart modulation by up to
    // 4.9 % (simulated shots, strong blur) against 0.2 % without them. The
    // low end's own two-cycle windows (`low`, clear of the end) stand in for them.
    let (s0, s1) = (prof.s[0], prof.s[prof.s.len() - 1]);
    let s_min = law.s_at_phase(law.phase(s0) + 0.5 * opts.window_cycles, s0, s1);
    let read_chart = |pts: &[MtfPoint], low: &[MtfPoint]| {
        normalise::chart_modulation(pts, s_min, low, opts.window_cycles, contrast, channel, id)
    };
    let (mut m_chart, mut m_chart_err, mut source, slope_rel) = read_chart(&points, &low)?;
    if m_chart_err > super::MAX_CHART_REL_ERR * m_chart {
        return Err(Failure::Unreliable(format!(
            "{channel}/{id}: the modulation is lost in noise (chart modulation {m_chart:.3} ± {m_chart_err:.3})"
        )));
    }
    // The light the lens's diffraction tail carries in from the surround:
    // an offset on the strip's values, taken out of every modulation.
    if slope_rel < 0.0 {
        let to_linear = |v: f64| fixed_value(tone_fix.as_ref(), v);
        let mean = prof.y.iter().sum::<f64>() / prof.y.len().max(1) as f64;
        let taken = surround_leak::Surround::read(planes, strip).and_then(|sur| {
            let leak_at = |s: f64| sur.leak_rel(slope_rel, strip, s, opts.margin, to_linear, mean);
            surround_leak::take_out(&mut points, &mut low, s_min, leak_at)
        });
        if let Some(leak) = taken {
            // Read again from the points as corrected: the light beyond the
            // strip's ends lowers its first periods more than the rest.
            match read_chart(&points, &low) {
                Ok((m, e, src, _)) => (m_chart, m_chart_err, source) = (m, e, src),
                Err(_) => m_chart *= 1.0 + leak,
            }
            m_chart_err = m_chart_err.hypot(surround_leak::LEAK_REL_ERR * leak.abs() * m_chart);
            source = format!("{source}{}", surround_leak::source_note(leak));
        }
    }
    // The block ripple is smoothed after the chart modulation is read from the
    // low end, so the lowest points stay independent (and unbent by the smoothing).
    if coding.block_ripple {
        block_ripple::smooth(&mut points, block_ripple::RIPPLE_RMS_MTF * m_chart);
    }
    let mut rounded_away_from = None;
    if let Some((table, tone)) = coding.jpeg_luma {
        let value_of_code = |c: f64| fixed_value(tone_fix.as_ref(), tone.apply(c));
        rounded_away_from = jpeg_deadzone::widen(&mut points, table, |p| {
            let mean = jpeg_deadzone::local_mean(&prof, p.s, 1.0 / p.freq_chart)?;
            Some(jpeg_deadzone::PointSine {
                freq_cy_px: p.freq_cy_px,
                angle_rad: strip.scale_at(p.s).angle_rad,
                codes_per_modulation: mean * jpeg_deadzone::codes_per_value(value_of_code, mean)?,
            })
        });
    }
    normalise::normalise(&mut points, m_chart, m_chart_err);
    let mut figures = curve::figures(&points);
    // A summary figure where the curve is noisier than ±0.05 is not given.
    let noisy_at = |f: Option<f64>| -> bool {
        f.is_some_and(|f| {
            let near: Vec<f64> = points
                .iter()
                .filter(|p| !p.aliased && (p.freq_cy_px - f).abs() <= 0.01)
                .map(|p| p.mtf_err)
                .collect();
            !near.is_empty() && near.iter().sum::<f64>() / near.len() as f64 > 0.05
        })
    };
    for fig in figures.crossings_mut() {
        if noisy_at(*fig) {
            *fig = None;
        }
    }
    if figures.mtf50_cy_px.is_none() {
        figures.mtf50_err_cy_px = None;
    }
    let aliasing_from = points.iter().find(|p| p.aliased).map(|p| p.freq_cy_px);
    let across = |s: f64| -> [Point; 2] {
        [
            strip.to_photo([s, opts.margin * strip.width]),
            strip.to_photo([s, (1.0 - opts.margin) * strip.width]),
        ]
    };
    let alias_line = points.iter().find(|p| p.aliased).map(|p| across(p.s));
    // A black level taken from the paper scales every modulation by
    // 1/(mean − α): its error is the chart modulation's too (the MTF, a
    // ratio of modulations, keeps only what differs along the strip).
    let black = tone_fix
        .as_ref()
        .and_then(|f| f.black.as_ref())
        .filter(|b| b.claims());
    // A camera tone curve seen clearly but not taken out (it would put the
    // values out of order): the modulations are read through it, by about
    // its effect on an MTF of 0.5 (the independent camera's `camera` seed 45
    // #2 and #5: effect −57 and −34 %, the chart modulation read +24 and
    // +29 % off, claiming ±0.7 and ±0.8 %).
    let not_taken_out = tone_fix.as_ref().filter(|f| f.needed() && !f.used);
    // Widens each point by an offset of relative scale `eps` (see
    // `tone_unseen::widen`), MTF50's uncertainty with them where it is
    // given; returns the chart modulation's share.
    let mut widen_points = |eps: f64| -> f64 {
        let share = tone_unseen::widen(&mut points, &low, &prof, &law, eps, m_chart, |alt, low| {
            read_chart(alt, low).ok().map(|c| c.0)
        });
        if figures.mtf50_cy_px.is_some() {
            figures.mtf50_err_cy_px = curve::mtf50_sigma(&points);
        }
        share
    };
    let (m_chart_err, source) = if let Some(b) = black {
        let rel = b.modulation_rel_err();
        // Where the light changes along the strip, α's error bends the MTF's
        // shape too (each modulation by δα over its local mean): each point
        // carries it, as an unseen black level's scale does.
        // (Independent camera, picture styles under light 1.5–2.6:1 with the
        // black level found, 80 shots: MTF50 |z| up to 3.6 without this, 1.9 with.)
        widen_points(rel);
        (
            m_chart_err.hypot(m_chart * rel),
            format!("{source}; ± {:.4} from the black level", m_chart * rel),
        )
    } else if let Some((eps, f)) = tone_fix
        .as_ref()
        .and_then(|f| Some((tone_unseen::scale(f)?, f)))
    {
        // Unseen (or a curve seen too weakly to take out), it leaves the
        // chart modulation and, where the light changes, each point
        // uncertain: said, not hidden.
        let share = widen_points(eps);
        (
            m_chart_err.hypot(share),
            format!("{source}{}", tone_unseen::source_note(share, eps, f)),
        )
    } else if let Some(f) = not_taken_out {
        // Read through the curve: the chart modulation by about its effect,
        // and, where the light changes, each point as an offset of that
        // scale would move it.
        let share = widen_points(f.effect.abs());
        (
            m_chart_err.hypot(share),
            format!("{source}; ± {share:.4} from the camera's tone curve, seen but not taken out"),
        )
    } else {
        (m_chart_err, source)
    };
    let (s_first, s_last) = (
        points.iter().map(|p| p.s).fold(f64::INFINITY, f64::min),
        points.iter().map(|p| p.s).fold(f64::NEG_INFINITY, f64::max),
    );
    Ok(Curve {
        channel: channel.to_string(),
        sweep_id: id.to_string(),
        law,
        strip_unit: if target_law.is_some() { "mm" } else { "px" },
        strip_length: strip.length,
        points,
        chart_modulation: m_chart,
        chart_modulation_err: m_chart_err,
        chart_modulation_source: source,
        figures,
        aliasing_from_cy_px: aliasing_from,
        rounded_away_from_cy_px: rounded_away_from,
        clipped_fraction: clipped,
        region_px: strip.image_quad(opts.margin * strip.width, (1.0 - opts.margin) * strip.width),
        outline_px: match strip.lens {
            Some(_) => super::profile::photo_outline(
                strip,
                opts.margin * strip.width,
                (1.0 - opts.margin) * strip.width,
            ),
            None => Vec::new(),
        },
        paper_bands_px,
        alias_line_px: alias_line,
        measured_lines_px: [across(s_first), across(s_last)],
        print_ends_inside_px: ends.map(|e| e.map(|e| e.inside_px)),
        tone_fix,
    })
}

/// A strip's whole outline in the photo (px, closed polyline): its long edges
/// bent where a lens model bends them.
fn outline(strip: &Strip) -> Vec<Point> {
    match strip.lens {
        Some(_) => super::profile::photo_outline(strip, 0.0, strip.width),
        None => strip.image_quad(0.0, strip.width).to_vec(),
    }
}
