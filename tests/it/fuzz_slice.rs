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
