//! The issue-7 bar, end to end on the project's camera simulator: random shots
//! of the shipped A4 log chart (`targets/a4_log.toml`; any rotation, tilt up to
//! 45°, bounding box covering 10–95 % of the frame's area, fall-off, a light
//! gradient, noise at SNR ≈ 50, mild defocus, JPEG q90) are located with no
//! corners given and measured; corners and every sweep's MTF are scored
//! against the simulator's truth.
//!
//! `-- --refine --shots 40` instead checks `--roi` refinement: the main sweep's
//! MTF RMS with exact and ±5 px corners, without and with refinement, for the
//! target frame's corners (with the target) and one strip's (without), and how
//! far the refined strip's ends are slanted from the printed bars; `--sweep 2`
//! scores the low-contrast (0.2) sweep instead.
//!
//! Run: `cargo run --release --features examples --example locate_sweep [-- --shots 200 --seed 7
//! --min-width 1000 --max-width 1600 --verbose --exact]`. Prints a line per shot
//! that misses a bar (all with `--verbose`; `--exact` measures it again with the
//! simulator's exact corners, to tell location's errors from measurement's), then the table: found rate, corner
//! RMS/max, MTF RMS median/95th/max per bar category, and time per shot.

#[path = "../tests/it/locate_support/sweep.rs"]
mod sweep;

use sweep::{Outcome, Pose, Rng, bar};

fn arg<T: std::str::FromStr>(args: &[String], name: &str, default: T) -> T {
    args.iter()
        .position(|a| a == name)
        .and_then(|i| args.get(i + 1))
        .and_then(|v| v.parse().ok())
        .unwrap_or(default)
}

fn pct(v: &mut [f64], q: f64) -> f64 {
    if v.is_empty() {
        return f64::NAN;
    }
    v.sort_by(f64::total_cmp);
    v[((v.len() - 1) as f64 * q).round() as usize]
}

fn describe(o: &Outcome) -> String {
    let p = &o.pose;
    format!(
        "{}×{} rot {:5.1} tilt {:4.1}/{:5.1} cover {:4.2} chart {:4.0} px falloff {:.2} grad {:+.2},{:+.2} SNR {:3.0} W020 {:.2}",
        p.size.0,
        p.size.1,
        p.rotate_deg,
        p.tilt_deg,
        p.tilt_axis_deg,
        p.cover,
        o.chart_px,
        p.falloff,
        p.gradient[0],
        p.gradient[1],
        p.snr(),
        p.w020
    )
}

fn main() {
    let args: Vec<String> = std::env::args().collect();
    let shots: usize = arg(&args, "--shots", 200);
    let seed: u64 = arg(&args, "--seed", 7);
    let wmin: usize = arg(&args, "--min-width", 1000);
    let wmax: usize = arg(&args, "--max-width", 1600);
    let verbose = args.iter().any(|a| a == "--verbose");
    let exact = args.iter().any(|a| a == "--exact");
    let target = sweep::a4_log();
    let mut rng = Rng(seed);
    let poses: Vec<Pose> = (0..shots)
        .map(|i| Pose::random(&mut rng, (wmin, wmax), seed * 1000 + i as u64))
        .collect();
    if args.iter().any(|a| a == "--refine") {
        let which: usize = arg(&args, "--sweep", 0);
        refine_report(&target, &poses, seed, which, verbose);
        return;
    }
    let mut outcomes = Vec::new();
    for (i, pose) in poses.iter().enumerate() {
        let o = sweep::run(&target, pose);
        let miss = o.error.is_some()
            || o.corner_err_px.iter().any(|e| *e > 1.0)
            || o.sweeps
                .iter()
                .any(|s| s.rms.is_nan() || s.rms > bar(s.contrast));
        if verbose || miss {
            println!("shot {i:3}: {}", describe(&o));
            match &o.error {
                Some(e) => println!("    FAILED: {e}"),
                None => {
                    let c: Vec<String> =
                        o.corner_err_px.iter().map(|e| format!("{e:.2}")).collect();
                    let s: Vec<String> = o
                        .sweeps
                        .iter()
                        .map(|s| {
                            format!(
                                "{} {:.4}{} (n {}, top {:.2} cy/px, worst {:.3} at {:.3})",
                                s.id,
                                s.rms,
                                if s.rms <= bar(s.contrast) {
                                    ""
                                } else {
                                    " MISS"
                                },
                                s.n,
                                s.f_top,
                                s.worst.0,
                                s.worst.1
                            )
                        })
                        .collect();
                    println!("    corners [{}] px; {}", c.join(", "), s.join("; "));
                    if exact {
                        let x = sweep::run_with(&target, pose, sweep::exact_corners);
                        let s: Vec<String> = x
                            .sweeps
                            .iter()
                            .map(|s| format!("{} {:.4}", s.id, s.rms))
                            .collect();
                        println!("    with the exact corners: {}", s.join("; "));
                    }
                }
            }
        }
        outcomes.push(o);
    }
    report(&outcomes);
}

fn report(outcomes: &[Outcome]) {
    let n = outcomes.len();
    let found: Vec<&Outcome> = outcomes.iter().filter(|o| o.error.is_none()).collect();
    let errs: Vec<f64> = found.iter().flat_map(|o| o.corner_err_px.clone()).collect();
    let rms = (errs.iter().map(|e| e * e).sum::<f64>() / errs.len().max(1) as f64).sqrt();
    let max = errs.iter().cloned().fold(0.0, f64::max);
    println!();
    println!(
        "shots {n}; found {} ({:.1} %); corner error RMS {rms:.3} px, max {max:.3} px",
        found.len(),
        100.0 * found.len() as f64 / n.max(1) as f64
    );
    println!();
    println!("| category | bar | sweeps | within bar | MTF RMS median | 95th | max |");
    println!("|---|---|---|---|---|---|---|");
    type Pick = Box<dyn Fn(&Outcome) -> bool>;
    let cats: Vec<(String, Pick)> = vec![
        ("all shots".into(), Box::new(|_: &Outcome| true)),
        (
            "tilt ≤ 30°".into(),
            Box::new(|o: &Outcome| o.pose.tilt_deg <= 30.0),
        ),
        (
            "tilt 30–45°".into(),
            Box::new(|o: &Outcome| o.pose.tilt_deg > 30.0),
        ),
        (
            "cover < 30 %".into(),
            Box::new(|o: &Outcome| o.pose.cover < 0.3),
        ),
        (
            "cover ≥ 30 %".into(),
            Box::new(|o: &Outcome| o.pose.cover >= 0.3),
        ),
    ];
    for id in ["main", "c0.4", "c0.2"] {
        for (name, pick) in &cats {
            let mut v: Vec<f64> = Vec::new();
            let mut b = 0.0;
            for o in found.iter().filter(|o| pick(o)) {
                for s in o.sweeps.iter().filter(|s| s.id == id) {
                    b = bar(s.contrast);
                    v.push(if s.rms.is_nan() { f64::INFINITY } else { s.rms });
                }
            }
            if v.is_empty() {
                continue;
            }
            let within = v.iter().filter(|r| **r <= b).count();
            let (med, p95, mx) = (pct(&mut v, 0.5), pct(&mut v, 0.95), pct(&mut v, 1.0));
            println!(
                "| {id} ({name}) | {b} | {} | {within} ({:.1} %) | {med:.4} | {p95:.4} | {mx:.4} |",
                v.len(),
                100.0 * within as f64 / v.len() as f64
            );
        }
    }
    let mut sim: Vec<f64> = outcomes.iter().map(|o| o.sim_ms).collect();
    let mut mea: Vec<f64> = outcomes.iter().map(|o| o.measure_ms).collect();
    println!();
    println!(
        "time per shot: simulate {:.0} ms median; decode + locate + measure {:.0} ms median, {:.0} ms max",
        pct(&mut sim, 0.5),
        pct(&mut mea, 0.5),
        pct(&mut mea, 1.0)
    );
}

/// `--refine`: MTF RMS of the main sweep with exact and ±5 px corners, without and
/// with `--roi` refinement, for the target frame's corners and a single strip's.
fn refine_report(
    target: &sweepmtf::target::Target,
    poses: &[Pose],
    seed: u64,
    which: usize,
    verbose: bool,
) {
    println!(
        "scored on sweep '{}' (contrast {})",
        target.sweeps[which].id, target.sweeps[which].contrast
    );
    println!(
        "| corners | shots | exact | exact, refined | ±5 px | ±5 px, refined | ±5 px refined − exact | refined corner error max | ends' slant max | fell back |"
    );
    println!("|---|---|---|---|---|---|---|---|---|---|");
    let mut refine_times = Vec::new();
    for strip in [false, true] {
        let mut rng = Rng(seed ^ 0xABCD);
        let mut cols: [Vec<f64>; 7] = Default::default();
        let mut ms: Vec<f64> = Vec::new();
        let mut fell = 0;
        let mut failed = 0;
        for (i, pose) in poses.iter().enumerate() {
            match sweep::refine_trial_on(target, pose, which, strip, 5.0, &mut rng) {
                Ok(t) => {
                    if verbose || t.jittered_refined > 1.5 * t.exact + 0.002 {
                        println!(
                            "shot {i:3} {}: exact {:.4} exact+refine {:.4} ±5 {:.4} ±5+refine {:.4}; corners given {:.2} → {:.2} px; ends' slant {:+.2} / {:+.2} px; {:?}",
                            if strip { "strip" } else { "target" },
                            t.exact,
                            t.exact_refined,
                            t.jittered,
                            t.jittered_refined,
                            t.given_err_px,
                            t.refined_err_px,
                            t.ends_slant_px[0],
                            t.ends_slant_px[1],
                            t.notes
                        );
                    }
                    ms.push(t.refine_ms);
                    if t.notes.iter().any(|n| n.contains("as given")) {
                        fell += 1;
                    }
                    for (c, v) in cols.iter_mut().zip([
                        t.exact,
                        t.exact_refined,
                        t.jittered,
                        t.jittered_refined,
                        t.refined_err_px,
                        t.jittered_refined - t.exact,
                        t.ends_slant_px[0].abs().max(t.ends_slant_px[1].abs()),
                    ]) {
                        c.push(if v.is_nan() { f64::INFINITY } else { v });
                    }
                }
                Err(e) => {
                    failed += 1;
                    println!("shot {i:3}: {e}");
                }
            }
        }
        let cell = |v: &mut Vec<f64>| format!("{:.4} / {:.4}", pct(v, 0.5), pct(v, 1.0));
        println!(
            "| {} | {}{} | {} | {} | {} | {} | {} | {:.2} px | {} | {fell} |",
            if strip {
                "one strip, no target"
            } else {
                "target frame, --target"
            },
            cols[0].len(),
            if failed > 0 {
                format!(" ({failed} failed)")
            } else {
                String::new()
            },
            cell(&mut cols[0]),
            cell(&mut cols[1]),
            cell(&mut cols[2]),
            cell(&mut cols[3]),
            cell(&mut cols[5]),
            pct(&mut cols[4], 1.0),
            if strip {
                format!("{:.2} px", pct(&mut cols[6], 1.0))
            } else {
                "–".to_string()
            },
        );
        refine_times.push((strip, pct(&mut ms, 0.5), pct(&mut ms, 1.0)));
    }
    println!(
        "(MTF RMS of the main sweep against the truth over 0.01–0.45 cy/px: median / max; \
         ends' slant: px along the strip between an end's two refined corners and the printed bar, by the simulator's exact corners)"
    );
    for (strip, med, max) in refine_times {
        println!(
            "refine_roi ({}): {med:.1} ms median, {max:.1} ms max",
            if strip { "strip" } else { "target" }
        );
    }
}
