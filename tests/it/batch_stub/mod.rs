//! A stand-in per-shot job for the batch tests: it really decodes the photo
//! (so corrupt, truncated, empty and non-image files fail as they would),
//! takes the shot's "true" Gaussian MTF width from the image's grey level and
//! its f-number from the file name, writes `STEM.mtf.csv` and `STEM.stub.txt`
//! atomically, and can sleep (slow shots) or panic (files named `panic*`).

#![allow(dead_code)]

use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicUsize, Ordering};
use std::time::Duration;
use sweepmtf::batch::atomic::write_atomic;
use sweepmtf::batch::{FailKind, PlannedShot, ShotFailure, ShotJob, ShotResult};

/// Gaussian blur σ (pixels) encoded by grey level `g`: σ = g / 100.
pub fn sigma_of_grey(g: u8) -> f64 {
    f64::from(g) / 100.0
}

/// MTF50 (cy/px) of a Gaussian PSF of width σ px: exp(−2π²σ²f²) = ½.
pub fn mtf50_of_sigma(sigma: f64) -> f64 {
    (std::f64::consts::LN_2 / (2.0 * std::f64::consts::PI.powi(2) * sigma * sigma)).sqrt()
}

/// Writes a 32×24 grey PNG of level `g` at `path`.
pub fn write_shot(path: &Path, g: u8) {
    std::fs::create_dir_all(path.parent().unwrap()).unwrap();
    image::GrayImage::from_pixel(32, 24, image::Luma([g]))
        .save(path)
        .unwrap();
}

/// The stub job.
#[derive(Default)]
pub struct StubJob {
    /// Settings fingerprint.
    pub settings: String,
    /// Sleep per shot.
    pub sleep: Duration,
    /// Jobs running right now.
    pub running: AtomicUsize,
    /// Most jobs seen running at once.
    pub max_running: AtomicUsize,
    /// Jobs started in total.
    pub started: AtomicUsize,
    /// Decode "in parallel" inside the job with rayon, as rawler does.
    pub nested_rayon: bool,
}

impl StubJob {
    pub fn new(settings: &str, sleep_ms: u64) -> Self {
        StubJob {
            settings: settings.to_string(),
            sleep: Duration::from_millis(sleep_ms),
            ..Default::default()
        }
    }

    fn measure(&self, source: &Path, dir: &Path, stem: &str) -> Result<ShotResult, ShotFailure> {
        let name = source.file_name().unwrap().to_string_lossy().to_string();
        if name.starts_with("panic") {
            panic!("decoder exploded on {name}");
        }
        let img = image::open(source)
            .map_err(|e| ShotFailure::new(FailKind::Input, format!("cannot decode: {e}")))?
            .to_luma8();
        if self.nested_rayon {
            use rayon::prelude::*;
            // Uneven parts: a worker that finishes its part early waits for
            // (and, in a rayon pool, steals work during) the long one.
            let step = self.sleep / 4;
            (0..4)
                .into_par_iter()
                .with_max_len(1)
                .for_each(|i| std::thread::sleep(step * if i % 2 == 0 { 1 } else { 3 }));
        } else if !self.sleep.is_zero() {
            std::thread::sleep(self.sleep);
        }
        let g = img.get_pixel(0, 0).0[0];
        if g == 0 {
            return Err(ShotFailure::new(FailKind::Locate, "no chart found"));
        }
        let sigma = sigma_of_grey(g);
        let mut csv = String::from("freq_cy_px,mtf,aliased\n");
        for i in 0..=60 {
            let f = i as f64 * 0.01;
            let m = (-2.0 * std::f64::consts::PI.powi(2) * sigma * sigma * f * f).exp();
            csv.push_str(&format!("{f},{m},{}\n", f > 0.5));
        }
        let curve = format!("{stem}.mtf.csv");
        write_atomic(&dir.join(&curve), csv.as_bytes())
            .map_err(|e| ShotFailure::new(FailKind::Output, e.to_string()))?;
        let note = format!("{stem}.stub.txt");
        write_atomic(&dir.join(&note), format!("sigma {sigma}\n").as_bytes())
            .map_err(|e| ShotFailure::new(FailKind::Output, e.to_string()))?;
        let f_number = name
            .strip_prefix('f')
            .and_then(|r| r.rsplit_once('.'))
            .and_then(|(n, _)| n.split('_').next()?.parse::<f64>().ok());
        Ok(ShotResult {
            mtf50_cy_px: Some(mtf50_of_sigma(sigma)),
            method: Some("stub".into()),
            f_number,
            make: Some("Stub".into()),
            curve_file: Some(curve.clone()),
            outputs: vec![curve, note],
            ..Default::default()
        })
    }
}

impl ShotJob for StubJob {
    fn fingerprint(&self, _shot: &PlannedShot) -> String {
        self.settings.clone()
    }

    fn run(&self, shot: &PlannedShot, shots_dir: &Path) -> Result<ShotResult, ShotFailure> {
        self.started.fetch_add(1, Ordering::SeqCst);
        let now = self.running.fetch_add(1, Ordering::SeqCst) + 1;
        self.max_running.fetch_max(now, Ordering::SeqCst);
        struct Dec<'a>(&'a AtomicUsize);
        impl Drop for Dec<'_> {
            fn drop(&mut self) {
                self.0.fetch_sub(1, Ordering::SeqCst);
            }
        }
        let _d = Dec(&self.running);
        self.measure(&shot.source, shots_dir, &shot.stem)
    }
}

/// A folder of `n` good shots `fN_i.png` at several f-numbers; returns
/// (file name, true MTF50) per shot.
pub fn good_folder(dir: &Path, n: usize) -> Vec<(String, f64)> {
    let stops = [2.8, 4.0, 5.6, 8.0, 11.0, 16.0];
    (0..n)
        .map(|i| {
            let f = stops[i % stops.len()];
            let g = 60 + (i as u8 % 7) * 10 + (i % stops.len()) as u8;
            let name = format!("f{}_{i:02}.png", f);
            write_shot(&dir.join(&name), g);
            (name, mtf50_of_sigma(sigma_of_grey(g)))
        })
        .collect()
}

/// Reads a summary CSV as rows of (column → value).
pub fn read_summary(path: &Path) -> Vec<std::collections::HashMap<String, String>> {
    let mut r = csv::Reader::from_path(path).unwrap();
    let h = r.headers().unwrap().clone();
    r.records()
        .map(|row| {
            let row = row.unwrap();
            h.iter()
                .zip(row.iter())
                .map(|(a, b)| (a.to_string(), b.to_string()))
                .collect()
        })
        .collect()
}

/// Every file under `dir` with its bytes, sorted (for "nothing changed" checks).
pub fn snapshot(dir: &Path) -> Vec<(PathBuf, Vec<u8>)> {
    let mut out = Vec::new();
    let mut stack = vec![dir.to_path_buf()];
    while let Some(d) = stack.pop() {
        for e in std::fs::read_dir(&d).unwrap() {
            let p = e.unwrap().path();
            if p.is_dir() {
                stack.push(p);
            } else {
                let b = std::fs::read(&p).unwrap();
                out.push((p, b));
            }
        }
    }
    out.sort();
    out
}

pub mod exif_jpeg;
