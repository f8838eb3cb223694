//! `OUT/summary.csv`: one row per shot, rebuilt from the per-shot records
//! (so a resumed or merged run gets the full table), written atomically.

use super::record::ShotRecord;
use super::{BatchError, atomic};
use std::path::Path;

/// Columns of the summary, in order (units in the names).
pub const COLUMNS: &[&str] = &[
    "file",
    "status",
    "error",
    "mtf50_cy_px",
    "mtf50_cy_mm",
    "mtf50_lw_ph",
    "mtf50_err_cy_px",
    "mtf20_cy_px",
    "mtf10_cy_px",
    "mtf50p_cy_px",
    "mtf20p_cy_px",
    "mtf10p_cy_px",
    "mtf_peak",
    "mtf_peak_cy_px",
    "mtf_nyquist",
    "method",
    "f_number",
    "focal_length_mm",
    "iso",
    "exposure_time_s",
    "make",
    "model",
    "lens",
    "run_time_s",
    "stem",
    "warnings",
];

fn num(v: Option<f64>) -> String {
    v.filter(|x| x.is_finite())
        .map(|x| x.to_string())
        .unwrap_or_default()
}

fn text(v: &Option<String>) -> String {
    v.clone().unwrap_or_default()
}

/// The summary row of `r`, one string per [`COLUMNS`] entry.
pub fn row(r: &ShotRecord) -> Vec<String> {
    let x = &r.result;
    vec![
        r.file.clone(),
        r.status.as_str().to_string(),
        text(&r.error),
        num(x.mtf50_cy_px),
        num(x.mtf50_cy_mm),
        num(x.mtf50_lw_ph),
        num(x.mtf50_err_cy_px),
        num(x.mtf20_cy_px),
        num(x.mtf10_cy_px),
        num(x.mtf50p_cy_px),
        num(x.mtf20p_cy_px),
        num(x.mtf10p_cy_px),
        num(x.mtf_peak),
        num(x.mtf_peak_cy_px),
        num(x.mtf_nyquist),
        text(&x.method),
        num(x.f_number),
        num(x.focal_length_mm),
        num(x.iso),
        num(x.exposure_time_s),
        text(&x.make),
        text(&x.model),
        text(&x.lens),
        format!("{:.3}", r.run_time_s),
        r.stem.clone(),
        x.warnings.join("; "),
    ]
}

/// The summary table as CSV bytes.
pub fn to_csv(records: &[ShotRecord]) -> Result<Vec<u8>, csv::Error> {
    let mut w = csv::Writer::from_writer(Vec::new());
    w.write_record(COLUMNS)?;
    for r in records {
        w.write_record(row(r))?;
    }
    w.into_inner().map_err(|e| e.into_error().into())
}

/// Writes the summary table to `path` atomically.
pub fn write_summary(path: &Path, records: &[ShotRecord]) -> Result<(), BatchError> {
    let bytes = to_csv(records).map_err(|e| BatchError::output(path, std::io::Error::other(e)))?;
    atomic::write_atomic(path, &bytes).map_err(|e| BatchError::output(path, e))
}
