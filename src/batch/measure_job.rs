//! Glue between the batch runner and the single-shot measurement: the
//! [`ShotJob`] that measures one photo as `sweepmtf measure` would (same
//! options and decoders, raws included; the same per-shot files
//! `STEM.mtf.csv`, `STEM.summary.json`, `STEM.mtf.png|svg`, `STEM.roi.png`,
//! written together atomically) and turns the result and the photo's EXIF
//! facts into a summary row.

use super::atomic::write_all_atomic_unsynced;
use super::record::{FailKind, ShotFailure, ShotResult};
use super::roi_file::RoiTable;
use super::runner::{PlannedShot, ShotJob};
use crate::geometry::Point;
use crate::measure::{Failure, MeasureOptions, Measurement, measure_file};
use crate::photo::exif::{self, ExifFacts};
use crate::report::atomic::ReportError;
use crate::report::csv::{curves_csv, lw_ph, patches_csv};
use crate::report::json::{Timings, summary_json};
use crate::report::mtf_plot::{PlotFormat, mtf_plot};
use crate::report::roi_plot::roi_plot;
use std::path::{Path, PathBuf};
use std::time::Instant;

/// Measures each shot with the same options; a region from the table (when
/// it lists the shot) replaces the options' region.
#[derive(Debug, Clone)]
pub struct MeasureJob {
    /// Measurement options shared by every shot.
    pub options: MeasureOptions,
    /// Format of each shot's MTF plot.
    pub plot: PlotFormat,
    /// Per-shot regions.
    pub rois: RoiTable,
}

/// The failure kind of a measurement failure.
pub fn kind_of(f: &Failure) -> FailKind {
    match f {
        Failure::Decode(_) | Failure::Raw(_) | Failure::Target(_) | Failure::Options(_) => {
            FailKind::Input
        }
        Failure::NoRoi | Failure::Region(_) | Failure::TooSmall(_) => FailKind::Locate,
        Failure::Clipped { .. }
        | Failure::NoOscillation(_)
        | Failure::ModulationUnknown(_)
        | Failure::Unreliable(_) => FailKind::Measure,
        Failure::Damaged { .. } => FailKind::Input,
    }
}

fn corners(c: [f64; 8]) -> [Point; 4] {
    [[c[0], c[1]], [c[2], c[3]], [c[4], c[5]], [c[6], c[7]]]
}

impl MeasureJob {
    /// The options for one shot (its own region, if the table lists it).
    pub fn options_for(&self, shot: &PlannedShot) -> MeasureOptions {
        let mut o = self.options.clone();
        if let Some(c) = self.rois.lookup(&shot.file) {
            o.roi = Some(corners(c));
        }
        o
    }
}

impl ShotJob for MeasureJob {
    fn fingerprint(&self, shot: &PlannedShot) -> String {
        format!(
            "sweepmtf {} measure {} plot {:?}",
            env!("CARGO_PKG_VERSION"),
            serde_json::to_string(&self.options_for(shot)).unwrap_or_default(),
            self.plot
        )
    }

    fn run(&self, shot: &PlannedShot, shots_dir: &Path) -> Result<ShotResult, ShotFailure> {
        let t0 = Instant::now();
        let opts = self.options_for(shot);
        let m = measure_file(&shot.source, &opts)
            .map_err(|e| ShotFailure::new(kind_of(&e.failure), e.failure.to_string()))?;
        let t1 = Instant::now();
        // Camera facts for the table (a photo without EXIF gives empty facts).
        let facts = exif::read_facts(&shot.source).unwrap_or_default();

        let name = |suffix: &str| format!("{}.{suffix}", shot.stem);
        let out_err = |e: ReportError| ShotFailure::new(FailKind::Output, e.to_string());
        let csv_name = name("mtf.csv");
        let mut files: Vec<(String, Vec<u8>)> = Vec::new();
        if m.curves.is_empty() {
            files.push((csv_name.clone(), patches_csv(&m)));
        } else {
            files.push((csv_name.clone(), curves_csv(&m)));
            if !m.patches.is_empty() {
                files.push((name("patches.csv"), patches_csv(&m)));
            }
        }
        let plot_name = match self.plot {
            PlotFormat::Png => name("mtf.png"),
            PlotFormat::Svg => name("mtf.svg"),
        };
        files.push((plot_name, mtf_plot(&m, self.plot).map_err(out_err)?));
        files.push((name("roi.png"), roi_plot(&m).map_err(out_err)?));
        let ms = |a: Instant, b: Instant| (b - a).as_secs_f64() * 1e3;
        let timings = Timings {
            measure_ms: ms(t0, t1),
            total_ms: ms(t0, Instant::now()),
        };
        files.push((name("summary.json"), summary_json(&m, Some(timings))));
        let names: Vec<String> = files.iter().map(|f| f.0.clone()).collect();
        let paths: Vec<(PathBuf, Vec<u8>)> = files
            .into_iter()
            .map(|(n, b)| (shots_dir.join(n), b))
            .collect();
        write_all_atomic_unsynced(&paths).map_err(|e| {
            ShotFailure::new(
                FailKind::Output,
                format!("{}: cannot write: {e}", shots_dir.display()),
            )
        })?;
        let curve = (!m.curves.is_empty()).then_some(csv_name);
        Ok(result_of(&m, &facts, curve, names))
    }
}

/// The summary fields of a measurement (its first curve) and the camera facts.
pub fn result_of(
    m: &Measurement,
    facts: &ExifFacts,
    curve_file: Option<String>,
    outputs: Vec<String>,
) -> ShotResult {
    let fig = m.curves.first().map(|c| c.figures);
    let mtf50 = fig.as_ref().and_then(|f| f.mtf50_cy_px);
    let mut warnings = m.warnings.clone();
    warnings.extend(facts.warnings.iter().cloned());
    ShotResult {
        mtf50_cy_px: mtf50,
        mtf50_cy_mm: mtf50.zip(m.pixel_pitch_mm).map(|(f, p)| f / p),
        mtf50_lw_ph: mtf50.map(|f| lw_ph(f, m.image_height)),
        mtf50_err_cy_px: fig.as_ref().and_then(|f| f.mtf50_err_cy_px),
        mtf20_cy_px: fig.as_ref().and_then(|f| f.mtf20_cy_px),
        mtf10_cy_px: fig.as_ref().and_then(|f| f.mtf10_cy_px),
        mtf50p_cy_px: fig.as_ref().and_then(|f| f.mtf50p_cy_px),
        mtf20p_cy_px: fig.as_ref().and_then(|f| f.mtf20p_cy_px),
        mtf10p_cy_px: fig.as_ref().and_then(|f| f.mtf10p_cy_px),
        mtf_peak: fig.as_ref().and_then(|f| f.peak_mtf),
        mtf_peak_cy_px: fig.as_ref().and_then(|f| f.peak_cy_px),
        mtf_nyquist: fig.as_ref().and_then(|f| f.mtf_nyquist),
        method: Some(m.method.name().to_string()),
        f_number: facts.f_number,
        focal_length_mm: facts.focal_length_mm,
        iso: facts.iso.map(f64::from),
        exposure_time_s: facts.exposure_time_s,
        make: facts.make.clone(),
        model: facts.model.clone(),
        lens: facts.lens_model.clone(),
        curve_file,
        outputs,
        warnings,
    }
}
