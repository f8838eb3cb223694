//! The lens distortion a measurement uses: the one given (`--distortion`,
//! checked against what a lens can have), or one estimated from the long
//! edges of the strip or, with a target, of its first strip whose edges
//! give a clear answer, or none.

use super::lens_fit::{self, DistortionFound};
use super::options::{MeasureOptions, REFINE_SEARCH_PX};
use super::region;
use super::result::Failure;
use crate::distortion::Lens;
use crate::geometry::Point;
use crate::target::Target;

/// The distortion the user gave, checked against the image size (exit 2 with the allowed range).
pub(super) fn given_distortion(
    opts: &MeasureOptions,
    roi: &[Point; 4],
    width: usize,
    height: usize,
) -> Result<Option<DistortionFound>, Failure> {
    let Some(model) = opts.distortion.filter(|d| !d.is_zero()) else {
        return Ok(None);
    };
    Lens::new(model, width, height)
        .check()
        .map_err(Failure::Options)?;
    Ok(Some(lens_fit::given(model, roi, width, height)))
}

/// The distortion of a shot: as given, or estimated from the long edges of
/// the strip (or, with a target, of the first sweep strip whose edges give a
/// clear answer) in the luminance `luma(quad)` gives (it must reach
/// [`lens_fit::search_pad_px`] beyond `quad`; `whole`: it shows the whole
/// strip, not only the bands about its long edges), or none when estimating
/// is off.
pub(super) fn resolve_distortion<'a>(
    opts: &MeasureOptions,
    roi: &[Point; 4],
    target: Option<&Target>,
    size: (usize, usize),
    whole: bool,
    luma: impl Fn(&[Point; 4]) -> Box<dyn lens_fit::Sampler + 'a>,
) -> Result<Option<DistortionFound>, Failure> {
    if opts.distortion.is_some() {
        return given_distortion(opts, roi, size.0, size.1);
    }
    if !opts.estimate_distortion {
        return Ok(None);
    }
    let Some(t) = target else {
        let plane = luma(roi);
        let mut d = lens_fit::estimate(&*plane, roi, size.0, size.1);
        // The refinement fitted straight lines to the long edges and turned
        // the ends along bars the lens bends; where a lens model is used, the
        // corners as given go onto the edges seen through it instead.
        let given = opts.roi.unwrap_or(*roi);
        if opts.refine_roi {
            d.snapped = lens_fit::snap_to_edges(
                &d,
                whole.then_some(&*plane),
                &given,
                size.0,
                size.1,
                2.0 * REFINE_SEARCH_PX + d.bow_px,
            );
        }
        return Ok(Some(d));
    };
    // Before, a target's strips were binned as if straight: a 3.6 % pincushion
    // put MTF50 29 % low on one strip and 5 % high on another. The strips are
    // tried in the target's order until one's edges give a clear answer
    // (a model used, or edges found all along and no distortion in them).
    let mut tried: Vec<DistortionFound> = Vec::new();
    for q in region::target_strip_quads(t, roi)? {
        let d = lens_fit::estimate(&*luma(&q), &q, size.0, size.1);
        let clear = d.used().is_some()
            || d.edge_coverage
                .is_some_and(|c| c >= lens_fit::MIN_EDGE_COVERAGE);
        if clear {
            return Ok(Some(d));
        }
        tried.push(d);
    }
    Ok(tried.into_iter().max_by_key(|d| d.edge_points))
}
