//! The model evaluated at given points (`sweepmtf model --at POINTS.csv`):
//! reads `u_cy_mm,v_cy_mm` rows and writes one row per point, in order, with
//! the total OTF and each factor's MTF, every number in Rust's shortest
//! round-trip form.

use super::model_io::{OutputError, factor_columns, fmt_f64, write_atomic};
use crate::model::System;
use std::path::Path;

/// Reads a points file with header `u_cy_mm,v_cy_mm` (other columns ignored).
pub fn read_points(path: &Path) -> Result<Vec<(f64, f64)>, String> {
    let shown = path.display();
    let mut r = csv::ReaderBuilder::new()
        .trim(csv::Trim::All)
        .from_path(path)
        .map_err(|e| format!("{shown}: {e}"))?;
    let headers = r.headers().map_err(|e| format!("{shown}: {e}"))?.clone();
    let col = |name: &str| {
        headers.iter().position(|h| h == name).ok_or_else(|| {
            format!("{shown}: no '{name}' column; the header must hold u_cy_mm,v_cy_mm")
        })
    };
    let (iu, iv) = (col("u_cy_mm")?, col("v_cy_mm")?);
    let mut pts = Vec::new();
    for (i, rec) in r.records().enumerate() {
        let line = i + 2;
        let rec = rec.map_err(|e| format!("{shown}: line {line}: {e}"))?;
        let get = |k: usize, name: &str| -> Result<f64, String> {
            let t = rec.get(k).unwrap_or("");
            match t.parse::<f64>() {
                Ok(x) if x.is_finite() => Ok(x),
                _ => Err(format!(
                    "{shown}: line {line}: {name} '{t}' is not a finite number (cycles/mm)"
                )),
            }
        };
        pts.push((get(iu, "u_cy_mm")?, get(iv, "v_cy_mm")?));
    }
    Ok(pts)
}

/// The CSV text for the system evaluated at `points`.
pub fn points_csv(system: &System, points: &[(f64, f64)]) -> String {
    let names: Vec<String> = system.factors.iter().map(|f| f.name()).collect();
    let mut out = String::from("u_cy_mm,v_cy_mm,otf_re,otf_im,mtf");
    for c in factor_columns(&names) {
        out.push(',');
        out.push_str(&c);
    }
    out.push('\n');
    for &(u, v) in points {
        let mut total = num_complex::Complex64::new(1.0, 0.0);
        let mut cols = String::new();
        for f in &system.factors {
            let o = f.otf(u, v);
            total *= o;
            cols.push(',');
            cols.push_str(&fmt_f64(o.norm()));
        }
        let row = [u, v, total.re, total.im, total.norm()]
            .map(fmt_f64)
            .join(",");
        out.push_str(&row);
        out.push_str(&cols);
        out.push('\n');
    }
    out
}

/// Writes the system evaluated at `points` to `path`, atomically.
pub fn write_points(
    system: &System,
    points: &[(f64, f64)],
    path: &Path,
) -> Result<(), OutputError> {
    write_atomic(path, points_csv(system, points).as_bytes())
}
