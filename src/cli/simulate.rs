//! `sweepmtf simulate`: renders a target description through a modelled camera
//! and writes the photo, `STEM.truth.csv` and `STEM.json` (see the library's
//! `simulate` module). Bad settings exit 2, an unreadable target or system
//! file 3, an unwritable output 6.

use super::factors::FactorArgs;
use super::{CliError, Code};
use std::path::PathBuf;
use sweepmtf::model::System;
use sweepmtf::simulate::{
    self, BayerOrder, Camera, Encoding, PixelAperture, RenderSettings, SimError,
};
use sweepmtf::target::{SweepLaw, Target, TargetError};
use sweepmtf::units::parse_length_mm;

/// Arguments of `sweepmtf simulate`.
#[derive(Debug, clap::Args)]
pub struct Args {
    /// Target description (TOML written by `chart`, or a sineMTF tgt.txt); `demo:log` or
    /// `demo:linear` for the built-in demo target.
    #[arg(long, value_name = "FILE")]
    pub target: String,
    /// Pixel pitch with a unit (e.g. 4.3um); default: the system's sampling grid, else 4.3um.
    #[arg(long, value_name = "LENGTH")]
    pub pixel_pitch: Option<String>,
    /// Image size in pixels, WxH.
    #[arg(long, value_name = "WxH", default_value = "1200x800")]
    pub size: String,
    /// Width of the target frame in the image, pixels (default: the target fills 80 % of the frame).
    #[arg(long, value_name = "N", conflicts_with = "magnification")]
    pub chart_px: Option<f64>,
    /// Magnification (image size / chart size).
    #[arg(long, value_name = "M")]
    pub magnification: Option<f64>,
    /// Rotation of the chart, degrees counter-clockwise on screen.
    #[arg(
        long,
        value_name = "DEG",
        default_value_t = 0.0,
        allow_hyphen_values = true
    )]
    pub rotate: f64,
    /// Perspective tilt, degrees, with the tilt axis: x (horizontal), y (vertical, default) or an angle in degrees.
    #[arg(long, value_name = "DEG[,AXIS]", allow_hyphen_values = true)]
    pub tilt: Option<String>,
    /// Focal length for the perspective, pixels (default: the frame's diagonal).
    #[arg(long, value_name = "PX")]
    pub focal_px: Option<f64>,
    /// Offset of the chart centre from the frame centre, pixels X,Y (y down).
    #[arg(long, value_name = "X,Y", allow_hyphen_values = true)]
    pub offset: Option<String>,
    /// Illumination fall-off: fraction of light lost at the frame corners.
    #[arg(
        long,
        value_name = "F",
        default_value_t = 0.0,
        allow_hyphen_values = true
    )]
    pub falloff: f64,
    /// Linear signal of paper white at the centre, fraction of clipping.
    #[arg(
        long,
        value_name = "E",
        default_value_t = 0.8,
        allow_hyphen_values = true
    )]
    pub exposure: f64,
    /// Full-well capacity in electrons: turns on photon shot noise.
    #[arg(long, value_name = "N", allow_hyphen_values = true)]
    pub full_well: Option<f64>,
    /// Read noise, electrons RMS (needs --full-well).
    #[arg(
        long,
        value_name = "E",
        default_value_t = 0.0,
        allow_hyphen_values = true
    )]
    pub read_noise: f64,
    /// Fixed-pattern noise: RMS relative gain spread of the pixels.
    #[arg(
        long,
        value_name = "F",
        default_value_t = 0.0,
        allow_hyphen_values = true
    )]
    pub fpn: f64,
    /// Linear reflectance of the scene around the target.
    #[arg(long, value_name = "R", default_value_t = 0.2)]
    pub surround: f64,
    /// Transfer curve: srgb, gamma:G or linear.
    #[arg(long, value_name = "CURVE", default_value = "srgb")]
    pub encoding: String,
    /// Bits per sample, 8 or 16.
    #[arg(long, value_name = "8|16", default_value_t = 8)]
    pub bits: u8,
    /// JPEG quality 1–100 (the output name must end in .jpg; default there 90).
    #[arg(long, value_name = "Q")]
    pub jpeg: Option<u8>,
    /// Write a 16-bit linear Bayer mosaic: RGGB, BGGR, GRBG or GBRG (as PNG, TIFF, or a
    /// camera-raw DNG when the output name ends in .dng).
    #[arg(long, value_name = "ORDER")]
    pub bayer: Option<String>,
    /// Demosaic the --bayer mosaic into a white-balanced RGB photo (bilinear, as a camera's
    /// fast path), written in --encoding and --bits as PNG, TIFF or JPEG.
    #[arg(long, value_name = "bilinear")]
    pub demosaic: Option<String>,
    /// Seed of the temporal noise.
    #[arg(long, value_name = "N", default_value_t = 0)]
    pub seed: u64,
    /// Radial lens distortion in Lensfun's PTLens form, ptlens:a=A,b=B,c=C (radius 1 = half
    /// the frame's smaller side; b > 0 pincushion, b < 0 barrel; at most ±20 % at the corner).
    #[arg(long, value_name = "ptlens:a=A,b=B,c=C", allow_hyphen_values = true)]
    pub distortion: Option<String>,
    /// Unsharp-mask sharpening in linear light after the noise, amount=A,radius=R (R: the
    /// Gaussian's σ in pixels); the truth includes its gain 1 + A(1 − G).
    #[arg(long, value_name = "amount=A,radius=R")]
    pub sharpen: Option<String>,
    /// Illumination gradient: the light falls by RATIO across the frame towards DEG
    /// (0 = right, 90 = down; default 0).
    #[arg(long, value_name = "RATIO[,DEG]", allow_hyphen_values = true)]
    pub light_gradient: Option<String>,
    /// Colour of the light as R,G,B gains in (0, 1] (not white-balanced): writes an RGB photo,
    /// each channel with its own noise.
    #[arg(long, value_name = "R,G,B")]
    pub light_colour: Option<String>,
    /// Chroma sampling of a colour JPEG: 420 (as most cameras), 422 or 444 (needs --light-colour).
    #[arg(long, value_name = "420|422|444")]
    pub chroma: Option<String>,
    /// The print's own blur: the chart's sines lose modulation by it at their chart
    /// frequency, gaussian:sigma=LENGTH (exp(−2π²σ²f²)) or dots:dpi=N (sinc(f·25.4/N));
    /// the truth stays the camera's MTF (the print's is `print_mtf` in STEM.json).
    #[arg(long, value_name = "gaussian:sigma=LENGTH|dots:dpi=N")]
    pub print_blur: Option<String>,
    /// Pixel aperture: auto (square unless the system has an aperture factor), square or none.
    #[arg(long, value_name = "KIND", default_value = "auto")]
    pub pixel_aperture: String,
    /// Renderer: fine-grid samples per pixel and axis.
    #[arg(long, value_name = "K", default_value_t = RenderSettings::default().oversample)]
    pub oversample: usize,
    /// Renderer: tile overlap, pixels.
    #[arg(long, value_name = "PX", default_value_t = RenderSettings::default().margin_px)]
    pub margin: usize,
    /// The model system: `--system FILE` and/or factor flags (none: a perfect lens).
    #[command(flatten)]
    pub factors: FactorArgs,
    /// The photo to write: .png, .jpg, .tif, or .dng (with --bayer); STEM.truth.csv and
    /// STEM.json go beside it.
    #[arg(short = 'o', long = "output", value_name = "STEM.png|.jpg|.tif|.dng")]
    pub output: PathBuf,
}

fn usage(m: impl Into<String>) -> CliError {
    CliError::new(Code::Usage, m)
}

fn sim_error(e: SimError) -> CliError {
    let code = match &e {
        SimError::Parameter(_) | SimError::Placement(_) => Code::Usage,
        SimError::Target(_) => Code::Input,
        SimError::Io { .. } => Code::Output,
        SimError::Encode(_) | SimError::Internal(_) => Code::Internal,
    };
    CliError::new(code, e.to_string())
}

fn load_target(spec: &str) -> Result<Target, CliError> {
    match spec {
        "demo:log" => return Ok(simulate::demo::demo_target(SweepLaw::Log)),
        "demo:linear" => return Ok(simulate::demo::demo_target(SweepLaw::Linear)),
        _ => {}
    }
    Target::load(std::path::Path::new(spec)).map_err(|e| match e {
        TargetError::Invalid(m) => CliError::new(Code::Input, format!("{spec}: {m}")),
        e => CliError::new(Code::Input, e.to_string()),
    })
}

fn pair(text: &str, what: &str, sep: char) -> Result<(f64, f64), CliError> {
    let bad = || {
        usage(format!(
            "--{what} '{text}': expected two numbers separated by '{sep}'"
        ))
    };
    let (a, b) = text.split_once(sep).ok_or_else(bad)?;
    let a: f64 = a.trim().parse().map_err(|_| bad())?;
    let b: f64 = b.trim().parse().map_err(|_| bad())?;
    Ok((a, b))
}

/// Builds the camera from the flags (ranges are checked by `Camera::validate`).
fn camera(a: &Args, pixel_pitch_um: f64) -> Result<Camera, CliError> {
    let (w, h) = pair(&a.size.to_ascii_lowercase(), "size", 'x')?;
    if !(w >= 1.0 && h >= 1.0 && w.fract() == 0.0 && h.fract() == 0.0) {
        return Err(usage(format!(
            "--size '{}': give whole pixels, e.g. 1200x800",
            a.size
        )));
    }
    let (tilt_deg, tilt_axis_deg) = match &a.tilt {
        None => (0.0, 90.0),
        Some(t) => {
            let (deg, axis) = t.split_once(',').unwrap_or((t, "y"));
            let deg: f64 = deg
                .trim()
                .parse()
                .map_err(|_| usage(format!("--tilt '{t}': the angle is not a number")))?;
            let axis = match axis.trim() {
                "x" => 0.0,
                "y" => 90.0,
                other => other.parse::<f64>().map_err(|_| {
                    usage(format!(
                        "--tilt '{t}': the axis must be x, y or an angle in degrees"
                    ))
                })?,
            };
            (deg, axis)
        }
    };
    let offset = match &a.offset {
        None => [0.0, 0.0],
        Some(o) => {
            let (x, y) = pair(o, "offset", ',')?;
            [x, y]
        }
    };
    let encoding: Encoding = a.encoding.parse().map_err(usage)?;
    let bayer = a
        .bayer
        .as_deref()
        .map(|b| b.parse::<BayerOrder>().map_err(usage))
        .transpose()?;
    let demosaic = a
        .demosaic
        .as_deref()
        .map(|d| d.parse::<simulate::Demosaic>().map_err(usage))
        .transpose()?;
    if demosaic.is_some() && bayer.is_none() {
        return Err(usage(
            "--demosaic needs a mosaic: give --bayer RGGB (or BGGR, GRBG, GBRG) too",
        ));
    }
    let pixel_aperture = match a.pixel_aperture.as_str() {
        "auto" => PixelAperture::Auto,
        "square" => PixelAperture::Square,
        "none" => PixelAperture::None,
        o => {
            return Err(usage(format!(
                "--pixel-aperture '{o}': one of auto, square, none"
            )));
        }
    };
    let distortion = a
        .distortion
        .as_deref()
        .map(|d| d.parse::<sweepmtf::distortion::Ptlens>().map_err(usage))
        .transpose()?;
    let sharpen = a
        .sharpen
        .as_deref()
        .map(|v| v.parse::<simulate::Sharpen>().map_err(usage))
        .transpose()?;
    let light_gradient = a
        .light_gradient
        .as_deref()
        .map(|v| v.parse::<simulate::LightGradient>().map_err(usage))
        .transpose()?;
    let print_blur = a
        .print_blur
        .as_deref()
        .map(|v| {
            v.parse::<sweepmtf::print_mtf::PrintMtf>()
                .map_err(|e| usage(format!("--print-blur {e}")))
        })
        .transpose()?;
    let light_colour = a
        .light_colour
        .as_deref()
        .map(|v| simulate::nuisance::parse_colour(v).map_err(usage))
        .transpose()?;
    let chroma = match (&a.chroma, light_colour) {
        (None, _) => simulate::Chroma::default(),
        (Some(_), None) => {
            return Err(usage(
                "--chroma applies to a colour JPEG: give --light-colour R,G,B too",
            ));
        }
        (Some(c), Some(_)) => c.parse().map_err(usage)?,
    };
    Ok(Camera {
        width_px: w as usize,
        height_px: h as usize,
        pixel_pitch_um,
        chart_px: a.chart_px,
        magnification: a.magnification,
        rotate_deg: a.rotate,
        tilt_deg,
        tilt_axis_deg,
        focal_px: a.focal_px,
        offset_px: offset,
        surround: a.surround,
        falloff: a.falloff,
        exposure: a.exposure,
        full_well_e: a.full_well,
        read_noise_e: a.read_noise,
        fpn: a.fpn,
        seed: a.seed,
        encoding,
        bits: a.bits,
        jpeg_quality: a.jpeg,
        bayer,
        demosaic,
        pixel_aperture,
        distortion,
        sharpen,
        light_gradient,
        light_colour,
        chroma,
        print_blur,
        render: RenderSettings {
            oversample: a.oversample,
            margin_px: a.margin,
            ..RenderSettings::default()
        },
        ..Camera::default()
    })
}

/// The model system named by `--system` and the factor flags; none named: a perfect lens
/// (the camera's square pixel aperture still applies).
fn system(a: &Args) -> Result<System, CliError> {
    if a.factors.is_empty() {
        Ok(System::default())
    } else {
        a.factors.build()
    }
}

/// The pixel pitch in µm: `--pixel-pitch`, else the system's square sampling grid, else 4.3 µm.
fn pitch_um(a: &Args, system: &System) -> Result<f64, CliError> {
    if let Some(p) = &a.pixel_pitch {
        let mm = parse_length_mm(p).map_err(|e| usage(format!("--pixel-pitch: {e}")))?;
        return Ok(mm * 1e3);
    }
    match system.nyquist() {
        Some((u, v)) if (u - v).abs() <= 1e-9 * u.max(v) && u > 0.0 => Ok(0.5 / u * 1e3),
        Some((u, v)) => Err(usage(format!(
            "the system's sampling grid is not square (Nyquist {u:.1} × {v:.1} cy/mm): give --pixel-pitch"
        ))),
        None => Ok(4.3),
    }
}

/// Runs `sweepmtf simulate`; every error message is folded onto one line.
pub fn run(a: &Args) -> Result<(), CliError> {
    run_inner(a).map_err(|mut e| {
        e.message = e
            .message
            .lines()
            .map(str::trim)
            .filter(|l| !l.is_empty())
            .collect::<Vec<_>>()
            .join(" ");
        e
    })
}

fn run_inner(a: &Args) -> Result<(), CliError> {
    let system = system(a)?;
    let cam = camera(a, pitch_um(a, &system)?)?;
    cam.validate().map_err(sim_error)?;
    simulate::check_output(&cam, &a.output).map_err(sim_error)?;
    let target = load_target(&a.target)?;
    let shot = simulate::render(&target, &system, &cam).map_err(sim_error)?;
    let written = simulate::write_shot(&shot, &a.output).map_err(sim_error)?;
    for w in &shot.warnings {
        super::messages::warning(w);
    }
    let mtf_nyq = shot.truth().and_then(|t| {
        t.rows
            .windows(2)
            .find(|w| w[0].freq_cy_px <= 0.5 && w[1].freq_cy_px > 0.5)
            .map(|w| w[0].mtf)
    });
    println!(
        "simulate: {}×{} px, pitch {} µm, factors {}{}; wrote {}",
        shot.width,
        shot.height,
        cam.pixel_pitch_um,
        shot.factors_applied.join(" × "),
        mtf_nyq
            .map(|m| format!(", MTF at Nyquist {m:.3}"))
            .unwrap_or_default(),
        written
            .iter()
            .map(|p| p.display().to_string())
            .collect::<Vec<_>>()
            .join(", ")
    );
    Ok(())
}
