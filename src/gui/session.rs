//! What the page works on: the photos the user named or uploaded (decoded
//! once, kept in memory), the targets it may choose, and the output folder.

use super::display::{self, Rendition};
use super::magnify::Full;
use super::{GuiConfig, GuiError};
use std::path::{Path, PathBuf};
use std::sync::{Arc, OnceLock};
use sweepmtf::photo::decode::decode_bytes;
use sweepmtf::photo::exif::{ExifFacts, facts_from_bytes};
use sweepmtf::photo::raw::RawFrame;
use sweepmtf::target::Target;

/// Where a photo's full-resolution data is.
pub enum Source {
    /// A JPEG, PNG or TIFF file's bytes, in memory (decoded for each
    /// measurement as `measure` decodes the file: only what it reads).
    File(Vec<u8>),
    /// A camera raw file named on the command line (measured from the file).
    Raw(PathBuf),
    /// A camera raw file uploaded from the page, decoded whole and kept in
    /// memory (its bytes were written to a private temporary file for the
    /// decoder, removed once read).
    Frame(Arc<RawFrame>),
}

/// One photo the page may measure.
pub struct Photo {
    /// The photo as named in messages and outputs (the path as given, or the upload's file name).
    pub name: String,
    /// The file name's stem, for `STEM.*` outputs.
    pub stem: String,
    /// The data.
    pub source: Source,
    /// Image width (pixels).
    pub width: usize,
    /// Image height (pixels).
    pub height: usize,
    /// EXIF facts (for the pixel pitch and the summary).
    pub facts: ExifFacts,
    /// What the page shows.
    pub display: Rendition,
    /// The full-resolution data, decoded on the magnifier's first request.
    pub full: OnceLock<Result<Arc<Full>, String>>,
}

/// A target the page may choose.
pub struct TargetChoice {
    /// Shown in the list.
    pub label: String,
    /// As written in the equivalent command line (`--target …`).
    pub arg: String,
    /// The description.
    pub target: Target,
}

/// A target description shipped with sweepmtf (compiled in).
pub struct ShippedTarget {
    /// Its path in the source tree (for the command line).
    pub path: &'static str,
    /// The TOML text.
    pub toml: &'static str,
}

/// One shipped target: its path (from the source tree's root) and its text.
macro_rules! shipped {
    ($($path:literal),* $(,)?) => {
        [$(ShippedTarget { path: $path, toml: include_str!(concat!("../../", $path)) }),*]
    };
}

/// The shipped target descriptions.
pub const SHIPPED: [ShippedTarget; 5] = shipped![
    "targets/a4_log.toml",
    "targets/a4_linear.toml",
    "targets/a3_log.toml",
    "targets/a3_linear.toml",
    "targets/a4_patches.toml",
];

/// The page's state.
pub struct Session {
    /// Photos by id (index).
    pub photos: Vec<Arc<Photo>>,
    /// Targets by id (index); the command line's first.
    pub targets: Vec<Arc<TargetChoice>>,
    /// Index of the command line's target.
    pub default_target: Option<usize>,
    /// The output folder (the only place the page writes).
    pub out_dir: PathBuf,
    /// The batch output folder named on the command line, if any.
    pub batch: Option<PathBuf>,
}

fn stem_of(name: &str) -> String {
    Path::new(name)
        .file_stem()
        .map(|s| s.to_string_lossy().into_owned())
        .filter(|s| !s.is_empty() && s != "..")
        .unwrap_or_else(|| "photo".into())
}

impl Session {
    /// Opens the photos and target named on the command line.
    pub fn open(config: &GuiConfig) -> Result<Session, GuiError> {
        let mut targets = Vec::new();
        let mut default_target = None;
        if let Some(p) = &config.target {
            let t = Target::load(p).map_err(|e| GuiError::Input(e.to_string()))?;
            default_target = Some(0);
            targets.push(Arc::new(TargetChoice {
                label: format!("{} ({})", t.name, p.display()),
                arg: p.display().to_string(),
                target: t,
            }));
        }
        for s in &SHIPPED {
            // The shipped files are checked by the tests; one that fails is left out.
            if let Ok(t) = toml::from_str::<Target>(s.toml)
                && t.validate().is_ok()
                && !targets.iter().any(|c: &Arc<TargetChoice>| c.target == t)
            {
                targets.push(Arc::new(TargetChoice {
                    label: format!("{} (shipped)", t.name),
                    arg: s.path.to_string(),
                    target: t,
                }));
            }
        }
        let mut session = Session {
            photos: Vec::new(),
            targets,
            default_target,
            out_dir: config.out_dir.clone(),
            batch: config.batch.clone(),
        };
        for p in &config.photos {
            let photo = open_path(p).map_err(GuiError::Input)?;
            session.photos.push(Arc::new(photo));
        }
        Ok(session)
    }
}

/// Opens a photo named on the command line (raws are measured from the file).
fn open_path(path: &Path) -> Result<Photo, String> {
    let name = path.display().to_string();
    if sweepmtf::photo::raw::is_raw_path(path) {
        let frame = sweepmtf::photo::raw::decode_raw(path).map_err(|e| e.to_string())?;
        return Ok(raw_photo(&frame, name, Source::Raw(path.to_path_buf())));
    }
    let bytes = std::fs::read(path).map_err(|e| format!("{name}: {e}"))?;
    from_bytes(bytes, name)
}

/// A raw photo: its display rendition from the frame's location plane.
fn raw_photo(frame: &RawFrame, name: String, source: Source) -> Photo {
    Photo {
        stem: stem_of(&name),
        name,
        width: frame.width,
        height: frame.height,
        facts: frame.facts.clone(),
        display: display::of_plane(&frame.location_plane()),
        source,
        full: OnceLock::new(),
    }
}

/// Keeps an uploaded camera raw file: its bytes go to a private temporary
/// file with the same extension (the decoders read files), which is removed
/// as soon as the frame is decoded; messages name `name`, not that file.
pub fn raw_from_bytes(bytes: &[u8], name: String) -> Result<Photo, String> {
    let ext = Path::new(&name)
        .extension()
        .map(|e| format!(".{}", e.to_string_lossy()))
        .unwrap_or_default();
    let mut tmp = tempfile::Builder::new()
        .prefix("sweepmtf-gui-")
        .suffix(&ext)
        .tempfile()
        .map_err(|e| format!("{name}: cannot keep the upload: {e}"))?;
    std::io::Write::write_all(&mut tmp, bytes)
        .map_err(|e| format!("{name}: cannot keep the upload: {e}"))?;
    let at = tmp.path().display().to_string();
    let frame = sweepmtf::photo::raw::decode_raw(tmp.path())
        .map_err(|e| e.to_string().replace(&at, &name))?;
    drop(tmp);
    let frame = Arc::new(frame);
    Ok(raw_photo(&frame, name, Source::Frame(frame.clone())))
}

/// Keeps an uploaded or read JPEG/PNG/TIFF, decoded once for its display
/// rendition; `name` is used in messages.
pub fn from_bytes(bytes: Vec<u8>, name: String) -> Result<Photo, String> {
    let dec = decode_bytes(&bytes, &name).map_err(|e| e.to_string())?;
    let facts = facts_from_bytes(&bytes);
    Ok(Photo {
        stem: stem_of(&name),
        width: dec.width,
        height: dec.height,
        display: display::of_decoded(&dec),
        source: Source::File(bytes),
        facts,
        name,
        full: OnceLock::new(),
    })
}
