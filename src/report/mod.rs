//! Writing results: CSV, JSON summaries and plots, atomically.

pub mod model_cut;
pub mod model_io;
pub mod model_map;
pub mod model_points;
