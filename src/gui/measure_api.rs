//! The measure view's endpoints: the session's state, a photo's display
//! rendition, uploads, a measurement, and saving it as `measure` does.
//!
//! The options go through the CLI's own flag checks
//! (`cli::measure_flags::MeasureFlags::options`) and the measurement through
//! the library call `measure_file` makes, so the page, the equivalent command
//! line and its files agree number for number.

use super::server::{MAX_UPLOAD_BYTES, Reply, Server};
use super::session::{self, Photo, Source, TargetChoice};
use crate::cli::measure_flags::{MeasureFlags, parse_channel, parse_method, parse_sweep};
use crate::cli::measure_model::{ModelArgs, prepare_with};
use crate::cli::{CliError, Code};
use clap::Parser;
use serde::Deserialize;
use serde_json::{Value, json};
use std::path::PathBuf;
use std::sync::Arc;
use std::time::{Duration, Instant};
use sweepmtf::measure::{
    MeasureError, MeasureOptions, Measurement, measure_bytes, measure_raw, measure_raw_frame,
};
use sweepmtf::report::json::{Timings, summary};
use sweepmtf::report::mtf_plot::PlotFormat;

fn info(id: usize, p: &Photo) -> Value {
    json!({
        "id": id,
        "name": p.name,
        "width": p.width,
        "height": p.height,
        "raw": matches!(p.source, Source::Raw(_) | Source::Frame(_)),
        "display_width": p.display.width,
        "display_height": p.display.height,
        "display_scale": p.display.scale,
    })
}

/// `GET /api/state`: photos, targets, output folder, limits.
pub fn state(s: &Server) -> Reply {
    let ses = s.session.lock().unwrap_or_else(|e| e.into_inner());
    let photos: Vec<Value> = ses
        .photos
        .iter()
        .enumerate()
        .map(|(i, p)| info(i, p))
        .collect();
    let targets: Vec<Value> = ses
        .targets
        .iter()
        .enumerate()
        .map(|(i, t)| json!({ "id": i, "label": t.label, "arg": t.arg }))
        .collect();
    Reply::json(&json!({
        "photos": photos,
        "targets": targets,
        "default_target": ses.default_target,
        "out_dir": ses.out_dir.display().to_string(),
        "batch_dir": ses.batch.as_ref().map(|b| b.display().to_string()),
        "max_upload_bytes": MAX_UPLOAD_BYTES,
        "photo_extensions": ["jpg", "jpeg", "png", "tif", "tiff"],
        "raw_extensions": sweepmtf::photo::raw::RAW_EXTENSIONS,
    }))
}

pub(super) fn photo(s: &Server, id: usize) -> Result<Arc<Photo>, Reply> {
    let ses = s.session.lock().unwrap_or_else(|e| e.into_inner());
    ses.photos
        .get(id)
        .cloned()
        .ok_or_else(|| Reply::error(404, 2, format!("no photo {id} is open")))
}

/// `GET /api/display?id=N`: the photo's display rendition (JPEG).
pub fn display(s: &Server, id: Option<&str>) -> Reply {
    let id = match id.and_then(|t| t.parse::<usize>().ok()) {
        Some(i) => i,
        None => return Reply::error(400, 2, "display: give id=<photo number>"),
    };
    match photo(s, id) {
        Ok(p) => Reply {
            status: 200,
            content_type: "image/jpeg",
            body: p.display.jpeg.clone(),
        },
        Err(r) => r,
    }
}

/// `POST /api/upload?name=FILE`: decodes an uploaded JPEG/PNG/TIFF or camera raw and keeps it.
pub fn upload(s: &Server, name: &str, bytes: Vec<u8>) -> Reply {
    // Only the file name is kept: it names the outputs, never a place to read.
    let name = std::path::Path::new(name)
        .file_name()
        .map(|n| n.to_string_lossy().into_owned())
        .unwrap_or_else(|| "upload".into());
    let t = Instant::now();
    let opened = if sweepmtf::photo::raw::is_raw_path(std::path::Path::new(&name)) {
        session::raw_from_bytes(&bytes, name)
    } else {
        session::from_bytes(bytes, name)
    };
    let p = match opened {
        Ok(p) => p,
        Err(e) => return Reply::error(422, Code::Input as u8, e),
    };
    let mut ses = s.session.lock().unwrap_or_else(|e| e.into_inner());
    ses.photos.push(Arc::new(p));
    let id = ses.photos.len() - 1;
    let mut v = info(id, &ses.photos[id]);
    v["decode_ms"] = json!(t.elapsed().as_secs_f64() * 1e3);
    Reply::json(&v)
}

/// A measurement request: the photo, the target and the `measure` flags.
#[derive(Debug, Default, Deserialize)]
#[serde(default, deny_unknown_fields)]
struct MeasureReq {
    photo: usize,
    /// Target id (see `/api/state`), none = a single strip.
    target: Option<usize>,
    /// Corners (image pixels); none = found from the target's fiducials.
    roi: Option<[[f64; 2]; 4]>,
    /// Refine the corners to the edges (`measure`'s default; the page's is off after a drag).
    refine: bool,
    method: Option<String>,
    channel: Option<String>,
    sweep: Option<String>,
    pixel_pitch: Option<String>,
    gamma: Option<f64>,
    chart_index: Option<usize>,
    /// Output folder for `/api/save` (default: the one given to `sweepmtf gui`).
    out_dir: Option<String>,
}

/// `measure`'s flags alone, to read their defaults from the one place they are declared.
#[derive(clap::Parser)]
struct Defaults {
    #[command(flatten)]
    flags: MeasureFlags,
}

/// What a request resolves to: the photo, target, options and the flags as typed.
struct Job {
    photo: Arc<Photo>,
    target: Option<Arc<TargetChoice>>,
    opts: MeasureOptions,
    args: Vec<String>,
}

fn parsed<T>(
    flag: &str,
    v: &Option<String>,
    parse: fn(&str) -> Result<T, String>,
    default: T,
) -> Result<T, CliError> {
    match v {
        None => Ok(default),
        Some(t) => parse(t).map_err(|e| CliError::usage(format!("--{flag}: {e}"))),
    }
}

fn job(s: &Server, r: &MeasureReq) -> Result<Job, Reply> {
    let photo = photo(s, r.photo)?;
    let target = match r.target {
        None => None,
        Some(i) => {
            let ses = s.session.lock().unwrap_or_else(|e| e.into_inner());
            Some(
                ses.targets
                    .get(i)
                    .cloned()
                    .ok_or_else(|| Reply::error(404, 2, format!("no target {i}")))?,
            )
        }
    };
    let method =
        parsed("method", &r.method, parse_method, Default::default()).map_err(Reply::cli)?;
    let channel =
        parsed("channel", &r.channel, parse_channel, Default::default()).map_err(Reply::cli)?;
    let sweep = parsed("sweep", &r.sweep, parse_sweep, Default::default()).map_err(Reply::cli)?;
    // `measure`'s own defaults for every flag the page does not set.
    let mut flags = match Defaults::try_parse_from(["measure"]) {
        Ok(d) => d.flags,
        Err(e) => return Err(Reply::error(500, 1, e.to_string())),
    };
    flags.roi = r.roi;
    flags.target = target.as_ref().map(|t| PathBuf::from(&t.arg));
    flags.no_refine_roi = !r.refine;
    flags.chart_index = r.chart_index;
    flags.method = method;
    flags.sweep = sweep;
    flags.gamma = r.gamma;
    flags.channel = channel;
    flags.pixel_pitch = r.pixel_pitch.clone().filter(|p| !p.trim().is_empty());
    let opts = flags.options().map_err(Reply::cli)?;
    let mut args = vec![photo.name.clone()];
    if let Some(t) = &target {
        args.extend(["--target".into(), t.arg.clone()]);
    }
    if let Some(c) = r.roi {
        let v: Vec<String> = c.iter().flatten().map(|x| x.to_string()).collect();
        args.extend(["--roi".into(), v.join(",")]);
        if !r.refine {
            args.push("--no-refine-roi".into());
        }
    }
    if let Some(i) = r.chart_index {
        args.extend(["--chart-index".into(), i.to_string()]);
    }
    for (flag, v) in [
        ("--method", &r.method),
        ("--channel", &r.channel),
        ("--sweep", &r.sweep),
        ("--pixel-pitch", &flags.pixel_pitch),
    ] {
        if let Some(v) = v {
            args.extend([flag.to_string(), v.clone()]);
        }
    }
    if let Some(g) = r.gamma {
        args.extend(["--gamma".into(), g.to_string()]);
    }
    Ok(Job {
        photo,
        target,
        opts,
        args,
    })
}

/// The measurement `measure_file` would make of this photo with these options.
fn run(j: &Job) -> Result<Measurement, MeasureError> {
    let target = j.target.as_ref().map(|t| &t.target);
    match &j.photo.source {
        Source::Raw(path) => measure_raw(path, &j.photo.name, target, &j.opts),
        Source::File(bytes) => measure_bytes(bytes, &j.photo.name, target, &j.opts),
        Source::Frame(f) => measure_raw_frame(f, &j.photo.name, target, &j.opts),
    }
}

fn failed(e: MeasureError) -> Reply {
    let code = crate::cli::measure::code_of(&e.failure);
    Reply::cli(CliError::new(code, e.to_string()))
}

/// Shell quoting for the copied command line (single quotes when needed).
fn quote(a: &str) -> String {
    let plain = !a.is_empty()
        && a.chars()
            .all(|c| c.is_ascii_alphanumeric() || "-_./,=:+@%".contains(c));
    if plain {
        a.to_string()
    } else {
        format!("'{}'", a.replace('\'', "'\\''"))
    }
}

fn command(args: &[String], out: &str) -> String {
    let mut v = vec!["sweepmtf".to_string(), "measure".into()];
    v.extend(args.iter().map(|a| quote(a)));
    v.extend(["-o".into(), quote(out)]);
    v.join(" ")
}

fn out_dir(s: &Server, r: &MeasureReq) -> PathBuf {
    match r
        .out_dir
        .as_deref()
        .map(str::trim)
        .filter(|d| !d.is_empty())
    {
        Some(d) => PathBuf::from(d),
        None => s
            .session
            .lock()
            .unwrap_or_else(|e| e.into_inner())
            .out_dir
            .clone(),
    }
}

fn request(v: Value) -> Result<MeasureReq, Reply> {
    serde_json::from_value(v).map_err(|e| Reply::error(400, 2, format!("bad request: {e}")))
}

/// A request read, resolved and measured: the request, its job, the
/// measurement and the time it took (an error reply at the first failure).
fn measured(s: &Server, v: Value) -> Result<(MeasureReq, Job, Measurement, Duration), Reply> {
    let r = request(v)?;
    let j = job(s, &r)?;
    let t = Instant::now();
    let m = run(&j).map_err(failed)?;
    Ok((r, j, m, t.elapsed()))
}

/// `POST /api/measure`: measures at full resolution and returns the curves,
/// the region, the figures, the warnings and the equivalent command line.
pub fn measure(s: &Server, v: Value) -> Reply {
    let (r, j, m, took) = match measured(s, v) {
        Ok(x) => x,
        Err(e) => return e,
    };
    let ms = took.as_secs_f64() * 1e3;
    let out = out_dir(s, &r);
    Reply::json(&json!({
        "photo": r.photo,
        "name": m.source,
        "image_width": m.image_width,
        "image_height": m.image_height,
        "pixel_pitch_mm": m.pixel_pitch_mm,
        "roi": m.roi,
        "curves": serde_json::to_value(&m.curves).unwrap_or(Value::Null),
        "patches": m.patches.len(),
        "warnings": m.warnings,
        "notes": m.notes,
        "summary": summary(&m, None),
        "command": command(&j.args, &out.display().to_string()),
        "measure_ms": ms,
    }))
}

/// `POST /api/save`: measures as `/api/measure` and writes the files
/// `measure` writes (`STEM.mtf.csv`, `STEM.mtf.png`, `STEM.roi.png`,
/// `STEM.summary.json`) into the output folder, atomically; nowhere else.
pub fn save(s: &Server, v: Value) -> Reply {
    let t = Instant::now();
    let (r, j, m, t_measured) = match measured(s, v) {
        Ok(x) => x,
        Err(e) => return e,
    };
    let out = out_dir(s, &r);
    let none = ModelArgs {
        model: None,
        wavelength: None,
        lens_mtf: false,
        chart_mtf: None,
        chart_length: None,
    };
    let written = prepare_with(&none, j.photo.facts.clone(), &j.photo.name).and_then(|prepared| {
        std::fs::create_dir_all(&out).map_err(|e| {
            CliError::new(
                Code::Output,
                format!("{}: cannot create output folder: {e}", out.display()),
            )
        })?;
        let timings = Timings {
            measure_ms: t_measured.as_secs_f64() * 1e3,
            total_ms: t.elapsed().as_secs_f64() * 1e3,
        };
        let o = crate::cli::measure::save_outputs(
            &m,
            &out,
            &j.photo.stem,
            PlotFormat::Png,
            &prepared,
            timings,
        )?;
        Ok(o.paths
            .iter()
            .map(|p| p.display().to_string())
            .collect::<Vec<_>>())
    });
    match written {
        Ok(files) => Reply::json(&json!({
            "written": files,
            "command": command(&j.args, &out.display().to_string()),
        })),
        Err(e) => Reply::cli(e),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn quoting() {
        assert_eq!(quote("a/b.jpg"), "a/b.jpg");
        assert_eq!(quote("my photo.jpg"), "'my photo.jpg'");
        assert_eq!(quote("it's"), "'it'\\''s'");
        assert_eq!(quote("-1.5,2"), "-1.5,2");
    }
}
