//! Speed of `measure` on a 24-megapixel JPEG against decoding the same file
//! alone with the same decoder (issue 5: measure ≤ 1.3× decode-only).
//! Run: `cargo bench --bench measure`.

use criterion::{Criterion, criterion_group, criterion_main};
use std::hint::black_box;
use sweepmtf::measure::synth::big_shot;
use sweepmtf::measure::{MeasureOptions, measure_decoded};
use sweepmtf::photo::decode::decode_bytes;

fn bench(c: &mut Criterion) {
    let shot = big_shot();
    let bytes = shot.encode(5);
    let opts = MeasureOptions {
        roi: Some(shot.quad),
        ..MeasureOptions::default()
    };
    let mut g = c.benchmark_group("24mp_jpeg");
    g.sample_size(10);
    g.bench_function("decode_only", |b| {
        b.iter(|| black_box(decode_bytes(black_box(&bytes), "big").unwrap()))
    });
    g.bench_function("decode_and_measure", |b| {
        b.iter(|| {
            let d = decode_bytes(black_box(&bytes), "big").unwrap();
            black_box(measure_decoded(&d, "big", None, &opts).unwrap())
        })
    });
    let dec = decode_bytes(&bytes, "big").unwrap();
    g.bench_function("measure_only", |b| {
        b.iter(|| black_box(measure_decoded(&dec, "big", None, &opts).unwrap()))
    });
    g.finish();
}

criterion_group! {
    name = benches;
    config = Criterion::default().without_plots();
    targets = bench
}
criterion_main!(benches);
