//! TEMPORARY stub of helper model-ap's sampling grids (replaced on merge):
//! only `rect:px=..,py=..`.

use super::params::Params;
use super::special::sinc;
use super::{Factor, ModelError};
use num_complex::Complex64;

/// Rectangular sampling grid px×py (mm).
#[derive(Debug)]
struct Rect {
    px: f64,
    py: f64,
}

impl Factor for Rect {
    fn name(&self) -> String {
        "sampling".into()
    }
    fn otf(&self, u: f64, v: f64) -> Complex64 {
        Complex64::new(sinc(self.px * u) * sinc(self.py * v), 0.0)
    }
    fn nyquist(&self) -> Option<(f64, f64)> {
        Some((0.5 / self.px, 0.5 / self.py))
    }
}

/// Parses a sampling spec (`rect:px=5um,py=5um`).
pub fn parse(spec: &str) -> Result<Box<dyn Factor>, ModelError> {
    let (shape, rest) = spec.split_once(':').unwrap_or((spec, ""));
    if shape != "rect" {
        return Err(ModelError::Unknown {
            what: "sampling grid".into(),
            name: shape.into(),
            allowed: "rect".into(),
        });
    }
    let p = Params::parse("sampling rect", rest)?;
    let px = p.positive_length("px")?;
    let py = p.positive_length("py")?;
    p.finish(&["px", "py"])?;
    Ok(Box::new(Rect { px, py }))
}
