//! Throughput and memory of the batch runner with a decode-bound job,
//! independent of the measurement: each shot is a W×H JPEG that the job
//! decodes in full (image crate), reduces to a column profile and writes as a
//! small CSV. Run it under `/usr/bin/time -v` with `--jobs 1` and `--jobs 2`
//! and compare wall time and peak RSS (see README, "Batch processing").
//!
//! ```sh
//! cargo run --release --features examples --example batch_bench -- make DIR 16 4000x3000
//! /usr/bin/time -v target/release/examples/batch_bench run DIR OUT 1
//! /usr/bin/time -v target/release/examples/batch_bench run DIR OUT 2
//! ```

use std::path::{Path, PathBuf};
use std::time::Instant;
use sweepmtf::batch::{
    self, FailKind, NoProgress, RunOptions, Shard, ShotFailure, ShotResult, runner::FnJob,
};

fn make(dir: &Path, n: usize, w: u32, h: u32) -> Result<(), Box<dyn std::error::Error>> {
    std::fs::create_dir_all(dir)?;
    for i in 0..n {
        // A sine pattern plus hash noise: compresses like a photo, not like a flat field.
        let img = image::GrayImage::from_fn(w, h, |x, y| {
            let s = ((x as f64 * (0.01 + 0.002 * i as f64)).sin() * 80.0 + 128.0) as u32;
            let noise = (x.wrapping_mul(2654435761) ^ y.wrapping_mul(40503)) >> 28;
            image::Luma([(s + noise).min(255) as u8])
        });
        let path = dir.join(format!("shot{i:02}.jpg"));
        let f = std::io::BufWriter::new(std::fs::File::create(&path)?);
        image::codecs::jpeg::JpegEncoder::new_with_quality(f, 90).encode_image(&img)?;
    }
    Ok(())
}

fn job(source: &Path, dir: &Path, stem: &str) -> Result<ShotResult, ShotFailure> {
    let img = image::open(source)
        .map_err(|e| ShotFailure::new(FailKind::Input, e.to_string()))?
        .to_luma32f();
    let (w, h) = img.dimensions();
    let mut profile = vec![0.0f64; w as usize];
    for (x, _, p) in img.enumerate_pixels() {
        profile[x as usize] += f64::from(p.0[0]);
    }
    let mut csv = String::from("freq_cy_px,mtf\n");
    for (i, v) in profile.iter().enumerate().step_by(64) {
        csv.push_str(&format!("{},{}\n", i as f64 / w as f64 * 0.5, v / h as f64));
    }
    let name = format!("{stem}.mtf.csv");
    batch::atomic::write_atomic(&dir.join(&name), csv.as_bytes())
        .map_err(|e| ShotFailure::new(FailKind::Output, e.to_string()))?;
    Ok(ShotResult {
        curve_file: Some(name.clone()),
        outputs: vec![name],
        ..Default::default()
    })
}

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let a: Vec<String> = std::env::args().collect();
    match a.get(1).map(String::as_str) {
        Some("make") => {
            let (w, h) = a[4].split_once('x').ok_or("WxH")?;
            make(Path::new(&a[2]), a[3].parse()?, w.parse()?, h.parse()?)
        }
        Some("run") => {
            let (dir, out, jobs) = (PathBuf::from(&a[2]), PathBuf::from(&a[3]), a[4].parse()?);
            let plan = batch::plan(std::slice::from_ref(&dir), false, &out, Shard::ALL)?;
            let opts = RunOptions {
                jobs,
                force: true,
                retry_failed: false,
            };
            let j = FnJob {
                fingerprint: "bench".into(),
                f: job,
            };
            let t = Instant::now();
            let o = batch::run_batch(&plan, &out, &j, &opts, &NoProgress)?;
            let s = t.elapsed().as_secs_f64();
            println!(
                "{} shots, jobs {jobs}: {s:.2} s, {:.2} shots/s, {} failed",
                o.run.records.len(),
                o.run.records.len() as f64 / s,
                o.run.failed()
            );
            Ok(())
        }
        _ => Err("usage: batch_bench make DIR N WxH | run DIR OUT JOBS".into()),
    }
}
