//! Target descriptions: everything `measure`, `simulate` and `locate` need to
//! know about a printed chart, in the chart's own frame (millimetres, origin at
//! the target's top-left corner, x right, y down). Written by `chart` beside
//! every chart as `NAME.toml`; also read from sineMTF `tgt.txt` files.
//!
//! The reflectance model is the contract between the chart renderer, the
//! simulator and the measurement: [`Target::reflectance`] gives the linear
//! reflectance (0 = black, 1 = paper white) at any chart point.

use serde::{Deserialize, Serialize};
use std::f64::consts::PI;
use std::path::Path;
use thiserror::Error;

pub mod sinemtf;

/// Why a target description could not be used.
#[derive(Debug, Error)]
pub enum TargetError {
    /// The file could not be read.
    #[error("{path}: cannot read target description: {source}")]
    Io {
        /// The file.
        path: String,
        /// The cause.
        source: std::io::Error,
    },
    /// The file is not a valid description.
    #[error("{path}: not a valid target description: {cause}")]
    Parse {
        /// The file.
        path: String,
        /// The cause.
        cause: String,
    },
    /// The description is self-inconsistent (a region outside the target, f_min ≥ f_max, …).
    #[error("invalid target description: {0}")]
    Invalid(String),
}

/// An axis-aligned rectangle on the chart (mm, top-left corner and size).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct Rect {
    /// Left edge (mm from the target's left edge).
    pub x_mm: f64,
    /// Top edge (mm from the target's top edge).
    pub y_mm: f64,
    /// Width (mm).
    pub width_mm: f64,
    /// Height (mm).
    pub height_mm: f64,
}

impl Rect {
    /// Chebyshev distance (mm) from a chart point to the rectangle (0 inside).
    pub fn chebyshev_distance(&self, x: f64, y: f64) -> f64 {
        let dx = (self.x_mm - x).max(x - (self.x_mm + self.width_mm));
        let dy = (self.y_mm - y).max(y - (self.y_mm + self.height_mm));
        dx.max(dy).max(0.0)
    }

    /// Whether the chart point (mm) lies inside.
    pub fn contains(&self, x: f64, y: f64) -> bool {
        x >= self.x_mm
            && x < self.x_mm + self.width_mm
            && y >= self.y_mm
            && y < self.y_mm + self.height_mm
    }
    /// The four corners in order round the rectangle (mm).
    pub fn corners(&self) -> [[f64; 2]; 4] {
        crate::geometry::rect_corners(
            self.x_mm,
            self.y_mm,
            self.x_mm + self.width_mm,
            self.y_mm + self.height_mm,
        )
    }
}

/// The chart axis along which a sine varies (and along which a sweep's frequency rises).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize, Default)]
#[serde(rename_all = "lowercase")]
pub enum Direction {
    /// Along +x (left to right on the chart).
    #[default]
    X,
    /// Along +y (top to bottom on the chart).
    Y,
}

/// How a sweep's frequency rises with distance.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum SweepLaw {
    /// f(s) = f_min + (f_max − f_min)·s/L.
    Linear,
    /// f(s) = f_min·(f_max/f_min)^(s/L).
    Log,
}

/// A sine sweep strip: reflectance = mean·(1 + contrast·cos 2π·phase(s)).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Sweep {
    /// Name of the strip ("main", "c0.2", …).
    pub id: String,
    /// Where the strip lies (mm).
    #[serde(flatten)]
    pub rect: Rect,
    /// Axis along which the frequency rises.
    #[serde(default)]
    pub direction: Direction,
    /// Frequency law.
    pub law: SweepLaw,
    /// Frequency at the strip's start (cycles/mm on the chart).
    pub f_min_cy_mm: f64,
    /// Frequency at the strip's end (cycles/mm on the chart).
    pub f_max_cy_mm: f64,
    /// Mean linear reflectance (0–1).
    pub mean: f64,
    /// Printed modulation (0–1].
    pub contrast: f64,
}

/// A constant-frequency sine patch: reflectance = mean·(1 + contrast·cos 2π·f·s).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct SinePatch {
    /// Name of the patch.
    pub id: String,
    /// Where the patch lies (mm).
    #[serde(flatten)]
    pub rect: Rect,
    /// Axis along which the sine varies.
    #[serde(default)]
    pub direction: Direction,
    /// Frequency (cycles/mm on the chart).
    pub freq_cy_mm: f64,
    /// Mean linear reflectance (0–1).
    pub mean: f64,
    /// Printed (or manufacturer-measured) modulation (0–1].
    pub contrast: f64,
}

/// A uniform reference patch of known reflectance (white, black, grey steps).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct GreyPatch {
    /// Name of the patch.
    pub id: String,
    /// Where the patch lies (mm).
    #[serde(flatten)]
    pub rect: Rect,
    /// Linear reflectance (0–1), relative to paper white.
    pub reflectance: f64,
    /// Optical density, when the description gave it (reflectance = 10^−density).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub density: Option<f64>,
}

/// The shape of a fiducial mark.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize, Default)]
#[serde(rename_all = "lowercase")]
pub enum FiducialKind {
    /// A solid black disk of the given diameter on a white square of twice the diameter.
    #[default]
    Disk,
    /// Like `Disk`, with a white centre disk of half the diameter (marks orientation).
    Ring,
}

/// A fiducial mark used to find the chart automatically.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Fiducial {
    /// Name ("tl", "tr", "br", "bl", …).
    pub id: String,
    /// Centre x (mm).
    pub x_mm: f64,
    /// Centre y (mm).
    pub y_mm: f64,
    /// Outer diameter of the black disk (mm).
    pub diameter_mm: f64,
    /// Shape.
    #[serde(default)]
    pub kind: FiducialKind,
}

/// A complete target description.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Target {
    /// Name of the target.
    pub name: String,
    /// Width of the target frame (mm).
    pub width_mm: f64,
    /// Height of the target frame (mm).
    pub height_mm: f64,
    /// Linear reflectance of the background (1 = paper white).
    #[serde(default = "one")]
    pub background: f64,
    /// Sine sweep strips.
    #[serde(default)]
    pub sweeps: Vec<Sweep>,
    /// Constant-frequency sine patches.
    #[serde(default)]
    pub patches: Vec<SinePatch>,
    /// Uniform reference patches.
    #[serde(default)]
    pub greys: Vec<GreyPatch>,
    /// Fiducial marks.
    #[serde(default)]
    pub fiducials: Vec<Fiducial>,
}

fn one() -> f64 {
    1.0
}

impl Sweep {
    /// Length of the strip along its direction (mm).
    pub fn length_mm(&self) -> f64 {
        match self.direction {
            Direction::X => self.rect.width_mm,
            Direction::Y => self.rect.height_mm,
        }
    }

    /// Distance along the sweep (mm from its low-frequency edge) of a chart point.
    pub fn s_of(&self, x: f64, y: f64) -> f64 {
        match self.direction {
            Direction::X => x - self.rect.x_mm,
            Direction::Y => y - self.rect.y_mm,
        }
    }

    /// Chart frequency (cycles/mm) at distance `s` mm along the sweep.
    pub fn freq_at(&self, s: f64) -> f64 {
        let t = s / self.length_mm();
        match self.law {
            SweepLaw::Linear => self.f_min_cy_mm + (self.f_max_cy_mm - self.f_min_cy_mm) * t,
            SweepLaw::Log => self.f_min_cy_mm * (self.f_max_cy_mm / self.f_min_cy_mm).powf(t),
        }
    }

    /// Distance `s` (mm) at which the sweep reaches frequency `f` (cycles/mm).
    pub fn s_at_freq(&self, f: f64) -> f64 {
        let l = self.length_mm();
        match self.law {
            SweepLaw::Linear => l * (f - self.f_min_cy_mm) / (self.f_max_cy_mm - self.f_min_cy_mm),
            SweepLaw::Log => {
                l * (f / self.f_min_cy_mm).ln() / (self.f_max_cy_mm / self.f_min_cy_mm).ln()
            }
        }
    }

    /// Phase in cycles at distance `s` mm: the integral of `freq_at` from 0 to `s`.
    pub fn phase_cycles(&self, s: f64) -> f64 {
        let l = self.length_mm();
        let (f0, f1) = (self.f_min_cy_mm, self.f_max_cy_mm);
        match self.law {
            SweepLaw::Linear => f0 * s + (f1 - f0) * s * s / (2.0 * l),
            SweepLaw::Log => {
                let k = (f1 / f0).ln() / l;
                if k.abs() < 1e-12 {
                    f0 * s
                } else {
                    // f0·(e^{ks} − 1)/k, with expm1 for accuracy near s = 0.
                    f0 * (k * s).exp_m1() / k
                }
            }
        }
    }

    /// Linear reflectance at distance `s` mm along the sweep.
    pub fn reflectance_at(&self, s: f64) -> f64 {
        self.mean * (1.0 + self.contrast * (2.0 * PI * self.phase_cycles(s)).cos())
    }
}

impl SinePatch {
    /// Linear reflectance at a chart point inside the patch (mm).
    pub fn reflectance_at(&self, x: f64, y: f64) -> f64 {
        let s = match self.direction {
            Direction::X => x - self.rect.x_mm,
            Direction::Y => y - self.rect.y_mm,
        };
        self.mean * (1.0 + self.contrast * (2.0 * PI * self.freq_cy_mm * s).cos())
    }
}

impl Fiducial {
    /// Linear reflectance of the mark at a chart point, or `None` outside its white square.
    pub fn reflectance_at(&self, x: f64, y: f64) -> Option<f64> {
        let (dx, dy) = (x - self.x_mm, y - self.y_mm);
        let d = self.diameter_mm;
        if dx.abs() >= d || dy.abs() >= d {
            return None;
        }
        let r = dx.hypot(dy);
        let black = match self.kind {
            FiducialKind::Disk => r < d / 2.0,
            FiducialKind::Ring => r < d / 2.0 && r >= d / 4.0,
        };
        Some(if black { 0.0 } else { 1.0 })
    }
}

impl Target {
    /// Reads a description: TOML written by `chart`, or a sineMTF `tgt.txt` (by content).
    pub fn load(path: &Path) -> Result<Target, TargetError> {
        let text = std::fs::read_to_string(path).map_err(|source| TargetError::Io {
            path: path.display().to_string(),
            source,
        })?;
        let parse_err = |cause: String| TargetError::Parse {
            path: path.display().to_string(),
            cause,
        };
        let target = if path.extension().is_some_and(|e| e == "toml") {
            toml::from_str::<Target>(&text).map_err(|e| parse_err(e.to_string()))?
        } else {
            sinemtf::parse(&text).map_err(parse_err)?
        };
        target.validate()?;
        Ok(target)
    }

    /// The description as TOML text.
    pub fn to_toml(&self) -> String {
        toml::to_string_pretty(self).expect("a target always serialises")
    }

    /// Checks sizes, ranges and that every region lies inside the target.
    pub fn validate(&self) -> Result<(), TargetError> {
        let bad = |m: String| Err(TargetError::Invalid(m));
        if !(self.width_mm > 0.0
            && self.height_mm > 0.0
            && self.width_mm.is_finite()
            && self.height_mm.is_finite())
        {
            return bad(format!(
                "target size {}×{} mm must be positive",
                self.width_mm, self.height_mm
            ));
        }
        let inside = |r: &Rect| {
            r.width_mm > 0.0
                && r.height_mm > 0.0
                && r.x_mm >= -1e-9
                && r.y_mm >= -1e-9
                && r.x_mm + r.width_mm <= self.width_mm + 1e-6
                && r.y_mm + r.height_mm <= self.height_mm + 1e-6
        };
        let mod_ok = |c: f64| c > 0.0 && c <= 1.0;
        for s in &self.sweeps {
            if !inside(&s.rect) {
                return bad(format!(
                    "sweep '{}' lies outside the target or has no area",
                    s.id
                ));
            }
            if !(s.f_min_cy_mm > 0.0 && s.f_max_cy_mm > s.f_min_cy_mm && s.f_max_cy_mm.is_finite())
            {
                return bad(format!("sweep '{}': need 0 < f_min < f_max", s.id));
            }
            if !mod_ok(s.contrast) {
                return bad(format!("sweep '{}': contrast must be in (0, 1]", s.id));
            }
        }
        for p in &self.patches {
            if !inside(&p.rect) {
                return bad(format!(
                    "patch '{}' lies outside the target or has no area",
                    p.id
                ));
            }
            if !(p.freq_cy_mm > 0.0 && p.freq_cy_mm.is_finite() && mod_ok(p.contrast)) {
                return bad(format!(
                    "patch '{}': need frequency > 0 and contrast in (0, 1]",
                    p.id
                ));
            }
        }
        for g in &self.greys {
            if !inside(&g.rect) {
                return bad(format!(
                    "grey patch '{}' lies outside the target or has no area",
                    g.id
                ));
            }
        }
        Ok(())
    }

    /// Linear reflectance at a chart point (mm) of a print whose sines have
    /// lost modulation by `print(f)` at their chart frequency f (cycles/mm):
    /// a sweep's local term is scaled by `print(freq_at(s))` (exact for a
    /// blur much shorter than the distance over which the frequency changes),
    /// a patch's by `print(freq_cy_mm)`; edges stay sharp. `print = |_| 1`
    /// gives [`Target::reflectance`].
    pub fn reflectance_printed(&self, x: f64, y: f64, print: impl Fn(f64) -> f64) -> f64 {
        if let Some(v) = self.fiducials.iter().find_map(|f| f.reflectance_at(x, y)) {
            return v;
        }
        if let Some(sw) = self.sweeps.iter().find(|s| s.rect.contains(x, y)) {
            let s = sw.s_of(x, y);
            let c = sw.contrast * print(sw.freq_at(s));
            return sw.mean * (1.0 + c * (2.0 * PI * sw.phase_cycles(s)).cos());
        }
        if let Some(p) = self.patches.iter().find(|p| p.rect.contains(x, y)) {
            let m = print(p.freq_cy_mm);
            return p.mean + m * (p.reflectance_at(x, y) - p.mean);
        }
        self.reflectance(x, y)
    }

    /// How far (mm, Chebyshev distance) a chart point lies from every printed
    /// region (fiducial squares, sweeps, sine and grey patches); 0 inside
    /// one. Within a smaller distance in x and y the reflectance is the
    /// background's.
    pub fn background_clearance(&self, x: f64, y: f64) -> f64 {
        let fid = self.fiducials.iter().map(|f| {
            let d = f.diameter_mm;
            ((x - f.x_mm).abs() - d)
                .max((y - f.y_mm).abs() - d)
                .max(0.0)
        });
        let rects = (self.sweeps.iter().map(|s| &s.rect))
            .chain(self.patches.iter().map(|p| &p.rect))
            .chain(self.greys.iter().map(|g| &g.rect))
            .map(|r| r.chebyshev_distance(x, y));
        fid.chain(rects).fold(f64::INFINITY, f64::min)
    }

    /// Linear reflectance (0 = black, 1 = paper white) at a chart point (mm).
    ///
    /// Later regions paint over earlier ones in this order: background, grey
    /// patches, sine patches, sweeps, fiducials. Outside the target: background.
    pub fn reflectance(&self, x: f64, y: f64) -> f64 {
        if let Some(v) = self.fiducials.iter().find_map(|f| f.reflectance_at(x, y)) {
            return v;
        }
        if let Some(s) = self.sweeps.iter().find(|s| s.rect.contains(x, y)) {
            return s.reflectance_at(s.s_of(x, y));
        }
        if let Some(p) = self.patches.iter().find(|p| p.rect.contains(x, y)) {
            return p.reflectance_at(x, y);
        }
        if let Some(g) = self.greys.iter().find(|g| g.rect.contains(x, y)) {
            return g.reflectance;
        }
        self.background
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn sweep(law: SweepLaw) -> Sweep {
        Sweep {
            id: "main".into(),
            rect: Rect {
                x_mm: 10.0,
                y_mm: 20.0,
                width_mm: 200.0,
                height_mm: 30.0,
            },
            direction: Direction::X,
            law,
            f_min_cy_mm: 0.5,
            f_max_cy_mm: 8.0,
            mean: 0.5,
            contrast: 0.8,
        }
    }

    #[test]
    fn phase_is_integral_of_frequency() {
        for law in [SweepLaw::Linear, SweepLaw::Log] {
            let sw = sweep(law);
            // Simpson's rule on freq_at, independent of the closed form.
            let n = 20000;
            let s1 = 137.0;
            let h = s1 / n as f64;
            let mut acc = sw.freq_at(0.0) + sw.freq_at(s1);
            for i in 1..n {
                acc += sw.freq_at(i as f64 * h) * if i % 2 == 1 { 4.0 } else { 2.0 };
            }
            let simpson = acc * h / 3.0;
            assert!((simpson - sw.phase_cycles(s1)).abs() < 1e-9, "{law:?}");
            assert!((sw.freq_at(200.0) - 8.0).abs() < 1e-12);
            assert!((sw.s_at_freq(sw.freq_at(77.0)) - 77.0).abs() < 1e-9);
        }
    }

    #[test]
    fn reflectance_layers() {
        let t = Target {
            name: "t".into(),
            width_mm: 297.0,
            height_mm: 210.0,
            background: 1.0,
            sweeps: vec![sweep(SweepLaw::Log)],
            patches: vec![],
            greys: vec![GreyPatch {
                id: "black".into(),
                rect: Rect {
                    x_mm: 10.0,
                    y_mm: 100.0,
                    width_mm: 20.0,
                    height_mm: 20.0,
                },
                reflectance: 0.1,
                density: None,
            }],
            fiducials: vec![Fiducial {
                id: "tl".into(),
                x_mm: 5.0,
                y_mm: 5.0,
                diameter_mm: 4.0,
                kind: FiducialKind::Ring,
            }],
        };
        t.validate().unwrap();
        assert_eq!(t.reflectance(5.0, 5.0), 1.0); // ring centre is white
        assert_eq!(t.reflectance(6.5, 5.0), 0.0);
        assert_eq!(t.reflectance(15.0, 110.0), 0.1);
        assert!((t.reflectance(10.0, 30.0) - 0.9).abs() < 1e-12);
        assert_eq!(t.reflectance(290.0, 200.0), 1.0);
        let back: Target = toml::from_str(&t.to_toml()).unwrap();
        assert_eq!(back, t);
    }
}
