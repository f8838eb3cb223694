//! Writing results: CSV, JSON summaries and plots, atomically.

pub mod atomic;
pub mod csv;
pub mod json;
pub mod mtf_plot;
pub mod roi_plot;
