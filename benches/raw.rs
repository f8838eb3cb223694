//! Raw decode and measure speed and memory.
//!
//! 1. The real Canon 550D DNG (1888×1182, 14-bit uncompressed): `decode_raw`
//!    alone, decode + the green planes, and the EXIF facts alone. Prints the
//!    first (cold) decode time, which includes rawler's one-off camera-table
//!    load, and the process's peak RSS against the decoded CFA frame's size.
//! 2. The issue-6 bar on a 24-megapixel raw: a 6000×4000 RGGB DNG written by
//!    `simulate` (demo log target, shot noise) into the temp folder, then
//!    `decode_raw` alone against `measure_raw --channel g` (decode included)
//!    with `--roi` on the first sweep strip, with `--roi` on the target
//!    frame's corners (`--target`), and with the chart found automatically
//!    from the target's fiducials. The file is deleted at the end. Peak RSS of
//!    a whole `measure` run is measured separately with `/usr/bin/time -v`
//!    (README, "Camera raw and EXIF"), since criterion keeps every case in one
//!    process.
//!
//! Run: `cargo bench --bench raw` (`-- 24mp` for the big file only).

use criterion::{Criterion, criterion_group, criterion_main};
use std::hint::black_box;
use std::path::{Path, PathBuf};
use std::time::Instant;
use sweepmtf::measure::{MeasureOptions, measure_raw};
use sweepmtf::model::System;
use sweepmtf::photo::exif::read_facts;
use sweepmtf::photo::linearise::Channel;
use sweepmtf::photo::raw::{RawChannel, decode_raw};
use sweepmtf::simulate::{self, BayerOrder, Camera};
use sweepmtf::target::SweepLaw;

fn dng() -> PathBuf {
    let beside = Path::new(concat!(env!("CARGO_MANIFEST_DIR"), "/../shared/realdata"));
    let above = Path::new(concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/../../shared/realdata"
    ));
    if beside.exists() { beside } else { above }
        .join("raw/tinydng_colorchart_canon550d_magiclantern.dng")
}

fn status_kib(key: &str) -> Option<u64> {
    let status = std::fs::read_to_string("/proc/self/status").ok()?;
    let line = status.lines().find(|l| l.starts_with(key))?;
    line.split_whitespace().nth(1)?.parse().ok()
}

fn peak_rss_kib() -> Option<u64> {
    status_kib("VmHWM:")
}

fn small(c: &mut Criterion) {
    let path = dng();
    let rss0 = peak_rss_kib();
    let t = Instant::now();
    let facts = read_facts(&path).unwrap();
    let cold_facts = t.elapsed();
    let rss1 = peak_rss_kib();
    let t = Instant::now();
    let frame = decode_raw(&path).unwrap();
    let decode = t.elapsed();
    let rss2 = peak_rss_kib();
    let planes = frame.channel_planes(RawChannel::G);
    let rss3 = peak_rss_kib();
    eprintln!(
        "cold read_facts (loads rawler's camera table once): {:.1} ms; first decode after it: {:.1} ms",
        cold_facts.as_secs_f64() * 1e3,
        decode.as_secs_f64() * 1e3
    );
    eprintln!(
        "decoded buffer {} KiB, green planes {} KiB; peak RSS KiB: start {:?}, after facts {:?}, \
         after decode {:?}, after green planes {:?} ({} facts warnings)",
        frame.decoded_bytes() / 1024,
        planes.iter().map(|p| p.data.len() * 4).sum::<usize>() / 1024,
        rss0,
        rss1,
        rss2,
        rss3,
        facts.warnings.len()
    );
    drop((frame, planes));

    c.bench_function("decode_raw dng", |b| {
        b.iter(|| black_box(decode_raw(black_box(&path)).unwrap()))
    });
    c.bench_function("decode_raw + green planes", |b| {
        b.iter(|| {
            let f = decode_raw(black_box(&path)).unwrap();
            black_box(f.channel_planes(RawChannel::G))
        })
    });
    let frame = decode_raw(&path).unwrap();
    c.bench_function("green planes only", |b| {
        b.iter(|| black_box(frame.channel_planes(RawChannel::G)))
    });
    c.bench_function("read_facts dng", |b| {
        b.iter(|| black_box(read_facts(black_box(&path)).unwrap()))
    });
}

/// Writes the 24 MP simulated DNG; returns its path, the first sweep's strip and the target corners.
fn big_dng(
    dir: &Path,
) -> (
    PathBuf,
    [[f64; 2]; 4],
    [[f64; 2]; 4],
    sweepmtf::target::Target,
) {
    let target = simulate::demo::demo_target(SweepLaw::Log);
    let camera = Camera {
        bayer: Some(BayerOrder::Rggb),
        full_well_e: Some(30000.0),
        read_noise_e: 3.0,
        ..Camera::noiseless(6000, 4000)
    };
    let t = Instant::now();
    let shot = simulate::render(&target, &System::default(), &camera).unwrap();
    let path = dir.join("big24.dng");
    simulate::write_shot(&shot, &path).unwrap();
    eprintln!(
        "24 MP DNG rendered and written in {:.1} s ({} MB)",
        t.elapsed().as_secs_f64(),
        std::fs::metadata(&path).unwrap().len() / 1_000_000
    );
    let quad = |q: [f64; 8]| [[q[0], q[1]], [q[2], q[3]], [q[4], q[5]], [q[6], q[7]]];
    (
        path,
        quad(shot.roi().unwrap()),
        quad(shot.target_corners),
        target,
    )
}

fn big(c: &mut Criterion) {
    let dir = tempfile::Builder::new()
        .prefix("sweepmtf-bench-raw")
        .tempdir_in(std::env::temp_dir())
        .unwrap();
    let (path, strip, corners, target) = big_dng(dir.path());
    let strip_opts = MeasureOptions {
        roi: Some(strip),
        channel: Channel::G,
        ..MeasureOptions::default()
    };
    let target_opts = MeasureOptions {
        roi: Some(corners),
        channel: Channel::G,
        ..MeasureOptions::default()
    };
    let frame = decode_raw(&path).unwrap();
    eprintln!(
        "24 MP frame {}×{}, decoded buffer {:.1} MB",
        frame.width,
        frame.height,
        frame.decoded_bytes() as f64 / 1e6
    );
    drop(frame);
    let mut g = c.benchmark_group("24mp_dng");
    g.sample_size(10);
    g.bench_function("decode_only", |b| {
        b.iter(|| black_box(decode_raw(black_box(&path)).unwrap()))
    });
    g.bench_function("measure_g_strip_roi", |b| {
        b.iter(|| black_box(measure_raw(&path, "big", None, &strip_opts).unwrap()))
    });
    g.bench_function("measure_g_target_corners", |b| {
        b.iter(|| black_box(measure_raw(&path, "big", Some(&target), &target_opts).unwrap()))
    });
    let auto_opts = MeasureOptions {
        channel: Channel::G,
        ..MeasureOptions::default()
    };
    g.bench_function("measure_g_auto_location", |b| {
        b.iter(|| black_box(measure_raw(&path, "big", Some(&target), &auto_opts).unwrap()))
    });
    g.finish();
    drop(dir);
}

criterion_group! {
    name = benches;
    config = Criterion::default().without_plots();
    targets = small, big
}
criterion_main!(benches);
