//! Interleaved timing of the 24 MP JPEG speed check (`cargo bench --bench
//! measure`'s shot): decode only, then decode + measure, in turns, N rounds;
//! prints each median and the median of the per-round ratios (robust on a
//! machine whose speed drifts). `cargo run --release --features examples --example jpeg_ratio -- [N]`.

use std::hint::black_box;
use std::time::Instant;
use sweepmtf::measure::synth::big_shot;
use sweepmtf::measure::{MeasureOptions, measure_decoded};
use sweepmtf::photo::decode::decode_bytes;

fn main() {
    let rounds: usize = std::env::args()
        .nth(1)
        .and_then(|n| n.parse().ok())
        .unwrap_or(21)
        .max(1);
    let shot = big_shot();
    let bytes = shot.encode(5);
    let opts = MeasureOptions {
        roi: Some(shot.quad),
        ..MeasureOptions::default()
    };
    let ms = |t: Instant| t.elapsed().as_secs_f64() * 1e3;
    let (mut dec, mut all, mut ratio, mut meas) = (Vec::new(), Vec::new(), Vec::new(), Vec::new());
    for _ in 0..rounds {
        let t = Instant::now();
        black_box(decode_bytes(&bytes, "big").unwrap());
        let d = ms(t);
        let t = Instant::now();
        let decoded = decode_bytes(&bytes, "big").unwrap();
        let t2 = Instant::now();
        black_box(measure_decoded(&decoded, "big", None, &opts).unwrap());
        meas.push(ms(t2));
        let a = ms(t);
        dec.push(d);
        all.push(a);
        ratio.push(a / d);
    }
    let median = |mut v: Vec<f64>| {
        v.sort_by(f64::total_cmp);
        v[v.len() / 2]
    };
    println!(
        "decode only {:.1} ms, decode + measure {:.1} ms (measure {:.1}), median ratio {:.3} ({rounds} rounds)",
        median(dec),
        median(all),
        median(meas),
        median(ratio)
    );
}
