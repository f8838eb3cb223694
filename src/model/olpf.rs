//! Birefringent optical low-pass (anti-aliasing) filter (`--olpf`).
//!
//! - `2spot:d=..[,axis=u|v]`: one plate splits each ray into two spots of equal
//!   power a distance d apart along x (`axis=u`, the default) or y; with the
//!   spots at ±d/2 the OTF is cos(π·d·u) (or cos(π·d·v)): real, zero at
//!   u = 1/(2d), which is the Nyquist frequency when d equals the pixel pitch.
//! - `4spot:d=..` or `4spot:dx=..,dy=..`: two crossed plates, four spots at the
//!   corners of a dx×dy rectangle: cos(π·dx·u)·cos(π·dy·v).
//!
//! The cosines are evaluated in half-turns of the exact product d·u, with
//! exact range reduction, so they stay exact even for huge arguments.

use super::params::Params;
use super::spec::split_shape;
use super::trig::cos_pi_prod;
use super::{Factor, ModelError};
use num_complex::Complex64;

/// A 2- or 4-spot birefringent filter with split distances dx, dy (mm; 0 = no split).
#[derive(Debug, Clone)]
pub struct Olpf {
    /// Split distance along x, mm (0 for none).
    pub dx: f64,
    /// Split distance along y, mm (0 for none).
    pub dy: f64,
}

impl Factor for Olpf {
    fn name(&self) -> String {
        "olpf".into()
    }
    fn otf(&self, u: f64, v: f64) -> Complex64 {
        Complex64::new(cos_pi_prod(self.dx, u) * cos_pi_prod(self.dy, v), 0.0)
    }
}

/// Parses an `--olpf` spec (`2spot:d=..,axis=u|v`, `4spot:d=..`, `4spot:dx=..,dy=..`).
pub fn parse(spec: &str) -> Result<Box<dyn Factor>, ModelError> {
    let (shape, rest) = split_shape("olpf", spec, &["2spot", "4spot"])?;
    if shape == "2spot" {
        let p = Params::parse("olpf 2spot", rest)?;
        let d = p.positive_length("d")?;
        let axis = p.choice_opt("axis", &["u", "v"])?;
        p.finish(&["d", "axis"])?;
        Ok(Box::new(if axis.as_deref() == Some("v") {
            Olpf { dx: 0.0, dy: d }
        } else {
            Olpf { dx: d, dy: 0.0 }
        }))
    } else {
        let p = Params::parse("olpf 4spot", rest)?;
        let (dx, dy) = if p.has("d") {
            if p.has("dx") || p.has("dy") {
                return Err(p.error("give either d=.. or dx=..,dy=.., not both"));
            }
            let d = p.positive_length("d")?;
            (d, d)
        } else {
            (p.positive_length("dx")?, p.positive_length("dy")?)
        };
        p.finish(&["d", "dx", "dy"])?;
        Ok(Box::new(Olpf { dx, dy }))
    }
}
