//! The strip's corners put on its long edges as seen through the lens
//! model (see [`snap_to_edges`]).

use super::*;

/// The photo seen through the lens undistorted: the value at undistorted
/// position p is the photo's at `lens.distort(p)`.
struct Undistorted<'a> {
    photo: &'a dyn Sampler,
    lens: &'a Lens,
}

impl crate::locate::sample::AtImage for Undistorted<'_> {
    fn at_img(&self, p: Point) -> Option<f64> {
        let q = self.lens.distort(p);
        self.photo.bilinear(q[0], q[1])
    }
}

/// The strip corners `roi` (as the user gave them) with their long edges
/// put on the edges seen (`d.edge_lines`, straight once undistorted by `d`'s
/// model) and each end turned about its centre along the printed bars as
/// they run once undistorted (as `plane` shows them; without a plane that
/// shows the whole strip, or where the bars are not clearly seen, kept on
/// its line through the undistorted end corners): what the corners' refinement, which fits straight lines and
/// bar directions to a photo the lens bends, cannot do. With the largest
/// move of a corner (px); `None` when the model is not used, no lines were fitted, or a corner would move more than
/// `max_move` px.
pub fn snap_to_edges(
    d: &DistortionFound,
    plane: Option<&dyn Sampler>,
    roi: &[Point; 4],
    width: usize,
    height: usize,
    max_move: f64,
) -> Option<([Point; 4], f64)> {
    let lens = d.lens(width, height)?;
    let lines = d.edge_lines?;

    let u = roi.map(|p| lens.undistort(p));
    // Intersection of line (p, dir) with the line through a and b.
    let meet = |[p, dir]: [Point; 2], a: Point, b: Point| -> Option<Point> {
        let e = [b[0] - a[0], b[1] - a[1]];
        let den = dir[0] * e[1] - dir[1] * e[0];
        if den.abs() < 1e-9 * e[0].hypot(e[1]).max(1e-300) {
            return None;
        }
        let t = ((a[0] - p[0]) * e[1] - (a[1] - p[1]) * e[0]) / den;
        Some([p[0] + t * dir[0], p[1] + t * dir[1]])
    };
    let mut snapped = [
        meet(lines[0], u[0], u[3])?,
        meet(lines[0], u[1], u[2])?,
        meet(lines[1], u[1], u[2])?,
        meet(lines[1], u[0], u[3])?,
    ];
    let square = crate::geometry::rect_corners(0.0, 0.0, 1.0, 1.0);
    if let Some(plane) = plane
        && let Ok(h) = crate::geometry::Homography::from_quads(&square, &snapped)
    {
        let view = Undistorted {
            photo: plane,
            lens: &lens,
        };
        let max_slant = 2.0 * crate::measure::REFINE_SEARCH_PX + 4.0;
        // (Until the ends' search was settled, one search left half of a
        // slant both ends shared, and these ends turned only beyond 0.5 px.)
        if let Ok(fit) = crate::locate::strip_ends::align_ends_settled(&view, &h, max_slant) {
            snapped = fit.corners;
        }
    }
    let snapped = snapped.map(|p| lens.distort(p));
    let moved = crate::geometry::largest_move(&snapped, roi);
    (moved.is_finite() && moved <= max_move && crate::geometry::check_quad(&snapped).is_ok())
        .then_some((snapped, moved))
}
