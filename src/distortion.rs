//! Radial lens distortion in the PTLens form that Lensfun publishes per lens,
//! shared by the simulator (which distorts) and the measurement (which
//! undistorts each pixel centre before the strip's homography).
//!
//! The model, as Lensfun defines `LF_DIST_MODEL_PTLENS` (lensfun.h,
//! `lfDistortionModel`; <https://lensfun.github.io/manual/latest/group__Lens.html>):
//!
//! r_d = r_u · (a·r_u³ + b·r_u² + c·r_u + 1 − a − b − c)
//!
//! maps the **undistorted** radius r_u (where a perfect rectilinear lens would
//! put the point) to the **distorted** radius r_d (where it lands in the
//! photo): Lensfun's manual, "How the corrections work → How it is really
//! done", states that its distortion formulae map the undistorted coordinate
//! to the distorted one. Radii are measured from the image centre and
//! normalised so that half the image's smaller side is 1 (Lensfun's manual,
//! `<center>`: "the smaller dimension … has the value 2"). So r_d = r_u on the
//! circle touching the frame's shorter edges; b > 0 is pincushion (points
//! move outwards beyond that circle), b < 0 barrel.
//!
//! Lensfun's coefficients hold for the frame the lens was calibrated on (its
//! `cropfactor` and `aspect-ratio`); for a camera of another format they must be
//! rescaled (as Lensfun itself does) before they are given here.

use serde::{Deserialize, Serialize};
use std::fmt;
use std::str::FromStr;

/// The PTLens coefficients a, b, c (dimensionless, radius normalised as above).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Ptlens {
    /// Coefficient of r_u⁴ in r_d.
    pub a: f64,
    /// Coefficient of r_u³ in r_d (the classic cubic term).
    pub b: f64,
    /// Coefficient of r_u² in r_d.
    pub c: f64,
}

/// Largest |distortion| at the frame corner a lens can be given with, percent.
pub const MAX_CORNER_PERCENT: f64 = 20.0;

impl Ptlens {
    /// r_d / r_u at normalised undistorted radius `r`.
    #[inline]
    pub fn ratio(&self, r: f64) -> f64 {
        ((self.a * r + self.b) * r + self.c) * r + 1.0 - self.a - self.b - self.c
    }

    /// d r_d / d r_u at normalised undistorted radius `r`.
    #[inline]
    pub fn slope(&self, r: f64) -> f64 {
        ((4.0 * self.a * r + 3.0 * self.b) * r + 2.0 * self.c) * r + 1.0 - self.a - self.b - self.c
    }

    /// Whether all three coefficients are zero.
    pub fn is_zero(&self) -> bool {
        self.a == 0.0 && self.b == 0.0 && self.c == 0.0
    }

    /// Undistorted normalised radius of distorted radius `rd` (Newton from r_u = r_d).
    #[inline]
    pub fn undistort_radius(&self, rd: f64) -> f64 {
        let mut r = rd;
        for _ in 0..12 {
            let f = r * self.ratio(r) - rd;
            let d = f / self.slope(r);
            r -= d;
            if d.abs() <= 1e-14 * (1.0 + r) {
                break;
            }
        }
        r
    }
}

impl fmt::Display for Ptlens {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "ptlens:a={},b={},c={}", self.a, self.b, self.c)
    }
}

impl FromStr for Ptlens {
    type Err = String;
    /// Parses `ptlens:a=A,b=B,c=C` (any subset of a, b, c; the others are 0).
    fn from_str(s: &str) -> Result<Self, String> {
        let usage = || {
            format!("distortion '{s}' is not of the form ptlens:a=A,b=B,c=C (e.g. ptlens:b=-0.01)")
        };
        let rest = s.trim().strip_prefix("ptlens:").ok_or_else(usage)?;
        let mut p = Ptlens {
            a: 0.0,
            b: 0.0,
            c: 0.0,
        };
        for part in rest.split(',').filter(|t| !t.trim().is_empty()) {
            let (k, v) = part.split_once('=').ok_or_else(usage)?;
            let v: f64 = v.trim().parse().map_err(|_| usage())?;
            if !v.is_finite() {
                return Err(usage());
            }
            match k.trim() {
                "a" => p.a = v,
                "b" => p.b = v,
                "c" => p.c = v,
                _ => return Err(usage()),
            }
        }
        Ok(p)
    }
}

/// A PTLens model placed on an image: its centre and normalising radius in pixels.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Lens {
    /// The coefficients.
    pub model: Ptlens,
    /// Distortion centre x, pixels (the image centre).
    pub cx: f64,
    /// Distortion centre y, pixels.
    pub cy: f64,
    /// Pixels per unit normalised radius: half the image's smaller side.
    pub norm_px: f64,
}

impl Lens {
    /// The model on an image of `width`×`height` pixels (centre at the image centre).
    pub fn new(model: Ptlens, width: usize, height: usize) -> Lens {
        Lens {
            model,
            cx: width as f64 / 2.0,
            cy: height as f64 / 2.0,
            norm_px: width.min(height) as f64 / 2.0,
        }
    }

    /// Normalised radius of the frame corner.
    pub fn corner_radius(&self) -> f64 {
        self.cx.hypot(self.cy) / self.norm_px
    }

    /// Distortion at the frame corner, percent: 100·(r_d/r_u − 1) at the corner's undistorted radius.
    pub fn corner_percent(&self) -> f64 {
        100.0 * (self.model.ratio(self.corner_radius()) - 1.0)
    }

    /// Checks that the model is one a lens can have on this frame: |corner
    /// distortion| ≤ [`MAX_CORNER_PERCENT`] and r_d rising with r_u out to
    /// beyond the corner (so every photo point has one undistorted point).
    pub fn check(&self) -> Result<(), String> {
        let m = &self.model;
        if ![m.a, m.b, m.c].iter().all(|v| v.is_finite()) {
            return Err(format!("distortion {m}: coefficients must be finite"));
        }
        let rc = self.corner_radius();
        let pct = self.corner_percent();
        if pct.abs() > MAX_CORNER_PERCENT {
            return Err(format!(
                "distortion {m} gives {pct:+.1} % at the frame corner; lenses lie within ±{MAX_CORNER_PERCENT} % (e.g. |b| ≤ {:.3} with a = c = 0 on this {}×{} frame)",
                MAX_CORNER_PERCENT / 100.0 / (rc * rc - 1.0).max(1e-9),
                (2.0 * self.cx).round(),
                (2.0 * self.cy).round()
            ));
        }
        let n = 200;
        for i in 0..=n {
            let r = 1.1 * rc * i as f64 / n as f64;
            if m.slope(r) <= 0.05 {
                return Err(format!(
                    "distortion {m} folds the image over (r_d stops rising at r_u = {r:.2} of half the short side); no lens does that inside the frame"
                ));
            }
        }
        Ok(())
    }

    /// Photo (distorted) position of undistorted pixel position `p`.
    #[inline]
    pub fn distort(&self, p: [f64; 2]) -> [f64; 2] {
        let (dx, dy) = (p[0] - self.cx, p[1] - self.cy);
        let r = dx.hypot(dy) / self.norm_px;
        let k = self.model.ratio(r);
        [self.cx + dx * k, self.cy + dy * k]
    }

    /// Undistorted position of photo pixel position `p` (the inverse of [`Lens::distort`]).
    #[inline]
    pub fn undistort(&self, p: [f64; 2]) -> [f64; 2] {
        let (dx, dy) = (p[0] - self.cx, p[1] - self.cy);
        let rd = dx.hypot(dy) / self.norm_px;
        if rd < 1e-300 {
            return p;
        }
        let k = self.model.undistort_radius(rd) / rd;
        [self.cx + dx * k, self.cy + dy * k]
    }

    /// Jacobian d(photo)/d(undistorted) at undistorted position `p`:
    /// [[dxd/dxu, dxd/dyu], [dyd/dxu, dyd/dyu]].
    pub fn jacobian(&self, p: [f64; 2]) -> [[f64; 2]; 2] {
        let (dx, dy) = (p[0] - self.cx, p[1] - self.cy);
        let r = dx.hypot(dy) / self.norm_px;
        let k = self.model.ratio(r);
        if r < 1e-12 {
            return [[k, 0.0], [0.0, k]];
        }
        // x_d = x·k(r): ∂x_d/∂x_u = k + x·k'(r)·∂r/∂x, with k' = (slope − k)/r.
        let kp = (self.model.slope(r) - k) / r;
        let (ux, uy) = (dx / self.norm_px / r, dy / self.norm_px / r);
        let g = kp * r; // x·k'·∂r/∂x = (x/N)·k'·(x/N)/r·… = ux·ux·r·k'
        [
            [k + g * ux * ux, g * ux * uy],
            [g * ux * uy, k + g * uy * uy],
        ]
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn lens(a: f64, b: f64, c: f64) -> Lens {
        Lens::new(Ptlens { a, b, c }, 1200, 800)
    }

    #[test]
    fn radius_one_is_half_the_short_side_and_fixed() {
        let l = lens(0.01, -0.03, 0.02);
        // A point 400 px (half of 800) from the centre does not move.
        let p = l.distort([600.0 + 400.0, 400.0]);
        assert!((p[0] - 1000.0).abs() < 1e-12 && (p[1] - 400.0).abs() < 1e-12);
        // Lensfun's formula by hand at r_u = 1.5 along the diagonal.
        let r: f64 = 1.5;
        let rd = r * (0.01 * r.powi(3) - 0.03 * r * r + 0.02 * r + 1.0 - 0.01 + 0.03 - 0.02);
        let q = l.distort([
            600.0 + 400.0 * r / 2f64.sqrt(),
            400.0 + 400.0 * r / 2f64.sqrt(),
        ]);
        assert!(((q[0] - 600.0).hypot(q[1] - 400.0) / 400.0 - rd).abs() < 1e-12);
    }

    #[test]
    fn undistort_inverts_distort_and_jacobian_matches_differences() {
        for (a, b, c) in [(0.0, 0.02, 0.0), (0.0, -0.015, 0.0), (0.01, -0.03, 0.015)] {
            let l = lens(a, b, c);
            for p in [[600.0, 400.0], [0.5, 0.5], [1199.5, 10.0], [700.0, 420.0]] {
                let q = l.undistort(l.distort(p));
                assert!(
                    (q[0] - p[0]).abs() < 1e-9 && (q[1] - p[1]).abs() < 1e-9,
                    "{p:?} {q:?}"
                );
                let j = l.jacobian(p);
                let e = 1e-4;
                for (k, col) in [[e, 0.0], [0.0, e]].iter().enumerate() {
                    let fp = l.distort([p[0] + col[0], p[1] + col[1]]);
                    let fm = l.distort([p[0] - col[0], p[1] - col[1]]);
                    for i in 0..2 {
                        let num = (fp[i] - fm[i]) / (2.0 * e);
                        assert!(
                            (num - j[i][k]).abs() < 1e-7,
                            "{p:?} {i}{k}: {num} vs {}",
                            j[i][k]
                        );
                    }
                }
            }
        }
        // At the centre: a uniform scale 1 − a − b − c.
        let l = lens(0.01, 0.02, 0.03);
        let j = l.jacobian([600.0, 400.0]);
        assert!((j[0][0] - 0.94).abs() < 1e-12 && j[0][1] == 0.0);
    }

    #[test]
    fn parses_checks_and_rejects() {
        let p: Ptlens = "ptlens:a=0.01,b=-0.02,c=0".parse().unwrap();
        assert_eq!(
            p,
            Ptlens {
                a: 0.01,
                b: -0.02,
                c: 0.0
            }
        );
        assert_eq!(p.to_string().parse::<Ptlens>().unwrap(), p);
        assert_eq!("ptlens:b=0.01".parse::<Ptlens>().unwrap().b, 0.01);
        for bad in ["poly3:k1=0.1", "ptlens:d=1", "ptlens:b=x", "ptlens:b=inf"] {
            assert!(bad.parse::<Ptlens>().is_err(), "{bad}");
        }
        assert!(lens(0.0, 0.0133, 0.0).check().is_ok());
        assert!(lens(0.0, -0.0133, 0.0).check().is_ok());
        // 1200×800: corner radius² = 3.25, so b = 0.1 gives +22.5 %.
        let e = lens(0.0, 0.1, 0.0).check().unwrap_err();
        assert!(e.contains("±20 %"), "{e}");
        assert!(lens(0.0, -0.1, 0.0).check().is_err());
    }
}
