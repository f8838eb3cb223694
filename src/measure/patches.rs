//! Sine-patch targets: one result per constant-frequency patch. Each patch is
//! binned along its sine's direction like a sweep strip (no resampling) and
//! fitted, over the whole patch with Hann weights, by a sine of the patch's
//! known chart frequency with free phase, mean and gradient.

#![allow(clippy::needless_range_loop, clippy::neg_cmp_op_on_partial_ord)]

use super::curve::Lattice;
use super::estimate::fit::{PhaseTable, local_fit};
use super::law::{LawKind, PhaseLaw};
use super::profile::{BinOptions, bin_planes};
use super::rect_strip;
use crate::geometry::Homography;
use crate::photo::PlaneRef;
use crate::target::Target;
use serde::Serialize;

/// The measurement of one sine patch.
#[derive(Debug, Clone, Serialize)]
pub struct PatchResult {
    /// Channel name.
    pub channel: String,
    /// Patch name from the target.
    pub patch_id: String,
    /// Chart frequency (cycles/mm on the chart).
    pub freq_chart_cy_mm: f64,
    /// Image frequency (cycles/pixel) at the patch centre.
    pub freq_cy_px: f64,
    /// Measured modulation in the image (linear light).
    pub modulation: f64,
    /// The patch's printed modulation (from the target).
    pub chart_modulation: f64,
    /// MTF = modulation / chart modulation.
    pub mtf: f64,
    /// One-sigma uncertainty of the MTF.
    pub mtf_err: f64,
    /// Above the sampling band: the value is not an MTF.
    pub aliased: bool,
    /// Image corners of the binned part of the patch.
    #[serde(skip)]
    pub region_px: [crate::geometry::Point; 4],
}

/// Measures every sine patch of the target in one plane; patches that cannot be measured are skipped.
pub fn measure_patches(
    planes: &[PlaneRef],
    channel: &str,
    h: &Homography,
    t: &Target,
    opts: &BinOptions,
) -> Vec<PatchResult> {
    t.patches
        .iter()
        .filter_map(|p| {
            let strip = rect_strip(h, &p.rect, p.direction);
            let sc = strip.scale_at(0.5 * strip.length);
            // Leave 6 % of the length at each end: the neighbours' blur.
            let end_px = (0.06 * strip.length / sc.s_per_px).max(2.0);
            let prof = bin_planes(planes, &strip, &BinOptions { end_px, ..*opts });
            if prof.s.len() < 8 {
                return None;
            }
            let law = PhaseLaw {
                kind: LawKind::Linear,
                c0: 0.0,
                c1: p.freq_cy_mm,
                c2: 0.0,
                persp: 0.0,
            };
            let table = PhaseTable::new(&prof, &law);
            let (a, b) = (prof.s[0], prof.s[prof.s.len() - 1]);
            let half = 0.5 * (b - a) * p.freq_cy_mm;
            let f_px = p.freq_cy_mm * sc.s_per_px;
            let aliased = Lattice::of(planes).outside(f_px, sc.angle_rad);
            let fit = local_fit(&prof, &table, &law, 0.5 * (a + b), half + 1e-9)?;
            if !(fit.mean > 0.0) {
                return None;
            }
            Some(PatchResult {
                channel: channel.to_string(),
                patch_id: p.id.clone(),
                freq_chart_cy_mm: p.freq_cy_mm,
                freq_cy_px: f_px,
                modulation: fit.modulation(),
                chart_modulation: p.contrast,
                mtf: fit.modulation() / p.contrast,
                mtf_err: fit.modulation_err() / p.contrast,
                aliased,
                region_px: strip
                    .image_quad(opts.margin * strip.width, (1.0 - opts.margin) * strip.width),
            })
        })
        .collect()
}
