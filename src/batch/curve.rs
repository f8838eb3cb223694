//! Reading a per-shot MTF curve (`STEM.mtf.csv`, columns `freq_cy_px`,
//! `mtf`, optionally `aliased`) for the summary plots. Aliased points are
//! left out: they are not MTF. When the file holds several curves (columns
//! `channel`/`sweep`), the first curve is taken.

use std::path::Path;

/// Reads the unaliased `(freq_cy_px, mtf)` points of a curve CSV.
pub fn read_curve(path: &Path) -> Result<Vec<(f64, f64)>, String> {
    let mut r = csv::ReaderBuilder::new()
        .comment(Some(b'#'))
        .trim(csv::Trim::All)
        .from_path(path)
        .map_err(|e| format!("{}: {e}", path.display()))?;
    let headers = r
        .headers()
        .map_err(|e| format!("{}: {e}", path.display()))?
        .clone();
    let col = |name: &str| headers.iter().position(|h| h == name);
    let (Some(fi), Some(mi)) = (col("freq_cy_px"), col("mtf")) else {
        return Err(format!("{}: no freq_cy_px and mtf columns", path.display()));
    };
    let ai = col("aliased");
    let group_cols: Vec<usize> = ["channel", "sweep"].iter().filter_map(|c| col(c)).collect();
    let mut first_group: Option<Vec<String>> = None;
    let mut pts = Vec::new();
    for row in r.records() {
        let row = row.map_err(|e| format!("{}: {e}", path.display()))?;
        let group: Vec<String> = group_cols
            .iter()
            .map(|&i| row.get(i).unwrap_or("").to_string())
            .collect();
        if *first_group.get_or_insert_with(|| group.clone()) != group {
            continue;
        }
        let aliased = ai
            .and_then(|i| row.get(i))
            .map(|a| matches!(a.to_ascii_lowercase().as_str(), "true" | "1" | "yes"))
            .unwrap_or(false);
        let f = row.get(fi).and_then(|s| s.parse::<f64>().ok());
        let m = row.get(mi).and_then(|s| s.parse::<f64>().ok());
        if let (Some(f), Some(m), false) = (f, m, aliased)
            && f.is_finite()
            && m.is_finite()
        {
            pts.push((f, m));
        }
    }
    Ok(pts)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn skips_aliased_and_bad_rows() {
        let d = tempfile::tempdir().unwrap();
        let p = d.path().join("c.csv");
        std::fs::write(
            &p,
            "freq_cy_px,freq_cy_mm,mtf,aliased\n0.1,20,0.9,false\n0.2,40,NaN,false\n0.3,60,0.4,false\n0.6,120,0.3,true\n",
        )
        .unwrap();
        assert_eq!(read_curve(&p).unwrap(), vec![(0.1, 0.9), (0.3, 0.4)]);
    }

    #[test]
    fn takes_the_first_of_several_curves() {
        let d = tempfile::tempdir().unwrap();
        let p = d.path().join("c.csv");
        std::fs::write(
            &p,
            "freq_cy_px,mtf,channel,sweep\n0.1,0.9,r,s1\n0.2,0.8,r,s1\n0.1,0.7,g,s1\n0.2,0.6,g,s1\n",
        )
        .unwrap();
        assert_eq!(read_curve(&p).unwrap(), vec![(0.1, 0.9), (0.2, 0.8)]);
    }

    #[test]
    fn missing_columns_is_an_error() {
        let d = tempfile::tempdir().unwrap();
        let p = d.path().join("c.csv");
        std::fs::write(&p, "f,m\n0.1,0.9\n").unwrap();
        assert!(read_curve(&p).is_err());
    }
}
