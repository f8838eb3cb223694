//! What the divided curves (`--lens-mtf`: system ÷ sensor; `--chart-mtf`:
//! measured ÷ print) share in the outputs: four CSV columns appended to each
//! row, and the summary figures of the quotient's given points.

use crate::measure::Curve;
use crate::measure::figures::{Figures, figures};

/// A value as the CSV writes it (6 decimals), empty when not finite (a flagged point).
pub(crate) fn cell(v: f64) -> String {
    if v.is_finite() {
        format!("{v:.6}")
    } else {
        String::new()
    }
}

/// Appends the columns `head` to a curves CSV whose data rows are `n`, the
/// cells of each row from `cells` (rows in curve, then point order);
/// unchanged when the CSV does not parse or its row count does not match.
pub(crate) fn append_columns(
    csv_bytes: &[u8],
    head: [&str; 4],
    n: usize,
    cells: impl Iterator<Item = [String; 4]>,
) -> Vec<u8> {
    let mut r = csv::ReaderBuilder::new()
        .has_headers(false)
        .from_reader(csv_bytes);
    let rows: Vec<csv::StringRecord> = match r.records().collect() {
        Ok(v) => v,
        Err(_) => return csv_bytes.to_vec(),
    };
    if rows.len() != n + 1 {
        return csv_bytes.to_vec();
    }
    let mut w = csv::Writer::from_writer(Vec::new());
    let mut first: Vec<String> = rows[0].iter().map(str::to_string).collect();
    first.extend(head.map(String::from));
    let _ = w.write_record(&first);
    for (row, extra) in rows[1..].iter().zip(cells) {
        let mut c: Vec<String> = row.iter().map(str::to_string).collect();
        c.extend(extra);
        let _ = w.write_record(&c);
    }
    w.into_inner().unwrap_or_else(|_| csv_bytes.to_vec())
}

/// The summary figures (MTF50 etc.) of a divided curve: `c`'s points with
/// MTF `values` ± `errs`, the points where `given` is false left out as
/// aliased ones are.
pub(crate) fn divided_figures(
    c: &Curve,
    values: &[f64],
    errs: &[f64],
    given: impl Fn(usize) -> bool,
) -> Figures {
    let pts: Vec<_> = c
        .points
        .iter()
        .zip(values.iter().zip(errs))
        .enumerate()
        .map(|(i, (p, (&v, &e)))| crate::measure::MtfPoint {
            mtf: v,
            mtf_err: e,
            aliased: !given(i),
            ..*p
        })
        .collect();
    figures(&pts)
}
