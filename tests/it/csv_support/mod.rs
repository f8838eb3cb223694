//! Test helpers shared by tests that compare a measured CSV with the
//! simulator's truth CSV.

use std::collections::HashMap;
use std::path::Path;

/// Every row of a CSV file as column name → text.
pub fn read_csv(path: &Path) -> Vec<HashMap<String, String>> {
    let mut r = csv::Reader::from_path(path).unwrap();
    let head: Vec<String> = r.headers().unwrap().iter().map(str::to_string).collect();
    r.records()
        .map(|rec| {
            let rec = rec.unwrap();
            head.iter()
                .cloned()
                .zip(rec.iter().map(str::to_string))
                .collect()
        })
        .collect()
}

/// Linear interpolation in a (freq, mtf) table sorted by frequency.
pub fn truth_at(truth: &[(f64, f64)], f: f64) -> f64 {
    let i = truth.partition_point(|p| p.0 < f).clamp(1, truth.len() - 1);
    let (a, b) = (truth[i - 1], truth[i]);
    a.1 + (b.1 - a.1) * (f - a.0) / (b.0 - a.0)
}
