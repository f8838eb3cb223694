//! A small built-in target and a Gaussian blur factor, so that tests of other
//! modules (and the shipped samples) can make shots with known truth without a
//! chart file or a model file: one sweep strip, white/grey/black patches and
//! four fiducials.

use super::{Camera, SimError};
use crate::model::Factor;
use crate::target::{Direction, Fiducial, FiducialKind, GreyPatch, Rect, Sweep, SweepLaw, Target};
use num_complex::Complex64;
use std::f64::consts::PI;

/// Width of the demo target, mm.
pub const DEMO_WIDTH_MM: f64 = 240.0;
/// Height of the demo target, mm.
pub const DEMO_HEIGHT_MM: f64 = 160.0;

/// The demo target: a 240×160 mm frame with one horizontal sweep strip
/// (0.04–2.8 cy/mm over 200 mm, mean 0.45, contrast 0.8, the given law),
/// white/grey/black patches below it, and fiducials tl (ring), tr, br, bl of
/// diameter 4 % of the short side, one diameter in from each edge.
pub fn demo_target(law: SweepLaw) -> Target {
    let (w, h) = (DEMO_WIDTH_MM, DEMO_HEIGHT_MM);
    let d = 0.04 * w.min(h);
    let fid = |id: &str, x: f64, y: f64, kind| Fiducial {
        id: id.into(),
        x_mm: x,
        y_mm: y,
        diameter_mm: d,
        kind,
    };
    let grey = |id: &str, x: f64, r: f64| GreyPatch {
        id: id.into(),
        rect: Rect {
            x_mm: x,
            y_mm: 100.0,
            width_mm: 40.0,
            height_mm: 30.0,
        },
        reflectance: r,
        density: Some(-r.log10()),
    };
    Target {
        name: format!(
            "demo-{}",
            if law == SweepLaw::Log {
                "log"
            } else {
                "linear"
            }
        ),
        width_mm: w,
        height_mm: h,
        background: 1.0,
        sweeps: vec![Sweep {
            id: "main".into(),
            rect: Rect {
                x_mm: 20.0,
                y_mm: 30.0,
                width_mm: 200.0,
                height_mm: 50.0,
            },
            direction: Direction::X,
            law,
            f_min_cy_mm: 0.04,
            f_max_cy_mm: 2.8,
            mean: 0.45,
            contrast: 0.8,
        }],
        patches: vec![],
        greys: vec![
            grey("white", 30.0, 0.9),
            grey("grey", 100.0, 0.18),
            grey("black", 170.0, 0.03),
        ],
        fiducials: vec![
            fid("tl", d, d, FiducialKind::Ring),
            fid("tr", w - d, d, FiducialKind::Disk),
            fid("br", w - d, h - d, FiducialKind::Disk),
            fid("bl", d, h - d, FiducialKind::Disk),
        ],
    }
}

/// The demo target with its sweep rescaled so that, placed by `camera`, it runs
/// from `f_min_cy_px` to `f_max_cy_px` in the image (exact without tilt; at the
/// strip's centre with tilt). Errors if the demo target cannot be placed.
pub fn demo_target_for(
    camera: &Camera,
    law: SweepLaw,
    f_min_cy_px: f64,
    f_max_cy_px: f64,
) -> Result<Target, SimError> {
    let mut t = demo_target(law);
    let p = super::placement::place(camera, &t)?;
    let sw = &t.sweeps[0];
    let c = [
        sw.rect.x_mm + sw.rect.width_mm / 2.0,
        sw.rect.y_mm + sw.rect.height_mm / 2.0,
    ];
    let j = p.chart_to_image.jacobian(c);
    let px_per_mm = j[0][0].hypot(j[1][0]); // image length of a chart mm along x
    if !(f_min_cy_px > 0.0 && f_max_cy_px > f_min_cy_px) {
        return Err(SimError::Parameter(format!(
            "sweep range {f_min_cy_px}–{f_max_cy_px} cy/px: need 0 < f_min < f_max"
        )));
    }
    t.sweeps[0].f_min_cy_mm = f_min_cy_px * px_per_mm;
    t.sweeps[0].f_max_cy_mm = f_max_cy_px * px_per_mm;
    Ok(t)
}

/// A long thin card (260×40 mm, white): one log sweep of contrast 0.8 and
/// mean 0.45, 240×20 mm, from `f_min_cy_mm` to `f_max_cy_mm` along its
/// length; no fiducials (measured from its strip's corners).
pub fn strip_card(f_min_cy_mm: f64, f_max_cy_mm: f64) -> Target {
    Target {
        name: "strip".into(),
        width_mm: 260.0,
        height_mm: 40.0,
        background: 1.0,
        sweeps: vec![Sweep {
            id: "main".into(),
            rect: Rect {
                x_mm: 10.0,
                y_mm: 10.0,
                width_mm: 240.0,
                height_mm: 20.0,
            },
            direction: Direction::X,
            law: SweepLaw::Log,
            f_min_cy_mm,
            f_max_cy_mm,
            mean: 0.45,
            contrast: 0.8,
        }],
        patches: vec![],
        greys: vec![],
        fiducials: vec![],
    }
}

/// An isotropic Gaussian point spread function of standard deviation `sigma_mm`
/// on the sensor: OTF = exp(−2π²σ²(u² + v²)), real and positive.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct GaussianPsf {
    /// Standard deviation of the PSF, mm.
    pub sigma_mm: f64,
}

impl Factor for GaussianPsf {
    fn name(&self) -> String {
        "gauss".into()
    }
    fn otf(&self, u: f64, v: f64) -> Complex64 {
        Complex64::new(
            (-2.0 * PI * PI * self.sigma_mm * self.sigma_mm * (u * u + v * v)).exp(),
            0.0,
        )
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn demo_target_for_reaches_the_asked_image_frequencies() {
        let cam = Camera {
            rotate_deg: 25.0,
            ..Camera::noiseless(600, 400)
        };
        let t = demo_target_for(&cam, SweepLaw::Log, 0.01, 0.7).unwrap();
        let p = crate::simulate::placement::place(&cam, &t).unwrap();
        let sw = &t.sweeps[0];
        let a = p.chart_to_image.apply([sw.rect.x_mm, 50.0]);
        let b = p.chart_to_image.apply([sw.rect.x_mm + 1.0, 50.0]);
        let px_per_mm = (b[0] - a[0]).hypot(b[1] - a[1]);
        assert!((sw.f_max_cy_mm / px_per_mm - 0.7).abs() < 1e-9);
        assert!((sw.f_min_cy_mm / px_per_mm - 0.01).abs() < 1e-9);
    }

    #[test]
    fn demo_target_is_valid_and_has_the_promised_layout() {
        for law in [SweepLaw::Log, SweepLaw::Linear] {
            let t = demo_target(law);
            t.validate().unwrap();
            let d = 0.04 * 160.0;
            assert_eq!(t.reflectance(d + 0.4 * d, d), 0.0); // ring of tl
            assert_eq!(t.reflectance(d, d), 1.0); // its white centre
            assert_eq!(t.reflectance(DEMO_WIDTH_MM - d, d), 0.0); // tr disk
            assert_eq!(t.reflectance(50.0, 115.0), 0.9);
        }
    }
}
