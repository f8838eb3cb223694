//! `sweepmtf gui`: a loopback HTTP server and one self-contained page to
//! measure a photo by hand (draggable corners, live MTF) and explore the model.
//!
//! Thin over the library: the handlers call the same functions as `measure`
//! and `model` (`measure::measure_decoded`, `report::*`, `model::*`) and only
//! convert to and from JSON. Server: `tiny_http` (small, synchronous, no async
//! runtime needed for a single local user). Page: plain HTML/JS/SVG compiled
//! into the binary (no network, no CDN). See `server` for the security rules.

mod assets;
mod batch_api;
mod charts_api;
mod display;
mod magnify;
mod measure_api;
mod model_api;
mod server;
mod session;

use std::path::PathBuf;
use std::sync::Arc;
use thiserror::Error;

/// What the page starts with.
#[derive(Debug, Clone, Default)]
pub struct GuiConfig {
    /// Photos named on the command line (the only files read besides uploads and targets).
    pub photos: Vec<PathBuf>,
    /// Target description named on the command line.
    pub target: Option<PathBuf>,
    /// Port on 127.0.0.1 (0 = a free port).
    pub port: u16,
    /// The output folder the page writes into (the only place it writes).
    pub out_dir: PathBuf,
    /// A `batch` output folder to show in the batch view.
    pub batch: Option<PathBuf>,
}

/// Why the server could not start.
#[derive(Debug, Error)]
pub enum GuiError {
    /// The port could not be bound.
    #[error("cannot listen on 127.0.0.1:{port}: {cause}")]
    Listen {
        /// The port asked for.
        port: u16,
        /// The cause.
        cause: String,
    },
    /// No random token could be drawn.
    #[error("cannot draw a random token: {0}")]
    Random(String),
    /// A photo or target named on the command line is unusable.
    #[error("{0}")]
    Input(String),
}

/// A running server: its address and token; stops when dropped.
pub struct Gui {
    inner: Arc<server::Server>,
    workers: Vec<std::thread::JoinHandle<()>>,
}

impl Gui {
    /// Opens the photos and target named in `config`, binds 127.0.0.1 and
    /// starts `threads` worker threads answering requests.
    pub fn start(config: GuiConfig, threads: usize) -> Result<Gui, GuiError> {
        let inner = Arc::new(server::Server::bind(config)?);
        let workers = (0..threads.max(1))
            .map(|_| {
                let s = Arc::clone(&inner);
                std::thread::spawn(move || s.serve())
            })
            .collect();
        Ok(Gui { inner, workers })
    }

    /// The page's URL, token included (`http://127.0.0.1:PORT/?token=…`).
    pub fn url(&self) -> String {
        format!("{}/?token={}", self.origin(), self.inner.token)
    }

    /// `http://127.0.0.1:PORT`, the only origin the server answers.
    pub fn origin(&self) -> String {
        format!("http://127.0.0.1:{}", self.inner.port)
    }

    /// Blocks while the server runs (until the process is stopped).
    pub fn wait(mut self) {
        for w in self.workers.drain(..) {
            let _ = w.join();
        }
    }

    fn shutdown(&mut self) {
        for _ in 0..self.workers.len() {
            self.inner.http.unblock();
        }
        for w in self.workers.drain(..) {
            let _ = w.join();
        }
    }
}

impl Drop for Gui {
    fn drop(&mut self) {
        self.shutdown();
    }
}
