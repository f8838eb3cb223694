//! Time per OTF evaluation of each detector aperture, sampling grid and the
//! polygon form (criterion). Each iteration evaluates 1024 points spread over
//! |f| ≤ 25/D in all directions. Group `otf_eval` is wall-clock time per 1024
//! evaluations (throughput line: evaluations/s); group `otf_eval_cpu` is this
//! thread's CPU time per single evaluation in ns, which stays meaningful on a
//! busy machine where wall-clock time includes waiting for a core.

use criterion::measurement::{Measurement, ValueFormatter};
use criterion::{Criterion, Throughput, criterion_group, criterion_main};
use std::hint::black_box;
use sweepmtf::model::Factor;
use sweepmtf::model::aperture::{Circle, Hexagon, LShape, Octagon, Polygon, Rect, Rhomb};
use sweepmtf::model::sampling::{HexGrid, RectGrid, Rows};

const D: f64 = 0.005;

/// 1024 points filling the disk |f| ≤ f_max·(1/D) evenly.
fn points_to(f_max: f64) -> Vec<(f64, f64)> {
    (0..POINTS)
        .map(|i| {
            let t = i as f64 * 2.399_963; // golden angle
            let r = f_max / D * ((i as f64 + 0.5) / POINTS as f64).sqrt();
            (r * t.cos(), r * t.sin())
        })
        .collect()
}

/// The benchmark points: |f| ≤ 25/D.
fn points() -> Vec<(f64, f64)> {
    points_to(25.0)
}

fn factors() -> Vec<(&'static str, Box<dyn Factor>)> {
    let s = D / 3f64.sqrt();
    let hex: Vec<[f64; 2]> = vec![
        [s, 0.0],
        [s / 2.0, D / 2.0],
        [-s / 2.0, D / 2.0],
        [-s, 0.0],
        [-s / 2.0, -D / 2.0],
        [s / 2.0, -D / 2.0],
    ];
    let ngon = |n: usize| -> Vec<[f64; 2]> {
        (0..n)
            .map(|k| {
                let a = 2.0 * std::f64::consts::PI * k as f64 / n as f64;
                [0.5 * D * a.cos(), 0.5 * D * a.sin()]
            })
            .collect()
    };
    vec![
        ("rect", Box::new(Rect::new(D, D).unwrap())),
        ("L", Box::new(LShape::new(D, D, 0.4 * D, 0.4 * D).unwrap())),
        ("rhomb", Box::new(Rhomb::new(D, D).unwrap())),
        ("hex", Box::new(Hexagon::new(D).unwrap())),
        ("oct", Box::new(Octagon::new(D).unwrap())),
        ("circle", Box::new(Circle::new(D).unwrap())),
        ("polygon_hex6", Box::new(Polygon::new(hex).unwrap())),
        ("polygon_32gon", Box::new(Polygon::new(ngon(32)).unwrap())),
        ("sampling_rect", Box::new(RectGrid::new(D, D).unwrap())),
        ("sampling_hex", Box::new(HexGrid::new(D, Rows::X).unwrap())),
    ]
}

const POINTS: usize = 1024;

/// Layout of `struct timespec` on 64-bit Linux.
#[repr(C)]
struct Timespec {
    sec: i64,
    nsec: i64,
}

unsafe extern "C" {
    fn clock_gettime(clock: i32, ts: *mut Timespec) -> i32;
}

/// CPU time of the calling thread, ns (Linux CLOCK_THREAD_CPUTIME_ID).
fn thread_cpu_ns() -> u64 {
    const CLOCK_THREAD_CPUTIME_ID: i32 = 3;
    let mut ts = Timespec { sec: 0, nsec: 0 };
    // SAFETY: clock_gettime writes one timespec into the valid, exclusive `ts`.
    unsafe { clock_gettime(CLOCK_THREAD_CPUTIME_ID, &mut ts) };
    ts.sec as u64 * 1_000_000_000 + ts.nsec as u64
}

/// Criterion measurement: thread CPU time, reported per single evaluation.
struct CpuPerEval;

/// Formats values already in ns per evaluation.
struct NsPerEval;

impl ValueFormatter for NsPerEval {
    fn scale_values(&self, _typical: f64, _values: &mut [f64]) -> &'static str {
        "ns/eval (CPU)"
    }
    fn scale_throughputs(&self, _t: f64, _th: &Throughput, _v: &mut [f64]) -> &'static str {
        "ns/eval (CPU)"
    }
    fn scale_for_machines(&self, _values: &mut [f64]) -> &'static str {
        "ns/eval"
    }
}

impl Measurement for CpuPerEval {
    type Intermediate = u64;
    type Value = u64;
    fn start(&self) -> u64 {
        thread_cpu_ns()
    }
    fn end(&self, i: u64) -> u64 {
        thread_cpu_ns() - i
    }
    fn add(&self, a: &u64, b: &u64) -> u64 {
        a + b
    }
    fn zero(&self) -> u64 {
        0
    }
    fn to_f64(&self, v: &u64) -> f64 {
        *v as f64 / POINTS as f64
    }
    fn formatter(&self) -> &dyn ValueFormatter {
        &NsPerEval
    }
}

fn bench_cpu(c: &mut Criterion<CpuPerEval>) {
    let pts = points();
    let mut g = c.benchmark_group("otf_eval_cpu");
    // the polygon's moment-series path (2π|f|R ≤ 4) alone: |f| ≤ 0.5/D
    let low = points_to(0.5);
    for (name, f) in factors()
        .into_iter()
        .filter(|(n, _)| n.starts_with("polygon"))
    {
        g.bench_function(format!("{name}_series_path"), |b| {
            b.iter(|| {
                let mut acc = 0.0;
                for &(u, v) in &low {
                    acc += f.otf(black_box(u), black_box(v)).re;
                }
                acc
            })
        });
    }
    for (name, f) in factors() {
        g.bench_function(name, |b| {
            b.iter(|| {
                let mut acc = 0.0;
                for &(u, v) in &pts {
                    acc += f.otf(black_box(u), black_box(v)).re;
                }
                acc
            })
        });
    }
    g.finish();
}

fn bench(c: &mut Criterion) {
    let pts = points();
    let mut g = c.benchmark_group("otf_eval");
    g.throughput(Throughput::Elements(pts.len() as u64));
    for (name, f) in factors() {
        g.bench_function(name, |b| {
            b.iter(|| {
                let mut acc = 0.0;
                for &(u, v) in &pts {
                    acc += f.otf(black_box(u), black_box(v)).re;
                }
                acc
            })
        });
    }
    g.finish();
}

criterion_group! {
    name = wall;
    config = Criterion::default().without_plots();
    targets = bench
}
criterion_group! {
    name = cpu;
    config = Criterion::default().without_plots().with_measurement(CpuPerEval);
    targets = bench_cpu
}
criterion_main!(wall, cpu);
