//! Sampling grids: the OTF of the grid's Wigner–Seitz cell (the area each
//! sample stands for) and the grid's Nyquist frequencies.
//!
//! `rect:px=..,py=..`: rectangular grid, cell px×py → sinc(px·u)·sinc(py·v),
//! Nyquist (1/(2px), 1/(2py)). `hex:pitch=..,rows=x|y`: hexagonal grid with
//! nearest-neighbour distance `pitch`; the cell is a regular hexagon with
//! flat-to-flat width = pitch; neighbours along y (`rows=y`) give a side-up
//! cell (eq. 33 with D = pitch), neighbours along x (`rows=x`) a corner-up
//! cell (u and v swapped). Nyquist is where the first Brillouin zone (the
//! reciprocal lattice's Wigner–Seitz cell) meets each axis: 2/(3·pitch)
//! along the neighbour direction and 1/(√3·pitch) across it.

use crate::model::aperture::{check_length, side_up_zonogon, zonogon::Zonogon};
use crate::model::params::Params;
use crate::model::special::sinc;
use crate::model::{Factor, ModelError};
use num_complex::Complex64;

/// Beyond |f|·(cell size) > 1e250 the cell OTF is returned as 0 (true value < 1e-250).
const FAR: f64 = 1e250;

/// A rectangular sampling grid with pitches `px` (x) and `py` (y), mm.
#[derive(Debug, Clone)]
pub struct RectGrid {
    px: f64,
    py: f64,
}

impl RectGrid {
    /// A grid with pitch `px_mm` along x and `py_mm` along y (both > 0).
    pub fn new(px_mm: f64, py_mm: f64) -> Result<RectGrid, ModelError> {
        Ok(RectGrid {
            px: check_length("sampling rect", "px", px_mm)?,
            py: check_length("sampling rect", "py", py_mm)?,
        })
    }
}

impl Factor for RectGrid {
    fn name(&self) -> String {
        "sampling_rect".into()
    }

    fn otf(&self, u: f64, v: f64) -> Complex64 {
        if u.abs().max(v.abs()) * self.px.min(self.py) > FAR {
            return Complex64::new(0.0, 0.0);
        }
        Complex64::new(sinc(self.px * u) * sinc(self.py * v), 0.0)
    }

    fn nyquist(&self) -> Option<(f64, f64)> {
        Some((0.5 / self.px, 0.5 / self.py))
    }
}

/// Which way the nearest neighbours of a hexagonal grid lie.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Rows {
    /// Neighbours along x (rows run along x): corner-up cell.
    X,
    /// Neighbours along y: side-up cell.
    Y,
}

/// A hexagonal sampling grid with nearest-neighbour distance `pitch` (mm).
#[derive(Debug, Clone)]
pub struct HexGrid {
    pitch: f64,
    rows: Rows,
    cell: Zonogon,
}

impl HexGrid {
    /// A hexagonal grid of nearest-neighbour distance `pitch_mm` (> 0), neighbours along `rows`.
    pub fn new(pitch_mm: f64, rows: Rows) -> Result<HexGrid, ModelError> {
        let pitch = check_length("sampling hex", "pitch", pitch_mm)?;
        Ok(HexGrid {
            pitch,
            rows,
            cell: side_up_zonogon(pitch),
        })
    }
}

impl Factor for HexGrid {
    fn name(&self) -> String {
        "sampling_hex".into()
    }

    fn otf(&self, u: f64, v: f64) -> Complex64 {
        if u.abs().max(v.abs()) * 0.25 * self.pitch > FAR {
            return Complex64::new(0.0, 0.0);
        }
        let (u, v) = match self.rows {
            Rows::Y => (u, v),
            Rows::X => (v, u),
        };
        Complex64::new(self.cell.otf(u, v), 0.0)
    }

    fn nyquist(&self) -> Option<(f64, f64)> {
        let along = 2.0 / (3.0 * self.pitch);
        let across = 1.0 / (3f64.sqrt() * self.pitch);
        Some(match self.rows {
            Rows::X => (along, across),
            Rows::Y => (across, along),
        })
    }
}

/// The sampling grid names accepted by [`parse`].
pub const GRIDS: &[&str] = &["rect", "hex"];

/// Builds a sampling grid from `rect:px=5um,py=5um` or `hex:pitch=5um,rows=x|y`.
pub fn parse(spec: &str) -> Result<Box<dyn Factor>, ModelError> {
    let (grid, rest) = spec.split_once(':').unwrap_or((spec, ""));
    let grid = grid.trim();
    let p = Params::parse(&format!("sampling {grid}"), rest)?;
    Ok(match grid {
        "rect" => {
            let px = p.positive_length("px")?;
            let py = p.positive_length("py")?;
            p.finish(&["px", "py"])?;
            Box::new(RectGrid::new(px, py)?)
        }
        "hex" => {
            let pitch = p.positive_length("pitch")?;
            let rows = match p.choice_opt("rows", &["x", "y"])?.as_deref() {
                Some("x") => Rows::X,
                Some(_) => Rows::Y,
                None => {
                    return Err(
                        p.error("missing rows=x|y (the direction of the nearest neighbours)")
                    );
                }
            };
            p.finish(&["pitch", "rows"])?;
            Box::new(HexGrid::new(pitch, rows)?)
        }
        _ => {
            return Err(ModelError::Unknown {
                what: "sampling grid".into(),
                name: grid.into(),
                allowed: GRIDS.join(", "),
            });
        }
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn parses_and_reports_nyquist() {
        let g = parse("rect:px=5um,py=4um").unwrap();
        assert_eq!(g.name(), "sampling_rect");
        assert_eq!(g.nyquist(), Some((100.0, 125.0)));
        assert_eq!(g.otf(200.0, 0.0).re, 0.0);
        let h = parse("hex:pitch=6um,rows=x").unwrap();
        let (nu, nv) = h.nyquist().unwrap();
        assert!((nu - 2.0 / 0.018).abs() < 1e-9 && (nv - 1.0 / (3f64.sqrt() * 0.006)).abs() < 1e-9);
        let hy = parse("hex:pitch=6um,rows=y").unwrap();
        assert_eq!(hy.otf(30.0, 70.0), h.otf(70.0, 30.0));
    }

    #[test]
    fn bad_specs() {
        assert!(
            parse("tri:px=1um")
                .unwrap_err()
                .to_string()
                .contains("rect, hex")
        );
        assert!(
            parse("hex:pitch=5um")
                .unwrap_err()
                .to_string()
                .contains("rows=x|y")
        );
        assert!(
            parse("hex:pitch=5um,rows=z")
                .unwrap_err()
                .to_string()
                .contains("x, y")
        );
        assert!(
            parse("rect:px=5um,py=0um")
                .unwrap_err()
                .to_string()
                .contains("py must be a positive")
        );
        assert!(
            parse("rect:px=5um,py=5um,pz=1um")
                .unwrap_err()
                .to_string()
                .contains("allowed: px, py")
        );
    }
}
