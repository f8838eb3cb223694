//! JPEG decoding cut to the rows and planes a measurement reads (issue 16):
//! the kept rows equal a whole decode; the decoder agrees with libjpeg-turbo's
//! `djpeg` (when installed) on files written by cameras and by `cjpeg`
//! (baseline and progressive, 4:4:4 / 4:2:2 / 4:2:0, with and without restart
//! markers); a measurement from the cut luma decode gives the MTF of a whole
//! RGB decode; corrupt but decodable scan data is measured with a warning
//! that reaches the batch summary.

use assert_cmd::Command as Cmd;
use std::path::{Path, PathBuf};
use std::process::Command;
use sweepmtf::measure::synth::{SynthShot, strip_quad};
use sweepmtf::measure::{MeasureOptions, measure_decoded, measure_file};
use sweepmtf::photo::decode::{Decoded, Samples, decode_bytes, decode_bytes_want};
use sweepmtf::photo::jpeg::JpegWant;

fn real(name: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("testdata/real")
        .join(name)
}

const REAL: [&str; 4] = [
    "exif_jpeg/canon_powershot_s40_downscaled.jpg", // 4:2:0
    "exif_jpeg/canon_powershot_sx60hs_hdr_NO.jpg",  // 4:2:2
    "exif_jpeg/nikon_d70_no_focalplane.jpg",        // 4:4:4
    "chart_photo/mtfmapper_perspective_chart_photo.jpg", // 4:2:0
];

fn u8s(d: &Decoded) -> &[u8] {
    match &d.samples {
        Samples::U8(v) => v,
        Samples::U16(_) | Samples::F32(_) => panic!("JPEGs are 8-bit"),
    }
}

fn has(tool: &str) -> bool {
    Command::new(tool)
        .arg("-version")
        .output()
        .is_ok_and(|o| o.status.success() || !o.stderr.is_empty())
}

/// Pixels of a binary PGM/PPM (as `djpeg` writes): (width, height, samples).
fn pnm(bytes: &[u8]) -> (usize, usize, Vec<u8>) {
    let mut fields = Vec::new();
    let mut i = 0;
    while fields.len() < 4 {
        while bytes[i].is_ascii_whitespace() {
            i += 1;
        }
        if bytes[i] == b'#' {
            while bytes[i] != b'\n' {
                i += 1;
            }
            continue;
        }
        let s = i;
        while !bytes[i].is_ascii_whitespace() {
            i += 1;
        }
        fields.push(String::from_utf8_lossy(&bytes[s..i]).to_string());
    }
    let w = fields[1].parse().unwrap();
    let h = fields[2].parse().unwrap();
    (w, h, bytes[i + 1..].to_vec())
}

fn djpeg(path: &Path, grey: bool) -> (usize, usize, Vec<u8>) {
    let mut c = Command::new("djpeg");
    if grey {
        c.arg("-grayscale");
    }
    let out = c.arg(path).output().unwrap();
    assert!(out.status.success(), "djpeg {}", path.display());
    pnm(&out.stdout)
}

/// Largest absolute difference of two code arrays.
fn max_diff(a: &[u8], b: &[u8]) -> u8 {
    assert_eq!(a.len(), b.len());
    a.iter()
        .zip(b)
        .map(|(x, y)| x.abs_diff(*y))
        .max()
        .unwrap_or(0)
}

#[test]
fn cut_decodes_equal_the_whole_decode_in_the_rows_asked_for() {
    for f in REAL {
        let bytes = std::fs::read(real(f)).unwrap();
        let whole = decode_bytes(&bytes, f).unwrap();
        let grey_whole = decode_bytes_want(
            &bytes,
            f,
            JpegWant {
                rows: None,
                luma_only: true,
            },
        )
        .unwrap();
        assert_eq!((whole.channels, grey_whole.channels), (3, 1), "{f}");
        let (w, h) = (whole.width, whole.height);
        for rows in [1, h / 3, h / 2 + 5, h - 20] {
            for luma_only in [false, true] {
                let cut = decode_bytes_want(
                    &bytes,
                    f,
                    JpegWant {
                        rows: Some(rows),
                        luma_only,
                    },
                )
                .unwrap();
                let reference = if luma_only { &grey_whole } else { &whole };
                let c = reference.channels;
                assert_eq!((cut.width, cut.height, cut.channels), (w, h, c), "{f}");
                // The cut happened (all four are sequential, one scan) and kept what was asked.
                assert!(
                    cut.rows >= rows && cut.rows <= rows + 32,
                    "{f}: {rows} → {}",
                    cut.rows
                );
                let n = cut.rows.min(h) * w * c;
                assert_eq!(
                    &u8s(&cut)[..n],
                    &u8s(reference)[..n],
                    "{f}, {rows} rows, luma {luma_only}"
                );
                // Below the decoded MCU rows (the picture's rows and at most one
                // MCU row of 8–32 px beneath, decoded as the cut's edge) nothing is written.
                let m = (cut.rows + 32).min(h) * w * c;
                assert!(u8s(&cut)[m..].iter().all(|&v| v == 0), "{f}: below the cut");
                assert!(cut.warnings.is_empty());
            }
        }
    }
}

/// The corpus: the camera files, plus files `cjpeg` writes (when installed)
/// from one of them: baseline and progressive × 4:4:4, 4:2:2, 4:2:0 × with
/// and without restart markers.
fn corpus(dir: &Path) -> Vec<PathBuf> {
    let mut files: Vec<PathBuf> = REAL.iter().map(|f| real(f)).collect();
    if !has("cjpeg") || !has("djpeg") {
        return files;
    }
    let src = dir.join("src.ppm");
    let ppm = Command::new("djpeg")
        .arg(real(REAL[3]))
        .output()
        .unwrap()
        .stdout;
    std::fs::write(&src, ppm).unwrap();
    for prog in [false, true] {
        for samp in ["1x1", "2x1", "2x2"] {
            for restart in [None, Some("1")] {
                let out = dir.join(format!(
                    "c_{}_{samp}_{}.jpg",
                    if prog { "prog" } else { "base" },
                    restart.map_or("norst", |_| "rst")
                ));
                let mut c = Command::new("cjpeg");
                c.args(["-quality", "92", "-sample", samp]);
                if prog {
                    c.arg("-progressive");
                }
                if let Some(r) = restart {
                    c.args(["-restart", r]);
                }
                let st = c.arg("-outfile").arg(&out).arg(&src).status().unwrap();
                assert!(st.success());
                files.push(out);
            }
        }
    }
    files
}

#[test]
fn decodes_agree_with_libjpeg_turbo() {
    if !has("djpeg") {
        eprintln!("djpeg not installed (libjpeg-turbo-progs): comparison skipped");
        return;
    }
    let dir = tempfile::tempdir().unwrap();
    for path in corpus(dir.path()) {
        let name = path.display().to_string();
        let bytes = std::fs::read(&path).unwrap();
        let (w, h, grey) = djpeg(&path, true);
        let ours = decode_bytes_want(
            &bytes,
            &name,
            JpegWant {
                rows: Some(h / 2),
                luma_only: true,
            },
        )
        .unwrap();
        assert_eq!((ours.width, ours.height), (w, h), "{name}");
        // Luma: the same integer IDCT's output, within one code.
        let n = (h / 2) * w;
        let d = max_diff(&u8s(&ours)[..n], &grey[..n]);
        assert!(d <= 1, "{name}: luma differs from djpeg by {d} codes");
        // RGB: colour conversion and chroma upsampling differ a little in rounding
        // (zune-jpeg against libjpeg-turbo; measured: up to 4 codes on the S40 file).
        let (_, _, rgb) = djpeg(&path, false);
        let ours = decode_bytes(&bytes, &name).unwrap();
        let diffs: Vec<u8> = u8s(&ours)
            .iter()
            .zip(&rgb)
            .map(|(a, b)| a.abs_diff(*b))
            .collect();
        let max = *diffs.iter().max().unwrap();
        let mean = diffs.iter().map(|&v| v as f64).sum::<f64>() / diffs.len() as f64;
        assert!(
            max <= 4 && mean < 0.3,
            "{name}: RGB max diff {max}, mean {mean:.3}"
        );
    }
}

fn shot() -> SynthShot {
    let mut s = sweepmtf::measure::synth::standard_cases().remove(1);
    // A strip in the upper half of a taller frame, so the cut saves rows.
    s.height = 600;
    s.quad = strip_quad(950.0, 150.0, s.length, 120.0, 2.0, 0.0);
    s
}

fn roi_arg(q: [[f64; 2]; 4]) -> String {
    let v: Vec<String> = q.iter().flatten().map(|v| format!("{v}")).collect();
    v.join(",")
}

#[test]
fn cut_luma_measurement_matches_a_whole_rgb_decode() {
    let s = shot();
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("s.jpg");
    std::fs::write(&path, s.encode(3)).unwrap();
    let opts = MeasureOptions {
        roi: Some(s.quad),
        ..MeasureOptions::default()
    };
    let cut = measure_file(&path, &opts).unwrap();
    // Today's path: the whole frame decoded to RGB, luminance of linear RGB.
    let whole = decode_bytes(&std::fs::read(&path).unwrap(), "s.jpg").unwrap();
    assert_eq!(whole.channels, 3);
    let reference = measure_decoded(&whole, "s.jpg", None, &opts).unwrap();
    let (a, b) = (&cut.curves[0].points, &reference.curves[0].points);
    assert_eq!(a.len(), b.len());
    let worst = a
        .iter()
        .zip(b.iter())
        .map(|(p, q)| (p.mtf - q.mtf).abs())
        .fold(0.0, f64::max);
    assert!(worst <= 0.001, "MTF moved by {worst}");
}

/// A JPEG with a stray restart marker in the middle of its scan data (a
/// classic bit error): decodable, but not as written.
fn corrupt(jpeg: &[u8]) -> Vec<u8> {
    let sos = jpeg.windows(2).position(|w| w == [0xFF, 0xDA]).unwrap();
    let mid = sos + (jpeg.len() - sos) / 3;
    let mut v = jpeg.to_vec();
    v.splice(mid..mid, [0xFF, 0xD3]);
    v
}

#[test]
fn corrupt_scan_data_is_measured_with_a_warning_that_reaches_the_batch_row() {
    let s = shot();
    let dir = tempfile::tempdir().unwrap();
    let shots = dir.path().join("shots");
    std::fs::create_dir_all(&shots).unwrap();
    let bad = shots.join("bad.jpg");
    std::fs::write(&bad, corrupt(&s.encode(3))).unwrap();
    // The library: zune-jpeg decodes it without complaint even in strict
    // mode; the scan check (photo::jpeg_check) names the damage.
    let bytes = std::fs::read(&bad).unwrap();
    let damage = sweepmtf::photo::jpeg_check::scan_damage(&bytes).expect("damage found");
    assert!(damage.contains("RST3 where RST0 was due"), "{damage}");
    // The CLI: measured (exit 0), the warning on stderr.
    let out = Cmd::cargo_bin("sweepmtf")
        .unwrap()
        .args(["measure", bad.to_str().unwrap(), "--roi", &roi_arg(s.quad)])
        .args(["-o", dir.path().join("one").to_str().unwrap()])
        .output()
        .unwrap();
    let err = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(0), "{err}");
    assert!(
        err.contains("warning") && err.contains("scan data"),
        "{err}"
    );
    // The batch summary's row carries it.
    let rois = format!(
        "file,x1,y1,x2,y2,x3,y3,x4,y4\nbad.jpg,{}\n",
        roi_arg(s.quad)
    );
    std::fs::write(dir.path().join("rois.csv"), rois).unwrap();
    let out_dir = dir.path().join("batch");
    let st = Cmd::cargo_bin("sweepmtf")
        .unwrap()
        .args([
            "batch",
            shots.to_str().unwrap(),
            "-o",
            out_dir.to_str().unwrap(),
        ])
        .args(["--roi-file", dir.path().join("rois.csv").to_str().unwrap()])
        .output()
        .unwrap();
    assert_eq!(
        st.status.code(),
        Some(0),
        "{}",
        String::from_utf8_lossy(&st.stderr)
    );
    let summary = std::fs::read_to_string(out_dir.join("summary.csv")).unwrap();
    let row = summary.lines().find(|l| l.starts_with("bad.jpg")).unwrap();
    assert!(row.contains("scan data"), "{row}");
}
