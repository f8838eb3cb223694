//! `sweepmtf`: measure a camera's MTF from a photograph of a sine-sweep chart,
//! print the charts, simulate shots with known truth, and model the
//! theoretical MTF of optics and sensor.
//!
//! Data flow (see DESIGN.md): `photo` → `locate` → `measure` (profile,
//! estimate, curve) → `report`; `target` describes charts, `chart` prints
//! them, `model` gives theoretical OTFs, `simulate` renders shots with truth,
//! `batch` runs many shots. Library code never prints and never exits.

pub mod batch;
pub mod chart;
pub mod distortion;
pub mod fuzz;
pub mod geometry;
pub(crate) mod linalg;
pub mod locate;
pub mod measure;
pub mod model;
pub mod photo;
pub mod plot;
pub mod print_mtf;
pub mod report;
pub mod simulate;
pub mod target;
pub mod units;
