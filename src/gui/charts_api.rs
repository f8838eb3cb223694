//! `GET /api/charts?id=N&target=T`: every copy of the target found in the
//! photo (left to right), so the page can offer a choice when a frame holds
//! several charts (`measure --chart-index`). Reads the full-resolution data
//! the magnifier keeps ([`super::magnify::full_of`]).

use super::magnify::{Full, full_of};
use super::server::{Reply, Server};
use crate::cli::Code;
use serde_json::json;
use std::time::Instant;

/// The charts found: `{charts: [{index, corners_px, score}], ms}`; an error
/// reply (exit code 4's message) when none is found.
pub fn endpoint(s: &Server, id: Option<&str>, target: Option<&str>) -> Reply {
    let parse = |v: Option<&str>| v.and_then(|t| t.parse::<usize>().ok());
    let (Some(id), Some(t)) = (parse(id), parse(target)) else {
        return Reply::error(
            400,
            Code::Usage as u8,
            "charts: give id=<photo> and target=<target>",
        );
    };
    let photo = match super::measure_api::photo(s, id) {
        Ok(p) => p,
        Err(r) => return r,
    };
    let choice = {
        let ses = s.session.lock().unwrap_or_else(|e| e.into_inner());
        ses.targets.get(t).cloned()
    };
    let Some(choice) = choice else {
        return Reply::error(404, Code::Usage as u8, format!("no target {t}"));
    };
    let started = Instant::now();
    let full = match full_of(&photo) {
        Ok(f) => f,
        Err(e) => return Reply::error(422, Code::Input as u8, e),
    };
    let found = match &*full {
        Full::Decoded(d) => sweepmtf::measure::charts_in(d, &choice.target),
        Full::Plane(p) => sweepmtf::locate::find_charts(p, &choice.target),
    };
    match found {
        Ok(charts) => Reply::json(&json!({
            "charts": charts.iter().enumerate().map(|(i, c)| json!({
                "index": i,
                "corners_px": c.corners_px,
                "score": c.score,
            })).collect::<Vec<_>>(),
            "ms": started.elapsed().as_secs_f64() * 1e3,
        })),
        Err(e) => Reply::error(
            422,
            Code::Locate as u8,
            format!("{}: automatic location failed: {e}", photo.name),
        ),
    }
}
