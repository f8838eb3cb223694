//! Where the chart sits in the frame: the homography from the target's own
//! frame (mm, origin top-left, y down) to image pixels, built from the chart's
//! scale (its width in pixels, or magnification and pixel pitch; by default
//! its placed bounding box fills 80 % of the frame), a perspective
//! tilt of the chart plane about an axis through its centre (pinhole camera of
//! focal length `focal_px`), a rotation on screen and an offset from the frame
//! centre. The four corners of the target are mapped through that exact chain;
//! since every step is projective, the homography through them is exact.

use super::{Camera, SimError};
use crate::geometry::{Homography, Point, rect_corners};
use crate::target::Target;

/// The chart's placement in the image.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Placement {
    /// Chart (mm) → image (px).
    pub chart_to_image: Homography,
    /// Image (px) → chart (mm).
    pub image_to_chart: Homography,
    /// Scale at the chart centre before tilt, pixels per chart millimetre.
    pub px_per_mm: f64,
}

/// Maps a chart point (mm) through scale, tilt, rotation and offset to image pixels.
fn map_point(
    camera: &Camera,
    target: &Target,
    s: f64,
    f: f64,
    p: Point,
) -> Result<Point, SimError> {
    // Centred chart-plane coordinates in pixels at the chart's centre depth.
    let a = (p[0] - target.width_mm / 2.0) * s;
    let b = (p[1] - target.height_mm / 2.0) * s;
    // Tilt about the axis u = (cos α, sin α) by τ: the component t along
    // w = (sin α, −cos α) ⟂ u leaves the plane; depth grows by t·sin τ from the
    // focal distance f. So a positive tilt about the vertical axis (α = 90°)
    // sends the right side away; about the horizontal axis (α = 0), the top.
    let (sa, ca) = camera.tilt_axis_deg.to_radians().sin_cos();
    let (st, ct) = camera.tilt_deg.to_radians().sin_cos();
    let along = a * ca + b * sa;
    let t = a * sa - b * ca;
    let x3 = along * ca + t * ct * sa;
    let y3 = along * sa - t * ct * ca;
    let z = f + t * st;
    if z <= 1e-6 * f {
        return Err(SimError::Placement(format!(
            "tilt {}° puts part of the chart behind the camera (focal length {f:.0} px)",
            camera.tilt_deg
        )));
    }
    let (px, py) = (f * x3 / z, f * y3 / z);
    // Counter-clockwise rotation on screen (y points down).
    let (sr, cr) = camera.rotate_deg.to_radians().sin_cos();
    let xr = px * cr + py * sr;
    let yr = -px * sr + py * cr;
    Ok([
        camera.width_px as f64 / 2.0 + camera.offset_px[0] + xr,
        camera.height_px as f64 / 2.0 + camera.offset_px[1] + yr,
    ])
}

/// Scale of the chart in the image (px per chart mm) from the camera's settings.
fn scale(camera: &Camera, target: &Target, f: f64) -> Result<f64, SimError> {
    if let Some(n) = camera.chart_px {
        return Ok(n / target.width_mm);
    }
    if let Some(m) = camera.magnification {
        return Ok(m / camera.pitch_mm());
    }
    // Default: the placed target's bounding box (after tilt and rotation) fills
    // 80 % of the frame in its tighter direction; a few fixed-point steps settle
    // the perspective's dependence on scale.
    let (w, h) = (camera.width_px as f64, camera.height_px as f64);
    let mut s = 0.8 * (w / target.width_mm).min(h / target.height_mm);
    for _ in 0..8 {
        let mut lo = [f64::INFINITY; 2];
        let mut hi = [f64::NEG_INFINITY; 2];
        for p in rect_corners(0.0, 0.0, target.width_mm, target.height_mm) {
            let q = map_point(camera, target, s, f, p)?;
            for a in 0..2 {
                lo[a] = lo[a].min(q[a]);
                hi[a] = hi[a].max(q[a]);
            }
        }
        let q = ((hi[0] - lo[0]) / (0.8 * w)).max((hi[1] - lo[1]) / (0.8 * h));
        if (q - 1.0).abs() < 1e-9 {
            break;
        }
        s /= q;
    }
    Ok(s)
}

/// Places `target` in the frame of `camera`; errors if the target leaves the frame.
pub fn place(camera: &Camera, target: &Target) -> Result<Placement, SimError> {
    let f = camera
        .focal_px
        .unwrap_or_else(|| (camera.width_px as f64).hypot(camera.height_px as f64));
    let s = scale(camera, target, f)?;
    let src = rect_corners(0.0, 0.0, target.width_mm, target.height_mm);
    let mut dst = [[0.0; 2]; 4];
    for (d, p) in dst.iter_mut().zip(src.iter()) {
        *d = map_point(camera, target, s, f, *p)?;
    }
    let (w, h) = (camera.width_px as f64, camera.height_px as f64);
    if let Some(c) = dst
        .iter()
        .find(|c| !(c[0] >= 0.0 && c[0] <= w && c[1] >= 0.0 && c[1] <= h))
    {
        return Err(SimError::Placement(format!(
            "the chart does not fit in the {}×{} px frame (a target corner lands at {:.1},{:.1} px); \
             make it smaller (--chart-px / --magnification) or move it (--offset)",
            camera.width_px, camera.height_px, c[0], c[1]
        )));
    }
    let chart_to_image = Homography::from_quads(&src, &dst)
        .map_err(|e| SimError::Placement(format!("degenerate placement: {e}")))?;
    let image_to_chart = chart_to_image
        .inverse()
        .ok_or_else(|| SimError::Placement("degenerate placement".into()))?;
    Ok(Placement {
        chart_to_image,
        image_to_chart,
        px_per_mm: s,
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::simulate::demo::demo_target;
    use crate::target::SweepLaw;

    #[test]
    fn untilted_placement_is_a_similarity_with_the_given_scale() {
        let t = demo_target(SweepLaw::Log);
        let cam = Camera {
            chart_px: Some(600.0),
            rotate_deg: 30.0,
            ..Camera::default()
        };
        let p = place(&cam, &t).unwrap();
        let c = p
            .chart_to_image
            .apply([t.width_mm / 2.0, t.height_mm / 2.0]);
        assert!((c[0] - 600.0).abs() < 1e-9 && (c[1] - 400.0).abs() < 1e-9);
        // The chart's +x axis turns 30° counter-clockwise on screen: up and right.
        let j = p.chart_to_image.jacobian([10.0, 10.0]);
        let s = 600.0 / t.width_mm;
        let (sn, cs) = 30f64.to_radians().sin_cos();
        assert!((j[0][0] - s * cs).abs() < 1e-9 && (j[1][0] + s * sn).abs() < 1e-9);
    }

    #[test]
    fn tilt_makes_the_far_side_smaller_and_bad_placements_fail() {
        let t = demo_target(SweepLaw::Log);
        let cam = Camera {
            tilt_deg: 30.0,
            ..Camera::default()
        };
        let p = place(&cam, &t).unwrap();
        let tl = p.chart_to_image.apply([0.0, 0.0]);
        let bl = p.chart_to_image.apply([0.0, t.height_mm]);
        let tr = p.chart_to_image.apply([t.width_mm, 0.0]);
        let br = p.chart_to_image.apply([t.width_mm, t.height_mm]);
        // Tilt about the vertical axis: the right edge recedes (positive tilt).
        assert!((br[1] - tr[1]) < (bl[1] - tl[1]));
        let big = Camera {
            chart_px: Some(5000.0),
            ..Camera::default()
        };
        assert!(matches!(place(&big, &t), Err(SimError::Placement(_))));
        let behind = Camera {
            tilt_deg: 89.0,
            focal_px: Some(100.0),
            ..Camera::default()
        };
        assert!(place(&behind, &t).is_err());
    }
}
