//! Detector apertures: the pixel's light-sensitive area p(x, y) and its OTF
//! (1/Area)∬p·exp(−j2π(ux + vy)) dx dy, one file per shape.
//!
//! Axes: x right, y up; lengths in mm, frequencies in cycles/mm. Specs on the
//! command line use µm: `rect:A=5um,B=5um`, `L:A=..,B=..,a=..,b=..`,
//! `rhomb:A=..,B=..`, `hex:D=..[,up=side|corner]`, `oct:D=..`, `circle:D=..`,
//! `polygon:x1 y1;x2 y2;…` (µm) or `polygon:@file.csv`.

mod circle;
mod guard;
mod hex;
mod lshape;
mod oct;
mod polygon;
mod rect;
mod rhomb;
pub(crate) mod zonogon;

pub use circle::Circle;
pub use hex::Hexagon;
pub use lshape::LShape;
pub use oct::Octagon;
pub use polygon::Polygon;
pub use rect::Rect;
pub use rhomb::Rhomb;

pub(crate) use guard::check_length;
pub(crate) use hex::side_up_zonogon;

use super::params::Params;
use super::{Factor, ModelError};

/// The aperture shape names accepted by [`parse`].
pub const SHAPES: &[&str] = &["rect", "L", "rhomb", "hex", "oct", "circle", "polygon"];

/// Builds an aperture from a spec such as `rect:A=5um,B=5um` or `polygon:0 0;5 0;0 5`.
pub fn parse(spec: &str) -> Result<Box<dyn Factor>, ModelError> {
    let (shape, rest) = spec.split_once(':').unwrap_or((spec, ""));
    let shape = shape.trim();
    let params = |_keys: &[&str]| Params::parse(&format!("aperture {shape}"), rest);
    Ok(match shape {
        "rect" => {
            let p = params(&["A", "B"])?;
            let (a, b) = (p.positive_length("A")?, p.positive_length("B")?);
            p.finish(&["A", "B"])?;
            Box::new(Rect::new(a, b)?)
        }
        "L" => {
            let keys = ["A", "B", "a", "b"];
            let p = params(&keys)?;
            let big_a = p.positive_length("A")?;
            let big_b = p.positive_length("B")?;
            let a = p.positive_length("a")?;
            let b = p.positive_length("b")?;
            p.finish(&keys)?;
            Box::new(LShape::new(big_a, big_b, a, b)?)
        }
        "rhomb" => {
            let p = params(&["A", "B"])?;
            let (a, b) = (p.positive_length("A")?, p.positive_length("B")?);
            p.finish(&["A", "B"])?;
            Box::new(Rhomb::new(a, b)?)
        }
        "hex" => {
            let p = params(&["D", "up"])?;
            let d = p.positive_length("D")?;
            let up = p.choice_opt("up", &["side", "corner"])?;
            p.finish(&["D", "up"])?;
            if up.as_deref() == Some("corner") {
                Box::new(Hexagon::corner_up(d)?)
            } else {
                Box::new(Hexagon::new(d)?)
            }
        }
        "oct" => {
            let p = params(&["D"])?;
            let d = p.positive_length("D")?;
            p.finish(&["D"])?;
            Box::new(Octagon::new(d)?)
        }
        "circle" => {
            let p = params(&["D"])?;
            let d = p.positive_length("D")?;
            p.finish(&["D"])?;
            Box::new(Circle::new(d)?)
        }
        "polygon" => Box::new(polygon::parse_vertices(rest)?),
        _ => {
            return Err(ModelError::Unknown {
                what: "aperture".into(),
                name: shape.into(),
                allowed: SHAPES.join(", "),
            });
        }
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn parses_every_shape() {
        for spec in [
            "rect:A=5um,B=4um",
            "L:A=5um,B=5um,a=2um,b=1um",
            "rhomb:A=5um,B=3um",
            "hex:D=5um",
            "hex:D=5um,up=corner",
            "oct:D=5um",
            "circle:D=5um",
            "polygon:0 0;5 0;0 5",
            "polygon:0um 0um; 0.005mm 0um; 0 5",
        ] {
            let f = parse(spec).unwrap_or_else(|e| panic!("{spec}: {e}"));
            assert!((f.otf(0.0, 0.0).re - 1.0).abs() < 1e-15, "{spec}");
            assert!(f.name().starts_with("aperture_"));
        }
    }

    #[test]
    fn bad_specs_name_the_problem() {
        let e = parse("square:A=5um").unwrap_err().to_string();
        assert!(e.contains("rect, L, rhomb"), "{e}");
        let e = parse("rect:A=5um,B=5um,C=1um").unwrap_err().to_string();
        assert!(e.contains("unknown key 'C'") && e.contains("A, B"), "{e}");
        let e = parse("rect:A=0um,B=5um").unwrap_err().to_string();
        assert!(e.contains("A must be a positive"), "{e}");
        let e = parse("circle:D=-1um").unwrap_err().to_string();
        assert!(e.contains("D must be a positive"), "{e}");
        let e = parse("rect:A=5,B=5um").unwrap_err().to_string();
        assert!(e.contains("A:"), "{e}");
        let e = parse("L:A=5um,B=5um,a=5um,b=1um").unwrap_err().to_string();
        assert!(e.contains("notch a"), "{e}");
        let e = parse("hex:D=5um,up=left").unwrap_err().to_string();
        assert!(e.contains("side, corner"), "{e}");
        let e = parse("polygon:0 0;1 1;0 1;1 0").unwrap_err().to_string();
        assert!(e.contains("self-intersecting"), "{e}");
        let e = parse("polygon:0 0;1 1").unwrap_err().to_string();
        assert!(e.contains("at least 3"), "{e}");
        let e = parse("polygon:0 0;1 0;1 0;0 1").unwrap_err().to_string();
        assert!(e.contains("same point"), "{e}");
        let e = parse("polygon:0 0;1 0;2 0").unwrap_err().to_string();
        assert!(e.contains("fold back") || e.contains("zero area"), "{e}");
        let e = parse("polygon:0 0;1 x;2 0").unwrap_err().to_string();
        assert!(e.contains("vertex 2"), "{e}");
    }
}
