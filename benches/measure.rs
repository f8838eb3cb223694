//! Speed of `measure` on a 24-megapixel JPEG against decoding the same file
//! alone with the same decoder (issue 5: measure ≤ 1.3× decode-only).
//! Run: `cargo bench --bench measure`.

use criterion::{Criterion, criterion_group, criterion_main};
use std::hint::black_box;
use sweepmtf::measure::synth::{SynthShot, standard_cases, strip_quad};
use sweepmtf::measure::{MeasureOptions, measure_decoded};
use sweepmtf::photo::decode::decode_bytes;

fn big_shot() -> SynthShot {
    let base = standard_cases().remove(1);
    SynthShot {
        name: "big".into(),
        width: 6000,
        height: 4000,
        quad: strip_quad(3000.0, 2000.0, 5600.0, 400.0, 3.0, 0.0),
        length: 5600.0,
        strip_width: 400.0,
        law: sweepmtf::measure::PhaseLaw {
            c2: (0.6f64 / 0.004).ln() / 5600.0,
            ..base.law
        },
        ..base
    }
}

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
