//! `sweepmtf._native`: the Rust half of the Python package. Thin: it turns
//! numpy arrays and JSON option documents into the library's types, calls the
//! library with the GIL released, and hands back numpy arrays, bytes and JSON
//! text. The Python half (`sweepmtf/__init__.py`) shapes the public API.

use num_complex::Complex64;
use numpy::{PyArray1, PyReadonlyArray1, PyReadonlyArrayDyn, PyUntypedArrayMethods};
use pyo3::create_exception;
use pyo3::exceptions::{PyException, PyOSError, PyValueError};
use pyo3::prelude::*;
use pyo3::types::{PyBytes, PyDict};
use rayon::prelude::*;
use std::path::{Path, PathBuf};
use sweepmtf::measure::in_memory::{
    decoded_from_samples, locate_file, locate_in_memory, measure_in_memory,
};
use sweepmtf::measure::{Failure, MeasureError, MeasureOptions, Measurement};
use sweepmtf::photo::decode::{Samples, decode_file};

/// Two float arrays handed to Python together: (values, coordinates).
type ArrayPair<'py> = (Bound<'py, PyArray1<f64>>, Bound<'py, PyArray1<f64>>);

create_exception!(
    sweepmtf,
    MeasurementError,
    PyException,
    "The photo cannot be measured: no region or chart found, too small, clipped, no oscillation."
);

/// The Python exception for a failed measurement, by the CLI's exit code:
/// input files → OSError, option values → ValueError, region and measurement → MeasurementError.
fn measure_err(e: MeasureError) -> PyErr {
    let msg = e.to_string();
    match e.failure {
        Failure::Decode(_) | Failure::Raw(_) | Failure::Target(_) | Failure::Damaged { .. } => {
            PyOSError::new_err(msg)
        }
        Failure::Options(_) => PyValueError::new_err(msg),
        _ => MeasurementError::new_err(msg),
    }
}

fn value_err(e: impl std::fmt::Display) -> PyErr {
    PyValueError::new_err(e.to_string())
}

/// Measurement options from their JSON document (MeasureOptions' field names).
fn options(json: &str) -> PyResult<MeasureOptions> {
    serde_json::from_str(json).map_err(|e| value_err(format!("measurement options: {e}")))
}

/// A measured photo (the library's `Measurement`).
#[pyclass(frozen, module = "sweepmtf._native")]
struct NativeMeasurement {
    m: Measurement,
}

#[pymethods]
impl NativeMeasurement {
    /// The photo as given (path, or "<array>").
    #[getter]
    fn source(&self) -> &str {
        &self.m.source
    }
    /// Warnings (something may be wrong with the result), one line each.
    #[getter]
    fn warnings(&self) -> Vec<String> {
        self.m.warnings.clone()
    }
    /// Notes (what was done or assumed), one line each.
    #[getter]
    fn notes(&self) -> Vec<String> {
        self.m.notes.clone()
    }
    /// Pixel pitch (mm), when known.
    #[getter]
    fn pixel_pitch_mm(&self) -> Option<f64> {
        self.m.pixel_pitch_mm
    }
    /// Region corners used (image px).
    #[getter]
    fn roi(&self) -> Vec<[f64; 2]> {
        self.m.roi.to_vec()
    }
    /// The JSON summary (as `STEM.summary.json`, without timings).
    fn summary_json(&self) -> String {
        sweepmtf::report::json::summary(&self.m, None).to_string()
    }
    /// The curves' CSV (as `STEM.mtf.csv`; patches CSV when there are only patches).
    fn csv<'py>(&self, py: Python<'py>) -> Bound<'py, PyBytes> {
        let bytes = py.detach(|| {
            if self.m.curves.is_empty() {
                sweepmtf::report::csv::patches_csv(&self.m)
            } else {
                sweepmtf::report::csv::curves_csv(&self.m)
            }
        });
        PyBytes::new(py, &bytes)
    }
    /// The sine patches' CSV (as `STEM.patches.csv`), or None without patches.
    fn patches_csv<'py>(&self, py: Python<'py>) -> Option<Bound<'py, PyBytes>> {
        (!self.m.patches.is_empty())
            .then(|| PyBytes::new(py, &sweepmtf::report::csv::patches_csv(&self.m)))
    }
    /// The MTF plot ("png" or "svg") as bytes (as `STEM.mtf.png|svg`).
    fn plot<'py>(&self, py: Python<'py>, format: &str) -> PyResult<Bound<'py, PyBytes>> {
        use sweepmtf::report::mtf_plot::{PlotFormat, mtf_plot};
        let f = match format {
            "png" => PlotFormat::Png,
            "svg" => PlotFormat::Svg,
            other => return Err(value_err(format!("plot format '{other}': use png or svg"))),
        };
        let bytes = py
            .detach(|| mtf_plot(&self.m, f))
            .map_err(|e| PyOSError::new_err(e.to_string()))?;
        Ok(PyBytes::new(py, &bytes))
    }
    /// The region picture (PNG bytes, as `STEM.roi.png`).
    fn roi_plot<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyBytes>> {
        let bytes = py
            .detach(|| sweepmtf::report::roi_plot::roi_plot(&self.m))
            .map_err(|e| PyOSError::new_err(e.to_string()))?;
        Ok(PyBytes::new(py, &bytes))
    }
    /// The curves: one dict each, numpy arrays per point and scalars per curve.
    fn curves<'py>(&self, py: Python<'py>) -> PyResult<Vec<Bound<'py, PyDict>>> {
        self.m
            .curves
            .iter()
            .map(|c| {
                let d = PyDict::new(py);
                let col = |f: fn(&sweepmtf::measure::MtfPoint) -> f64| {
                    PyArray1::from_vec(py, c.points.iter().map(f).collect())
                };
                d.set_item("channel", &c.channel)?;
                d.set_item("sweep_id", &c.sweep_id)?;
                d.set_item("strip_unit", c.strip_unit)?;
                d.set_item("s", col(|p| p.s))?;
                d.set_item("freq_cy_px", col(|p| p.freq_cy_px))?;
                d.set_item("freq_chart", col(|p| p.freq_chart))?;
                d.set_item("modulation", col(|p| p.modulation))?;
                d.set_item("mtf", col(|p| p.mtf))?;
                d.set_item("mtf_err", col(|p| p.mtf_err))?;
                let aliased: Vec<bool> = c.points.iter().map(|p| p.aliased).collect();
                d.set_item("aliased", PyArray1::from_vec(py, aliased))?;
                let limited: Vec<bool> = c.points.iter().map(|p| p.jpeg_limited).collect();
                d.set_item("jpeg_limited", PyArray1::from_vec(py, limited))?;
                d.set_item("chart_modulation", c.chart_modulation)?;
                d.set_item("chart_modulation_source", &c.chart_modulation_source)?;
                d.set_item("mtf50_cy_px", c.figures.mtf50_cy_px)?;
                d.set_item("mtf50_err_cy_px", c.figures.mtf50_err_cy_px)?;
                d.set_item("mtf30_cy_px", c.figures.mtf30_cy_px)?;
                d.set_item("mtf20_cy_px", c.figures.mtf20_cy_px)?;
                d.set_item("mtf10_cy_px", c.figures.mtf10_cy_px)?;
                d.set_item("mtf50p_cy_px", c.figures.mtf50p_cy_px)?;
                d.set_item("mtf20p_cy_px", c.figures.mtf20p_cy_px)?;
                d.set_item("mtf10p_cy_px", c.figures.mtf10p_cy_px)?;
                d.set_item("peak_mtf", c.figures.peak_mtf)?;
                d.set_item("peak_cy_px", c.figures.peak_cy_px)?;
                d.set_item("sharpening_peak", c.figures.sharpening_peak)?;
                d.set_item("mtf_nyquist", c.figures.mtf_nyquist)?;
                d.set_item("aliasing_from_cy_px", c.aliasing_from_cy_px)?;
                d.set_item("rounded_away_from_cy_px", c.rounded_away_from_cy_px)?;
                d.set_item("clipped_fraction", c.clipped_fraction)?;
                d.set_item("region_px", c.region_px.to_vec())?;
                Ok(d)
            })
            .collect()
    }

    /// The print's MTF divided out (`measure --chart-mtf`): one dict per curve.
    #[pyo3(signature = (print, chart_length_mm=None))]
    fn chart_mtf<'py>(
        &self,
        py: Python<'py>,
        print: &str,
        chart_length_mm: Option<f64>,
    ) -> PyResult<Vec<Bound<'py, PyDict>>> {
        use sweepmtf::measure::chart_mtf::{ChartMtf, ChartMtfError, chart_curve_scaled};
        let err = |e: ChartMtfError| match e {
            ChartMtfError::File { .. } => PyOSError::new_err(e.to_string()),
            _ => value_err(e),
        };
        let chart = ChartMtf::from_arg(print).map_err(err)?;
        let mut out = Vec::new();
        for (i, c) in self.m.curves.iter().enumerate() {
            let cc = chart_curve_scaled(c, &chart, chart_length_mm).map_err(err)?;
            let g = sweepmtf::report::chart_mtf::camera_figures(&self.m, i, &cc);
            let d = PyDict::new(py);
            d.set_item("channel", &c.channel)?;
            d.set_item("sweep_id", &c.sweep_id)?;
            d.set_item("chart_mtf", PyArray1::from_vec(py, cc.chart_mtf.clone()))?;
            d.set_item("camera_mtf", PyArray1::from_vec(py, cc.camera_mtf.clone()))?;
            d.set_item(
                "camera_mtf_err",
                PyArray1::from_vec(py, cc.camera_mtf_err.clone()),
            )?;
            let flags: Vec<&str> = cc.flag.iter().map(|f| f.as_str()).collect();
            d.set_item("chart_flag", flags)?;
            d.set_item("camera_mtf50_cy_px", g.mtf50_cy_px)?;
            d.set_item("camera_mtf50p_cy_px", g.mtf50p_cy_px)?;
            d.set_item("camera_mtf10_cy_px", g.mtf10_cy_px)?;
            d.set_item("print", chart.describe())?;
            out.push(d);
        }
        Ok(out)
    }
}

/// Code values of a numpy array (C-contiguous, H×W or H×W×3; uint8, uint16 or
/// float32) as the library's samples, with (width, height, channels). The one copy.
fn samples_of(
    py: Python<'_>,
    photo: &Bound<'_, PyAny>,
) -> PyResult<(usize, usize, usize, Samples)> {
    fn shape(s: &[usize]) -> PyResult<(usize, usize, usize)> {
        match *s {
            [h, w] => Ok((w, h, 1)),
            [h, w, 3] => Ok((w, h, 3)),
            _ => Err(value_err(format!(
                "photo array of shape {s:?}: use H×W (grey) or H×W×3 (RGB)"
            ))),
        }
    }
    fn take<T: numpy::Element + Copy + Send + Sync>(
        py: Python<'_>,
        a: PyReadonlyArrayDyn<'_, T>,
    ) -> PyResult<(usize, usize, usize, Vec<T>)> {
        let (w, h, c) = shape(a.shape())?;
        let s = a
            .as_slice()
            .map_err(|_| value_err("photo array is not C-contiguous"))?;
        let v = py.detach(|| s.to_vec());
        Ok((w, h, c, v))
    }
    if let Ok(a) = photo.extract::<PyReadonlyArrayDyn<'_, u8>>() {
        let (w, h, c, v) = take(py, a)?;
        Ok((w, h, c, Samples::U8(v)))
    } else if let Ok(a) = photo.extract::<PyReadonlyArrayDyn<'_, u16>>() {
        let (w, h, c, v) = take(py, a)?;
        Ok((w, h, c, Samples::U16(v)))
    } else if let Ok(a) = photo.extract::<PyReadonlyArrayDyn<'_, f32>>() {
        let (w, h, c, v) = take(py, a)?;
        Ok((w, h, c, Samples::F32(v)))
    } else {
        Err(value_err(
            "photo array must be uint8, uint16 or float32 (float64 is converted by the caller)",
        ))
    }
}

thread_local! {
    /// This (Python) thread's own pools, by thread count: two Python threads
    /// asking for 1 thread each get one worker each, not one shared worker.
    static POOLS: std::cell::RefCell<std::collections::HashMap<usize, std::sync::Arc<rayon::ThreadPool>>> =
        Default::default();
}

/// Runs `f` on `threads` worker threads of this thread's own pool (None: the global pool).
fn with_threads<T: Send>(threads: Option<usize>, f: impl FnOnce() -> T + Send) -> PyResult<T> {
    let Some(n) = threads else {
        return Ok(f());
    };
    if n == 0 {
        return Err(value_err("threads must be at least 1"));
    }
    let pool = POOLS.with(|p| -> PyResult<_> {
        let mut p = p.borrow_mut();
        if let Some(pool) = p.get(&n) {
            return Ok(pool.clone());
        }
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(n)
            .build()
            .map_err(|e| PyOSError::new_err(format!("cannot start {n} threads: {e}")))?;
        let pool = std::sync::Arc::new(pool);
        p.insert(n, pool.clone());
        Ok(pool)
    })?;
    Ok(pool.install(f))
}

/// Measures a photo file with options given as JSON, on `threads` threads (None: all cores).
#[pyfunction]
#[pyo3(signature = (path, options_json, threads=None))]
fn measure_path(
    py: Python<'_>,
    path: PathBuf,
    options_json: &str,
    threads: Option<usize>,
) -> PyResult<NativeMeasurement> {
    let opts = options(options_json)?;
    let m = py
        .detach(|| with_threads(threads, || sweepmtf::measure::measure_file(&path, &opts)))?
        .map_err(measure_err)?;
    Ok(NativeMeasurement { m })
}

/// Seconds per call of the library's `measure_file` alone (no Python objects
/// made), the best of `repeats` calls: the reference for the bindings' overhead.
#[pyfunction]
fn time_measure_path(
    py: Python<'_>,
    path: PathBuf,
    options_json: &str,
    repeats: usize,
) -> PyResult<f64> {
    let opts = options(options_json)?;
    py.detach(|| {
        let mut best = f64::INFINITY;
        for _ in 0..repeats.max(1) {
            let t = std::time::Instant::now();
            let m = sweepmtf::measure::measure_file(&path, &opts).map_err(measure_err)?;
            best = best.min(t.elapsed().as_secs_f64());
            drop(m);
        }
        Ok(best)
    })
}

/// Measures a numpy array (code values) with options given as JSON; `name` stands for it in messages.
#[pyfunction]
#[pyo3(signature = (photo, options_json, name, threads=None))]
fn measure_array(
    py: Python<'_>,
    photo: &Bound<'_, PyAny>,
    options_json: &str,
    name: &str,
    threads: Option<usize>,
) -> PyResult<NativeMeasurement> {
    let opts = options(options_json)?;
    let (w, h, c, samples) = samples_of(py, photo)?;
    let m = py
        .detach(|| {
            with_threads(threads, || {
                let dec =
                    decoded_from_samples(w, h, c, samples).map_err(|failure| MeasureError {
                        path: name.to_string(),
                        failure,
                    })?;
                measure_in_memory(&dec, name, &opts)
            })
        })?
        .map_err(measure_err)?;
    Ok(NativeMeasurement { m })
}

/// Decodes a JPEG, PNG or TIFF file to its code values: (array H×W or H×W×3, bits).
#[pyfunction]
fn read_photo<'py>(py: Python<'py>, path: PathBuf) -> PyResult<(Bound<'py, PyAny>, u32)> {
    let dec = py
        .detach(|| decode_file(&path))
        .map_err(|e| PyOSError::new_err(e.to_string()))?;
    let bits = dec.bits();
    let (h, w, c) = (dec.height, dec.width, dec.channels);
    let flat = match dec.samples {
        Samples::U8(v) => PyArray1::from_vec(py, v).into_any(),
        Samples::U16(v) => PyArray1::from_vec(py, v).into_any(),
        Samples::F32(v) => PyArray1::from_vec(py, v).into_any(),
    };
    let shape: Vec<usize> = if c == 1 { vec![h, w] } else { vec![h, w, c] };
    Ok((flat.call_method1("reshape", (shape,))?, bits))
}

fn load_target(path: &Path) -> PyResult<sweepmtf::target::Target> {
    sweepmtf::target::Target::load(path).map_err(|e| PyOSError::new_err(e.to_string()))
}

/// The charts found, as dicts (corners, homography, fiducials, score, warnings).
fn located_dicts<'py>(
    py: Python<'py>,
    found: Vec<sweepmtf::locate::Located>,
) -> PyResult<Vec<Bound<'py, PyDict>>> {
    found
        .into_iter()
        .map(|l| {
            let d = PyDict::new(py);
            d.set_item("corners_px", l.corners_px.to_vec())?;
            let m: Vec<Vec<f64>> = l.homography.m.chunks(3).map(|r| r.to_vec()).collect();
            d.set_item("homography", m)?;
            d.set_item("fiducials", l.fiducials)?;
            d.set_item("hidden", l.hidden)?;
            d.set_item("warnings", l.warnings)?;
            d.set_item("score", l.score)?;
            Ok(d)
        })
        .collect()
}

/// Finds every copy of a target in a photo file, left to right.
#[pyfunction]
fn locate_path<'py>(
    py: Python<'py>,
    path: PathBuf,
    target: PathBuf,
) -> PyResult<Vec<Bound<'py, PyDict>>> {
    let t = load_target(&target)?;
    let found = py.detach(|| locate_file(&path, &t)).map_err(measure_err)?;
    located_dicts(py, found)
}

/// Finds every copy of a target in a numpy array (code values), left to right.
#[pyfunction]
fn locate_array<'py>(
    py: Python<'py>,
    photo: &Bound<'py, PyAny>,
    target: PathBuf,
    name: &str,
) -> PyResult<Vec<Bound<'py, PyDict>>> {
    let t = load_target(&target)?;
    let (w, h, c, samples) = samples_of(py, photo)?;
    let found = py
        .detach(|| {
            let dec = decoded_from_samples(w, h, c, samples)?;
            locate_in_memory(&dec, &t)
        })
        .map_err(|failure| {
            measure_err(MeasureError {
                path: name.to_string(),
                failure,
            })
        })?;
    located_dicts(py, found)
}

/// A model system: the product of the named factors.
#[pyclass(frozen, module = "sweepmtf._native")]
struct NativeModel {
    system: sweepmtf::model::System,
    name: Option<String>,
}

#[pymethods]
impl NativeModel {
    /// Builds a system from a TOML system file and/or (kind, spec) pairs, as the CLI's flags.
    #[new]
    #[pyo3(signature = (specs, system=None))]
    fn new(specs: Vec<(String, String)>, system: Option<PathBuf>) -> PyResult<Self> {
        use sweepmtf::model::spec::parse_factor;
        use sweepmtf::model::system_file::SystemFile;
        let mut sys = sweepmtf::model::System::default();
        let mut name = None;
        if let Some(path) = &system {
            let shown = path.display().to_string();
            let text = std::fs::read_to_string(path)
                .map_err(|e| PyOSError::new_err(format!("--system {shown}: {e}")))?;
            let file = SystemFile::parse(&text, &shown).map_err(value_err)?;
            sys = file.build(&shown).map_err(value_err)?;
            name = file.name;
        }
        for (kind, spec) in &specs {
            let f =
                parse_factor(kind, spec).map_err(|e| value_err(format!("--{kind} {spec}: {e}")))?;
            sys.factors.push(f);
        }
        if sys.factors.is_empty() {
            return Err(value_err(
                "no model factor named; give system=FILE or at least one of aperture, sampling, optics, diffusion, cte, olpf, gaussian, defocus",
            ));
        }
        Ok(NativeModel { system: sys, name })
    }
    /// The system file's name, if any.
    #[getter]
    fn name(&self) -> Option<String> {
        self.name.clone()
    }
    /// The factors' names, in order.
    #[getter]
    fn factors(&self) -> Vec<String> {
        self.system.factors.iter().map(|f| f.name()).collect()
    }
    /// Nyquist frequencies (u, v), cycles/mm, of the first sampling factor.
    #[getter]
    fn nyquist(&self) -> Option<(f64, f64)> {
        self.system.nyquist()
    }
    /// Complex OTF at (u, v) cycles/mm, 1-D float64 arrays of equal length.
    fn otf<'py>(
        &self,
        py: Python<'py>,
        u: PyReadonlyArray1<'py, f64>,
        v: PyReadonlyArray1<'py, f64>,
    ) -> PyResult<Bound<'py, PyArray1<Complex64>>> {
        let (u, v) = (
            u.as_slice().map_err(value_err)?,
            v.as_slice().map_err(value_err)?,
        );
        if u.len() != v.len() {
            return Err(value_err("u and v differ in length"));
        }
        let out: Vec<Complex64> = py.detach(|| {
            u.par_iter()
                .with_min_len(256)
                .zip(v.par_iter())
                .map(|(&a, &b)| self.system.otf(a, b))
                .collect()
        });
        Ok(PyArray1::from_vec(py, out))
    }
    /// A cut along `direction` (u, v or deg=θ) from 0 to f_max cycles/mm in `points` samples.
    fn cut<'py>(
        &self,
        py: Python<'py>,
        direction: &str,
        f_max: f64,
        points: usize,
    ) -> PyResult<Bound<'py, PyDict>> {
        use sweepmtf::report::model_cut::{CutDirection, compute_cut};
        let dir = CutDirection::parse(direction).map_err(|e| value_err(format!("cut: {e}")))?;
        if !(f_max.is_finite() && f_max > 0.0) {
            return Err(value_err(format!(
                "f_max must be a positive number of cycles/mm, got {f_max}"
            )));
        }
        if !(2..=10_000_000).contains(&points) {
            return Err(value_err("points must be between 2 and 10000000"));
        }
        let cut = py.detach(|| compute_cut(&self.system, dir, f_max, points));
        let d = PyDict::new(py);
        let (u, v): (Vec<f64>, Vec<f64>) = cut.uv.iter().copied().unzip();
        d.set_item("freq_cy_mm", PyArray1::from_vec(py, cut.freq))?;
        d.set_item("u_cy_mm", PyArray1::from_vec(py, u))?;
        d.set_item("v_cy_mm", PyArray1::from_vec(py, v))?;
        let mtf: Vec<f64> = cut.otf.iter().map(|o| o.norm()).collect();
        d.set_item("otf", PyArray1::from_vec(py, cut.otf))?;
        d.set_item("mtf", PyArray1::from_vec(py, mtf))?;
        let factors = PyDict::new(py);
        for (name, vals) in cut.factors {
            factors.set_item(name, PyArray1::from_vec(py, vals))?;
        }
        d.set_item("factors", factors)?;
        d.set_item("nyquist_cy_mm", cut.nyquist)?;
        Ok(d)
    }
    /// A size×size map of the MTF over ±f_max cycles/mm: (flat mtf, coords).
    fn map<'py>(&self, py: Python<'py>, f_max: f64, size: usize) -> PyResult<ArrayPair<'py>> {
        use sweepmtf::report::model_map::compute_map;
        if !(f_max.is_finite() && f_max > 0.0) {
            return Err(value_err(format!(
                "f_max must be a positive number of cycles/mm, got {f_max}"
            )));
        }
        if !(2..=4096).contains(&size) {
            return Err(value_err("size must be between 2 and 4096"));
        }
        let map = py.detach(|| compute_map(&self.system, f_max, size));
        let coords: Vec<f64> = (0..size).map(|i| map.coord(i)).collect();
        Ok((
            PyArray1::from_vec(py, map.mtf),
            PyArray1::from_vec(py, coords),
        ))
    }
}

/// A simulated shot (the library's `Shot`).
#[pyclass(frozen, module = "sweepmtf._native")]
struct NativeShot {
    shot: sweepmtf::simulate::Shot,
}

#[pymethods]
impl NativeShot {
    /// Image size (width, height), pixels.
    #[getter]
    fn size(&self) -> (usize, usize) {
        (self.shot.width, self.shot.height)
    }
    /// The recorded linear image (noise, clipping), flat float32, row-major.
    fn linear<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<f32>> {
        PyArray1::from_slice(py, &self.shot.linear)
    }
    /// The noiseless, unclipped linear signal, flat float32, row-major.
    fn signal<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<f32>> {
        PyArray1::from_slice(py, &self.shot.signal)
    }
    /// The settings document (as `STEM.json`), JSON text.
    fn settings_json(&self, photo: &str) -> String {
        self.shot.settings_json(photo).to_string()
    }
    /// The truth of every sweep: dicts of id, roi, chart_contrast and numpy columns.
    fn truth<'py>(&self, py: Python<'py>) -> PyResult<Vec<Bound<'py, PyDict>>> {
        self.shot
            .sweeps
            .iter()
            .map(|s| {
                let d = PyDict::new(py);
                let col = |f: fn(&sweepmtf::simulate::TruthRow) -> f64| {
                    PyArray1::from_vec(py, s.rows.iter().map(f).collect())
                };
                d.set_item("id", &s.id)?;
                d.set_item("roi", s.roi.to_vec())?;
                d.set_item("chart_contrast", s.chart_contrast)?;
                d.set_item("freq_cy_px", col(|r| r.freq_cy_px))?;
                d.set_item("mtf", col(|r| r.mtf))?;
                d.set_item("s_mm", col(|r| r.s_mm))?;
                d.set_item("freq_cy_mm", col(|r| r.freq_cy_mm))?;
                d.set_item("chart_freq_cy_mm", col(|r| r.chart_freq_cy_mm))?;
                d.set_item("x_px", col(|r| r.x_px))?;
                d.set_item("y_px", col(|r| r.y_px))?;
                Ok(d)
            })
            .collect()
    }
    /// Writes the photo (format from the extension) with STEM.truth.csv and STEM.json; the paths written.
    fn write(&self, py: Python<'_>, path: PathBuf) -> PyResult<Vec<PathBuf>> {
        py.detach(|| sweepmtf::simulate::write_shot(&self.shot, &path))
            .map_err(|e| match e {
                sweepmtf::simulate::SimError::Io { .. } => PyOSError::new_err(e.to_string()),
                _ => value_err(e),
            })
    }
}

/// Simulates a shot of a target through a model system with a camera given as JSON.
#[pyfunction]
#[pyo3(signature = (target, camera_json, model=None))]
fn simulate(
    py: Python<'_>,
    target: PathBuf,
    camera_json: &str,
    model: Option<&NativeModel>,
) -> PyResult<NativeShot> {
    let t = load_target(&target)?;
    let camera: sweepmtf::simulate::Camera =
        serde_json::from_str(camera_json).map_err(|e| value_err(format!("camera: {e}")))?;
    let empty = sweepmtf::model::System::default();
    let system = model.map(|m| &m.system).unwrap_or(&empty);
    let shot = py
        .detach(|| sweepmtf::simulate::render(&t, system, &camera))
        .map_err(|e| match e {
            sweepmtf::simulate::SimError::Target(_) => PyOSError::new_err(e.to_string()),
            _ => value_err(e),
        })?;
    Ok(NativeShot { shot })
}

/// The native module.
#[pymodule]
fn _native(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add("MeasurementError", m.py().get_type::<MeasurementError>())?;
    m.add_class::<NativeMeasurement>()?;
    m.add_class::<NativeModel>()?;
    m.add_class::<NativeShot>()?;
    m.add_function(wrap_pyfunction!(measure_path, m)?)?;
    m.add_function(wrap_pyfunction!(measure_array, m)?)?;
    m.add_function(wrap_pyfunction!(read_photo, m)?)?;
    m.add_function(wrap_pyfunction!(time_measure_path, m)?)?;
    m.add_function(wrap_pyfunction!(locate_path, m)?)?;
    m.add_function(wrap_pyfunction!(locate_array, m)?)?;
    m.add_function(wrap_pyfunction!(simulate, m)?)?;
    m.add_function(wrap_pyfunction!(chart::chart, m)?)?;
    Ok(())
}

mod chart;
