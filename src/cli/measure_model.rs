//! `measure --model SYSTEM.toml|auto [--wavelength 550nm]`: the model beside
//! the measurement (an `mtf_model` CSV column, a dashed curve on the plot, the
//! model's MTF50 and measured/modelled MTF50 in the summary; for sine patches
//! a ring at each patch's model value and the median and furthest
//! measured/model), and the photo's EXIF facts in the summary and as the
//! plot's caption.

use super::{CliError, Code};
use serde_json::Value;
use std::path::Path;
use sweepmtf::measure::Measurement;
use sweepmtf::measure::PatchResult;
use sweepmtf::measure::chart_mtf::{ChartCurve, ChartMtf, ChartMtfError, chart_curve_scaled};
use sweepmtf::measure::lens_mtf::{LensCurve, SensorPart, is_sensor_factor, lens_curve};
use sweepmtf::measure::model_overlay::{
    CurveModel, MIN_MODEL_FOR_RATIO, ModelOverlay, ModelSource, OverlayError, PatchComparison,
    compare_patches, evaluate, evaluate_patches,
};
use sweepmtf::photo::exif::ExifFacts;
use sweepmtf::report::chart_mtf::{
    add_chart_columns, add_chart_json, camera_figures, chart_plot_curves, print_plot_curve,
};
use sweepmtf::report::lens_mtf::{add_lens_columns, add_lens_json, lens_figures, lens_plot_curves};
use sweepmtf::report::model_overlay::{
    PlotExtras, add_exif, add_model, add_mtf_model_column, add_patch_comparison,
    patch_comparison_text, plot_extras,
};

/// The model options of `sweepmtf measure`.
#[derive(Debug, Clone, clap::Args)]
pub struct ModelArgs {
    /// Draw a model beside the measurement: a system TOML file, or `auto`
    /// (diffraction at the EXIF f-number × a square pixel aperture of the pitch).
    #[arg(long, value_name = "SYSTEM.toml|auto")]
    pub model: Option<String>,
    /// Wavelength of the `auto` model's diffraction (default 550nm).
    #[arg(long, value_name = "LENGTH")]
    pub wavelength: Option<String>,
    /// Also give the lens MTF: the MTF divided by the sensor part (the
    /// `--model` file's aperture and OLPF factors; else a 100 % fill square
    /// pixel); points where that divisor is below 0.2 are flagged, not given.
    #[arg(long)]
    pub lens_mtf: bool,
    /// Also give the camera MTF: the MTF divided by the print's own MTF at each
    /// point's chart frequency (needs --target). FILE: the `.mtf.csv` measured from a
    /// scan or close, sharp capture of the same print; or a model,
    /// gaussian:sigma=LENGTH or dots:dpi=N. Points where the print's MTF is below
    /// 0.3 are flagged, not given.
    #[arg(long, value_name = "FILE|gaussian:sigma=LENGTH|dots:dpi=N")]
    pub chart_mtf: Option<String>,
    /// With --chart-mtf and no --target: the printed length of the sweep strip
    /// between the --roi's short edges (corners 1–4 and 2–3), e.g. 200mm.
    #[arg(long, value_name = "LENGTH", requires = "chart_mtf")]
    pub chart_length: Option<String>,
}

/// A chart MTF that cannot be used: a bad model string or no scale exits 2, a bad file 3.
fn chart_err(e: ChartMtfError) -> CliError {
    match e {
        ChartMtfError::File { .. } => CliError::new(Code::Input, e.to_string()),
        ChartMtfError::Spec { .. } | ChartMtfError::NoScale | ChartMtfError::BadLength => {
            CliError::usage(e.to_string())
        }
    }
}

fn overlay_err(e: OverlayError) -> CliError {
    match e {
        OverlayError::Usage(_) => CliError::usage(e.to_string()),
        OverlayError::Model(_) => CliError::new(Code::Input, e.to_string()),
    }
}

/// What is known before measuring: the EXIF facts and the model source (file read and checked).
#[derive(Debug)]
pub struct Prepared {
    facts: ExifFacts,
    source: Option<ModelSource>,
    wavelength_mm: f64,
    lens_mtf: bool,
    /// `--chart-mtf`: the print's MTF (file read and checked before measuring).
    chart: Option<ChartMtf>,
    /// `--chart-length`: the printed length (mm) of a target-less strip.
    chart_length_mm: Option<f64>,
}

/// Reads the EXIF facts and the model file; checks `auto` has an f-number. Runs before measuring.
pub fn prepare(a: &ModelArgs, photo: &Path) -> Result<Prepared, CliError> {
    let facts = sweepmtf::photo::exif::read_facts(photo).unwrap_or_default();
    prepare_with(a, facts, &photo.display().to_string())
}

/// [`prepare`] with the EXIF facts already read (`sweepmtf gui`, which holds
/// uploaded photos in memory); `name` is the photo as shown in messages.
pub fn prepare_with(a: &ModelArgs, facts: ExifFacts, name: &str) -> Result<Prepared, CliError> {
    let wavelength_mm = match &a.wavelength {
        None => 550e-6,
        Some(t) => {
            if a.model.as_deref() != Some("auto") {
                return Err(CliError::usage(
                    "--wavelength applies only to --model auto (a system file names its own)",
                ));
            }
            let w = sweepmtf::units::parse_length_mm(t)
                .map_err(|e| CliError::usage(format!("--wavelength: {e}")))?;
            if !(w > 0.0 && w < 0.1) {
                return Err(CliError::usage(format!(
                    "--wavelength {t}: not a plausible wavelength"
                )));
            }
            w
        }
    };
    let source = match a.model.as_deref() {
        None => None,
        Some("auto") => {
            if facts.f_number.is_none() {
                return Err(CliError::usage(format!(
                    "--model auto: {name} has no usable EXIF f-number, so diffraction cannot be \
                     placed; give --model SYSTEM.toml instead"
                )));
            }
            Some(ModelSource::Auto)
        }
        Some(file) => Some(ModelSource::from_file(Path::new(file)).map_err(overlay_err)?),
    };
    // A model without sensor factors leaves nothing to divide by: refused before measuring.
    if a.lens_mtf
        && let Some(ModelSource::File { system, .. }) = &source
        && !system.factors.iter().any(|f| is_sensor_factor(&f.name()))
    {
        let e = SensorPart::from_system(system.clone(), Some(1.0));
        if let Err(e) = e {
            return Err(CliError::usage(e.to_string()));
        }
    }
    let chart = a
        .chart_mtf
        .as_deref()
        .map(ChartMtf::from_arg)
        .transpose()
        .map_err(chart_err)?;
    let chart_length_mm = match &a.chart_length {
        None => None,
        Some(t) => {
            let l = sweepmtf::units::parse_length_mm(t)
                .map_err(|e| CliError::usage(format!("--chart-length: {e}")))?;
            if !(l > 0.0 && l.is_finite()) {
                return Err(chart_err(ChartMtfError::BadLength));
            }
            Some(l)
        }
    };
    Ok(Prepared {
        facts,
        source,
        wavelength_mm,
        lens_mtf: a.lens_mtf,
        chart,
        chart_length_mm,
    })
}

/// The model evaluated beside a measurement, and what it adds to each output.
#[derive(Debug)]
pub struct Extras {
    facts: ExifFacts,
    model: Option<(ModelOverlay, Vec<CurveModel>)>,
    /// Model MTF of each sine patch (empty without a model).
    patch_model: Vec<f64>,
    /// The patches (for naming the furthest one) and measured/model over them.
    patch_cmp: Option<(Vec<PatchResult>, PatchComparison)>,
    /// Extras for the MTF plot.
    pub plot: PlotExtras,
    /// `--lens-mtf`: the divisor and the lens MTF of each curve.
    lens: Option<(SensorPart, Vec<LensCurve>)>,
    /// `--chart-mtf`: the print's MTF and the camera MTF of each curve.
    chart: Option<(ChartMtf, Vec<ChartCurve>)>,
}

impl Prepared {
    /// Builds the model at the measurement's pixel pitch and evaluates it at every point.
    pub fn finish(&self, m: &Measurement) -> Result<Extras, CliError> {
        let model = match self.source.clone() {
            None => None,
            Some(src) => {
                let o = ModelOverlay::build(src, &self.facts, m.pixel_pitch_mm, self.wavelength_mm)
                    .map_err(overlay_err)?;
                let cms = evaluate(m, &o);
                Some((o, cms))
            }
        };
        let lens = if self.lens_mtf {
            let sensor = match &self.source {
                Some(ModelSource::File { system, .. }) => {
                    SensorPart::from_system(system.clone(), m.pixel_pitch_mm)
                        .map_err(|e| CliError::usage(e.to_string()))?
                }
                // `auto`'s sensor part is the square pixel of the pitch: the default.
                _ => SensorPart::SquarePixel,
            };
            let lcs: Vec<LensCurve> = m.curves.iter().map(|c| lens_curve(c, &sensor)).collect();
            Some((sensor, lcs))
        } else {
            None
        };
        let chart = match &self.chart {
            Some(ch) => {
                let ccs = m
                    .curves
                    .iter()
                    .map(|c| chart_curve_scaled(c, ch, self.chart_length_mm))
                    .collect::<Result<Vec<_>, _>>()
                    .map_err(chart_err)?;
                Some((ch.clone(), ccs))
            }
            None => None,
        };
        let has_facts = !self.facts.describe().is_empty();
        let mut plot = plot_extras(
            model.as_ref().map(|(o, c)| (o, c.as_slice())),
            has_facts.then_some(&self.facts),
            m,
        );
        let patch_model = model
            .as_ref()
            .map(|(o, _)| evaluate_patches(m, o))
            .unwrap_or_default();
        let patch_cmp = compare_patches(&m.patches, &patch_model).map(|c| (m.patches.clone(), c));
        if let Some((_, lcs)) = &lens {
            plot.lens_curves = lens_plot_curves(m, lcs);
        }
        if let Some((_, ccs)) = &chart {
            plot.chart_curves = chart_plot_curves(m, ccs);
            plot.print_curve = print_plot_curve(m, ccs);
        }
        Ok(Extras {
            facts: self.facts.clone(),
            model,
            patch_model,
            patch_cmp,
            plot,
            lens,
            chart,
        })
    }
}

impl Extras {
    /// The curves CSV with `mtf_model` added when a model is given.
    pub fn csv(&self, bytes: Vec<u8>) -> Vec<u8> {
        let bytes = match &self.model {
            Some((_, cms)) => add_mtf_model_column(&bytes, cms),
            None => bytes,
        };
        let bytes = match &self.lens {
            Some((_, lcs)) => add_lens_columns(&bytes, lcs),
            None => bytes,
        };
        match &self.chart {
            Some((_, ccs)) => add_chart_columns(&bytes, ccs),
            None => bytes,
        }
    }

    /// The sine-patch CSV with `mtf_model` added when a model is given.
    pub fn patches_csv(&self, bytes: Vec<u8>) -> Vec<u8> {
        if self.patch_model.is_empty() {
            bytes
        } else {
            sweepmtf::report::model_overlay::add_model_values(&bytes, &self.patch_model)
        }
    }

    /// Warnings the extras add: with `--chart-mtf`, each curve whose measured
    /// frequencies pass the point where the print stops being sharp enough
    /// (print MTF < 0.99: its plain MTF there is lowered by the print by more
    /// than 1 %).
    pub fn warnings(&self, m: &Measurement) -> Vec<String> {
        let Some((_, ccs)) = &self.chart else {
            return Vec::new();
        };
        m.curves
            .iter()
            .zip(ccs)
            .filter_map(|(c, l)| {
                let (f, n) = l.soft_from(c)?;
                Some(format!(
                    "{}/{}: the print's MTF is below {} from {f:.3} cy/px on ({n} points): the MTF there includes the print's loss; camera_mtf is the camera's own",
                    c.channel,
                    c.sweep_id,
                    sweepmtf::chart::suitability::SHARP_ENOUGH
                ))
            })
            .collect()
    }

    /// The JSON summary with `exif` and, with a model, `model` and the MTF50 ratios.
    pub fn json(&self, mut v: Value, m: &Measurement) -> Value {
        add_exif(&mut v, &self.facts);
        if let Some((s, lcs)) = &self.lens {
            add_lens_json(&mut v, m, s, lcs);
        }
        if let Some((ch, ccs)) = &self.chart {
            add_chart_json(&mut v, m, ch, ccs);
        }
        if let Some(Value::Array(w)) = v.get_mut("warnings") {
            w.extend(self.warnings(m).into_iter().map(Value::String));
        }
        if let Some((o, cms)) = &self.model {
            add_model(&mut v, o, cms);
            if let Some((ps, c)) = &self.patch_cmp {
                add_patch_comparison(&mut v, c, ps);
            }
        }
        v
    }

    /// Text appended to the summary line: the model's MTF50 and the ratio per
    /// sweep, and for sine patches the median and furthest measured/model.
    pub fn line_suffix(&self, m: &Measurement) -> String {
        let lens = match &self.lens {
            Some((_, lcs)) => lcs
                .iter()
                .enumerate()
                .map(|(i, l)| match lens_figures(m, i, l).mtf50_cy_px {
                    Some(f) => format!(" | lens MTF50 {f:.3} cy/px"),
                    None => " | lens MTF50 not reached".to_string(),
                })
                .collect::<String>(),
            None => String::new(),
        };
        let chart = match &self.chart {
            Some((_, ccs)) => ccs
                .iter()
                .enumerate()
                .map(|(i, l)| match camera_figures(m, i, l).mtf50_cy_px {
                    Some(f) => format!(" | camera MTF50 {f:.3} cy/px (print divided out)"),
                    None => " | camera MTF50 not reached (print divided out)".to_string(),
                })
                .collect::<String>(),
            None => String::new(),
        };
        format!("{}{lens}{chart}", self.model_suffix())
    }

    /// The model's part of [`Extras::line_suffix`].
    fn model_suffix(&self) -> String {
        let Some((o, cms)) = &self.model else {
            return String::new();
        };
        let mut parts: Vec<String> = cms
            .iter()
            .map(|c| match (c.mtf50_model_cy_px, c.mtf50_ratio) {
                (Some(f), Some(r)) => format!("model MTF50 {f:.3} cy/px, measured/model {r:.3}"),
                (Some(f), None) => format!("model MTF50 {f:.3} cy/px"),
                _ => "model MTF50 not reached".to_string(),
            })
            .collect();
        match &self.patch_cmp {
            Some((ps, c)) => parts.push(patch_comparison_text(c, ps)),
            None if !self.patch_model.is_empty() => parts.push(format!(
                "no patch below Nyquist with model MTF ≥ {MIN_MODEL_FOR_RATIO} to compare"
            )),
            None => {}
        }
        if parts.is_empty() {
            format!(" | model {}", o.name)
        } else {
            format!(" | model {}: {}", o.name, parts.join("; "))
        }
    }
}
