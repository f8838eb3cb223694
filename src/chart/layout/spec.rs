//! What defines a chart: the frequency [`Law`] and the [`ChartSpec`], and the
//! check of every parameter before a layout.

use crate::chart::labels::format_freq;
use crate::chart::{ChartError, MIN_DOTS_PER_CYCLE, WARN_DOTS_PER_CYCLE};

/// How frequency is laid out along the chart.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Law {
    /// Logarithmic sweep: f(s) = f_min·(f_max/f_min)^(s/L).
    Log,
    /// Linear sweep: f(s) = f_min + (f_max − f_min)·s/L.
    Linear,
    /// Discrete constant-frequency patches, log-spaced from f_min to f_max.
    Patches,
}

impl Law {
    /// The law's name as used on the command line.
    pub fn name(&self) -> &'static str {
        match self {
            Law::Log => "log",
            Law::Linear => "linear",
            Law::Patches => "patches",
        }
    }
}

/// Everything that defines a chart.
#[derive(Debug, Clone, PartialEq)]
pub struct ChartSpec {
    /// Name written into the description and the title.
    pub name: String,
    /// Frequency layout.
    pub law: Law,
    /// Lowest chart frequency (cycles/mm on the print).
    pub f_min_cy_mm: f64,
    /// Highest chart frequency (cycles/mm on the print).
    pub f_max_cy_mm: f64,
    /// Page width (mm); sweeps run along it.
    pub width_mm: f64,
    /// Page height (mm).
    pub height_mm: f64,
    /// Printer resolution (dots per inch).
    pub dpi: u32,
    /// Modulation of each row of sweeps/patches; the first is the main one (0–1].
    pub contrasts: Vec<f64>,
    /// Mean linear reflectance of the sines (0–1).
    pub mean: f64,
    /// Number of patches per contrast for [`Law::Patches`].
    pub patch_count: usize,
    /// Darkest reflectance the output encoding can print (0 for sRGB/gamma).
    pub darkest: f64,
    /// Encoding named in the title ("sRGB", "gamma 2.2", …).
    pub encoding_name: String,
}

impl ChartSpec {
    /// A default spec: log sweep on A4 landscape at 600 dpi, contrast 0.8, mean 0.5.
    pub fn new(law: Law, f_min_cy_mm: f64, f_max_cy_mm: f64) -> ChartSpec {
        ChartSpec {
            name: "sweepmtf chart".into(),
            law,
            f_min_cy_mm,
            f_max_cy_mm,
            width_mm: 297.0,
            height_mm: 210.0,
            dpi: 600,
            contrasts: vec![0.8],
            mean: 0.5,
            patch_count: 12,
            darkest: 0.0,
            encoding_name: "sRGB".into(),
        }
    }
}

pub(super) fn check_spec(s: &ChartSpec) -> Result<(f64, Vec<String>), ChartError> {
    let inv = |m: String| Err(ChartError::Invalid(m));
    let fin = |v: f64| v.is_finite();
    if !(fin(s.f_min_cy_mm) && s.f_min_cy_mm > 0.0) {
        return inv(format!(
            "--f-min {} must be a positive frequency (cycles/mm)",
            s.f_min_cy_mm
        ));
    }
    if !(fin(s.f_max_cy_mm) && s.f_max_cy_mm > 0.0) {
        return inv(format!(
            "--f-max {} must be a positive frequency (cycles/mm)",
            s.f_max_cy_mm
        ));
    }
    if s.f_min_cy_mm >= s.f_max_cy_mm {
        return inv(format!(
            "--f-min {} must be below --f-max {}",
            s.f_min_cy_mm, s.f_max_cy_mm
        ));
    }
    if !(fin(s.width_mm) && fin(s.height_mm) && s.width_mm > 0.0 && s.height_mm > 0.0) {
        return inv(format!(
            "chart size {}×{} mm must be positive",
            s.width_mm, s.height_mm
        ));
    }
    if !(25..=10_000).contains(&s.dpi) {
        return inv(format!("--dpi {} must lie between 25 and 10000", s.dpi));
    }
    if s.contrasts.is_empty() {
        return inv("at least one contrast is needed".into());
    }
    if !(fin(s.mean) && s.mean > 0.0 && s.mean < 1.0) {
        return inv(format!("--mean {} must lie in (0, 1)", s.mean));
    }
    for &c in &s.contrasts {
        if !(fin(c) && c > 0.0 && c <= 1.0) {
            return inv(format!("contrast {c} must lie in (0, 1]"));
        }
        if s.mean * (1.0 + c) > 1.0 + 1e-12 {
            return inv(format!(
                "mean {} × (1 + contrast {c}) = {:.4} exceeds paper white (1); lower --mean or the contrast",
                s.mean,
                s.mean * (1.0 + c)
            ));
        }
        if s.mean * (1.0 - c) < s.darkest - 1e-12 {
            return inv(format!(
                "mean {} × (1 − contrast {c}) = {:.4} is darker than the printer's black ({:.4}); \
                 lower the contrast or raise --mean",
                s.mean,
                s.mean * (1.0 - c),
                s.darkest
            ));
        }
    }
    if s.law == Law::Patches && !(2..=60).contains(&s.patch_count) {
        return inv(format!(
            "--patches {} must lie between 2 and 60",
            s.patch_count
        ));
    }
    let dpc = s.dpi as f64 / 25.4 / s.f_max_cy_mm;
    let mut warnings = Vec::new();
    if dpc < MIN_DOTS_PER_CYCLE {
        return inv(format!(
            "--f-max {} cy/mm leaves {:.2} printer dots per cycle at {} dpi; at least {} are needed \
             (raise --dpi to {} or lower --f-max to {})",
            s.f_max_cy_mm,
            dpc,
            s.dpi,
            MIN_DOTS_PER_CYCLE,
            (MIN_DOTS_PER_CYCLE * 25.4 * s.f_max_cy_mm).ceil(),
            format_freq(s.dpi as f64 / 25.4 / MIN_DOTS_PER_CYCLE)
        ));
    }
    if dpc < WARN_DOTS_PER_CYCLE {
        warnings.push(format!(
            "only {:.2} printer dots per cycle at {} cy/mm ({} dpi): the printed highest frequencies \
             will not be clean sines; {} dots per cycle or more are advised",
            dpc, s.f_max_cy_mm, s.dpi, WARN_DOTS_PER_CYCLE
        ));
    }
    Ok((dpc, warnings))
}
