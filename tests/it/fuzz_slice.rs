//! A short slice of the fuzzing harness (`examples/fuzz.rs` runs long ones):
//! mutated JPEG, PNG, TIFF, DNG, target, sineMTF and system files fed to the
//! library; none may panic or take more than 10 s.

use std::time::Instant;
use sweepmtf::fuzz::Corpus;

/// Cases of the slice (every seed file about ten times).
const CASES: u64 = 140;

#[test]
fn fuzz_slice_no_panic_no_hang() {
    let corpus = Corpus::new(env!("CARGO_MANIFEST_DIR").as_ref()).unwrap();
    let dir = tempfile::tempdir().unwrap();
    let (mut ok, mut clean) = (0, 0);
    let mut bad = Vec::new();
    for i in 0..CASES {
        let t = Instant::now();
        let r = std::panic::catch_unwind(|| corpus.run(19, i, dir.path()));
        let s = t.elapsed().as_secs_f64();
        let (seed, _, what) = corpus.case(19, i);
        match r {
            Ok(Ok(())) => ok += 1,
            Ok(Err(_)) => clean += 1,
            Err(_) => bad.push(format!("case {i} [{}: {what}] panicked", seed.name)),
        }
        if s > 10.0 {
            bad.push(format!("case {i} [{}: {what}] took {s:.1} s", seed.name));
        }
    }
    assert!(bad.is_empty(), "{bad:#?}");
    // Both outcomes occur: the mutations neither always break nor never break a file.
    assert!(ok > 10 && clean > 10, "{ok} ok, {clean} clean errors");
}

/// Cases a longer run found (seed 2615): raw files whose damaged colour
/// pattern has no green site panicked in the distortion estimate's sampler.
#[test]
fn fuzz_cases_found_by_longer_runs_end_cleanly() {
    let corpus = Corpus::new(env!("CARGO_MANIFEST_DIR").as_ref()).unwrap();
    let dir = tempfile::tempdir().unwrap();
    for (seed, i) in [(2615, 2925), (2615, 3541)] {
        let r = std::panic::catch_unwind(|| corpus.run(seed, i, dir.path()));
        let (s, _, what) = corpus.case(seed, i);
        assert!(
            r.is_ok(),
            "case {i} of seed {seed} [{}: {what}] panicked",
            s.name
        );
    }
}

/// DNGs whose directories rawler 0.8 would follow without end or read from
/// the file's header: refused as corrupt, promptly. A chain whose next
/// pointer leads back made `measure` hang; an EXIF pointer of 0 (seed 4816,
/// case 1090) had rawler allocate 4 GB, which aborts where memory is
/// limited.
#[test]
fn dngs_with_looping_or_zero_directory_pointers_are_refused() {
    let corpus = Corpus::new(env!("CARGO_MANIFEST_DIR").as_ref()).unwrap();
    let dng = &corpus
        .seeds
        .iter()
        .find(|s| s.name.ends_with(".dng"))
        .expect("a simulated DNG seed")
        .bytes;
    let le = |b: &[u8], at: usize| u32::from_le_bytes(b[at..at + 4].try_into().unwrap()) as usize;
    let n = |b: &[u8], at: usize| u16::from_le_bytes([b[at], b[at + 1]]) as usize;
    assert_eq!(&dng[..4], b"II*\0");
    let ifd0 = le(dng, 4);
    let entries = n(dng, ifd0);
    // The chain's next pointer back to the first directory.
    let mut looped = dng.clone();
    let next = ifd0 + 2 + 12 * entries;
    looped[next..next + 4].copy_from_slice(&(ifd0 as u32).to_le_bytes());
    // The EXIF pointer (or, without one, a SubIFD pointer made of the first
    // entry) set to 0, and a value of the first directory that the header
    // read as a directory takes for a count made 4 GB.
    let mut zero = dng.clone();
    let exif = (0..entries)
        .map(|k| ifd0 + 2 + 12 * k)
        .find(|&e| n(dng, e) == 0x8769)
        .unwrap_or(ifd0 + 2);
    zero[exif..exif + 2].copy_from_slice(&0x8769u16.to_le_bytes());
    zero[exif + 2..exif + 4].copy_from_slice(&4u16.to_le_bytes());
    zero[exif + 4..exif + 8].copy_from_slice(&1u32.to_le_bytes());
    zero[exif + 8..exif + 12].copy_from_slice(&0u32.to_le_bytes());
    // The header read as a directory has entry k at 2 + 12k: its count at
    // 6 + 12k. One inside the first directory, clear of the EXIF entry.
    let count_at = (1..)
        .map(|k| 6 + 12 * k)
        .find(|&c| c >= ifd0 + 2 && (c + 4 <= exif || c >= exif + 12))
        .unwrap();
    zero[count_at..count_at + 4].copy_from_slice(&u32::MAX.to_le_bytes());
    let dir = tempfile::tempdir().unwrap();
    for (name, bytes) in [("looped.dng", looped), ("zero.dng", zero)] {
        let path = dir.path().join(name);
        std::fs::write(&path, bytes).unwrap();
        let (tx, rx) = std::sync::mpsc::channel();
        let p = path.clone();
        std::thread::spawn(move || {
            let opts = sweepmtf::measure::MeasureOptions {
                roi: Some([[8.0, 20.0], [56.0, 20.0], [56.0, 28.0], [8.0, 28.0]]),
                channel: sweepmtf::photo::linearise::Channel::G,
                ..Default::default()
            };
            let _ = tx.send(
                sweepmtf::measure::measure_file(&p, &opts)
                    .map(|_| ())
                    .map_err(|e| e.to_string()),
            );
        });
        let r = rx
            .recv_timeout(std::time::Duration::from_secs(30))
            .unwrap_or_else(|_| panic!("{name}: no answer within 30 s"));
        let e = r.expect_err(name);
        assert!(
            e.contains("corrupt") && (e.contains("loop") || e.contains("claims")),
            "{name}: {e}"
        );
    }
}
