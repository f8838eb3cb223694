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
//!    frame's corners (`--target`), each as given (`--no-refine-roi`) and
//!    refined to the edges (the command line's default), and with the chart found automatically
//!    from the target's fiducials; then the same for the mosaic stored as
//!    lossless-JPEG strips and as 256-px lossless-JPEG tiles (DNG
//!    compression 7, as most cameras' raws are compressed). Each group also
//!    times rawler's own whole decode (`decode_raw_with_rawler`) beside our
//!    windowed reader's (`decode_raw`). The files are deleted at the end unless
//!    `SWEEPMTF_BENCH_DNG_DIR` names a folder to keep them in. Peak RSS of
//!    a whole `measure` run is measured separately with `/usr/bin/time -v`
//!    (README, "Camera raw and EXIF") or the `raw_memory` example, since
//!    criterion keeps every case in one process.
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
use sweepmtf::photo::raw::{RawChannel, decode_raw, decode_raw_with_rawler};
use sweepmtf::simulate::dng::{DngSettings, encode_mosaic};
use sweepmtf::simulate::{self, BayerOrder, Camera};
use sweepmtf::target::SweepLaw;

fn dng() -> PathBuf {
    Path::new(concat!(env!("CARGO_MANIFEST_DIR"), "/../testdata/real"))
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

/// The 24 MP files: an uncompressed DNG (as `simulate -o X.dng` writes it)
/// and the same mosaic in lossless-JPEG strips, with the strip, the target
/// corners and the target.
struct Big {
    plain: PathBuf,
    ljpeg: PathBuf,
    tiles: PathBuf,
    strip: [[f64; 2]; 4],
    corners: [[f64; 2]; 4],
    target: sweepmtf::target::Target,
}

fn big_dngs(dir: &Path) -> Big {
    let target = simulate::demo::demo_target(SweepLaw::Log);
    let camera = Camera {
        bayer: Some(BayerOrder::Rggb),
        full_well_e: Some(30000.0),
        read_noise_e: 3.0,
        ..Camera::noiseless(6000, 4000)
    };
    let t = Instant::now();
    let shot = simulate::render(&target, &System::default(), &camera).unwrap();
    let plain = dir.join("big24.dng");
    simulate::write_shot(&shot, &plain).unwrap();
    let ljpeg = dir.join("big24_ljpeg.dng");
    let settings = DngSettings {
        lossless_jpeg: true,
        ..DngSettings::default()
    };
    let bytes = encode_mosaic(&shot.linear, 6000, 4000, BayerOrder::Rggb, 4.3, &settings).unwrap();
    std::fs::write(&ljpeg, bytes).unwrap();
    let tiles = dir.join("big24_ljpeg_tiles.dng");
    let settings = DngSettings {
        lossless_jpeg: true,
        tile_px: 256,
        ..DngSettings::default()
    };
    let bytes = encode_mosaic(&shot.linear, 6000, 4000, BayerOrder::Rggb, 4.3, &settings).unwrap();
    std::fs::write(&tiles, bytes).unwrap();
    let size = |p: &Path| std::fs::metadata(p).unwrap().len() as f64 / 1e6;
    eprintln!(
        "24 MP DNGs rendered and written in {:.1} s (uncompressed {:.1} MB, lossless JPEG strips {:.1} MB, tiles {:.1} MB)",
        t.elapsed().as_secs_f64(),
        size(&plain),
        size(&ljpeg),
        size(&tiles)
    );
    let quad = |q: [f64; 8]| [[q[0], q[1]], [q[2], q[3]], [q[4], q[5]], [q[6], q[7]]];
    Big {
        plain,
        ljpeg,
        tiles,
        strip: quad(shot.roi().unwrap()),
        corners: quad(shot.target_corners),
        target,
    }
}

fn big(c: &mut Criterion) {
    // SWEEPMTF_BENCH_DNG_DIR=folder keeps the files there (for `/usr/bin/time -v` runs).
    let keep = std::env::var_os("SWEEPMTF_BENCH_DNG_DIR").map(PathBuf::from);
    let tmp = tempfile::Builder::new()
        .prefix("sweepmtf-bench-raw")
        .tempdir_in(std::env::temp_dir())
        .unwrap();
    let dir = keep.clone().unwrap_or_else(|| tmp.path().to_path_buf());
    let big = big_dngs(&dir);
    let strip_opts = MeasureOptions {
        roi: Some(big.strip),
        channel: Channel::G,
        ..MeasureOptions::default()
    };
    let target_opts = MeasureOptions {
        roi: Some(big.corners),
        channel: Channel::G,
        ..MeasureOptions::default()
    };
    // The command line refines given corners by default (`--no-refine-roi` turns it off).
    let strip_refined = MeasureOptions {
        refine_roi: true,
        ..strip_opts.clone()
    };
    let target_refined = MeasureOptions {
        refine_roi: true,
        ..target_opts.clone()
    };
    let auto_opts = MeasureOptions {
        channel: Channel::G,
        ..MeasureOptions::default()
    };
    let frame = decode_raw(&big.plain).unwrap();
    eprintln!(
        "24 MP frame {}×{}, decoded buffer {:.1} MB; strip {:?}; target corners {:?}",
        frame.width,
        frame.height,
        frame.decoded_bytes() as f64 / 1e6,
        big.strip,
        big.corners
    );
    drop(frame);
    for (group, path) in [
        ("24mp_dng", &big.plain),
        ("24mp_dng_ljpeg", &big.ljpeg),
        ("24mp_dng_ljpeg_tiles", &big.tiles),
    ] {
        let mut g = c.benchmark_group(group);
        g.sample_size(10);
        g.bench_function("decode_only", |b| {
            b.iter(|| black_box(decode_raw(black_box(path)).unwrap()))
        });
        g.bench_function("decode_only_rawler", |b| {
            b.iter(|| black_box(decode_raw_with_rawler(black_box(path)).unwrap()))
        });
        g.bench_function("measure_g_strip_roi", |b| {
            b.iter(|| black_box(measure_raw(path, "big", None, &strip_opts).unwrap()))
        });
        g.bench_function("measure_g_strip_roi_refined", |b| {
            b.iter(|| black_box(measure_raw(path, "big", None, &strip_refined).unwrap()))
        });
        g.bench_function("measure_g_target_corners", |b| {
            b.iter(|| black_box(measure_raw(path, "big", Some(&big.target), &target_opts).unwrap()))
        });
        g.bench_function("measure_g_target_corners_refined", |b| {
            b.iter(|| {
                black_box(measure_raw(path, "big", Some(&big.target), &target_refined).unwrap())
            })
        });
        g.bench_function("measure_g_auto_location", |b| {
            b.iter(|| black_box(measure_raw(path, "big", Some(&big.target), &auto_opts).unwrap()))
        });
        g.finish();
    }
    if keep.is_some() {
        eprintln!(
            "kept {}, {} and {}",
            big.plain.display(),
            big.ljpeg.display(),
            big.tiles.display()
        );
    }
    drop(tmp);
}

criterion_group! {
    name = benches;
    config = Criterion::default().without_plots();
    targets = small, big
}
criterion_main!(benches);
