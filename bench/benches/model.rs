//! Model speed: time per OTF evaluation of each non-aperture factor (over a
//! fixed set of 1024 points spread over 0..1.5× the diffraction cutoff), and a
//! 1024×1024 map of full systems (rayon, all cores), with and without the
//! PNG rendering. Run: `cargo bench --bench model`.

use criterion::{BenchmarkId, Criterion, Throughput, criterion_group, criterion_main};
use std::hint::black_box;
use sweepmtf::model::spec::parse_factor;
use sweepmtf::model::{Factor, System};
use sweepmtf::report::model_map::{compute_map, render_map};

fn points() -> Vec<(f64, f64)> {
    (0..1024)
        .map(|i| {
            let r = 700.0 * ((i * 7919) % 1024) as f64 / 1024.0;
            let a = i as f64 * 0.618;
            (r * a.cos(), r * a.sin())
        })
        .collect()
}

fn factors(c: &mut Criterion) {
    let pts = points();
    let specs = [
        ("optics", "diffraction:lambda=550nm,fnum=4"),
        ("defocus", "wave:lambda=550nm,fnum=4,w020=0.5"),
        ("defocus", "wave:lambda=550nm,fnum=4,w020=5"),
        ("defocus", "geometric:blur=20um"),
        ("gaussian", "sigma=1.5um"),
        ("olpf", "4spot:d=4.3um"),
        ("diffusion", "lambda=650nm,depletion=2um,length=20um"),
        ("cte", "n=1000,cti=1e-5,pitch=4.3um"),
        ("cte", "n=100000000,cti=1e-7,pitch=4.3um,model=exact"),
        ("aperture", "rect:A=4.3um,B=4.3um"),
        ("sampling", "rect:px=4.3um,py=4.3um"),
    ];
    let mut g = c.benchmark_group("factor_otf");
    g.throughput(Throughput::Elements(pts.len() as u64));
    for (kind, spec) in specs {
        let f: Box<dyn Factor> = parse_factor(kind, spec).unwrap();
        g.bench_with_input(BenchmarkId::new(kind, spec), &f, |b, f| {
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

fn system(path: &str) -> System {
    System::from_file(
        concat!(env!("CARGO_MANIFEST_DIR"), "/../targets/systems/").to_string() + path,
    )
    .unwrap()
}

fn maps(c: &mut Criterion) {
    let mut g = c.benchmark_group("map_1024");
    g.sample_size(10);
    for name in [
        "aps_c_f4.toml",
        "phone_cmos_f2.toml",
        "ccd_interline_cte.toml",
    ] {
        let s = system(name);
        g.bench_function(BenchmarkId::new("compute", name), |b| {
            b.iter(|| compute_map(&s, 300.0, 1024))
        });
    }
    let s = system("aps_c_f4.toml");
    let m = compute_map(&s, 300.0, 1024);
    g.bench_function("render_png aps_c_f4", |b| {
        b.iter(|| render_map(&m, "bench").unwrap())
    });
    g.finish();
}

criterion_group! {
    name = benches;
    config = Criterion::default()
        .without_plots()
        .warm_up_time(std::time::Duration::from_millis(300))
        .measurement_time(std::time::Duration::from_secs(1));
    targets = factors, maps
}
criterion_main!(benches);
