//! Peak memory and time of one raw measurement in a fresh process (criterion
//! keeps every case in one process, so its peaks mix): run once per case on
//! the 24 MP DNGs that `cargo bench --manifest-path bench/Cargo.toml --bench raw` keeps with
//! `SWEEPMTF_BENCH_DNG_DIR=folder`.
//!
//! `cargo run --release --features examples --example raw_memory -- FILE.dng MODE`, MODE one of
//! `decode` (our decoder, whole frame), `rawler` (rawler's whole decode),
//! `strip` (`--roi` on the demo target's sweep strip), `corners` (`--roi` =
//! the target frame's corners, with the target) or `auto` (chart found from
//! the fiducials); `strip+refine` and `corners+refine` refine the given
//! corners to the edges first, as the command line does by default. Prints the process's peak RSS (VmHWM) and the wall time.
//! An optional third argument repeats the case N times (for `perf record`)
//! and prints the median time as well.
//!
//! Several modes joined by commas (`decode,auto+refine`) take turns, one run
//! of each per repetition, and each later mode's median time is also given
//! relative to the first's, as the median of the per-repetition ratios: on a
//! shared machine whose speed drifts, neighbouring runs see the same load.

use std::path::PathBuf;
use std::time::Instant;
use sweepmtf::measure::{MeasureOptions, measure_raw};
use sweepmtf::photo::linearise::Channel;
use sweepmtf::photo::raw::{decode_raw, decode_raw_with_rawler};
use sweepmtf::simulate::demo::demo_target;
use sweepmtf::target::SweepLaw;

fn peak_rss_mb() -> f64 {
    let status = std::fs::read_to_string("/proc/self/status").unwrap_or_default();
    status
        .lines()
        .find(|l| l.starts_with("VmHWM:"))
        .and_then(|l| l.split_whitespace().nth(1))
        .and_then(|v| v.parse::<f64>().ok())
        .map_or(f64::NAN, |kib| kib * 1024.0 / 1e6)
}

fn main() {
    let mut args = std::env::args().skip(1);
    let (Some(file), Some(mode)) = (args.next(), args.next()) else {
        eprintln!(
            "usage: raw_memory FILE.dng decode|rawler|strip[+refine]|corners[+refine]|auto [REPEAT]"
        );
        std::process::exit(2);
    };
    let path = PathBuf::from(file);
    let target = demo_target(SweepLaw::Log);
    // The demo target's strip and frame on the bench's 6000×4000 shot (px).
    let strip = [
        [1000.0, 1000.0],
        [5000.0, 1000.0],
        [5000.0, 2000.0],
        [1000.0, 2000.0],
    ];
    let corners = [
        [600.0, 400.0],
        [5400.0, 400.0],
        [5400.0, 3600.0],
        [600.0, 3600.0],
    ];
    let modes: Vec<&str> = mode.split(',').collect();
    let repeat: usize = args.next().and_then(|n| n.parse().ok()).unwrap_or(1).max(1);
    // times[m][r]: mode m's wall time in repetition r (ms).
    let mut times = vec![Vec::with_capacity(repeat); modes.len()];
    let mut last = vec![None; modes.len()];
    for _ in 0..repeat {
        for (k, m) in modes.iter().enumerate() {
            let opts = |roi| MeasureOptions {
                roi,
                channel: Channel::G,
                refine_roi: m.ends_with("+refine"),
                ..MeasureOptions::default()
            };
            let t = Instant::now();
            last[k] = Some(run(&path, m, &target, strip, corners, &opts));
            times[k].push(t.elapsed().as_secs_f64() * 1e3);
        }
    }
    let median = |mut v: Vec<f64>| {
        v.sort_by(f64::total_cmp);
        v[v.len() / 2]
    };
    for (k, m) in modes.iter().enumerate() {
        let first = times[k][0];
        let med = median(times[k].clone());
        let ratio = if k > 0 {
            let r = times[k].iter().zip(&times[0]).map(|(b, a)| b / a).collect();
            format!(", {:.2} × {} (median ratio)", median(r), modes[0])
        } else {
            String::new()
        };
        match last[k].take().expect("at least one run") {
            Ok(w) => println!(
                "{m}: {first:.1} ms (median of {repeat}: {med:.1} ms{ratio}), peak RSS {:.1} MB ({w})",
                peak_rss_mb()
            ),
            Err(e) => {
                eprintln!("{e}");
                std::process::exit(1);
            }
        }
    }
}

/// One run of MODE on PATH: what it found, or the error line.
fn run(
    path: &std::path::Path,
    mode: &str,
    target: &sweepmtf::target::Target,
    strip: [[f64; 2]; 4],
    corners: [[f64; 2]; 4],
    opts: &dyn Fn(Option<[[f64; 2]; 4]>) -> MeasureOptions,
) -> Result<String, String> {
    let path = path.to_path_buf();
    let target = target.clone();
    match mode.trim_end_matches("+refine") {
        "decode" => decode_raw(&path)
            .map(|f| f.decoder)
            .map_err(|e| e.to_string()),
        "rawler" => decode_raw_with_rawler(&path)
            .map(|f| f.decoder)
            .map_err(|e| e.to_string()),
        "strip" => measure_raw(&path, "shot", None, &opts(Some(strip)))
            .map(|m| format!("{} curves", m.curves.len()))
            .map_err(|e| e.to_string()),
        "corners" => measure_raw(&path, "shot", Some(&target), &opts(Some(corners)))
            .map(|m| format!("{} curves", m.curves.len()))
            .map_err(|e| e.to_string()),
        "auto" => measure_raw(&path, "shot", Some(&target), &opts(None))
            .map(|m| format!("{} curves", m.curves.len()))
            .map_err(|e| e.to_string()),
        other => Err(format!("unknown mode {other}")),
    }
}
