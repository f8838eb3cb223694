//! A testing aid, not part of measuring: mutated copies of valid files fed to
//! the library's entry points (decode, EXIF, locate, measure, target and
//! system parsers), for `examples/fuzz.rs` (long runs, each case guarded in a
//! child process) and the short slice in `cargo test`. A case is reproducible
//! from its run seed and number alone.

pub mod mutate;

use crate::measure::MeasureOptions;
use mutate::{Layout, Rng};
use std::path::{Path, PathBuf};

/// What kind of file a seed is, which decides its mutations and entry points.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Kind {
    /// JPEG photo.
    Jpeg,
    /// PNG photo.
    Png,
    /// TIFF photo.
    Tiff,
    /// DNG camera raw.
    Dng,
    /// Target description written by `chart` (TOML).
    TargetToml,
    /// sineMTF target description (text).
    SineMtf,
    /// Model system file (TOML).
    SystemToml,
}

impl Kind {
    /// File extension for the mutated copy.
    pub fn ext(self) -> &'static str {
        match self {
            Kind::Jpeg => "jpg",
            Kind::Png => "png",
            Kind::Tiff => "tif",
            Kind::Dng => "dng",
            Kind::TargetToml | Kind::SystemToml => "toml",
            Kind::SineMtf => "txt",
        }
    }
}

/// A valid file that cases mutate.
#[derive(Debug, Clone)]
pub struct Seed {
    /// Its kind.
    pub kind: Kind,
    /// Where it came from.
    pub name: String,
    /// Its bytes.
    pub bytes: Vec<u8>,
}

/// The seeds and the fixed files the cases measure against.
#[derive(Debug)]
pub struct Corpus {
    /// The valid files.
    pub seeds: Vec<Seed>,
    /// The crate's folder (for the README sample shot and target).
    pub root: PathBuf,
}

fn read(root: &Path, rel: &str, kind: Kind) -> Result<Seed, String> {
    let p = root.join(rel);
    Ok(Seed {
        kind,
        name: rel.to_string(),
        bytes: std::fs::read(&p).map_err(|e| format!("{}: {e}", p.display()))?,
    })
}

impl Corpus {
    /// The seeds from the repository at `root` (testdata, targets) plus a
    /// small 16-bit TIFF and two small simulated DNGs made here.
    pub fn new(root: &Path) -> Result<Corpus, String> {
        let mut seeds = vec![
            read(root, "testdata/a4_log_shot.jpg", Kind::Jpeg)?,
            read(root, "testdata/sweep_log_srgb_q90.jpg", Kind::Jpeg)?,
            read(
                root,
                "testdata/real/exif_jpeg/nikon_d70_no_focalplane.jpg",
                Kind::Jpeg,
            )?,
            read(root, "testdata/sweep_linear_srgb.png", Kind::Png)?,
            read(root, "targets/a4_log.toml", Kind::TargetToml)?,
            read(root, "targets/a4_patches.toml", Kind::TargetToml)?,
            read(
                root,
                "testdata/real/sine_target_scan/mitre_sinemtf_tgt.txt",
                Kind::SineMtf,
            )?,
        ];
        for s in [
            "aps_c_f4",
            "ccd_interline_cte",
            "dslr_olpf_f8",
            "hex_sensor",
        ] {
            seeds.push(read(
                root,
                &format!("targets/systems/{s}.toml"),
                Kind::SystemToml,
            )?);
        }
        // A small 16-bit grey TIFF from the PNG.
        let png = image::load_from_memory(&seeds[3].bytes).map_err(|e| e.to_string())?;
        let small = png.resize(240, 160, image::imageops::FilterType::Triangle);
        let mut tif = std::io::Cursor::new(Vec::new());
        image::DynamicImage::ImageLuma16(small.to_luma16())
            .write_to(&mut tif, image::ImageFormat::Tiff)
            .map_err(|e| e.to_string())?;
        seeds.push(Seed {
            kind: Kind::Tiff,
            name: "sweep_linear 240x160 grey16.tif".into(),
            bytes: tif.into_inner(),
        });
        // Two small simulated RGGB DNGs: one uncompressed strip, one lossless JPEG.
        let camera = crate::simulate::Camera {
            bayer: Some(crate::simulate::BayerOrder::Rggb),
            ..crate::simulate::Camera::noiseless(192, 128)
        };
        let target = crate::simulate::demo::demo_target(crate::target::SweepLaw::Log);
        let shot = crate::simulate::render(&target, &crate::model::System::default(), &camera)
            .map_err(|e| e.to_string())?;
        for lossless in [false, true] {
            let settings = crate::simulate::dng::DngSettings {
                lossless_jpeg: lossless,
                ..Default::default()
            };
            let bytes = crate::simulate::dng::encode_mosaic(
                &shot.linear,
                shot.width,
                shot.height,
                crate::simulate::BayerOrder::Rggb,
                4.3,
                &settings,
            )
            .map_err(|e| e.to_string())?;
            seeds.push(Seed {
                kind: Kind::Dng,
                name: format!("simulated 192x128 RGGB lossless={lossless}.dng"),
                bytes,
            });
        }
        Ok(Corpus {
            seeds,
            root: root.to_path_buf(),
        })
    }

    /// Case `i` of run `seed`: the seed it mutates (round robin), the mutated
    /// bytes and what was done to them.
    pub fn case(&self, seed: u64, i: u64) -> (&Seed, Vec<u8>, String) {
        let s = &self.seeds[(i % self.seeds.len() as u64) as usize];
        let mut rng = Rng::new(seed, i);
        let mut bytes = s.bytes.clone();
        let what = match s.kind {
            Kind::Jpeg => mutate::mutate_binary(&mut bytes, Layout::Jpeg, &mut rng),
            Kind::Png => mutate::mutate_binary(&mut bytes, Layout::Png, &mut rng),
            Kind::Tiff | Kind::Dng => mutate::mutate_binary(&mut bytes, Layout::Tiff, &mut rng),
            _ => {
                let mut t = String::from_utf8_lossy(&bytes).into_owned();
                let w = mutate::mutate_text(&mut t, &mut rng);
                bytes = t.into_bytes();
                w
            }
        };
        (s, bytes, what)
    }

    /// Runs case `i`: feeds the mutated file to the entry points of its kind,
    /// writing it as `dir/case.EXT` where a path is needed. `Ok` = accepted,
    /// `Err` = refused with a clean error; a panic is the caller's to catch.
    pub fn run(&self, seed: u64, i: u64, dir: &Path) -> Result<(), String> {
        let (s, bytes, _) = self.case(seed, i);
        let path = dir.join(format!("case.{}", s.kind.ext()));
        std::fs::write(&path, &bytes).map_err(|e| format!("harness: {e}"))?;
        let target = self.root.join("targets/a4_log.toml");
        let shot = self.root.join("testdata/a4_log_shot.jpg");
        let measure = |photo: &Path, opts: MeasureOptions| {
            crate::measure::measure_file_each(photo, &opts)
                .map(|_| ())
                .map_err(|e| e.to_string())
        };
        // A fixed region inside any image of at least 64×48 px (no search).
        let roi_opts = MeasureOptions {
            roi: Some([[8.0, 20.0], [56.0, 20.0], [56.0, 28.0], [8.0, 28.0]]),
            ..MeasureOptions::default()
        };
        match s.kind {
            Kind::Jpeg | Kind::Png | Kind::Tiff => {
                let _ = crate::photo::jpeg_check::scan_damage(&bytes);
                let _ = crate::photo::exif::facts_from_bytes(&bytes);
                let d = crate::photo::decode::decode_bytes(&bytes, "case")
                    .map_err(|e| e.to_string())?;
                if d.width * d.height > 4_000_000 {
                    // Decoded fine; measuring a huge picture only costs time.
                    return Ok(());
                }
                drop(d);
                if i.is_multiple_of(2) {
                    measure(
                        &path,
                        MeasureOptions {
                            target: Some(target),
                            ..MeasureOptions::default()
                        },
                    )
                } else {
                    measure(&path, roi_opts)
                }
            }
            Kind::Dng => {
                let _ = crate::photo::raw::read_raw_facts(&path);
                measure(
                    &path,
                    MeasureOptions {
                        channel: crate::photo::linearise::Channel::G,
                        ..roi_opts
                    },
                )
            }
            Kind::TargetToml | Kind::SineMtf => {
                crate::target::Target::load(&path).map_err(|e| e.to_string())?;
                if s.kind == Kind::TargetToml && i.is_multiple_of(3) {
                    measure(
                        &shot,
                        MeasureOptions {
                            target: Some(path),
                            ..MeasureOptions::default()
                        },
                    )
                } else {
                    Ok(())
                }
            }
            Kind::SystemToml => {
                let text = String::from_utf8_lossy(&bytes);
                let file = crate::model::system_file::SystemFile::parse(&text, "case")
                    .map_err(|e| e.to_string())?;
                let system = file.build("case").map_err(|e| e.to_string())?;
                use crate::report::{model_cut, model_map};
                let cut = model_cut::compute_cut(&system, model_cut::CutDirection::U, 400.0, 64);
                let _ = model_cut::cut_csv(&cut);
                let _ = model_map::compute_map(&system, 400.0, 16);
                Ok(())
            }
        }
    }
}
