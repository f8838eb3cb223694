//! Region: where on the photo a measurement reads. The corners given
//! (`--roi`, checked against the image) or found from a target's fiducials,
//! refined to the edges seen; the raw window a windowed raw decode needs; the
//! strips (one per sweep of a target, or the quadrilateral itself) with their
//! homographies and the target's printed laws; and the read set (crop and
//! per-row column span) that binning touches, so only that is converted.

use super::profile::{self, Strip};
use super::{Failure, LawKind, MeasureOptions, PhaseLaw, REFINE_SEARCH_PX, Said};
use crate::distortion::Lens;
use crate::geometry::{GeometryError, Homography, Point, check_quad, rect_corners};
use crate::photo::Plane;
use crate::photo::decode::Decoded;
use crate::photo::linearise::{Channel, Crop, file_tone, planes};
use crate::target::{Direction, Sweep, SweepLaw, Target};

/// The chart `opts.chart_index` picks in `plane` (see [`crate::locate::find_chart`]):
/// its corners (image px), the search's messages added to `said`.
pub(super) fn locate_region<S: crate::locate::Source + ?Sized>(
    plane: &S,
    target: &Target,
    opts: &MeasureOptions,
    said: &mut Said,
) -> Result<[Point; 4], Failure> {
    let loc =
        crate::locate::find_chart(plane, target, opts.chart_index).map_err(location_failed)?;
    let found = found_said(&loc, 0, 1);
    said.warnings.extend(found.warnings);
    said.notes.extend(found.notes);
    Ok(loc.corners_px)
}

/// The failure of automatic location.
pub(super) fn location_failed(e: crate::locate::LocateError) -> Failure {
    Failure::Region(format!("automatic location failed: {e}"))
}

/// The messages of a chart found automatically: the search's own warnings;
/// notes saying how it was found and which of `n` charts (left to right) it is.
pub(super) fn found_said(c: &crate::locate::Located, i: usize, n: usize) -> Said {
    let mut notes = vec!["region found automatically from the target's fiducials".to_string()];
    if n > 1 {
        notes.push(format!("chart index {i} of the {n} found (left to right)"));
    }
    Said {
        warnings: c.warnings.clone(),
        notes,
    }
}

/// The image rectangle a raw measurement with the corners `roi` reads (frame
/// pixels, unclamped): the corners' bounding box padded by the refinement's
/// reach (moves of up to √2·search + 2 px plus a strip's inward trim, and the
/// search band around the moved edges) and by the preview's context (as in
/// [`super::preview::preview_from`], from the corners as refined, so with some slack).
pub(super) fn raw_read_window(roi: &[Point; 4]) -> Crop {
    let xmin = roi.iter().map(|p| p[0]).fold(f64::INFINITY, f64::min);
    let xmax = roi.iter().map(|p| p[0]).fold(f64::NEG_INFINITY, f64::max);
    let ymin = roi.iter().map(|p| p[1]).fold(f64::INFINITY, f64::min);
    let ymax = roi.iter().map(|p| p[1]).fold(f64::NEG_INFINITY, f64::max);
    let reach = 4.0 * REFINE_SEARCH_PX + 16.0;
    let pad = 0.08 * ((xmax - xmin).max(ymax - ymin) + 2.0 * reach) + 8.0 + reach;
    let lo = |v: f64| (v - pad).floor().max(0.0) as usize;
    let hi = |v: f64| (v + pad).ceil().clamp(0.0, usize::MAX as f64) as usize;
    Crop {
        x0: lo(xmin),
        y0: lo(ymin),
        x1: hi(xmax),
        y1: hi(ymax),
    }
}

/// The given corners refined to the edges seen in `plane`, or as given (with
/// a warning saying why) when the edges are not clearly seen; refused where
/// a strip's bars are seen clearly, slanted across its given ends farther
/// than refining may turn them (its bins would smear them: the independent
/// study's strips clicked ±30 px off: one read MTF50 75 % low, claiming ±0.6 %).
pub(super) fn refine_or_keep<S: crate::locate::AtImage + ?Sized>(
    src: &S,
    given: [Point; 4],
    target: Option<&Target>,
    said: &mut Said,
) -> Result<[Point; 4], Failure> {
    Ok(
        match crate::locate::refine_roi(src, given, target, REFINE_SEARCH_PX) {
            Ok(refined) => {
                let moved = crate::geometry::largest_move(&given, &refined);
                if target.is_some() {
                    said.notes.push(format!(
                        "region corners refined to the edges (moved up to {moved:.2} px)"
                    ));
                } else {
                    // Split each corner's move into across the strip (long edges fitted
                    // to the edges seen) and along it (ends turned along the bars).
                    let (dx, dy) = (given[1][0] - given[0][0], given[1][1] - given[0][1]);
                    let len = dx.hypot(dy).max(1e-12);
                    let (ux, uy) = (dx / len, dy / len);
                    let (mut along, mut across) = (0.0f64, 0.0f64);
                    for (a, b) in given.iter().zip(&refined) {
                        let (ex, ey) = (b[0] - a[0], b[1] - a[1]);
                        along = along.max((ex * ux + ey * uy).abs());
                        across = across.max((ey * ux - ex * uy).abs());
                    }
                    said.notes.push(format!(
                    "region corners refined to the edges: long edges moved up to {across:.2} px \
                     across the strip onto the edges seen; ends kept, turned along the printed \
                     bars (corners slid up to {along:.2} px along the strip)"
                ));
                }
                refined
            }
            Err(e @ crate::locate::LocateError::EndsSlanted(..)) => {
                return Err(Failure::Unreliable(e.to_string()));
            }
            Err(e) => {
                // Without a target, a strip whose long edges are not clearly seen
                // (a grey surround at the sweep's mean shows none) still has its
                // ends turned: the bins must run along the bars.
                let turned = match target {
                    Some(_) => None,
                    None => match crate::locate::turn_strip_ends(src, given, REFINE_SEARCH_PX) {
                        Ok(turned) => Some(turned),
                        Err(e2 @ crate::locate::LocateError::EndsSlanted(..)) => {
                            return Err(Failure::Unreliable(e2.to_string()));
                        }
                        Err(_) => None,
                    },
                };
                match turned {
                    Some(turned) => {
                        let moved = crate::geometry::largest_move(&given, &turned);
                        said.warnings.push(format!(
                            "region's long edges used as given: {e}; its ends turned along \
                             the printed bars (corners slid up to {moved:.2} px along the strip)"
                        ));
                        turned
                    }
                    None => {
                        said.warnings
                            .push(format!("region corners used as given: {e}"));
                        given
                    }
                }
            }
        },
    )
}

/// The whole photo as one linear luminance plane (default tone), for chart location.
pub(super) fn full_grey(dec: &Decoded) -> Vec<Plane> {
    let full = Crop {
        x0: 0,
        y0: 0,
        x1: dec.width,
        y1: dec.height,
    };
    planes(dec, full, &file_tone(dec).0, Channel::Luma)
}

/// The photo as the chart search reads it: linear luminance (the file's tone, the
/// same values as [`full_grey`]), converted only where the search looks.
pub(super) fn grey_source(dec: &Decoded) -> impl crate::locate::Source + '_ {
    grey_source_with(dec, None)
}

/// [`grey_source`] with its search image, if summed while decoding.
pub(super) fn grey_source_with<'a>(
    dec: &'a Decoded,
    pre: Option<&'a crate::locate::row_reduction::ReducedSearch>,
) -> impl crate::locate::Source + 'a {
    crate::locate::of_decoded(dec, &file_tone(dec).0, Channel::Luma).with_reduced(pre)
}

/// Every copy of `target` in a decoded photo (left to right), found from its
/// luma as `measure` finds them (for a page that lets the user pick one).
pub fn charts_in(
    dec: &Decoded,
    target: &Target,
) -> Result<Vec<crate::locate::Located>, crate::locate::LocateError> {
    crate::locate::find_charts(&grey_source(dec), target)
}

/// The `--roi` corners, checked: in order round the region and inside the `w`×`h` image.
pub(super) fn resolve_roi(
    opts: &MeasureOptions,
    w: usize,
    h: usize,
) -> Result<[Point; 4], Failure> {
    // Without --target there is nothing to locate (measure_decoded calls `locate` when a target is given).
    let roi = opts.roi.ok_or(Failure::NoRoi)?;
    check_quad(&roi).map_err(|e| match e {
        GeometryError::SelfCrossing => {
            Failure::Region("the corners cross over; give them in order round the region".into())
        }
        other => Failure::Region(other.to_string()),
    })?;
    for (i, p) in roi.iter().enumerate() {
        if p[0] < 0.0 || p[1] < 0.0 || p[0] > w as f64 || p[1] > h as f64 {
            return Err(Failure::Region(format!(
                "corner {} ({}, {}) lies outside the {w}×{h} image",
                i + 1,
                p[0],
                p[1]
            )));
        }
    }
    Ok(roi)
}

/// The bounding box of `q` padded by `pad` px, clamped to the `w`×`h` image.
pub(super) fn bbox_crop(q: &[Point], w: usize, h: usize, pad: f64) -> Crop {
    let xmin = q.iter().map(|p| p[0]).fold(f64::INFINITY, f64::min) - pad;
    let xmax = q.iter().map(|p| p[0]).fold(f64::NEG_INFINITY, f64::max) + pad;
    let ymin = q.iter().map(|p| p[1]).fold(f64::INFINITY, f64::min) - pad;
    let ymax = q.iter().map(|p| p[1]).fold(f64::NEG_INFINITY, f64::max) + pad;
    let x0 = (xmin.floor().max(0.0) as usize).min(w - 1);
    let y0 = (ymin.floor().max(0.0) as usize).min(h - 1);
    Crop {
        x0,
        y0,
        x1: (xmax.ceil().max(0.0) as usize).clamp(x0 + 1, w),
        y1: (ymax.ceil().max(0.0) as usize).clamp(y0 + 1, h),
    }
}

/// The strips to measure: (id, strip, law from the target, chart modulation from the target).
pub(super) type StripSpec = (String, Strip, Option<PhaseLaw>, Option<f64>);

/// The strips of region `roi` (photo corners); with `lens`, the corners are
/// undistorted first and each strip carries the lens, so that strip points map
/// to the photo through the homography and then the distortion.
pub(super) fn strips(
    roi: &[Point; 4],
    target: Option<&Target>,
    lens: Option<&Lens>,
) -> Result<Vec<StripSpec>, Failure> {
    let photo_roi = roi;
    let undistorted;
    let roi = match lens {
        Some(l) => {
            undistorted = roi.map(|p| l.undistort(p));
            &undistorted
        }
        None => photo_roi,
    };
    let mut out: Vec<StripSpec> = match target {
        None => {
            let d = |a: Point, b: Point| (a[0] - b[0]).hypot(a[1] - b[1]);
            let len = 0.5 * (d(roi[0], roi[1]) + d(roi[3], roi[2]));
            let wid = 0.5 * (d(roi[0], roi[3]) + d(roi[1], roi[2]));
            let h = Homography::from_quads(&rect_corners(0.0, 0.0, len, wid), roi)
                .map_err(|e| Failure::Region(e.to_string()))?;
            vec![(
                "strip".into(),
                Strip {
                    to_image: h,
                    lens: None,
                    length: len,
                    width: wid,
                },
                None,
                None,
            )]
        }
        Some(t) => {
            let h = target_homography(t, roi)?;
            t.sweeps
                .iter()
                .map(|sw| {
                    (
                        sw.id.clone(),
                        sweep_strip(&h, sw),
                        Some(target_law(sw)),
                        Some(sw.contrast),
                    )
                })
                .collect()
        }
    };
    for sp in out.iter_mut() {
        sp.1.lens = lens.copied();
    }
    Ok(out)
}

/// Each sweep strip of a target whose frame corners are `roi`, as its photo
/// corners (corners 1→2 and 4→3 run along the sweep, as for a strip given by
/// hand); the lens's distortion is not applied.
pub(super) fn target_strip_quads(t: &Target, roi: &[Point; 4]) -> Result<Vec<[Point; 4]>, Failure> {
    let h = target_homography(t, roi)?;
    Ok(t.sweeps
        .iter()
        .map(|sw| {
            let st = sweep_strip(&h, sw);
            st.image_quad(0.0, st.width)
        })
        .collect())
}

/// The photo outlines binning reads (closed polygons, image px): each strip
/// and sine patch inside its long-edge margins; a strip seen through a lens
/// as its curved outline, densely sampled.
fn binned_outlines(
    roi: &[Point; 4],
    target: Option<&Target>,
    margin: f64,
    lens: Option<&Lens>,
) -> Result<Vec<Vec<Point>>, Failure> {
    let m = margin.clamp(0.0, 0.45);
    let outline = |st: &Strip| {
        let (a, b) = (m * st.width, (1.0 - m) * st.width);
        match st.lens {
            Some(_) => profile::photo_outline(st, a, b),
            None => st.image_quad(a, b).to_vec(),
        }
    };
    let mut outlines: Vec<Vec<Point>> = strips(roi, target, lens)?
        .iter()
        .map(|sp| outline(&sp.1))
        .collect();
    if let Some(t) = target
        && !t.patches.is_empty()
    {
        let h = target_homography(t, roi)?;
        outlines.extend(
            t.patches
                .iter()
                .map(|p| outline(&rect_strip(&h, &p.rect, p.direction))),
        );
    }
    Ok(outlines)
}

/// What a measurement reads: the crop around the binned regions, and for each
/// image row y the columns [a, b) to convert (the regions' span over y ± 2 px,
/// widened by 2 px, 3 on the right). Under a lens the span follows the
/// regions' curved outlines (before, it widened the straight corner quads by
/// their bow, which missed parts of a strongly distorted strip: at −19.5 %
/// barrel 7 % of the samples read as unconverted zeros, refused as clipped).
#[allow(clippy::type_complexity)]
pub(super) fn read_set(
    roi: &[Point; 4],
    target: Option<&Target>,
    margin: f64,
    lens: Option<&Lens>,
    width: usize,
    height: usize,
) -> Result<(Crop, impl Fn(usize) -> (usize, usize) + Sync), Failure> {
    let outlines = binned_outlines(roi, target, margin, lens)?;
    let crop = outlines
        .iter()
        .map(|q| bbox_crop(q, width, height, 3.0))
        .reduce(|a, b| Crop {
            x0: a.x0.min(b.x0),
            y0: a.y0.min(b.y0),
            x1: a.x1.max(b.x1),
            y1: a.y1.max(b.y1),
        })
        .unwrap_or_else(|| bbox_crop(roi, width, height, 2.0));
    let span = move |y: usize| -> (usize, usize) {
        let yc = y as f64 + 0.5;
        let mut lo = f64::INFINITY;
        let mut hi = f64::NEG_INFINITY;
        for q in &outlines {
            for dy in [-2.0, 0.0, 2.0] {
                if let Some((a, b)) = profile::row_span(q, yc + dy) {
                    lo = lo.min(a);
                    hi = hi.max(b);
                }
            }
        }
        if lo > hi {
            (0, 0)
        } else {
            ((lo - 2.0).max(0.0) as usize, (hi + 3.0).max(0.0) as usize)
        }
    };
    Ok((crop, span))
}

/// The homography from the target frame (mm) to the image, given the target's corners in the image.
pub fn target_homography(t: &Target, roi: &[Point; 4]) -> Result<Homography, Failure> {
    Homography::from_quads(&rect_corners(0.0, 0.0, t.width_mm, t.height_mm), roi)
        .map_err(|e| Failure::Region(e.to_string()))
}

/// A strip frame for a rectangle on the chart whose sine runs along `dir`.
pub fn rect_strip(h: &Homography, rect: &crate::target::Rect, dir: Direction) -> Strip {
    let (len, wid, s) = match dir {
        Direction::X => (
            rect.width_mm,
            rect.height_mm,
            Homography {
                m: [1.0, 0.0, rect.x_mm, 0.0, 1.0, rect.y_mm, 0.0, 0.0, 1.0],
            },
        ),
        Direction::Y => (
            rect.height_mm,
            rect.width_mm,
            Homography {
                m: [0.0, 1.0, rect.x_mm, 1.0, 0.0, rect.y_mm, 0.0, 0.0, 1.0],
            },
        ),
    };
    Strip {
        to_image: h.compose(&s),
        lens: None,
        length: len,
        width: wid,
    }
}

/// The strip frame of a target sweep (mm).
fn sweep_strip(h: &Homography, sw: &Sweep) -> Strip {
    rect_strip(h, &sw.rect, sw.direction)
}

/// The phase law the target prints for a sweep (cycles/mm along the sweep, s in mm).
fn target_law(sw: &Sweep) -> PhaseLaw {
    let l = sw.length_mm();
    match sw.law {
        SweepLaw::Linear => PhaseLaw {
            kind: LawKind::Linear,
            c0: 0.0,
            c1: sw.f_min_cy_mm,
            c2: (sw.f_max_cy_mm - sw.f_min_cy_mm) / (2.0 * l),
            persp: 0.0,
        },
        SweepLaw::Log => PhaseLaw {
            kind: LawKind::Log,
            c0: 0.0,
            c1: sw.f_min_cy_mm,
            c2: (sw.f_max_cy_mm / sw.f_min_cy_mm).ln() / l,
            persp: 0.0,
        },
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::distortion::Ptlens;

    /// Every sample binning reads through a strong lens lies inside the read
    /// set's span of its row (else it would read an unconverted zero).
    #[test]
    fn read_set_covers_a_strongly_distorted_strip() {
        let (w, h) = (1200, 800);
        let roi = [
            [145.0, 644.0],
            [1067.0, 641.0],
            [1052.0, 708.0],
            [159.0, 712.0],
        ];
        for b in [-0.0867, 0.0867] {
            let lens = Lens::new(Ptlens { a: 0.0, b, c: 0.0 }, w, h);
            let margin = 0.1;
            let (crop, span) = read_set(&roi, None, margin, Some(&lens), w, h).unwrap();
            let specs = strips(&roi, None, Some(&lens)).unwrap();
            let st = &specs[0].1;
            let (t0, t1) = (margin * st.width, (1.0 - margin) * st.width);
            for i in 0..=400 {
                for k in 0..=8 {
                    let p = st.to_photo([
                        st.length * i as f64 / 400.0,
                        t0 + (t1 - t0) * k as f64 / 8.0,
                    ]);
                    if p[0] < 0.0 || p[1] < 0.0 || p[0] >= w as f64 || p[1] >= h as f64 {
                        continue;
                    }
                    let (x, y) = (p[0] as usize, p[1] as usize);
                    assert!(y >= crop.y0 && y < crop.y1 && x >= crop.x0 && x < crop.x1);
                    let (a, bx) = span(y);
                    assert!(
                        a < x && x + 2 <= bx,
                        "b {b}: ({x}, {y}) outside [{a}, {bx})"
                    );
                }
            }
        }
    }
}
