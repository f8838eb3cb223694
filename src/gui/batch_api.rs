//! The batch view's endpoints: a `sweepmtf batch` output folder's table
//! (`GET /api/batch?dir=D`: its `summary.csv` as columns and rows, and the
//! overview pictures present) and its pictures (`GET /api/batch/file?dir=D&name=N`).
//!
//! Only what a batch folder holds for people to look at is served: the two
//! overview pictures and, for a stem listed in its summary, the shot's
//! `shots/STEM.mtf.png|svg` and `shots/STEM.roi.png`; nothing else is read,
//! whatever the request names. Nothing is written.

use super::server::Reply;
use crate::cli::Code;
use serde_json::json;
use std::path::{Path, PathBuf};
use sweepmtf::batch::{CURVES_PNG, F_NUMBER_PNG, SHOTS_DIR, SUMMARY_CSV};

/// Largest `summary.csv` read (bytes; ≈ 100 000 shots).
const MAX_SUMMARY_BYTES: u64 = 64 << 20;

/// A batch folder's summary table: (column names, rows).
type Table = (Vec<String>, Vec<Vec<String>>);

/// Reads `dir/summary.csv`; an error names the folder and the cause.
fn read_summary(dir: &Path) -> Result<Table, String> {
    let path = dir.join(SUMMARY_CSV);
    let meta = std::fs::metadata(&path).map_err(|e| {
        if dir.is_dir() {
            format!(
                "{}: no {SUMMARY_CSV} ({e}): not a sweepmtf batch output folder",
                dir.display()
            )
        } else {
            format!("{}: not a folder", dir.display())
        }
    })?;
    if meta.len() > MAX_SUMMARY_BYTES {
        return Err(format!(
            "{}: {} bytes, more than the {} MiB a batch summary can need",
            path.display(),
            meta.len(),
            MAX_SUMMARY_BYTES >> 20
        ));
    }
    let bad = |e: csv::Error| format!("{}: not a batch summary: {e}", path.display());
    let mut rd = csv::Reader::from_path(&path).map_err(bad)?;
    let columns: Vec<String> = rd
        .headers()
        .map_err(bad)?
        .iter()
        .map(String::from)
        .collect();
    if !columns.iter().any(|c| c == "stem") || !columns.iter().any(|c| c == "file") {
        return Err(format!(
            "{}: not a batch summary (no 'file' and 'stem' columns)",
            path.display()
        ));
    }
    let mut rows = Vec::new();
    for r in rd.records() {
        rows.push(r.map_err(bad)?.iter().map(String::from).collect());
    }
    Ok((columns, rows))
}

/// The folder named by the request (trimmed; `~` is not expanded).
fn folder(dir: Option<&str>) -> Result<PathBuf, Reply> {
    match dir.map(str::trim).filter(|d| !d.is_empty()) {
        Some(d) => Ok(PathBuf::from(d)),
        None => Err(Reply::error(
            400,
            Code::Usage as u8,
            "batch: give dir=<batch output folder>",
        )),
    }
}

/// `GET /api/batch?dir=D`: `{dir, columns, rows, pictures}`.
pub fn table(dir: Option<&str>) -> Reply {
    let dir = match folder(dir) {
        Ok(d) => d,
        Err(r) => return r,
    };
    match read_summary(&dir) {
        Ok((columns, rows)) => {
            let pictures: Vec<&str> = [CURVES_PNG, F_NUMBER_PNG]
                .into_iter()
                .filter(|p| dir.join(p).is_file())
                .collect();
            Reply::json(&json!({
                "dir": dir.display().to_string(),
                "columns": columns,
                "rows": rows,
                "pictures": pictures,
            }))
        }
        Err(e) => Reply::error(422, Code::Input as u8, e),
    }
}

/// Whether `name` is a picture the batch folder shows: an overview picture,
/// or a listed shot's plot or region picture.
fn servable(name: &str, stems: &[String]) -> Option<&'static str> {
    if name == CURVES_PNG || name == F_NUMBER_PNG {
        return Some("image/png");
    }
    let rest = name.strip_prefix(SHOTS_DIR)?.strip_prefix('/')?;
    for (ext, mime) in [
        (".mtf.png", "image/png"),
        (".mtf.svg", "image/svg+xml"),
        (".roi.png", "image/png"),
    ] {
        if let Some(stem) = rest.strip_suffix(ext)
            && !stem.contains(['/', '\\'])
            && !stem.starts_with('.')
            && stems.iter().any(|s| s == stem)
        {
            return Some(mime);
        }
    }
    None
}

/// `GET /api/batch/file?dir=D&name=N`: one of the folder's pictures.
pub fn file(dir: Option<&str>, name: Option<&str>) -> Reply {
    let dir = match folder(dir) {
        Ok(d) => d,
        Err(r) => return r,
    };
    let Some(name) = name else {
        return Reply::error(400, Code::Usage as u8, "batch file: give name=<picture>");
    };
    let (columns, rows) = match read_summary(&dir) {
        Ok(t) => t,
        Err(e) => return Reply::error(422, Code::Input as u8, e),
    };
    let k = columns.iter().position(|c| c == "stem").unwrap_or(0);
    let stems: Vec<String> = rows.iter().filter_map(|r| r.get(k).cloned()).collect();
    let Some(mime) = servable(name, &stems) else {
        return Reply::error(
            404,
            Code::Usage as u8,
            format!("{name}: not a picture of this batch folder"),
        );
    };
    match std::fs::read(dir.join(name)) {
        Ok(body) => Reply {
            status: 200,
            content_type: mime,
            body,
        },
        Err(e) => Reply::error(
            404,
            Code::Input as u8,
            format!("{}: {e}", dir.join(name).display()),
        ),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn only_the_folders_pictures_are_served() {
        // A crafted summary may list any stem: one that climbs is still refused.
        let stems = vec!["f4".to_string(), "a__x".to_string(), "../up".to_string()];
        assert_eq!(servable("curves.png", &stems), Some("image/png"));
        assert_eq!(servable("shots/f4.mtf.png", &stems), Some("image/png"));
        assert_eq!(servable("shots/a__x.roi.png", &stems), Some("image/png"));
        assert_eq!(servable("shots/f4.mtf.svg", &stems), Some("image/svg+xml"));
        for bad in [
            "summary.csv",
            "shots/f4.mtf.csv",
            "shots/f5.mtf.png",
            "shots/../f4.mtf.png",
            "../shots/f4.mtf.png",
            "/etc/passwd",
            "shots/f4.done.json",
            "shots/sub/f4.mtf.png",
            "shots/../up.mtf.png",
        ] {
            assert_eq!(servable(bad, &stems), None, "{bad}");
        }
    }
}
