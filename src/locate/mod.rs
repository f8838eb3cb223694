//! Finding the chart in a photo without help: the target's fiducial marks are
//! searched on a reduced copy of the image (dark, elliptical blobs on a white
//! surround, robust to vignetting and gradients), four of them are chosen that
//! form a projective quad consistent with the target description (the `Ring`
//! mark fixes the orientation), their centres are refined at full resolution
//! to sub-pixel precision (with the perspective shift of an imaged disk's
//! centre corrected), and the homography target mm → image px follows. When
//! one mark is hidden, the chart is solved from three marks and the target's
//! straight edges. [`refine_roi`] refines user-given corners to the edges of a
//! strip or target (a strip's ends to its printed bars, [`strip_ends`]).
//!
//! Pipeline: [`downscale`] → [`blobs`] → [`assign`] → [`ellipse`] → (when a
//! mark is hidden) [`refine`].

pub mod assign;
pub mod blobs;
pub mod coded;
pub mod conic;
pub mod debug;
pub mod downscale;
pub mod ellipse;
mod masks;
pub mod refine;
pub mod row_reduction;
pub mod sample;
pub mod source;
pub mod strip_ends;

use crate::geometry::{Homography, Point};
use crate::target::Target;
use thiserror::Error;

pub use coded::{Coded, of_decoded};
pub use debug::debug_image;
pub use sample::{AtImage, ConvertedCrop};
pub use source::{Converted, Source};

/// Why no chart (or no refined region) could be given.
#[derive(Debug, Error)]
pub enum LocateError {
    /// Nothing matching the target's fiducials was found in the image.
    #[error("no chart found: looked for {looked_for}; saw {seen}")]
    NotFound {
        /// What was searched for, in words.
        looked_for: String,
        /// What was seen instead, in words.
        seen: String,
        /// Every blob examined (for [`debug_image`]).
        candidates: Vec<Candidate>,
    },
    /// The target description has no usable fiducials (needs at least three).
    #[error(
        "the target description has {0} fiducial(s); automatic location needs 3 or more (give --roi)"
    )]
    NoFiducials(usize),
    /// `chart_index` asked for a chart that is not there.
    #[error("chart index {index} asked for, but {found} chart(s) found")]
    NoSuchChart {
        /// The index asked for (0-based).
        index: usize,
        /// How many charts were found.
        found: usize,
    },
    /// The given region could not be refined (edges not found, bad corners).
    #[error("cannot refine the region: {0}")]
    Refine(String),
    /// A strip's printed bars were seen clearly, slanted across its given
    /// ends farther than refining may turn them (px across the strip at its
    /// low and high ends; the largest turn allowed, px).
    #[error(
        "the printed bars run {0:.1} / {1:.1} px across the strip off its given low / high ends, \
         more than the {2:.1} px refining may turn them: corners this far off the strip's ends \
         smear its bars across the bins; place the corners on the strip's ends"
    )]
    EndsSlanted(f64, f64, f64),
    /// The image is empty or too small to search.
    #[error("image of {0}×{1} samples is too small to search for a chart")]
    TooSmall(usize, usize),
}

/// A blob looked at during the search (image pixel coordinates).
#[derive(Debug, Clone, PartialEq)]
pub struct Candidate {
    /// Centre (image px).
    pub centre_px: Point,
    /// Covariance of the equivalent solid ellipse (image px²): its edge is at 2σ.
    pub cov_px2: [f64; 3],
    /// How bright the centre is between the dark mark (0) and the white surround (1).
    pub ring_score: f64,
    /// (white − dark)/white around the blob.
    pub contrast: f64,
    /// Whether it passed the disk test (else it was rejected as not a fiducial).
    pub disk_like: bool,
    /// Why it failed the disk test ("" when it passed).
    pub why: &'static str,
    /// Whether it ended up as one of a located chart's fiducials.
    pub used: bool,
}

/// A chart found in an image.
#[derive(Debug, Clone, PartialEq)]
pub struct Located {
    /// Target frame (mm) → image (px).
    pub homography: Homography,
    /// Target frame corners (0,0), (w,0), (w,h), (0,h) in image px.
    pub corners_px: [Point; 4],
    /// Every fiducial used, by id, at its refined image centre (px, image of the mark's centre).
    pub fiducials: Vec<(String, Point)>,
    /// The id of a fiducial that was not seen (solved from the others), if any.
    pub hidden: Option<String>,
    /// Things the user should know (hidden fiducial, weak contrast, …).
    pub warnings: Vec<String>,
    /// Agreement of the image with the target's pattern under this homography (correlation, −1…1).
    pub score: f64,
}

impl Located {
    /// A chart rectangle (mm) placed in the image: its corners in image px, in order round it.
    pub fn place(&self, rect: &crate::target::Rect) -> [Point; 4] {
        rect.corners().map(|p| self.homography.apply(p))
    }
}

/// Everything the search saw: candidates and charts (for [`debug_image`]).
#[derive(Debug, Clone, Default)]
pub struct Search {
    /// Every blob examined.
    pub candidates: Vec<Candidate>,
    /// Charts found, in order (left to right by centre).
    pub charts: Vec<Located>,
}

/// Finds every copy of `target` in the image, left to right by centre.
pub fn find_charts<S: Source + ?Sized>(
    src: &S,
    target: &Target,
) -> Result<Vec<Located>, LocateError> {
    found(search(src, target)?, target)
}

/// [`find_charts`] with the target's pattern already sampled
/// ([`assign::Pattern::new`]; it does not depend on the image, so a caller
/// may make it while the photo is decoded).
pub fn find_charts_with<S: Source + ?Sized>(
    src: &S,
    target: &Target,
    pattern: &assign::Pattern,
) -> Result<Vec<Located>, LocateError> {
    found(search_with(src, target, Some(pattern))?, target)
}

/// The charts a search found, or why none was.
fn found(s: Search, target: &Target) -> Result<Vec<Located>, LocateError> {
    if s.charts.is_empty() {
        return Err(not_found(target, s.candidates));
    }
    Ok(s.charts)
}

/// Finds one chart: the only one, or the `chart_index`-th (0-based, left to right) of several.
///
/// With several charts and no index, the first is returned with a warning.
pub fn find_chart<S: Source + ?Sized>(
    src: &S,
    target: &Target,
    chart_index: Option<usize>,
) -> Result<Located, LocateError> {
    let mut charts = find_charts(src, target)?;
    let n = charts.len();
    match chart_index {
        Some(i) if i >= n => Err(LocateError::NoSuchChart { index: i, found: n }),
        Some(i) => Ok(charts.swap_remove(i)),
        None => {
            let mut c = charts.swap_remove(0);
            if n > 1 {
                c.warnings.push(format!(
                    "{n} charts found; using the leftmost (choose with --chart-index)"
                ));
            }
            Ok(c)
        }
    }
}

/// Runs the search and returns what was seen, even when nothing was found.
///
/// `src` is a linear [`Plane`](crate::photo::Plane) or a photo converted on demand ([`Converted`]):
/// the search reads a reduced image and full resolution only near the marks.
pub fn search<S: Source + ?Sized>(src: &S, target: &Target) -> Result<Search, LocateError> {
    search_with(src, target, None)
}

/// [`search`] with the target's pattern, if already sampled.
fn search_with<S: Source + ?Sized>(
    src: &S,
    target: &Target,
    pattern: Option<&assign::Pattern>,
) -> Result<Search, LocateError> {
    let nf = target.fiducials.len();
    if nf < 3 {
        return Err(LocateError::NoFiducials(nf));
    }
    let (w, h) = src.size();
    if w < 16 || h < 16 || !src.complete() {
        return Err(LocateError::TooSmall(w, h));
    }
    // The target's pattern does not depend on the image: made while the
    // image is reduced (memory-bound) rather than beside the blob search.
    let made;
    let (small, pattern) = match pattern {
        Some(p) => (src.reduced(), p),
        None => {
            let (small, p) = rayon::join(|| src.reduced(), || assign::Pattern::new(target));
            made = p;
            (small, &made)
        }
    };
    let mut candidates = blobs::find_candidates(&small);
    let picks = assign::choose(&small, target, pattern, &candidates);
    let mut charts = Vec::new();
    for pick in picks {
        if let Some(mut located) = ellipse::finish(src, target, &pick, &candidates) {
            // Re-verify under the final homography.
            let score = pattern
                .verify(&small, &located.homography, f64::NEG_INFINITY)
                .unwrap_or(0.0);
            let min = if pick.hidden.is_some() {
                assign::MIN_SCORE_TRIPLE
            } else {
                assign::MIN_SCORE_QUAD
            };
            if score < min {
                continue;
            }
            located.score = score;
            if score < 0.8 {
                located.warnings.push(format!(
                    "weak agreement between image and target pattern (correlation {score:.2})"
                ));
            }
            for &ci in pick.cand_idx.iter() {
                candidates[ci].used = true;
            }
            charts.push(located);
        }
    }
    charts.sort_by(|a, b| centre_x(a).total_cmp(&centre_x(b)));
    Ok(Search { candidates, charts })
}

fn centre_x(l: &Located) -> f64 {
    l.corners_px.iter().map(|c| c[0]).sum::<f64>() / 4.0
}

fn not_found(target: &Target, candidates: Vec<Candidate>) -> LocateError {
    let kinds: Vec<String> = target
        .fiducials
        .iter()
        .map(|f| {
            format!(
                "{} {} ({:.1} mm)",
                f.id,
                match f.kind {
                    crate::target::FiducialKind::Disk => "disk",
                    crate::target::FiducialKind::Ring => "ring",
                },
                f.diameter_mm
            )
        })
        .collect();
    let disks = candidates.iter().filter(|c| c.disk_like).count();
    LocateError::NotFound {
        looked_for: format!(
            "{} black fiducial marks of '{}' on white squares [{}] forming the target's quad (at least 3 needed)",
            target.fiducials.len(),
            target.name,
            kinds.join(", ")
        ),
        seen: format!(
            "{} dark blob(s), {} disk-like, none forming the target",
            candidates.len(),
            disks
        ),
        candidates,
    }
}

/// Refines four approximate corners (image px, in order round the region, error up to
/// about `search_px`) to the region's straight edges, to sub-pixel precision.
///
/// With `target`, the corners are the target frame's (0,0), (w,0), (w,h), (0,h) and
/// every straight edge of its sweeps, patches and grey patches is used (each with
/// the polarity the target gives it); without, the corners are those of one strip:
/// its long edges are refined, its ends keep the given lines' centres and are only
/// turned along the printed bars ([`strip_ends`]; an error when the bars are not clearly seen).
/// Errors (edges not clearly seen, ambiguous, or corners that would move further
/// than `search_px` allows) leave the caller to use the corners as given.
pub fn refine_roi<S: AtImage + ?Sized>(
    src: &S,
    corners: [Point; 4],
    target: Option<&Target>,
    search_px: f64,
) -> Result<[Point; 4], LocateError> {
    refine::refine_roi(src, corners, target, search_px)
}

/// One strip's four corners (image px, error up to about `search_px`) with
/// only its ends turned along the printed bars ([`strip_ends`]) and its long
/// edges as given: for a strip whose long edges are not clearly seen (a grey
/// surround at the sweep's mean has no edge, only the bars stop), whose bins
/// must still run along the bars. Errors as [`refine_roi`]'s.
pub fn turn_strip_ends<S: AtImage + ?Sized>(
    src: &S,
    corners: [Point; 4],
    search_px: f64,
) -> Result<[Point; 4], LocateError> {
    refine::turn_strip_ends(src, corners, search_px)
}
