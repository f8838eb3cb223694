//! Speed of automatic chart location on a 24-megapixel frame (6000×4000):
//! search on the reduced image, refine at full resolution. Bar: ≤ 200 ms.
//! Run: `cargo bench --bench locate`.

#[path = "../../tests/it/locate_support/mod.rs"]
mod locate_support;

use criterion::{Criterion, criterion_group, criterion_main};
use locate_support::*;
use sweepmtf::locate;

fn bench(c: &mut Criterion) {
    let t = test_target(200.0, 140.0);
    let (w, h) = (6000, 4000);
    let mut g = c.benchmark_group("locate_24mp");
    g.sample_size(10);
    for (name, coverage, seed) in [("chart_50pct", 0.5, 3u64), ("chart_10pct", 0.1, 5)] {
        let mut rng = Rng(seed);
        let hom = random_pose(&t, w, h, 30.0, coverage, &mut rng);
        let look = Look {
            blur_px: 1.5,
            vignette: 0.3,
            gradient: [0.2, -0.1],
            noise: [0.004, 0.01],
            supersample: 1,
            ..Look::default()
        };
        let plane = render(&[(&t, hom)], w, h, &look, &mut rng);
        let found = locate::find_chart(&plane, &t, None).expect("chart found");
        let truth = true_corners(&t, &hom);
        let err = (0..4)
            .map(|i| {
                (found.corners_px[i][0] - truth[i][0]).hypot(found.corners_px[i][1] - truth[i][1])
            })
            .fold(0.0, f64::max);
        eprintln!("{name}: max corner error {err:.3} px");
        g.bench_function(name, |b| {
            b.iter(|| locate::find_chart(&plane, &t, None).unwrap())
        });
    }
    g.finish();
    // The real photo of another chart design (no chart of ours in it): time to say so.
    let path = concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/../testdata/real/chart_photo/mtfmapper_perspective_chart_photo.jpg"
    );
    let plane = load_linear_luma(path);
    c.bench_function("locate_realphoto_not_found", |b| {
        b.iter(|| locate::find_chart(&plane, &t, None).unwrap_err())
    });
}

criterion_group! {
    name = benches;
    config = Criterion::default().without_plots();
    targets = bench
}
criterion_main!(benches);
