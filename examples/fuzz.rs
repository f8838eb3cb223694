//! Fuzzing on stable Rust: mutated JPEG, PNG, TIFF, DNG, target TOML,
//! sineMTF target and system TOML files (see `sweepmtf::fuzz`) fed to the
//! library's entry points, every case guarded.
//!
//! ```text
//! cargo run --release --features examples --example fuzz -- [--cases N] [--seed S] [--from K] [--log FILE]
//! cargo run --release --features examples --example fuzz -- --seed S --dump K FILE
//! ```
//!
//! The cases run in a child process (this program re-run with `--child`),
//! each inside `catch_unwind`, its peak RSS measured (Linux: `clear_refs`
//! then `VmHWM`), the child's address space capped at 4 GB. The parent
//! reads the child's per-case lines; a child that dies or stays silent for
//! 60 s is killed, its case counted, and a new child goes on from the next
//! case. Prints counts: clean errors, successes, panics, crashes, cases over
//! 10 s, cases over 1 GB; lists every bad case with its mutation, so it can
//! be rerun alone (`--from K --cases 1`).

use std::io::{BufRead, BufReader, Write};
use std::path::PathBuf;
use std::process::{Command, Stdio};
use std::sync::mpsc;
use std::time::{Duration, Instant};
use sweepmtf::fuzz::Corpus;

const SLOW_S: f64 = 10.0;
const BIG_KB: u64 = 1 << 20;
const KILL_AFTER: Duration = Duration::from_secs(60);

fn arg(args: &[String], name: &str) -> Option<String> {
    args.iter()
        .position(|a| a == name)
        .and_then(|i| args.get(i + 1).cloned())
}

fn root() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
}

fn main() {
    let args: Vec<String> = std::env::args().collect();
    let seed: u64 = arg(&args, "--seed")
        .and_then(|s| s.parse().ok())
        .unwrap_or(19);
    // `--dump K FILE`: writes case K's mutated file, to look at or rerun.
    if let (Some(k), Some(file)) = (
        arg(&args, "--dump"),
        args.iter().skip_while(|a| *a != "--dump").nth(2),
    ) {
        let corpus = Corpus::new(&root()).expect("seeds");
        let (s, bytes, what) = corpus.case(seed, k.parse().expect("a case number"));
        std::fs::write(file, &bytes).expect("writes the case");
        println!("case {k}: {} ({what}) -> {file}", s.name);
        return;
    }
    if args.iter().any(|a| a == "--child") {
        let from: u64 = arg(&args, "--from").unwrap().parse().unwrap();
        let to: u64 = arg(&args, "--to").unwrap().parse().unwrap();
        child(seed, from, to);
        return;
    }
    let cases: u64 = arg(&args, "--cases")
        .and_then(|s| s.parse().ok())
        .unwrap_or(1000);
    let start: u64 = arg(&args, "--from")
        .and_then(|s| s.parse().ok())
        .unwrap_or(0);
    let log = arg(&args, "--log").map(PathBuf::from);
    parent(seed, start, start + cases, log);
}

/// Linux only: resets the peak RSS of this process.
fn reset_peak() {
    let _ = std::fs::write("/proc/self/clear_refs", "5");
}

/// Linux only: the peak RSS in kB since the last reset.
fn peak_kb() -> u64 {
    std::fs::read_to_string("/proc/self/status")
        .ok()
        .and_then(|s| {
            s.lines()
                .find(|l| l.starts_with("VmHWM:"))
                .and_then(|l| l.split_whitespace().nth(1)?.parse().ok())
        })
        .unwrap_or(0)
}

fn child(seed: u64, from: u64, to: u64) {
    #[cfg(target_os = "linux")]
    unsafe {
        let lim = libc::rlimit {
            rlim_cur: 4 << 30,
            rlim_max: 4 << 30,
        };
        libc::setrlimit(libc::RLIMIT_AS, &lim);
    }
    std::panic::set_hook(Box::new(|info| {
        eprintln!("panic: {info}");
    }));
    let corpus = Corpus::new(&root()).expect("seeds");
    let dir = tempfile::tempdir().expect("temp dir");
    let out = std::io::stdout();
    for i in from..to {
        {
            let mut o = out.lock();
            let _ = writeln!(o, "B {i}");
            let _ = o.flush();
        }
        reset_peak();
        let t = Instant::now();
        let r = std::panic::catch_unwind(|| corpus.run(seed, i, dir.path()));
        let ms = t.elapsed().as_secs_f64() * 1e3;
        let status = match r {
            Ok(Ok(())) => "ok".to_string(),
            Ok(Err(e)) => format!("err {}", e.replace('\n', " ")),
            Err(_) => "panic".to_string(),
        };
        let mut o = out.lock();
        let _ = writeln!(o, "E {i} {ms:.1} {} {status}", peak_kb());
        let _ = o.flush();
    }
}

#[derive(Default)]
struct Counts {
    ok: u64,
    clean: u64,
    contained: u64,
    panic: u64,
    crash: u64,
    slow: u64,
    big: u64,
    max_ms: f64,
    max_kb: u64,
    bad: Vec<String>,
}

fn parent(seed: u64, from: u64, to: u64, log: Option<PathBuf>) {
    let corpus = Corpus::new(&root()).expect("seeds");
    let exe = std::env::current_exe().expect("own path");
    let mut log = log.map(|p| std::fs::File::create(p).expect("log file"));
    let mut c = Counts::default();
    let t0 = Instant::now();
    let mut next = from;
    while next < to {
        let mut child = Command::new(&exe)
            .args(["--child", "--seed", &seed.to_string()])
            .args(["--from", &next.to_string(), "--to", &to.to_string()])
            .stdout(Stdio::piped())
            .stderr(Stdio::null())
            .spawn()
            .expect("spawn child");
        let (tx, rx) = mpsc::channel();
        let stdout = child.stdout.take().unwrap();
        std::thread::spawn(move || {
            for line in BufReader::new(stdout).lines() {
                if tx.send(line.unwrap_or_default()).is_err() {
                    break;
                }
            }
        });
        let mut current: Option<u64> = None;
        loop {
            match rx.recv_timeout(KILL_AFTER) {
                Ok(line) => {
                    let mut it = line.splitn(5, ' ');
                    match (it.next(), it.next().and_then(|s| s.parse::<u64>().ok())) {
                        (Some("B"), Some(i)) => current = Some(i),
                        (Some("E"), Some(i)) => {
                            let ms: f64 = it.next().and_then(|s| s.parse().ok()).unwrap_or(0.0);
                            let kb: u64 = it.next().and_then(|s| s.parse().ok()).unwrap_or(0);
                            let status = it.next().unwrap_or("");
                            record(&mut c, &corpus, seed, i, ms, kb, status, &mut log);
                            current = None;
                            next = i + 1;
                            let done = next - from;
                            if done.is_multiple_of(1000) {
                                eprintln!(
                                    "{done} cases, {:.0} s: {} ok, {} clean errors, {} panics, {} crashes, {} slow, {} big",
                                    t0.elapsed().as_secs_f64(),
                                    c.ok,
                                    c.clean,
                                    c.panic,
                                    c.crash,
                                    c.slow,
                                    c.big
                                );
                            }
                        }
                        _ => {}
                    }
                }
                Err(mpsc::RecvTimeoutError::Timeout) => {
                    let _ = child.kill();
                    let _ = child.wait();
                    if let Some(i) = current {
                        let ms = KILL_AFTER.as_secs_f64() * 1e3;
                        record(
                            &mut c,
                            &corpus,
                            seed,
                            i,
                            ms,
                            0,
                            "killed (no answer)",
                            &mut log,
                        );
                        next = i + 1;
                    }
                    break;
                }
                Err(mpsc::RecvTimeoutError::Disconnected) => {
                    let status = child.wait().ok();
                    if let Some(i) = current {
                        let why = format!("crash ({status:?})");
                        record(&mut c, &corpus, seed, i, 0.0, 0, &why, &mut log);
                        next = i + 1;
                    } else if next < to {
                        eprintln!("child ended early ({status:?}); stopping");
                        next = to;
                    }
                    break;
                }
            }
        }
    }
    let n = to - from;
    println!(
        "{n} cases (seed {seed}, {from}..{to}) in {:.0} s: {} clean errors (of which {} rawler panics contained by the library), {} successes, {} panics, {} crashes, {} over {SLOW_S} s, {} over 1 GB; slowest {:.0} ms, largest peak RSS {:.0} MB",
        t0.elapsed().as_secs_f64(),
        c.clean,
        c.contained,
        c.ok,
        c.panic,
        c.crash,
        c.slow,
        c.big,
        c.max_ms,
        c.max_kb as f64 / 1024.0
    );
    for b in &c.bad {
        println!("  {b}");
    }
}

#[allow(clippy::too_many_arguments)]
fn record(
    c: &mut Counts,
    corpus: &Corpus,
    seed: u64,
    i: u64,
    ms: f64,
    kb: u64,
    status: &str,
    log: &mut Option<std::fs::File>,
) {
    c.max_ms = c.max_ms.max(ms);
    c.max_kb = c.max_kb.max(kb);
    let slow = ms > SLOW_S * 1e3;
    let big = kb > BIG_KB;
    c.slow += slow as u64;
    c.big += big as u64;
    let bad = if status == "ok" {
        c.ok += 1;
        false
    } else if status.starts_with("err") {
        c.clean += 1;
        // rawler panics on some files; the library catches that and says so.
        c.contained += status.contains("raw decoder failed") as u64;
        false
    } else if status == "panic" {
        c.panic += 1;
        true
    } else {
        c.crash += 1;
        true
    };
    let (s, _, what) = corpus.case(seed, i);
    if bad || slow || big {
        c.bad.push(format!(
            "case {i} [{}: {what}]: {status}, {ms:.0} ms, {} MB",
            s.name,
            kb / 1024
        ));
    }
    if let Some(f) = log {
        let _ = writeln!(f, "{i}\t{}\t{what}\t{ms:.1}\t{kb}\t{status}", s.name);
    }
}
