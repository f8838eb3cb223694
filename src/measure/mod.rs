//! Measurement of MTF from a photo: profile binning, modulation estimators, sweep-law fit, normalisation.

pub mod estimate;
pub mod law;
pub mod profile;
