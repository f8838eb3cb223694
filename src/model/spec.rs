//! The factor-flag dispatcher: turns a factor kind (`optics`, `cte`, …) and
//! its spec text (`diffraction:lambda=550nm,fnum=4`) into a [`Factor`]. Every
//! front end (CLI flags, system files) goes through [`parse_factor`].

use super::{Factor, ModelError};

/// The factor kinds, in the order the CLI lists them.
pub const KINDS: &[&str] = &[
    "aperture",
    "sampling",
    "optics",
    "diffusion",
    "cte",
    "olpf",
    "gaussian",
    "defocus",
];

/// Builds one factor of kind `kind` from its spec text.
pub fn parse_factor(kind: &str, spec: &str) -> Result<Box<dyn Factor>, ModelError> {
    let spec = spec.trim();
    match kind {
        "aperture" => super::aperture::parse(spec),
        "sampling" => super::sampling::parse(spec),
        "optics" => super::optics::parse(spec),
        "diffusion" => super::diffusion::parse(spec),
        "cte" => super::cte::parse(spec),
        "olpf" => super::olpf::parse(spec),
        "gaussian" => super::gaussian::parse(spec),
        "defocus" => super::optics::parse_defocus(spec),
        other => Err(ModelError::Unknown {
            what: "factor kind".into(),
            name: other.into(),
            allowed: KINDS.join(", "),
        }),
    }
}

/// Splits `shape:key=value,…` into the shape and the parameter text, checking
/// the shape against `allowed` (`what` names the factor kind for errors).
pub fn split_shape<'a>(
    what: &str,
    spec: &'a str,
    allowed: &[&str],
) -> Result<(&'a str, &'a str), ModelError> {
    let (shape, rest) = spec.split_once(':').unwrap_or((spec, ""));
    let shape = shape.trim();
    if allowed.contains(&shape) {
        Ok((shape, rest))
    } else {
        Err(ModelError::Unknown {
            what: format!("{what} type"),
            name: shape.into(),
            allowed: allowed.join(", "),
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn unknown_kinds_and_shapes_are_named() {
        let e = parse_factor("lens", "x").unwrap_err().to_string();
        assert!(e.contains("'lens'") && e.contains("optics"), "{e}");
        let e = parse_factor("optics", "pinhole:d=1um")
            .unwrap_err()
            .to_string();
        assert!(e.contains("'pinhole'") && e.contains("diffraction"), "{e}");
    }

    #[test]
    fn every_kind_parses_an_example() {
        for (k, s) in [
            ("optics", "diffraction:lambda=550nm,fnum=4"),
            ("diffusion", "alpha=0.05/um,depletion=2um,length=10um"),
            ("diffusion", "lambda=550nm,depletion=2um,length=10um"),
            ("cte", "n=1000,cti=1e-5,pitch=5um"),
            ("cte", "n=1000,cte=0.99999,pitch=5um,model=exact,axis=v"),
            ("olpf", "2spot:d=4um"),
            ("olpf", "4spot:dx=4um,dy=3um"),
            ("gaussian", "sigma=1.5um"),
            ("defocus", "wave:lambda=550nm,fnum=4,w020=0.5"),
            ("aperture", "rect:A=4um,B=4um"),
            ("sampling", "rect:px=4um,py=4um"),
        ] {
            let f = parse_factor(k, s).unwrap_or_else(|e| panic!("{k} {s}: {e}"));
            assert!((f.otf(0.0, 0.0).re - 1.0).abs() < 1e-15, "{k} {s}");
        }
    }
}
