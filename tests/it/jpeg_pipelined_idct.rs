//! The vendored zune-jpeg's threaded IDCT (vendor/zune-jpeg/SWEEPMTF.md):
//! a luma decode with the IDCT and row copy on a second thread gives the same
//! result as the unmodified inline path, byte for byte and error for error,
//! on the repository's JPEGs and on generated ones (4:4:4, 4:2:2, 4:4:0,
//! 4:2:0, 4:1:1, grey; sizes not multiples of 8 or 16; restart intervals;
//! q 50–98), also truncated, damaged, or with markers in the scan data,
//! strict and lenient. RGB and progressive decodes (never pipelined) too.

use jpeg_encoder::{ColorType, Encoder, SamplingFactor};
use std::path::Path;
use zune_core::bytestream::ZCursor;
use zune_core::colorspace::ColorSpace;
use zune_core::options::DecoderOptions;
use zune_jpeg::JpegDecoder;

/// The decoder's result and the whole output buffer (pre-filled with a
/// pattern, so bytes left untouched count too).
fn decode(bytes: &[u8], strict: bool, out: ColorSpace, pipelined: bool) -> (String, Vec<u8>) {
    let opts = DecoderOptions::default()
        .set_strict_mode(strict)
        .set_max_width(usize::MAX)
        .set_max_height(usize::MAX)
        .jpeg_set_out_colorspace(out);
    let mut d = JpegDecoder::new_with_options(ZCursor::new(bytes), opts);
    if let Err(e) = d.decode_headers() {
        return (format!("headers: {e}"), vec![]);
    }
    let Some((w, h)) = d.dimensions() else {
        return ("no dimensions".into(), vec![]);
    };
    let mut buf: Vec<u8> = (0..w * h * out.num_components())
        .map(|i| (i * 7 % 251) as u8)
        .collect();
    d.set_pipelined_idct(Some(pipelined));
    let r = d.decode_into(&mut buf);
    (format!("{r:?}"), buf)
}

/// Inline and pipelined decodes agree (strict and lenient); returns how many
/// strict decodes succeeded.
fn same(bytes: &[u8], what: &str) -> usize {
    let mut ok = 0;
    for strict in [true, false] {
        for out in [ColorSpace::Luma, ColorSpace::RGB] {
            let (ra, a) = decode(bytes, strict, out, false);
            let (rb, b) = decode(bytes, strict, out, true);
            assert_eq!(ra, rb, "{what}: strict {strict}, {out:?}: results differ");
            assert!(
                a == b,
                "{what}: strict {strict}, {out:?}: pixels differ ({ra})"
            );
            ok += usize::from(strict && ra == "Ok(())" && out == ColorSpace::Luma);
        }
    }
    ok
}

/// A picture with flat areas (1×1 IDCT), smooth ramps (4×4) and noise and
/// edges (full IDCT); `channels` 1 or 3.
pub(crate) fn picture(w: usize, h: usize, channels: usize, seed: u64) -> Vec<u8> {
    let mut s = seed | 1;
    let mut rnd = move || {
        s ^= s << 13;
        s ^= s >> 7;
        s ^= s << 17;
        s
    };
    let mut v = Vec::with_capacity(w * h * channels);
    for y in 0..h {
        for x in 0..w {
            for c in 0..channels {
                let p = match (x * 4 / w.max(1), y * 3 / h.max(1)) {
                    (0, _) => 90 + 40 * c,
                    (1, _) => (x * 255 / w.max(1) + y / 3 + 20 * c) % 256,
                    (2, 0) => {
                        if (x / 5 + y / 7) % 2 == 0 {
                            30
                        } else {
                            220 - 30 * c
                        }
                    }
                    _ => (rnd() % 256) as usize,
                };
                v.push(p as u8);
            }
        }
    }
    v
}

pub(crate) fn encode(
    w: usize,
    h: usize,
    grey: bool,
    sampling: SamplingFactor,
    q: u8,
    restart: u16,
    progressive: bool,
) -> Vec<u8> {
    let mut out = Vec::new();
    let mut e = Encoder::new(&mut out, q);
    e.set_sampling_factor(sampling);
    if restart > 0 {
        e.set_restart_interval(restart);
    }
    e.set_progressive(progressive);
    let (channels, ct) = if grey {
        (1, ColorType::Luma)
    } else {
        (3, ColorType::Rgb)
    };
    let px = picture(w, h, channels, (w * 31 + h * 17 + usize::from(q)) as u64);
    e.encode(&px, w as u16, h as u16, ct).expect("encodes");
    out
}

/// Where the entropy-coded data starts (after the first SOS segment).
pub(crate) fn scan_start(b: &[u8]) -> usize {
    let mut i = 2;
    while i + 4 <= b.len() {
        let len = usize::from(u16::from_be_bytes([b[i + 2], b[i + 3]]));
        if b[i + 1] == 0xDA {
            return i + 2 + len;
        }
        i += 2 + len;
    }
    b.len()
}

/// The file damaged in ways that reach the decoder's exits: cut short
/// (premature end), bytes changed (bad Huffman codes), an EOI, a DHT or an
/// unknown marker inside the scan data.
pub(crate) fn damaged(b: &[u8]) -> Vec<(String, Vec<u8>)> {
    let s = scan_start(b);
    let n = b.len() - s;
    let mut v = Vec::new();
    for f in [0.0, 0.1, 0.5, 0.9] {
        let at = s + (n as f64 * f) as usize;
        v.push((format!("cut at {at}"), b[..at].to_vec()));
    }
    v.push(("no EOI".into(), b[..b.len() - 2].to_vec()));
    for f in [0.2, 0.6] {
        let at = s + (n as f64 * f) as usize;
        let mut c = b.to_vec();
        for k in at..(at + 16).min(b.len() - 2) {
            if c[k] != 0xFF && c[k - 1] != 0xFF {
                c[k] ^= 0x5A;
                if c[k] == 0xFF {
                    c[k] = 0x7F;
                }
            }
        }
        v.push((format!("bytes changed at {at}"), c));
        for marker in [
            vec![0xFF, 0xD9],
            vec![0xFF, 0xC4, 0x00, 0x02],
            vec![0xFF, 0xFE, 0x00, 0x04, 0x41, 0x42],
            vec![0xFF, 0xC9, 0x00, 0x02],
        ] {
            let mut c = b[..at].to_vec();
            c.extend_from_slice(&marker);
            c.extend_from_slice(&b[at..]);
            v.push((format!("marker {marker:02X?} at {at}"), c));
        }
    }
    v
}

#[test]
fn jpeg_pipelined_idct_matches_inline_on_repository_files() {
    let mut files = Vec::new();
    let mut dirs = vec![Path::new(env!("CARGO_MANIFEST_DIR")).join("testdata")];
    while let Some(d) = dirs.pop() {
        for e in std::fs::read_dir(&d).expect("testdata").flatten() {
            let p = e.path();
            if p.is_dir() {
                dirs.push(p);
            } else if p
                .extension()
                .is_some_and(|x| x.eq_ignore_ascii_case("jpg") || x.eq_ignore_ascii_case("jpeg"))
            {
                files.push(p);
            }
        }
    }
    assert!(files.len() >= 5, "{files:?}");
    let mut ok = 0;
    for p in &files {
        let b = std::fs::read(p).expect("read");
        ok += same(&b, &p.display().to_string());
        // A camera's multi-megapixel file takes every fourth damage (its
        // 16 variants cost ≈ 9 s of the test's 11): the smaller files ≥ 512²
        // (the pipelined path) take all of them.
        let step = if b.len() > 500_000 { 4 } else { 1 };
        for (what, c) in damaged(&b).into_iter().step_by(step) {
            same(&c, &format!("{} {what}", p.display()));
        }
    }
    assert_eq!(ok, files.len(), "every repository JPEG decodes");
}

#[test]
fn jpeg_pipelined_idct_matches_inline_on_generated_files() {
    use SamplingFactor::*;
    let samplings = [
        (F_1_1, "4:4:4"),
        (F_2_1, "4:2:2"),
        (F_1_2, "4:4:0"),
        (F_2_2, "4:2:0"),
        (F_4_1, "4:1:1"),
    ];
    let sizes = [
        (1, 1),
        (7, 5),
        (8, 8),
        (17, 9),
        (33, 47),
        (250, 131),
        (161, 240),
    ];
    let mut ok = 0;
    let mut n = 0;
    for (si, &(sampling, name)) in samplings.iter().enumerate() {
        for grey in [false, true] {
            if grey && si > 0 {
                continue;
            }
            for (zi, &(w, h)) in sizes.iter().enumerate() {
                for (qi, q) in [50, 75, 92, 98].into_iter().enumerate() {
                    let restart = [0, 1, 3, 7][(qi + zi) % 4];
                    let b = encode(w, h, grey, sampling, q, restart, false);
                    let what = format!("{name} grey {grey} {w}×{h} q{q} restart {restart}");
                    ok += same(&b, &what);
                    n += 1;
                    if (w, h) == (250, 131) && q == 92 {
                        for (d, c) in damaged(&b) {
                            same(&c, &format!("{what}, {d}"));
                        }
                    }
                }
            }
        }
    }
    assert_eq!(ok, n, "every generated JPEG decodes");
    // Progressive (decoded inline either way).
    let b = encode(250, 131, false, F_2_2, 90, 0, true);
    assert_eq!(same(&b, "progressive 4:2:0"), 1);
}

#[test]
fn jpeg_pipelined_idct_matches_inline_on_a_large_file() {
    // Many MCU rows in flight: 4:2:0 and 4:4:4, with restart markers.
    for (sampling, restart) in [(SamplingFactor::F_2_2, 0), (SamplingFactor::F_1_1, 5)] {
        let b = encode(1501, 1203, false, sampling, 92, restart, false);
        assert_eq!(same(&b, &format!("1501×1203 {sampling:?}")), 1);
        let s = scan_start(&b);
        let cut = &b[..s + (b.len() - s) * 2 / 3];
        same(cut, "1501×1203 cut at 2/3");
    }
}
