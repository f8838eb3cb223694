//! The theoretical MTF of a camera (K. Fliegel, "Modeling and Measurement of
//! Image Sensor Characteristics", sections 2–5): optics × detector aperture ×
//! sampling grid × sensor effects, each a [`Factor`], multiplied in a [`System`].
//!
//! Frequencies are in cycles/mm and lengths in millimetres inside the model;
//! axes: x right, y up; OTF = (1/Area)∬p(x,y)·exp(−j2π(ux+vy)) dx dy.

pub mod aperture;
pub mod cte;
pub mod diffusion;
pub mod gaussian;
pub mod olpf;
pub mod optics;
pub mod params;
pub mod sampling;
pub mod spec;
pub mod special;
pub mod system_file;
pub mod trig;

use num_complex::Complex64;
use thiserror::Error;

/// Why a model could not be built from its description.
#[derive(Debug, Clone, PartialEq, Error)]
pub enum ModelError {
    /// A parameter is missing, out of range, or of the wrong kind.
    #[error("{factor}: {message}")]
    Parameter {
        /// Which factor (e.g. "aperture rect").
        factor: String,
        /// What is wrong and what is allowed.
        message: String,
    },
    /// The factor kind is unknown.
    #[error("unknown {what} '{name}'; allowed: {allowed}")]
    Unknown {
        /// What kind of thing ("aperture", "factor", "key").
        what: String,
        /// The name given.
        name: String,
        /// The names allowed.
        allowed: String,
    },
    /// A system file could not be read.
    #[error("{path}: {cause}")]
    File {
        /// The file.
        path: String,
        /// The cause.
        cause: String,
    },
}

/// One multiplicative factor of the system OTF.
pub trait Factor: Send + Sync + std::fmt::Debug {
    /// Short name used in output columns (`mtf_<name>`) and plot legends.
    fn name(&self) -> String;
    /// Complex OTF at spatial frequency (u, v), cycles/mm.
    fn otf(&self, u: f64, v: f64) -> Complex64;
    /// Nyquist frequencies (u, v) in cycles/mm when the factor defines a sampling pitch.
    fn nyquist(&self) -> Option<(f64, f64)> {
        None
    }
}

/// The product of the factors the user named, and nothing else.
#[derive(Debug, Default)]
pub struct System {
    /// The factors, in the order given.
    pub factors: Vec<Box<dyn Factor>>,
}

impl System {
    /// Complex system OTF at (u, v), cycles/mm.
    pub fn otf(&self, u: f64, v: f64) -> Complex64 {
        self.factors
            .iter()
            .fold(Complex64::new(1.0, 0.0), |acc, f| acc * f.otf(u, v))
    }

    /// System MTF |OTF| at (u, v), cycles/mm.
    pub fn mtf(&self, u: f64, v: f64) -> f64 {
        self.otf(u, v).norm()
    }

    /// The first Nyquist frequency any factor defines, cycles/mm.
    pub fn nyquist(&self) -> Option<(f64, f64)> {
        self.factors.iter().find_map(|f| f.nyquist())
    }
}
