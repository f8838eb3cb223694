//! `sweepmtf gui`: starts the local page (see `crate::gui`), prints its URL,
//! opens the default browser unless `--no-open`, and serves until Ctrl-C.

use super::{CliError, Code};
use crate::gui::{Gui, GuiConfig, GuiError};
use std::io::Write;
use std::path::PathBuf;

/// Arguments of `sweepmtf gui`.
#[derive(Debug, clap::Args)]
pub struct Args {
    /// Photos to open (JPEG, PNG, TIFF or camera raw); more can be uploaded from the page.
    pub photos: Vec<PathBuf>,
    /// Target description (chart TOML or sineMTF tgt.txt); the shipped targets are listed too.
    #[arg(long, value_name = "FILE")]
    pub target: Option<PathBuf>,
    /// Port on 127.0.0.1 (default: a free one).
    #[arg(long, default_value_t = 0, value_name = "N")]
    pub port: u16,
    /// Print the URL only; do not open a browser.
    #[arg(long)]
    pub no_open: bool,
    /// A `sweepmtf batch` output folder to browse in the batch view (its table and plots).
    #[arg(long, value_name = "DIR")]
    pub batch: Option<PathBuf>,
    /// Output folder the page saves into (the only place it writes).
    #[arg(short = 'o', long = "out", default_value = ".", value_name = "DIR")]
    pub out: PathBuf,
}

/// Opens `url` in the default browser; false when no opener could be started.
fn open_browser(url: &str) -> bool {
    let mut cmd = if cfg!(target_os = "macos") {
        std::process::Command::new("open")
    } else if cfg!(windows) {
        let mut c = std::process::Command::new("cmd");
        c.args(["/C", "start", ""]);
        c
    } else {
        std::process::Command::new("xdg-open")
    };
    cmd.arg(url)
        .stdin(std::process::Stdio::null())
        .stdout(std::process::Stdio::null())
        .stderr(std::process::Stdio::null())
        .spawn()
        .is_ok()
}

/// Runs `sweepmtf gui` (returns only on a start-up error).
pub fn run(a: &Args) -> Result<(), CliError> {
    let config = GuiConfig {
        photos: a.photos.clone(),
        target: a.target.clone(),
        port: a.port,
        out_dir: a.out.clone(),
        batch: a.batch.clone(),
    };
    let gui = Gui::start(config, 4).map_err(|e| match e {
        GuiError::Input(m) => CliError::new(Code::Input, m),
        other => CliError::new(Code::Output, other.to_string()),
    })?;
    let url = gui.url();
    // Not println!: a closed stdout (the reader gone) must not stop the server.
    let mut out = std::io::stdout();
    let _ = writeln!(out, "sweepmtf gui: {url}");
    let _ = writeln!(
        out,
        "sweepmtf gui: serving {} only; Ctrl-C stops",
        gui.origin()
    );
    let _ = out.flush();
    if !a.no_open && !open_browser(&url) {
        eprintln!("sweepmtf: could not start a browser; open the URL above");
    }
    gui.wait();
    Ok(())
}
