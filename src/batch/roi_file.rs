//! `--roi-file ROIS.csv`: a region per shot for shots that need one. Columns
//! `file,x1,y1,x2,y2,x3,y3,x4,y4` (a header line, `#` comments allowed);
//! corners in image pixel coordinates (origin at the top-left corner, x
//! right, y down; the top-left pixel's centre is 0.5,0.5), in the order
//! `measure --roi` takes them. `file` is the shot's path as the batch shows
//! it (relative to its input folder) or, when unambiguous, its file name.

use super::BatchError;
use std::collections::HashMap;
use std::path::Path;

/// Regions by file.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct RoiTable {
    by_path: HashMap<String, [f64; 8]>,
}

impl RoiTable {
    /// Reads a region table.
    pub fn read(path: &Path) -> Result<RoiTable, BatchError> {
        let text = std::fs::read_to_string(path).map_err(|e| BatchError::input(path, e))?;
        Self::parse(&text).map_err(|cause| BatchError::Input {
            path: path.display().to_string(),
            cause,
        })
    }

    /// Parses a region table from CSV text.
    pub fn parse(text: &str) -> Result<RoiTable, String> {
        let mut r = csv::ReaderBuilder::new()
            .comment(Some(b'#'))
            .trim(csv::Trim::All)
            .flexible(true)
            .from_reader(text.as_bytes());
        let headers = r.headers().map_err(|e| e.to_string())?.clone();
        let want = ["file", "x1", "y1", "x2", "y2", "x3", "y3", "x4", "y4"];
        let cols: Vec<usize> = want
            .iter()
            .map(|w| {
                headers
                    .iter()
                    .position(|h| h.eq_ignore_ascii_case(w))
                    .ok_or_else(|| format!("no column '{w}' (need {})", want.join(",")))
            })
            .collect::<Result<_, _>>()?;
        let mut by_path = HashMap::new();
        for (n, row) in r.records().enumerate() {
            let row = row.map_err(|e| e.to_string())?;
            let line = row.position().map(|p| p.line()).unwrap_or(n as u64 + 2);
            let file = row.get(cols[0]).unwrap_or("").replace('\\', "/");
            if file.is_empty() {
                return Err(format!("line {line}: empty file name"));
            }
            let mut c = [0.0; 8];
            for (k, &ci) in cols[1..].iter().enumerate() {
                let s = row.get(ci).unwrap_or("");
                c[k] = s
                    .parse::<f64>()
                    .ok()
                    .filter(|v| v.is_finite())
                    .ok_or_else(|| {
                        format!("line {line}: {} = '{s}' is not a number", want[k + 1])
                    })?;
            }
            if by_path.insert(file.clone(), c).is_some() {
                return Err(format!("line {line}: '{file}' is listed twice"));
            }
        }
        Ok(RoiTable { by_path })
    }

    /// Number of regions.
    pub fn len(&self) -> usize {
        self.by_path.len()
    }

    /// Whether the table is empty.
    pub fn is_empty(&self) -> bool {
        self.by_path.is_empty()
    }

    /// The region for the shot shown as `display` (exact path first, then
    /// its file name when the table lists it by name alone).
    pub fn lookup(&self, display: &str) -> Option<[f64; 8]> {
        if let Some(c) = self.by_path.get(display) {
            return Some(*c);
        }
        let name = display.rsplit('/').next()?;
        self.by_path.get(name).copied()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn parses_and_looks_up_by_path_or_name() {
        let t = RoiTable::parse(
            "# regions\nfile,x1,y1,x2,y2,x3,y3,x4,y4\nsub/a.jpg,1,2,3,4,5,6,7,8\nb.png, 0.5,0.5,10,0.5,10,5,0.5,5\n",
        )
        .unwrap();
        assert_eq!(t.lookup("sub/a.jpg").unwrap()[7], 8.0);
        assert_eq!(t.lookup("other/b.png").unwrap()[2], 10.0);
        assert!(t.lookup("a.jpg").is_none());
    }

    #[test]
    fn bad_tables_name_the_line() {
        let e =
            RoiTable::parse("file,x1,y1,x2,y2,x3,y3,x4,y4\na.jpg,1,2,3,x,5,6,7,8\n").unwrap_err();
        assert!(e.contains("line 2") && e.contains("y2"), "{e}");
        assert!(RoiTable::parse("file,x1\n").is_err());
    }
}
