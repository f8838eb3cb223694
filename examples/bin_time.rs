//! CPU time of binning one 24 MP strip (`measure::profile::bin_planes` over
//! a JPEG's 8-bit codes read through a tone table, as `measure` bins a
//! luma decode): a 4170 × 541 px strip of a log sweep, on a pool of one
//! thread and of two, medians of N runs.
//!
//! ```sh
//! cargo run --release --features examples --example bin_time -- [N [DEGREES]]
//! ```

use std::time::Instant;
use sweepmtf::geometry::{Homography, rect_corners};
use sweepmtf::measure::profile::{BinOptions, Strip, bin_planes};
use sweepmtf::photo::plane_ref::{Codes, PlaneData, PlaneRef};

fn main() {
    let n: usize = std::env::args()
        .nth(1)
        .map_or(15, |s| s.parse().expect("a count"));
    let (w, h) = (6000usize, 4000usize);
    // A log sweep along x (0.005 to 0.45 cy/px), slightly turned, with noise.
    let (x0, y0, len, wid) = (900.0, 380.0, 4170.0, 541.0);
    let mut codes = vec![0u8; w * h];
    let mut st = 1u64;
    for j in 0..h {
        for i in 0..w {
            let s = (i as f64 - x0).clamp(0.0, len);
            let (f0, f1) = (0.005f64, 0.45f64);
            let k = (f1 / f0).ln() / len;
            let phase = f0 * ((k * s).exp() - 1.0) / k;
            st = st
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            let noise = ((st >> 40) as f64 / (1u64 << 24) as f64 - 0.5) * 6.0;
            let v = 128.0 + 90.0 * (std::f64::consts::TAU * phase).cos() + noise;
            codes[j * w + i] = v.clamp(0.0, 255.0) as u8;
        }
    }
    let lut: Vec<f32> = (0..256).map(|c| (c as f32 / 255.0).powf(2.2)).collect();
    let mix = [(0usize, 1.0f32)];
    let plane = PlaneRef {
        width: w,
        height: h,
        step: (1, 1),
        offset: (0, 0),
        data: PlaneData::Codes8(Codes {
            codes: &codes,
            channels: 1,
            mix: &mix,
            lut: &lut,
        }),
    };
    let a = std::env::args()
        .nth(2)
        .map_or(0.3, |s| s.parse::<f64>().expect("an angle in degrees"))
        .to_radians();
    let (c, s) = (a.cos(), a.sin());
    let quad = [
        [x0, y0],
        [x0 + len * c, y0 + len * s],
        [x0 + len * c - wid * s, y0 + len * s + wid * c],
        [x0 - wid * s, y0 + wid * c],
    ];
    let strip = Strip {
        to_image: Homography::from_quads(&rect_corners(0.0, 0.0, len, wid), &quad)
            .expect("a strip"),
        lens: None,
        length: len,
        width: wid,
    };
    let opts = BinOptions::default();
    for threads in [1, 2] {
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .expect("a pool");
        let mut t = Vec::new();
        let mut samples = 0;
        for _ in 0..n {
            let s = Instant::now();
            let p = pool.install(|| bin_planes(&[plane], &strip, &opts));
            t.push(s.elapsed().as_secs_f64() * 1e3);
            samples = p.samples;
        }
        t.sort_by(f64::total_cmp);
        println!(
            "{threads} thread(s): {:.2} ms median, {:.2} min of {n}; {samples} samples, {:.2} ns/sample (min)",
            t[n / 2],
            t[0],
            t[0] * 1e6 / samples as f64 * threads as f64
        );
    }
}
