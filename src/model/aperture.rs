//! TEMPORARY stub of helper model-ap's detector apertures (replaced on merge):
//! only `rect:A=..,B=..`.

use super::params::Params;
use super::special::sinc;
use super::{Factor, ModelError};
use num_complex::Complex64;

/// Rectangular aperture A×B (mm).
#[derive(Debug)]
struct Rect {
    a: f64,
    b: f64,
}

impl Factor for Rect {
    fn name(&self) -> String {
        "aperture".into()
    }
    fn otf(&self, u: f64, v: f64) -> Complex64 {
        Complex64::new(sinc(self.a * u) * sinc(self.b * v), 0.0)
    }
}

/// Parses an aperture spec (`rect:A=5um,B=5um`).
pub fn parse(spec: &str) -> Result<Box<dyn Factor>, ModelError> {
    let (shape, rest) = spec.split_once(':').unwrap_or((spec, ""));
    if shape != "rect" {
        return Err(ModelError::Unknown {
            what: "aperture".into(),
            name: shape.into(),
            allowed: "rect".into(),
        });
    }
    let p = Params::parse("aperture rect", rest)?;
    let a = p.positive_length("A")?;
    let b = p.positive_length("B")?;
    p.finish(&["A", "B"])?;
    Ok(Box::new(Rect { a, b }))
}
