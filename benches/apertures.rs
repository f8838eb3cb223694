//! Time per OTF evaluation of each detector aperture, sampling grid and the
//! polygon form (criterion). Each iteration evaluates 1024 points spread over
//! |f| ≤ 25/D in all directions; the throughput line gives evaluations/s.

use criterion::{Criterion, Throughput, criterion_group, criterion_main};
use std::hint::black_box;
use sweepmtf::model::Factor;
use sweepmtf::model::aperture::{Circle, Hexagon, LShape, Octagon, Polygon, Rect, Rhomb};
use sweepmtf::model::sampling::{HexGrid, RectGrid, Rows};

const D: f64 = 0.005;

fn points() -> Vec<(f64, f64)> {
    (0..1024)
        .map(|i| {
            let t = i as f64 * 2.399_963; // golden angle
            let r = 25.0 / D * ((i as f64 + 0.5) / 1024.0).sqrt();
            (r * t.cos(), r * t.sin())
        })
        .collect()
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
    name = benches;
    config = Criterion::default().without_plots();
    targets = bench
}
criterion_main!(benches);
