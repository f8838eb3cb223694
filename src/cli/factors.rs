//! The factor flags shared by every subcommand that needs a model (`model`,
//! `simulate`, `measure --model`): `--system FILE` plus one repeatable flag
//! per factor kind. Flatten [`FactorArgs`] into a subcommand's `Args` with
//! `#[command(flatten)]` and call [`FactorArgs::build`].

use super::{CliError, Code};
use std::path::PathBuf;
use sweepmtf::model::spec::parse_factor;
use sweepmtf::model::system_file::SystemFile;
use sweepmtf::model::{ModelError, System};

/// `--system` and the factor flags.
#[derive(Debug, Clone, Default, clap::Args)]
pub struct FactorArgs {
    /// TOML system file with [[factor]] tables (kind, spec); flags add to it.
    #[arg(long, value_name = "FILE")]
    pub system: Option<PathBuf>,
    /// Detector aperture: rect:A=..,B=.. | L:A=..,B=..,a=..,b=.. | rhomb:A=..,B=.. | hex:D=.. | oct:D=.. | circle:D=.. | polygon:x1 y1;x2 y2;… (µm)
    #[arg(long, value_name = "SPEC")]
    pub aperture: Vec<String>,
    /// Sampling grid: rect:px=..,py=.. | hex:pitch=..,rows=x|y
    #[arg(long, value_name = "SPEC")]
    pub sampling: Vec<String>,
    /// Optics: diffraction:lambda=..,fnum=..
    #[arg(long, value_name = "SPEC")]
    pub optics: Vec<String>,
    /// Carrier diffusion: alpha=..|lambda=..,depletion=..,length=..
    #[arg(long, value_name = "SPEC")]
    pub diffusion: Vec<String>,
    /// Charge transfer: n=..,cti=..|cte=..,pitch=..[,model=exp|exact][,axis=u|v]
    #[arg(long, value_name = "SPEC")]
    pub cte: Vec<String>,
    /// Birefringent low-pass filter: 2spot:d=..[,axis=u|v] | 4spot:d=.. | 4spot:dx=..,dy=..
    #[arg(long, value_name = "SPEC")]
    pub olpf: Vec<String>,
    /// Gaussian blur: sigma=.. | sigma_x=..,sigma_y=..
    #[arg(long, value_name = "SPEC")]
    pub gaussian: Vec<String>,
    /// Defocus: wave:lambda=..,fnum=..,w020=..|dz=.. | geometric:blur=..|dz=..,fnum=..
    #[arg(long, value_name = "SPEC")]
    pub defocus: Vec<String>,
}

/// A model error from a flag or file as a one-line usage error.
fn usage(e: ModelError) -> CliError {
    CliError::new(Code::Usage, e.to_string())
}

impl FactorArgs {
    /// The flags as (kind, spec) pairs, in the order of [`sweepmtf::model::spec::KINDS`].
    pub fn flag_specs(&self) -> Vec<(&'static str, &str)> {
        let lists: [(&'static str, &Vec<String>); 8] = [
            ("aperture", &self.aperture),
            ("sampling", &self.sampling),
            ("optics", &self.optics),
            ("diffusion", &self.diffusion),
            ("cte", &self.cte),
            ("olpf", &self.olpf),
            ("gaussian", &self.gaussian),
            ("defocus", &self.defocus),
        ];
        lists
            .iter()
            .flat_map(|(k, v)| v.iter().map(move |s| (*k, s.as_str())))
            .collect()
    }

    /// Whether neither a system file nor any factor flag was given.
    pub fn is_empty(&self) -> bool {
        self.system.is_none() && self.flag_specs().is_empty()
    }

    /// Builds the system and its display name (from the system file, if any).
    pub fn build_named(&self) -> Result<(Option<String>, System), CliError> {
        if self.is_empty() {
            return Err(CliError::usage(
                "no model factor named; give --system FILE or at least one of --aperture, --sampling, --optics, --diffusion, --cte, --olpf, --gaussian, --defocus",
            ));
        }
        let mut name = None;
        let mut system = System::default();
        if let Some(path) = &self.system {
            let shown = path.display().to_string();
            let text = std::fs::read_to_string(path)
                .map_err(|e| CliError::new(Code::Input, format!("--system {shown}: {e}")))?;
            let file = SystemFile::parse(&text, &shown).map_err(usage)?;
            system = file.build(&shown).map_err(usage)?;
            name = file.name;
        }
        for (kind, spec) in self.flag_specs() {
            let f = parse_factor(kind, spec)
                .map_err(|e| CliError::usage(format!("--{kind} {spec}: {e}")))?;
            system.factors.push(f);
        }
        if system.factors.is_empty() {
            return Err(CliError::usage(
                "the system file names no factor and no factor flag was given",
            ));
        }
        Ok((name, system))
    }

    /// Builds the system (see [`FactorArgs::build_named`]).
    #[allow(dead_code)] // for `simulate` and `measure --model`
    pub fn build(&self) -> Result<System, CliError> {
        self.build_named().map(|(_, s)| s)
    }
}
