//! Measurement of MTF from a photo: profile binning, modulation estimators, sweep-law fit, normalisation.
