//! `sweepmtf chart`: arguments, the set-up ↔ frequency conversion, and the
//! atomic writing of the chart, its description (`NAME.toml`) and preview
//! (`NAME.preview.png`).

use super::{CliError, Code};
use std::fs::File;
use std::io::BufWriter;
use std::path::{Path, PathBuf};
use sweepmtf::chart::{
    self, ChartError, ChartSpec, Encoding, Format, Law, PrinterCurve, Setup, labels::format_freq,
};

/// Frequency layout on the command line.
#[derive(Debug, Clone, Copy, clap::ValueEnum)]
pub enum LawArg {
    /// Logarithmic sweep.
    Log,
    /// Linear sweep.
    Linear,
    /// Discrete constant-frequency sine patches.
    Patches,
}

/// Arguments of `sweepmtf chart`.
#[derive(Debug, clap::Args)]
pub struct Args {
    /// Frequency layout: log or linear sweep, or constant-frequency patches.
    #[arg(long, value_enum, default_value = "log")]
    pub law: LawArg,
    /// Lowest chart frequency (cycles/mm on the print).
    #[arg(long)]
    pub f_min: Option<f64>,
    /// Highest chart frequency (cycles/mm on the print).
    #[arg(long)]
    pub f_max: Option<f64>,
    /// Page size: A5, A4, A3, A2, letter (all landscape) or WxH with a unit (e.g. 400x300mm).
    #[arg(long, default_value = "A4")]
    pub size: String,
    /// Printer resolution (dots per inch).
    #[arg(long, default_value_t = 600)]
    pub dpi: u32,
    /// Modulation of the main row (0–1].
    #[arg(long)]
    pub contrast: Option<f64>,
    /// Modulations of all rows, main first (e.g. 0.8,0.4,0.2).
    #[arg(long, value_delimiter = ',')]
    pub contrasts: Vec<f64>,
    /// Mean linear reflectance of the sines (0–1).
    #[arg(long, default_value_t = 0.5)]
    pub mean: f64,
    /// Encode for a pure power-law output (reflectance = value^G) instead of sRGB.
    #[arg(long, conflicts_with = "printer_curve")]
    pub gamma: Option<f64>,
    /// Encode for a measured printer: CSV with columns `value` and `reflectance`.
    #[arg(long)]
    pub printer_curve: Option<PathBuf>,
    /// Number of patches per contrast for --law patches.
    #[arg(long, default_value_t = 12)]
    pub patches: usize,
    /// Intended camera's pixel pitch (e.g. 4.3um).
    #[arg(long)]
    pub pixel_pitch: Option<String>,
    /// Intended lens focal length (e.g. 50mm).
    #[arg(long)]
    pub focal_length: Option<String>,
    /// Intended distance from the lens to the chart (e.g. 2m).
    #[arg(long)]
    pub distance: Option<String>,
    /// Image frequency range to cover, cycles/pixel (e.g. 0.005,0.7); needs the set-up.
    #[arg(long, value_delimiter = ',')]
    pub cy_px: Vec<f64>,
    /// Chart name written into the title and the description (default: file stem).
    #[arg(long)]
    pub name: Option<String>,
    /// Also write NAME.print_mtf.csv: the printer's nominal dot model (a square dot of
    /// 1/dpi inch, |sinc(f·25.4/dpi)|) up to 1.2 × --f-max, a starting file for
    /// `measure --chart-mtf` until the print is measured.
    #[arg(long)]
    pub dot_model: bool,
    /// Output file: NAME.png, NAME.tif or NAME.pdf (NAME.toml and NAME.preview.png go beside it).
    #[arg(short = 'o', long)]
    pub output: PathBuf,
}

fn usage(m: impl Into<String>) -> CliError {
    CliError::new(Code::Usage, m)
}

fn from_chart_error(e: ChartError) -> CliError {
    let code = match e {
        ChartError::Invalid(_) | ChartError::TooLarge(_) => Code::Usage,
        ChartError::PrinterCurve(_) => Code::Input,
        ChartError::Output { .. } => Code::Output,
    };
    CliError::new(code, e.to_string())
}

/// Page size (width, height in mm, landscape for the named sizes).
pub fn parse_size(text: &str) -> Result<(f64, f64), String> {
    let named = [
        ("a5", 210.0, 148.0),
        ("a4", 297.0, 210.0),
        ("a3", 420.0, 297.0),
        ("a2", 594.0, 420.0),
        ("letter", 279.4, 215.9),
    ];
    let t = text.trim().to_ascii_lowercase();
    if let Some(&(_, w, h)) = named.iter().find(|n| n.0 == t) {
        return Ok((w, h));
    }
    let bad = || {
        format!("--size '{text}' is not A5, A4, A3, A2, letter or WxH with a unit (e.g. 400x300mm)")
    };
    let (a, b) = t.split_once('x').ok_or_else(bad)?;
    let unit: String = b
        .chars()
        .skip_while(|c| c.is_ascii_digit() || *c == '.')
        .collect();
    if unit.is_empty() {
        return Err(bad());
    }
    let w = sweepmtf::units::parse_length_mm(&format!("{a}{unit}")).map_err(|_| bad())?;
    let h = sweepmtf::units::parse_length_mm(b).map_err(|_| bad())?;
    Ok((w, h))
}

fn length(flag: &str, v: &Option<String>) -> Result<Option<f64>, CliError> {
    v.as_deref()
        .map(|t| sweepmtf::units::parse_length_mm(t).map_err(|e| usage(format!("--{flag}: {e}"))))
        .transpose()
}

/// Temporary path beside `p` for atomic writing.
fn temp_path(p: &Path) -> PathBuf {
    let name = p
        .file_name()
        .map(|n| n.to_string_lossy().to_string())
        .unwrap_or_default();
    p.with_file_name(format!(".{name}.tmp{}", std::process::id()))
}

/// The description and preview paths beside the chart: NAME.toml, NAME.preview.png.
pub fn side_paths(output: &Path) -> (PathBuf, PathBuf) {
    let stem = output
        .file_stem()
        .map(|s| s.to_string_lossy().to_string())
        .unwrap_or_default();
    (
        output.with_file_name(format!("{stem}.toml")),
        output.with_file_name(format!("{stem}.preview.png")),
    )
}

/// Runs `sweepmtf chart`.
pub fn run(args: &Args) -> Result<(), CliError> {
    let format = Format::from_path(&args.output).ok_or_else(|| {
        usage(format!(
            "{}: output must end in .png, .tif, .tiff or .pdf",
            args.output.display()
        ))
    })?;
    let (width_mm, height_mm) = parse_size(&args.size).map_err(usage)?;
    // Set-up and frequency range.
    let pitch = length("pixel-pitch", &args.pixel_pitch)?;
    let focal = length("focal-length", &args.focal_length)?;
    let dist = length("distance", &args.distance)?;
    let setup = match (pitch, focal, dist) {
        (Some(p), Some(f), Some(d)) => Some(Setup::new(p, f, d).map_err(from_chart_error)?),
        (None, None, None) => None,
        _ => {
            return Err(usage(
                "--pixel-pitch, --focal-length and --distance must be given together",
            ));
        }
    };
    let (f_min, f_max) = match (args.f_min, args.f_max, args.cy_px.as_slice()) {
        (Some(a), Some(b), []) => (a, b),
        (None, None, [lo, hi]) => {
            let s = setup.ok_or_else(|| {
                usage("--cy-px needs --pixel-pitch, --focal-length and --distance")
            })?;
            if !(*lo > 0.0 && lo < hi) {
                return Err(usage(format!(
                    "--cy-px {lo},{hi}: need 0 < low < high (cycles/pixel)"
                )));
            }
            (s.chart_cy_mm(*lo), s.chart_cy_mm(*hi))
        }
        (None, None, []) => {
            return Err(usage(
                "give the chart range (--f-min, --f-max in cycles/mm) or the set-up \
                 (--pixel-pitch, --focal-length, --distance, --cy-px LOW,HIGH)",
            ));
        }
        (_, _, [_, _]) => {
            return Err(usage("give either --f-min/--f-max or --cy-px, not both"));
        }
        (_, _, []) => return Err(usage("--f-min and --f-max must be given together")),
        _ => return Err(usage("--cy-px takes two values: LOW,HIGH (cycles/pixel)")),
    };
    // Encoding.
    let encoding = match (&args.gamma, &args.printer_curve) {
        (Some(g), _) => {
            if !(g.is_finite() && *g > 0.0) {
                return Err(usage(format!("--gamma {g} must be positive")));
            }
            Encoding::Gamma(*g)
        }
        (None, Some(p)) => Encoding::Printer(PrinterCurve::load(p).map_err(from_chart_error)?),
        (None, None) => Encoding::Srgb,
    };
    let contrasts = match (args.contrast, args.contrasts.is_empty()) {
        (None, true) => vec![0.8],
        (Some(c), true) => vec![c],
        (None, false) => args.contrasts.clone(),
        (Some(c), false) => {
            if args.contrasts[0] != c {
                return Err(usage(format!(
                    "--contrast {c} differs from the first of --contrasts ({}); the first row is the main one",
                    args.contrasts[0]
                )));
            }
            args.contrasts.clone()
        }
    };
    let name = args.name.clone().unwrap_or_else(|| {
        args.output
            .file_stem()
            .map(|s| s.to_string_lossy().to_string())
            .unwrap_or_else(|| "chart".into())
    });
    let spec = ChartSpec {
        name,
        law: match args.law {
            LawArg::Log => Law::Log,
            LawArg::Linear => Law::Linear,
            LawArg::Patches => Law::Patches,
        },
        f_min_cy_mm: f_min,
        f_max_cy_mm: f_max,
        width_mm,
        height_mm,
        dpi: args.dpi,
        contrasts,
        mean: args.mean,
        patch_count: args.patches,
        darkest: encoding.darkest(),
        encoding_name: encoding.describe(),
    };
    let chart = chart::layout(&spec).map_err(from_chart_error)?;
    format.check_size(&chart).map_err(from_chart_error)?;
    for w in &chart.warnings {
        super::messages::warning(w);
    }
    let dot_model = args.dot_model.then(|| {
        let stem = args
            .output
            .file_stem()
            .map(|s| s.to_string_lossy().to_string())
            .unwrap_or_default();
        let model = sweepmtf::print_mtf::PrintMtf::Dots {
            dpi: args.dpi as f64,
        };
        (
            args.output.with_file_name(format!("{stem}.print_mtf.csv")),
            sweepmtf::print_mtf::table_csv(&model, 1.2 * f_max, 400).into_bytes(),
        )
    });
    write_all(&chart, &encoding, format, &args.output, dot_model)?;
    let mut line = format!(
        "wrote {} ({}×{} px, {}×{} mm at {} dpi): {} {}–{} cy/mm, {:.1} dots/cycle at the top",
        args.output.display(),
        chart.width_px,
        chart.height_px,
        format_freq(width_mm),
        format_freq(height_mm),
        args.dpi,
        spec.law.name(),
        format_freq(f_min),
        format_freq(f_max),
        chart.dots_per_cycle
    );
    if let Some(s) = setup {
        line.push_str(&format!(
            "; = {}–{} cy/px for {} pixels, {} mm lens at {} mm",
            format_freq(s.cy_px(f_min)),
            format_freq(s.cy_px(f_max)),
            sweepmtf::units::format_um(s.pixel_pitch_mm),
            format_freq(s.focal_length_mm),
            format_freq(s.distance_mm)
        ));
    }
    println!("{line}");
    Ok(())
}

/// Writes chart, description and preview to temporary files, then renames them all.
fn write_all(
    chart: &chart::Chart,
    encoding: &Encoding,
    format: Format,
    output: &Path,
    extra: Option<(PathBuf, Vec<u8>)>,
) -> Result<(), CliError> {
    let (toml_path, preview_path) = side_paths(output);
    let mut targets = vec![output.to_path_buf(), toml_path, preview_path];
    if let Some((p, _)) = &extra {
        targets.push(p.clone());
    }
    let temps: Vec<PathBuf> = targets.iter().map(|p| temp_path(p)).collect();
    let cleanup = |temps: &[PathBuf]| {
        for t in temps {
            let _ = std::fs::remove_file(t);
        }
    };
    let out_err = |p: &Path, e: String| {
        CliError::new(Code::Output, format!("{}: cannot write: {e}", p.display()))
    };
    let result = (|| -> Result<(), CliError> {
        let f = File::create(&temps[0]).map_err(|e| out_err(output, e.to_string()))?;
        let written = chart::write_chart(
            chart,
            encoding,
            format,
            &mut BufWriter::with_capacity(1 << 20, f),
            &output.display().to_string(),
        )
        .map_err(from_chart_error)?;
        std::fs::write(&temps[1], chart.target.to_toml())
            .map_err(|e| out_err(&targets[1], e.to_string()))?;
        let f = File::create(&temps[2]).map_err(|e| out_err(&targets[2], e.to_string()))?;
        written
            .preview
            .write_png(BufWriter::new(f))
            .map_err(|e| out_err(&targets[2], e.to_string()))?;
        if let Some((p, bytes)) = &extra {
            std::fs::write(&temps[3], bytes).map_err(|e| out_err(p, e.to_string()))?;
        }
        for (t, p) in temps.iter().zip(&targets) {
            std::fs::rename(t, p).map_err(|e| out_err(p, e.to_string()))?;
        }
        Ok(())
    })();
    if result.is_err() {
        cleanup(&temps);
    }
    result
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn sizes() {
        assert_eq!(parse_size("A4").unwrap(), (297.0, 210.0));
        assert_eq!(parse_size("a3").unwrap(), (420.0, 297.0));
        assert_eq!(parse_size("400x300mm").unwrap(), (400.0, 300.0));
        let (w, h) = parse_size("10x8in").unwrap();
        assert!((w - 254.0).abs() < 1e-9 && (h - 203.2).abs() < 1e-9);
        assert!(parse_size("400x300").is_err());
        assert!(parse_size("B5").is_err());
    }

    #[test]
    fn side_files() {
        let (t, p) = side_paths(Path::new("out/chart.v2.pdf"));
        assert_eq!(t, Path::new("out/chart.v2.toml"));
        assert_eq!(p, Path::new("out/chart.v2.preview.png"));
    }
}
