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
use sweepmtf::measure::model_overlay::{
    CurveModel, MIN_MODEL_FOR_RATIO, ModelOverlay, ModelSource, OverlayError, PatchComparison,
    compare_patches, evaluate, evaluate_patches,
};
use sweepmtf::photo::exif::ExifFacts;
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
    Ok(Prepared {
        facts,
        source,
        wavelength_mm,
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
        let has_facts = !self.facts.describe().is_empty();
        let plot = plot_extras(
            model.as_ref().map(|(o, c)| (o, c.as_slice())),
            has_facts.then_some(&self.facts),
            m,
        );
        let patch_model = model
            .as_ref()
            .map(|(o, _)| evaluate_patches(m, o))
            .unwrap_or_default();
        let patch_cmp = compare_patches(&m.patches, &patch_model).map(|c| (m.patches.clone(), c));
        Ok(Extras {
            facts: self.facts.clone(),
            model,
            patch_model,
            patch_cmp,
            plot,
        })
    }
}

impl Extras {
    /// The curves CSV with `mtf_model` added when a model is given.
    pub fn csv(&self, bytes: Vec<u8>) -> Vec<u8> {
        match &self.model {
            Some((_, cms)) => add_mtf_model_column(&bytes, cms),
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

    /// The JSON summary with `exif` and, with a model, `model` and the MTF50 ratios.
    pub fn json(&self, mut v: Value) -> Value {
        add_exif(&mut v, &self.facts);
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
    pub fn line_suffix(&self) -> String {
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
