//! Stage timings of the search on a 24 MP frame (documented release run, not a
//! bar: `cargo test --release --test it -- --ignored locate_timing:: --nocapture`).

use crate::locate_support;

use locate_support::*;
use std::time::Instant;
use sweepmtf::locate;

#[test]
#[ignore]
fn stage_timings_24mp() {
    let t = test_target(200.0, 140.0);
    let mut rng = Rng(3);
    let hom = random_pose(&t, 6000, 4000, 30.0, 0.5, &mut rng);
    let look = Look {
        blur_px: 1.5,
        supersample: 1,
        ..Look::default()
    };
    let plane = render(&[(&t, hom)], 6000, 4000, &look, &mut rng);
    let cpu = || {
        // utime + stime of all threads, in clock ticks (100 Hz).
        let st = std::fs::read_to_string("/proc/self/stat").unwrap();
        let f: Vec<&str> = st.rsplit(')').next().unwrap().split_whitespace().collect();
        (f[11].parse::<f64>().unwrap() + f[12].parse::<f64>().unwrap()) * 10.0
    };
    let n = 30;
    let (w0, c0) = (Instant::now(), cpu());
    for _ in 0..n {
        locate::find_chart(&plane, &t, None).unwrap();
    }
    eprintln!(
        "find_chart on 24 MP: {:.1} ms wall, {:.1} ms CPU (all threads) per call",
        w0.elapsed().as_secs_f64() * 1e3 / n as f64,
        (cpu() - c0) / n as f64
    );
    for _ in 0..3 {
        let t0 = Instant::now();
        let small = locate::downscale::reduce_for_search(&plane);
        let t1 = Instant::now();
        let c = locate::blobs::find_candidates(&small);
        let t2 = Instant::now();
        let s = locate::search(&plane, &t).unwrap();
        let t3 = Instant::now();
        eprintln!(
            "reduce {:.1} ms, blobs {:.1} ms ({} candidates), full search {:.1} ms ({} charts)",
            (t1 - t0).as_secs_f64() * 1e3,
            (t2 - t1).as_secs_f64() * 1e3,
            c.len(),
            (t3 - t2).as_secs_f64() * 1e3,
            s.charts.len()
        );
    }
}
