//! Raw decode speed and memory on the real Canon 550D DNG (1888×1182, 14-bit
//! uncompressed): `decode_raw` alone, decode + the green planes a `--channel g`
//! measurement bins, and the EXIF facts alone. Prints the first (cold) decode
//! time, which includes rawler's one-off camera-table load, and the process's
//! peak RSS against the decoded CFA frame's size.
//!
//! Run: `cargo bench --bench raw`

use criterion::{Criterion, criterion_group, criterion_main};
use std::hint::black_box;
use std::path::{Path, PathBuf};
use std::time::Instant;
use sweepmtf::photo::exif::read_facts;
use sweepmtf::photo::raw::{RawChannel, decode_raw};

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

fn bench(c: &mut Criterion) {
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
    eprintln!(
        "current RSS with frame and planes held: {:?} KiB",
        status_kib("VmRSS:")
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

criterion_group!(benches, bench);
criterion_main!(benches);
