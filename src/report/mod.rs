//! Writing results: CSV, JSON summaries and plots, atomically.

pub mod atomic;
pub mod chart_check_plot;
pub mod chart_mtf;
pub mod csv;
mod divided;
pub mod json;
pub mod lens_mtf;
pub mod model_cut;
pub mod model_io;
pub mod model_map;
pub mod model_overlay;
pub mod model_points;
pub mod mtf_plot;
pub mod roi_plot;
