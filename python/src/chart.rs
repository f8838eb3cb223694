//! `chart()`: lays out and writes a printable chart with its description
//! (NAME.toml) and preview (NAME.preview.png) beside it, all or nothing.

use crate::value_err;
use numpy::PyArray1;
use pyo3::exceptions::PyOSError;
use pyo3::prelude::*;
use pyo3::types::PyDict;
use std::io::Cursor;
use std::path::PathBuf;
use sweepmtf::chart::{self as lib_chart, ChartError, ChartSpec, Encoding, Format, Law};

fn chart_err(e: ChartError) -> PyErr {
    match e {
        ChartError::Output { .. } => PyOSError::new_err(e.to_string()),
        _ => value_err(e),
    }
}

/// Writes a chart to `path` (.png, .tif or .pdf) with NAME.toml and NAME.preview.png beside it.
#[pyfunction]
#[pyo3(signature = (path, law, f_min_cy_mm, f_max_cy_mm, width_mm, height_mm, dpi, contrasts, mean, patches, gamma=None, name=None))]
#[allow(clippy::too_many_arguments)]
pub fn chart<'py>(
    py: Python<'py>,
    path: PathBuf,
    law: &str,
    f_min_cy_mm: f64,
    f_max_cy_mm: f64,
    width_mm: f64,
    height_mm: f64,
    dpi: u32,
    contrasts: Vec<f64>,
    mean: f64,
    patches: usize,
    gamma: Option<f64>,
    name: Option<String>,
) -> PyResult<Bound<'py, PyDict>> {
    let format = Format::from_path(&path).ok_or_else(|| {
        value_err(format!(
            "{}: output must end in .png, .tif, .tiff or .pdf",
            path.display()
        ))
    })?;
    let law = match law {
        "log" => Law::Log,
        "linear" => Law::Linear,
        "patches" => Law::Patches,
        other => {
            return Err(value_err(format!(
                "law '{other}': use log, linear or patches"
            )));
        }
    };
    let encoding = match gamma {
        Some(g) if !(g.is_finite() && g > 0.0) => {
            return Err(value_err(format!("gamma {g} must be positive")));
        }
        Some(g) => Encoding::Gamma(g),
        None => Encoding::Srgb,
    };
    let stem = path
        .file_stem()
        .map(|s| s.to_string_lossy().into_owned())
        .unwrap_or_else(|| "chart".into());
    let spec = ChartSpec {
        name: name.unwrap_or_else(|| stem.clone()),
        law,
        f_min_cy_mm,
        f_max_cy_mm,
        width_mm,
        height_mm,
        dpi,
        contrasts,
        mean,
        patch_count: patches,
        darkest: encoding.darkest(),
        encoding_name: encoding.describe(),
    };
    let shown = path.display().to_string();
    let (laid, preview, bytes) = py
        .detach(|| -> Result<_, ChartError> {
            let laid = lib_chart::layout(&spec)?;
            let mut out = Cursor::new(Vec::new());
            let written = lib_chart::write_chart(&laid, &encoding, format, &mut out, &shown)?;
            Ok((laid, written.preview, out.into_inner()))
        })
        .map_err(chart_err)?;
    let toml_path = path.with_file_name(format!("{stem}.toml"));
    let preview_path = path.with_file_name(format!("{stem}.preview.png"));
    let mut png = Vec::new();
    preview
        .write_png(&mut png)
        .map_err(|e| PyOSError::new_err(format!("{}: {e}", preview_path.display())))?;
    let toml = laid.target.to_toml();
    let files = vec![
        (path.clone(), bytes),
        (toml_path.clone(), toml.clone().into_bytes()),
        (preview_path.clone(), png),
    ];
    py.detach(|| sweepmtf::report::atomic::write_all_atomic(&files))
        .map_err(|e| PyOSError::new_err(e.to_string()))?;
    let d = PyDict::new(py);
    d.set_item("path", path)?;
    d.set_item("target_path", toml_path)?;
    d.set_item("preview_path", preview_path)?;
    d.set_item("target_toml", toml)?;
    d.set_item("width_px", laid.width_px)?;
    d.set_item("height_px", laid.height_px)?;
    d.set_item("dots_per_cycle", laid.dots_per_cycle)?;
    d.set_item("warnings", laid.warnings)?;
    let flat = PyArray1::from_vec(py, preview.pixels);
    d.set_item(
        "preview",
        flat.call_method1("reshape", ((preview.height, preview.width),))?,
    )?;
    Ok(d)
}
