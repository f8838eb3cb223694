//! The whole `sweepmtf measure` command against libjpeg-turbo's `djpeg` on
//! 24-megapixel JPEGs (issue 16): interleaved pairs (djpeg, then sweepmtf),
//! the median of the per-pair wall-time ratios, printed as a table.
//!
//! ```sh
//! cargo build --release && cargo run --release --features examples --example djpeg_ratio -- make DIR
//! target/release/examples/djpeg_ratio run DIR [PAIRS]
//! ```
//! `make` writes `wide.jpg` (a 5200×1700 px strip, ≈ 37 % of the frame, q92,
//! region given by `--roi`) and `target.jpg` (the simulator's A4 log target,
//! 6000×4000, q92, region found from the fiducials) with their arguments;
//! `run` also times the wide strip binned through a lens model.
//! `run` skips (exit 0 with a note) when `djpeg` is not installed;
//! `SWEEPMTF_BIN=path` times another build of the CLI instead.
//! Peak memory: `/usr/bin/time -v target/release/sweepmtf measure DIR/wide.jpg $(cat DIR/wide.args)`.

use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};
use std::time::Instant;

fn sweepmtf() -> PathBuf {
    // Another build to compare (e.g. an older commit's binary).
    if let Some(p) = std::env::var_os("SWEEPMTF_BIN") {
        return PathBuf::from(p);
    }
    let exe = std::env::current_exe().expect("own path");
    // target/release/examples/djpeg_ratio → target/release/sweepmtf
    exe.parent()
        .and_then(Path::parent)
        .expect("target folder")
        .join("sweepmtf")
}

fn make(dir: &Path) {
    std::fs::create_dir_all(dir).expect("folder");
    let shot = sweepmtf::measure::synth::wide_strip_shot();
    std::fs::write(dir.join("wide.jpg"), shot.encode(5)).expect("write");
    let roi: Vec<String> = shot
        .quad
        .iter()
        .flatten()
        .map(|v| format!("{v:.2}"))
        .collect();
    std::fs::write(dir.join("wide.args"), format!("--roi {}", roi.join(","))).expect("write");
    let target = Path::new(env!("CARGO_MANIFEST_DIR")).join("targets/a4_log.toml");
    let st = Command::new(sweepmtf())
        .args(["simulate", "--target"])
        .arg(&target)
        .arg("--output")
        .arg(dir.join("target.jpg"))
        .args([
            "--size",
            "6000x4000",
            "--jpeg",
            "92",
            "--full-well",
            "20000",
        ])
        .args(["--read-noise", "3", "--rotate", "2"])
        .status()
        .expect("run sweepmtf simulate");
    assert!(st.success(), "simulate failed");
    std::fs::write(
        dir.join("target.args"),
        format!("--target {}", target.display()),
    )
    .expect("write");
}

fn wall(cmd: &mut Command) -> f64 {
    let t = Instant::now();
    let st = cmd
        .stdout(Stdio::null())
        .stderr(Stdio::null())
        .status()
        .expect("run");
    assert!(st.success(), "{cmd:?} failed");
    t.elapsed().as_secs_f64() * 1e3
}

fn median(mut v: Vec<f64>) -> f64 {
    v.sort_by(f64::total_cmp);
    v[v.len() / 2]
}

fn run(dir: &Path, pairs: usize) {
    if Command::new("djpeg").arg("-version").output().is_err() {
        println!("djpeg is not installed (Debian: libjpeg-turbo-progs); nothing to compare with");
        return;
    }
    let out = tempfile_dir();
    println!("| shot | djpeg ms | sweepmtf measure ms | median ratio | pairs |");
    println!("|---|---|---|---|---|");
    for (name, extra) in [
        ("wide", vec![]),
        ("wide", vec!["--no-refine-roi"]),
        // The cost of binning through a lens model (the shot itself is not
        // distorted, so only the time means anything here).
        ("wide", vec!["--distortion", "ptlens:b=-0.01"]),
        ("target", vec![]),
    ] {
        let photo = dir.join(format!("{name}.jpg"));
        if !photo.exists() {
            continue;
        }
        let args = std::fs::read_to_string(dir.join(format!("{name}.args"))).expect("args");
        let args: Vec<&str> = args.split_whitespace().collect();
        let (mut d, mut m, mut r) = (Vec::new(), Vec::new(), Vec::new());
        for _ in 0..pairs {
            let a = wall(Command::new("djpeg").arg(&photo).stdout(Stdio::null()));
            let b = wall(
                Command::new(sweepmtf())
                    .arg("measure")
                    .arg(&photo)
                    .args(&args)
                    .args(&extra)
                    .arg("-o")
                    .arg(&out),
            );
            d.push(a);
            m.push(b);
            r.push(b / a);
        }
        println!(
            "| {name}{} {} | {:.1} | {:.1} | **{:.2}×** | {pairs} |",
            if extra.is_empty() { "" } else { "," },
            extra.join(" "),
            median(d),
            median(m),
            median(r)
        );
    }
    let _ = std::fs::remove_dir_all(&out);
}

fn tempfile_dir() -> PathBuf {
    let p = std::env::temp_dir().join(format!("djpeg_ratio_{}", std::process::id()));
    std::fs::create_dir_all(&p).expect("temp folder");
    p
}

fn main() {
    let a: Vec<String> = std::env::args().collect();
    let dir = PathBuf::from(a.get(2).map(String::as_str).unwrap_or("bench_shots"));
    match a.get(1).map(String::as_str) {
        Some("make") => make(&dir),
        Some("run") => run(&dir, a.get(3).and_then(|n| n.parse().ok()).unwrap_or(21)),
        _ => eprintln!("usage: djpeg_ratio make DIR | run DIR [PAIRS]"),
    }
}
