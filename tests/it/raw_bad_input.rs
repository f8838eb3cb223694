//! Corrupt, truncated, foreign and missing raw files must give an error that
//! names the file, never a crash (rawler panics on some of them; the adapter
//! contains that).

use std::path::{Path, PathBuf};
use sweepmtf::photo::exif::read_facts;
use sweepmtf::photo::raw::{RawError, decode_raw};

fn realdata(rel: &str) -> PathBuf {
    Path::new(concat!(env!("CARGO_MANIFEST_DIR"), "/testdata/real")).join(rel)
}

/// A fixed-seed xorshift byte stream.
fn noise(n: usize, mut s: u64) -> Vec<u8> {
    (0..n)
        .map(|_| {
            s ^= s << 13;
            s ^= s >> 7;
            s ^= s << 17;
            (s >> 24) as u8
        })
        .collect()
}

fn expect_error(path: &Path) -> RawError {
    let e = decode_raw(path).expect_err(&format!("{} decoded", path.display()));
    let line = e.to_string();
    assert!(line.contains(&path.display().to_string()), "{line}");
    assert!(!line.contains('\n'), "one line: {line}");
    // facts never fail on a readable file
    if path.exists() {
        read_facts(path).unwrap();
    }
    e
}

#[test]
fn truncated_copies_of_the_dng_are_errors() {
    let bytes = std::fs::read(realdata(
        "raw/tinydng_colorchart_canon550d_magiclantern.dng",
    ))
    .unwrap();
    let dir = tempfile::tempdir().unwrap();
    for len in [
        0,
        1,
        7,
        8,
        100,
        600,
        1536,
        4096,
        100_000,
        2_000_000,
        bytes.len() - 1000,
        bytes.len() - 1,
    ] {
        let p = dir.path().join(format!("cut_{len}.dng"));
        std::fs::write(&p, &bytes[..len]).unwrap();
        let e = expect_error(&p);
        assert!(
            matches!(
                e,
                RawError::Corrupt { .. }
                    | RawError::DecoderPanic { .. }
                    | RawError::Unrecognised { .. }
            ),
            "{len}: {e}"
        );
    }
}

#[test]
fn random_bytes_with_raw_extensions_are_errors() {
    let dir = tempfile::tempdir().unwrap();
    for (i, ext) in ["dng", "cr2", "cr3", "nef", "arw", "raf"]
        .iter()
        .enumerate()
    {
        let p = dir.path().join(format!("noise.{ext}"));
        std::fs::write(&p, noise(300_000, 0x9E37_79B9_7F4A_7C15 + i as u64)).unwrap();
        expect_error(&p);
    }
    // TIFF and DNG headers followed by noise reach deeper into the decoders
    for (i, head) in [&b"II*\0\x08\0\0\0"[..], b"MM\0*\0\0\0\x08"]
        .iter()
        .enumerate()
    {
        let mut b = head.to_vec();
        b.extend(noise(200_000, 12345 + i as u64));
        let p = dir.path().join(format!("tiffnoise{i}.dng"));
        std::fs::write(&p, b).unwrap();
        expect_error(&p);
    }
}

#[test]
fn corrupted_pixel_and_header_bytes_in_the_dng_are_errors_or_decode() {
    // Flipping bytes inside the header must never crash; inside the pixel data
    // an uncompressed DNG still decodes (the values are simply different).
    let bytes = std::fs::read(realdata(
        "raw/tinydng_colorchart_canon550d_magiclantern.dng",
    ))
    .unwrap();
    let dir = tempfile::tempdir().unwrap();
    for (k, at) in (8..1536).step_by(37).enumerate() {
        let mut b = bytes.clone();
        for j in 0..4 {
            b[at + j] ^= 0xA5;
        }
        let p = dir.path().join(format!("flip{k}.dng"));
        std::fs::write(&p, &b).unwrap();
        let _ = decode_raw(&p); // either way, no crash
        let _ = read_facts(&p);
    }
}

#[test]
fn a_jpeg_named_dng_and_a_missing_file_name_the_problem() {
    let dir = tempfile::tempdir().unwrap();
    let p = dir.path().join("photo.dng");
    std::fs::copy(realdata("exif_jpeg/canon_powershot_s40_downscaled.jpg"), &p).unwrap();
    match expect_error(&p) {
        RawError::Unsupported { make, model, .. } => {
            assert_eq!(make, "Canon");
            assert_eq!(model, "Canon PowerShot S40");
        }
        e => panic!("{e}"),
    }
    let missing = dir.path().join("nope.cr2");
    assert!(matches!(expect_error(&missing), RawError::Io { .. }));
    assert!(read_facts(&missing).is_err());
}

#[test]
fn a_decoder_panic_becomes_an_error_for_that_file() {
    // rawler hits `todo!()` on a DNG whose raw IFD has an unknown photometric
    // interpretation: patch PhotometricInterpretation 32803 (CFA) to 2 (RGB).
    let mut bytes = std::fs::read(realdata(
        "raw/tinydng_colorchart_canon550d_magiclantern.dng",
    ))
    .unwrap();
    let entry = [0x06, 0x01, 0x03, 0x00, 0x01, 0x00, 0x00, 0x00, 0x23, 0x80];
    let at = bytes
        .windows(entry.len())
        .position(|w| w == entry)
        .expect("PhotometricInterpretation entry");
    bytes[at + 8] = 2;
    bytes[at + 9] = 0;
    let dir = tempfile::tempdir().unwrap();
    let p = dir.path().join("rgb_photometric.dng");
    std::fs::write(&p, &bytes).unwrap();
    match expect_error(&p) {
        RawError::DecoderPanic { cause, .. } => assert!(!cause.is_empty()),
        e => panic!("expected a contained panic, got {e}"),
    }
    // the process is fine afterwards: the intact file still decodes
    decode_raw(&realdata(
        "raw/tinydng_colorchart_canon550d_magiclantern.dng",
    ))
    .unwrap();
}
