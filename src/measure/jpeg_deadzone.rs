//! A JPEG quantiser's hold on a weak sine. Each 8×8 block's DCT coefficient
//! is rounded to a multiple of its step in the luma table, so a sine whose
//! coefficients stay below half a step is rounded away in every block (the
//! quantiser's dead zone), and one a few steps strong is read with a bias
//! that its phase against the blocks does not average out. The lens
//! amplitudes that the decoded one is consistent with, through the
//! quantiser averaged over the sine's phases against the blocks, give each
//! point the uncertainty the quantiser adds.
//!
//! Found at f/16 on q75 (the independent camera, `jpeg75` seed 57 #9
//! rendered without noise): the curve reached 0 at 0.40 cy/px where the
//! lens passes 0.02, claimed ±0.0016. The 2-code sine's DCT coefficient
//! (≈ 5.7 × its amplitude, square to the blocks) lay under half of q75's
//! steps of 20–31 there.

use super::MtfPoint;
use num_complex::Complex64;

/// Phases of the sine against the block grid, evenly spread, over which a
/// point's blocks are averaged (the smoothing of a coarse JPEG's curve
/// averages neighbouring points, whose phases differ).
const PHASES: usize = 16;
/// Lens amplitudes tried per point.
const AMPLITUDES: usize = 64;
/// Noise sigmas within which a lens amplitude's decoded reading counts as
/// consistent with the point's.
const CONSISTENT_SIGMAS: f64 = 2.0;
/// Beyond this many dead-zone amplitudes (the amplitude at which the sine's
/// largest coefficient reaches half its step) the rounding errors of the
/// phases average out (under 1 % of the amplitude): the point is left as is.
const CLEAR_OF_DEAD_ZONE: f64 = 8.0;

/// Where a point's sine lies in the photo, for its blocks.
#[derive(Debug, Clone, Copy)]
pub(super) struct PointSine {
    /// Frequency across the bars (cycles/pixel).
    pub freq_cy_px: f64,
    /// Direction of the sweep in the image (radians from +x towards +y).
    pub angle_rad: f64,
    /// Code values (0–255) per unit of modulation at the point: its local
    /// mean times the codes per strip value there.
    pub codes_per_modulation: f64,
}

/// The orthonormal 8-point DCT-II (JPEG's FDCT along one axis) of
/// e^{i 2π f (x − 3.5)}, x = 0..7: entry u is its coefficient on basis u.
fn dct_of_exponential(f: f64) -> [Complex64; 8] {
    std::array::from_fn(|u| {
        let norm = if u == 0 { (1.0f64 / 8.0).sqrt() } else { 0.5 };
        (0..8)
            .map(|x| {
                let basis = ((2 * x + 1) as f64 * u as f64 * std::f64::consts::PI / 16.0).cos();
                Complex64::from_polar(norm * basis, std::f64::consts::TAU * f * (x as f64 - 3.5))
            })
            .sum()
    })
}

/// The quantiser's view of one point's sine: its unit-amplitude
/// coefficients at each phase and the steps they are rounded to.
struct Blocks {
    /// Per phase, the coefficients (natural order, DCT units) of a unit
    /// cosine cos(2π(fx·x + fy·y) + φ) over a block.
    unit: Vec<[f64; 64]>,
    /// Σ over phases of Σ coefficient² (the projection's norm).
    norm: f64,
    /// The AC coefficients that some amplitude up to the one the blocks
    /// were made for lifts to half a step or more at some phase (the others
    /// round to 0 at every amplitude tried, and add nothing to the read-back).
    live: Vec<usize>,
}

/// The complex DCT coefficients (natural order: v rows, u columns) of
/// e^{i 2π(fx·x + fy·y)} over a block, whose real part at phase φ is the
/// cosine's: the product of the 1-D ones, cos(A + B + φ) = Re(e^{iφ} e^{iA} e^{iB}).
fn block_coefficients(sine: &PointSine) -> [Complex64; 64] {
    let ex = dct_of_exponential(sine.freq_cy_px * sine.angle_rad.cos());
    let ey = dct_of_exponential(sine.freq_cy_px * sine.angle_rad.sin());
    std::array::from_fn(|k| ey[k / 8] * ex[k % 8])
}

/// The amplitude (codes) at which the largest of the coefficients `z`
/// reaches half its step in `table` at some phase.
fn dead_zone(z: &[Complex64; 64], table: &[u16; 64]) -> f64 {
    (1..64)
        .filter(|&k| z[k].norm() > 1e-9)
        .map(|k| table[k].max(1) as f64 / (2.0 * z[k].norm()))
        .fold(f64::INFINITY, f64::min)
}

impl Blocks {
    /// The blocks of a sine of coefficients `z` ([`block_coefficients`])
    /// under `table`, for amplitudes up to `a_max` (codes).
    fn of(z: &[Complex64; 64], table: &[u16; 64], a_max: f64) -> Blocks {
        let unit: Vec<[f64; 64]> = (0..PHASES)
            .map(|j| {
                let turn =
                    Complex64::from_polar(1.0, std::f64::consts::TAU * j as f64 / PHASES as f64);
                std::array::from_fn(|k| (turn * z[k]).re)
            })
            .collect();
        let norm = unit.iter().flatten().map(|c| c * c).sum();
        let live = (1..64)
            .filter(|&k| a_max * z[k].norm() >= 0.5 * table[k].max(1) as f64)
            .collect();
        Blocks { unit, norm, live }
    }

    /// The amplitude (codes) read back from a sine of amplitude `a` (codes)
    /// (up to the blocks' `a_max`) after every AC coefficient is rounded to
    /// its step: the decoded
    /// blocks projected on the sine, over all phases. The DC is left
    /// exact (the blocks' means carry the strip's mean, whose rounding
    /// falls anywhere against the sine's share).
    fn read_back(&self, a: f64, table: &[u16; 64]) -> f64 {
        let mut dot = 0.0;
        for unit in &self.unit {
            dot += a * unit[0] * unit[0];
            for &k in &self.live {
                let step = table[k].max(1) as f64;
                dot += step * (a * unit[k] / step).round() * unit[k];
            }
        }
        dot / self.norm
    }
}

/// The RMS error (codes) the quantiser leaves in a point read as `a_read`
/// ± `sigma` (codes): over the lens amplitudes whose read-back lies within
/// [`CONSISTENT_SIGMAS`]·`sigma` of it (the nearest one when none does),
/// the RMS of read-back − amplitude, that bias first averaged over a
/// dead zone's width of amplitudes (the steps of one set of phases fall
/// elsewhere for another, so only its trend is the blocks'). Zero well
/// clear of the dead zone, where the rounding errors of the blocks' phases
/// average out (their ripple is [`super::block_ripple`]'s).
/// `z` are the sine's [`block_coefficients`], `dz` their [`dead_zone`].
fn error_codes(z: &[Complex64; 64], dz: f64, table: &[u16; 64], a_read: f64, sigma: f64) -> f64 {
    let reach = CONSISTENT_SIGMAS * sigma;
    if !(dz.is_finite() && dz > 0.0) || a_read - reach > CLEAR_OF_DEAD_ZONE * dz {
        return 0.0;
    }
    let lo = (a_read - reach - 4.0 * dz).max(0.0);
    let hi = a_read.max(0.0) + reach + 4.0 * dz;
    let blocks = Blocks::of(z, table, hi);
    let step = (hi - lo) / (AMPLITUDES - 1) as f64;
    let tried: Vec<(f64, f64)> = (0..AMPLITUDES)
        .map(|i| {
            let a = lo + step * i as f64;
            (a, blocks.read_back(a, table))
        })
        .collect();
    let half = (0.5 * dz / step).round() as usize;
    let trend: Vec<f64> = (0..tried.len())
        .map(|i| {
            let near = &tried[i.saturating_sub(half)..(i + half + 1).min(tried.len())];
            near.iter().map(|(a, r)| r - a).sum::<f64>() / near.len() as f64
        })
        .collect();
    let consistent: Vec<f64> = tried
        .iter()
        .zip(&trend)
        .filter(|((_, r), _)| (r - a_read).abs() <= reach)
        .map(|(_, b)| *b)
        .collect();
    let bias = if consistent.is_empty() {
        tried
            .iter()
            .zip(&trend)
            .min_by(|x, y| (x.0.1 - a_read).abs().total_cmp(&(y.0.1 - a_read).abs()))
            .map(|(_, b)| vec![*b])
            .unwrap_or_default()
    } else {
        consistent
    };
    (bias.iter().map(|b| b * b).sum::<f64>() / bias.len().max(1) as f64).sqrt()
}

/// The mean of the profile's values within `half_width` (strip units) of
/// `s`; None where no bin lies there or the mean is not positive.
pub(super) fn local_mean(prof: &super::profile::Profile, s: f64, half_width: f64) -> Option<f64> {
    let lo = prof.s.partition_point(|&x| x < s - half_width);
    let hi = prof.s.partition_point(|&x| x <= s + half_width);
    let near = prof.y.get(lo..hi).filter(|v| !v.is_empty())?;
    let mean = near.iter().sum::<f64>() / near.len() as f64;
    (mean > 0.0 && mean.is_finite()).then_some(mean)
}

/// Code values (0–255) per unit of the strip's value `y`, where
/// `value_of_code` maps a code (0–1) to that value (rising): its slope
/// inverted at the code that gives `y` (found by bisection).
pub(super) fn codes_per_value(value_of_code: impl Fn(f64) -> f64, y: f64) -> Option<f64> {
    let (mut lo, mut hi) = (0.0f64, 1.0f64);
    for _ in 0..50 {
        let mid = 0.5 * (lo + hi);
        if value_of_code(mid) < y {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    let c = 0.5 * (lo + hi);
    let h = 1.0 / 512.0;
    let (a, b) = ((c - h).max(0.0), (c + h).min(1.0));
    let slope = (value_of_code(b) - value_of_code(a)) / (b - a);
    (slope > 0.0 && slope.is_finite()).then(|| 255.0 / slope)
}

/// A point read at most this many dead zones (beyond its noise) has had its
/// sine rounded away: what is left is the file's, not the lens's.
const ROUNDED_AWAY: f64 = 0.5;

/// Adds to each point's uncertainty (modulation units, before the chart
/// modulation divides it) the error the JPEG's luma quantiser `table`
/// leaves there, and marks the point `jpeg_limited` where that error is
/// larger than the rest of its uncertainty or its sine is rounded away;
/// `sine_at` gives a point's sine in the photo, None where its codes are
/// not known. Returns the frequency (cycles/pixel) from which
/// every non-aliased point to the curve's end reads its sine rounded away
/// (within [`ROUNDED_AWAY`] dead zones of nothing), if the last one does.
pub(super) fn widen(
    points: &mut [MtfPoint],
    table: &[u16; 64],
    sine_at: impl Fn(&MtfPoint) -> Option<PointSine>,
) -> Option<f64> {
    let mut lost_from = None;
    for p in points.iter_mut().filter(|p| !p.aliased) {
        let Some(sine) = sine_at(p).filter(|s| {
            s.codes_per_modulation.is_finite()
                && s.codes_per_modulation > 0.0
                && s.freq_cy_px.is_finite()
        }) else {
            lost_from = None;
            continue;
        };
        let k = sine.codes_per_modulation;
        let (a_read, sigma) = (p.modulation * k, p.mtf_err * k);
        let z = block_coefficients(&sine);
        let dz = dead_zone(&z, table);
        let e = error_codes(&z, dz, table, a_read, sigma) / k;
        if e.is_finite() && e > 0.0 {
            p.jpeg_limited = e > p.mtf_err;
            p.mtf_err = p.mtf_err.hypot(e);
        }
        if a_read.abs() + CONSISTENT_SIGMAS * sigma <= ROUNDED_AWAY * dz {
            p.jpeg_limited = true;
            lost_from.get_or_insert(p.freq_cy_px);
        } else {
            lost_from = None;
        }
    }
    lost_from
}

/// The warning for a curve whose sine the quantiser rounds away from
/// `from` (cycles/pixel) to its end; `name` the curve's.
pub(super) fn rounded_away_warning(name: &str, from: f64) -> String {
    format!(
        "{name}: from {from:.3} cy/px to the curve's end the JPEG's quantiser rounds the sine \
         away (under half its steps in every 8×8 block): the MTF there is the file's, not the \
         lens's, and its points claim so; shoot at a higher quality or raw to measure the lens there"
    )
}

#[cfg(test)]
mod tests;
