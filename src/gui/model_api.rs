//! The model view's endpoint: factors given as `model`'s (kind, spec) pairs,
//! evaluated by the library into a 1-D cut (total and per factor) and a 2-D
//! map (viridis PNG, axes drawn by the page).

use super::server::Reply;
use crate::cli::Code;
use serde::Deserialize;
use serde_json::{Value, json};
use std::time::Instant;
use sweepmtf::model::System;
use sweepmtf::model::spec::parse_factor;
use sweepmtf::report::model_cut::{CutDirection, compute_cut};
use sweepmtf::report::model_map::{compute_map, viridis};

/// One factor as on the command line: `--KIND SPEC`.
#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct FactorReq {
    kind: String,
    spec: String,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct ModelReq {
    factors: Vec<FactorReq>,
    /// `u`, `v` or `deg=θ`.
    #[serde(default = "u")]
    cut: String,
    /// Highest cut frequency and half-width of the map (cycles/mm).
    f_max: f64,
    /// Samples of the cut.
    #[serde(default = "points")]
    points: usize,
    /// Samples per side of the map (0 = no map).
    #[serde(default)]
    map_size: usize,
}

fn u() -> String {
    "u".into()
}
fn points() -> usize {
    401
}

fn usage(msg: String) -> Reply {
    Reply::error(400, Code::Usage as u8, msg)
}

/// `POST /api/model`: the cut and (when `map_size` > 0) the map.
pub fn model(v: Value) -> Reply {
    let r: ModelReq = match serde_json::from_value(v) {
        Ok(r) => r,
        Err(e) => return usage(format!("bad request: {e}")),
    };
    let dir = match CutDirection::parse(&r.cut) {
        Ok(d) => d,
        Err(e) => return usage(format!("--cut: {e}")),
    };
    if !(r.f_max.is_finite() && r.f_max > 0.0) {
        return usage(format!(
            "--f-max must be a positive number of cycles/mm, got {}",
            r.f_max
        ));
    }
    if !(2..=100_000).contains(&r.points) {
        return usage("--points must be between 2 and 100000".into());
    }
    if r.map_size > 4096 {
        return usage("--size must be between 2 and 4096".into());
    }
    let mut system = System::default();
    for f in &r.factors {
        match parse_factor(&f.kind, &f.spec) {
            Ok(x) => system.factors.push(x),
            Err(e) => return usage(format!("--{} {}: {e}", f.kind, f.spec)),
        }
    }
    if system.factors.is_empty() {
        return usage("no model factor named; switch on at least one factor".into());
    }
    let t = Instant::now();
    let cut = compute_cut(&system, dir, r.f_max, r.points);
    let cut_ms = t.elapsed().as_secs_f64() * 1e3;
    let total: Vec<f64> = cut.otf.iter().map(|o| o.norm()).collect();
    let factors: Vec<Value> = cut
        .factors
        .iter()
        .map(|(n, m)| json!({ "name": n, "mtf": m }))
        .collect();
    let mut reply = json!({
        "cut": {
            "direction": dir.label(),
            "freq_cy_mm": cut.freq,
            "mtf": total,
            "factors": factors,
            "nyquist_cy_mm": cut.nyquist,
        },
        "names": system.factors.iter().map(|f| f.name()).collect::<Vec<_>>(),
        "cut_ms": cut_ms,
    });
    if r.map_size >= 2 {
        let t = Instant::now();
        let map = compute_map(&system, r.f_max, r.map_size);
        let rgb: Vec<u8> = map.mtf.iter().flat_map(|&m| viridis(m)).collect();
        let png =
            match sweepmtf::report::model_io::encode_png(&rgb, map.size as u32, map.size as u32) {
                Ok(p) => p,
                Err(e) => return Reply::error(500, Code::Internal as u8, e),
            };
        reply["map"] = json!({
            "size": map.size,
            "f_max_cy_mm": map.f_max,
            "nyquist_cy_mm": map.nyquist,
            "png_base64": sweepmtf::batch::base64::encode(&png),
        });
        reply["map_ms"] = json!(t.elapsed().as_secs_f64() * 1e3);
    }
    Reply::json(&reply)
}
