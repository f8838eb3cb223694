//! `sweepmtf chart` end to end: every output is read back with an independent
//! decoder (the `image` crate for pixels, `png`/`tiff` for metadata, the PDF's
//! text for its MediaBox) and checked against the frequency law written out
//! here, the requested contrast, and the written description.

#![allow(clippy::needless_range_loop)] // index loops read better in the small solver

use assert_cmd::Command;
use std::path::{Path, PathBuf};
use sweepmtf::target::{Target, TargetError};

const DPI: f64 = 150.0;

fn run(dir: &Path, args: &[&str]) -> std::process::Output {
    Command::cargo_bin("sweepmtf")
        .unwrap()
        .current_dir(dir)
        .arg("chart")
        .args(args)
        .output()
        .unwrap()
}

fn make(dir: &Path, name: &str, args: &[&str]) -> (PathBuf, Target) {
    let mut a: Vec<&str> = args.to_vec();
    a.extend(["-o", name]);
    let out = run(dir, &a);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let path = dir.join(name);
    let stem = path.file_stem().unwrap().to_string_lossy().to_string();
    let t = Target::load(&dir.join(format!("{stem}.toml"))).unwrap();
    (path, t)
}

/// sRGB decoding (IEC 61966-2-1), written here independently of the encoder.
fn srgb_to_linear(v: f64) -> f64 {
    if v <= 0.04045 {
        v / 12.92
    } else {
        ((v + 0.055) / 1.055).powf(2.4)
    }
}

fn linear_to_srgb16(l: f64) -> u16 {
    let v = if l <= 0.0031308 {
        12.92 * l
    } else {
        1.055 * l.powf(1.0 / 2.4) - 0.055
    };
    (v * 65535.0).round() as u16
}

fn load_luma16(path: &Path) -> image::ImageBuffer<image::Luma<u16>, Vec<u16>> {
    image::open(path).unwrap().to_luma16()
}

/// Phase (cycles) of the sweep law at distance s, integrated by hand.
fn law_phase(law: &str, f0: f64, f1: f64, len: f64, s: f64) -> f64 {
    match law {
        "log" => {
            let r = f1 / f0;
            f0 * len / r.ln() * (r.powf(s / len) - 1.0)
        }
        _ => f0 * s + (f1 - f0) * s * s / (2.0 * len),
    }
}

fn law_freq(law: &str, f0: f64, f1: f64, len: f64, s: f64) -> f64 {
    match law {
        "log" => f0 * (f1 / f0).powf(s / len),
        _ => f0 + (f1 - f0) * s / len,
    }
}

/// Positions (mm from x0) where the row crosses `level`, by linear interpolation.
fn crossings(row: &[f64], level: f64, pitch: f64, x0: f64) -> Vec<f64> {
    let mut out = vec![];
    for i in 1..row.len() {
        let (a, b) = (row[i - 1] - level, row[i] - level);
        if (a < 0.0) != (b < 0.0) && a != b {
            let t = a / (a - b);
            out.push((i as f64 - 1.0 + 0.5 + t) * pitch - x0);
        }
    }
    out
}

struct SweepCheck {
    max_freq_err: f64,
    max_mod_err: f64,
}

/// Measures local frequency (periods between crossings) and modulation
/// (least-squares sine fit) along the middle row of every sweep.
fn check_sweeps(img: &image::ImageBuffer<image::Luma<u16>, Vec<u16>>, t: &Target) -> SweepCheck {
    let pitch = 25.4 / DPI;
    let mut max_freq_err: f64 = 0.0;
    let mut max_mod_err: f64 = 0.0;
    for sw in &t.sweeps {
        let law = match sw.law {
            sweepmtf::target::SweepLaw::Log => "log",
            sweepmtf::target::SweepLaw::Linear => "linear",
        };
        let (f0, f1, len) = (sw.f_min_cy_mm, sw.f_max_cy_mm, sw.rect.width_mm);
        let j = ((sw.rect.y_mm + sw.rect.height_mm / 2.0) / pitch) as u32;
        let i0 = (sw.rect.x_mm / pitch).ceil() as usize;
        let i1 = ((sw.rect.x_mm + len) / pitch - 1.0).floor() as usize;
        let refl: Vec<f64> = (i0..i1)
            .map(|i| srgb_to_linear(img.get_pixel(i as u32, j)[0] as f64 / 65535.0))
            .collect();
        let x0 = sw.rect.x_mm - i0 as f64 * pitch;
        let xs = crossings(&refl, sw.mean, pitch, x0);
        let mut checked = 0;
        for frac in [0.05, 0.2, 0.35, 0.5, 0.65, 0.8, 0.95] {
            let s = frac * len;
            let f = law_freq(law, f0, f1, len, s);
            let px_per_cycle = 1.0 / (f * pitch);
            if px_per_cycle < 6.0 {
                continue;
            }
            // Crossings spanning about four periods around s.
            let k = xs.partition_point(|&x| x < s);
            let half = 4;
            if k < half || k + half >= xs.len() {
                continue;
            }
            let (a, b) = (xs[k - half], xs[k + half]);
            let cycles = (2 * half) as f64 / 2.0;
            // Mean measured frequency over [a, b] against the law's mean there.
            let measured = cycles / (b - a);
            let truth = (law_phase(law, f0, f1, len, b) - law_phase(law, f0, f1, len, a)) / (b - a);
            max_freq_err = max_freq_err.max((measured / truth - 1.0).abs());
            // Modulation: fit c + p·cos 2πΦ + q·sin 2πΦ over the same window.
            let (ia, ib) = (((a + x0) / pitch) as usize, ((b + x0) / pitch) as usize);
            let mut m = [[0.0f64; 4]; 3];
            for (i, &r) in refl.iter().enumerate().take(ib).skip(ia) {
                let ph = 2.0
                    * std::f64::consts::PI
                    * law_phase(law, f0, f1, len, (i as f64 + 0.5) * pitch - x0);
                let basis = [1.0, ph.cos(), ph.sin()];
                for u in 0..3 {
                    for v in 0..3 {
                        m[u][v] += basis[u] * basis[v];
                    }
                    m[u][3] += basis[u] * r;
                }
            }
            let sol = solve3(m);
            let modulation = sol[1].hypot(sol[2]) / sol[0];
            max_mod_err = max_mod_err.max((modulation / sw.contrast - 1.0).abs());
            checked += 1;
        }
        assert!(checked >= 3, "sweep {} checked at {checked} places", sw.id);
    }
    SweepCheck {
        max_freq_err,
        max_mod_err,
    }
}

fn solve3(mut m: [[f64; 4]; 3]) -> [f64; 3] {
    for c in 0..3 {
        let p = (c..3)
            .max_by(|&a, &b| m[a][c].abs().total_cmp(&m[b][c].abs()))
            .unwrap();
        m.swap(c, p);
        for r in 0..3 {
            if r != c {
                let f = m[r][c] / m[c][c];
                for k in c..4 {
                    m[r][k] -= f * m[c][k];
                }
            }
        }
    }
    [m[0][3] / m[0][0], m[1][3] / m[1][1], m[2][3] / m[2][2]]
}

/// Every pixel equals encode(reflectance) at its dot centre, except label ink on background.
fn check_description_matches(img: &image::ImageBuffer<image::Luma<u16>, Vec<u16>>, t: &Target) {
    let pitch = 25.4 / DPI;
    let mut ink = 0usize;
    for (i, j, p) in img.enumerate_pixels() {
        let (x, y) = ((i as f64 + 0.5) * pitch, (j as f64 + 0.5) * pitch);
        let r = t.reflectance(x, y);
        let want = linear_to_srgb16(r);
        let got = p[0];
        if got.abs_diff(want) <= 1 {
            continue;
        }
        assert!(
            r == t.background && got < want,
            "pixel ({i},{j}) = {got}, description says {want} (reflectance {r})"
        );
        for f in &t.fiducials {
            let d = f.diameter_mm;
            assert!(
                (x - f.x_mm).abs() >= d || (y - f.y_mm).abs() >= d,
                "label ink at ({x},{y}) within a fiducial's keep-out"
            );
        }
        ink += 1;
    }
    assert!(
        ink > 1000,
        "labels and ticks are printed ({ink} ink pixels)"
    );
}

fn check_greys_and_fiducials(img: &image::ImageBuffer<image::Luma<u16>, Vec<u16>>, t: &Target) {
    let pitch = 25.4 / DPI;
    let at = |x: f64, y: f64| {
        srgb_to_linear(img.get_pixel((x / pitch) as u32, (y / pitch) as u32)[0] as f64 / 65535.0)
    };
    let main = &t
        .sweeps
        .first()
        .map(|s| (s.mean, s.contrast))
        .unwrap_or_else(|| {
            let p = &t.patches[0];
            (p.mean, p.contrast)
        });
    for g in &t.greys {
        let v = at(
            g.rect.x_mm + g.rect.width_mm / 2.0,
            g.rect.y_mm + g.rect.height_mm / 2.0,
        );
        assert!((v - g.reflectance).abs() < 1e-4, "{}: {v}", g.id);
    }
    let white = t.greys.iter().find(|g| g.id == "white").unwrap();
    let black = t.greys.iter().find(|g| g.id == "black").unwrap();
    assert!((white.reflectance - main.0 * (1.0 + main.1)).abs() < 1e-12);
    assert!((black.reflectance - main.0 * (1.0 - main.1)).abs() < 1e-12);
    // Fiducials: conventions, and what the raster shows at and around the centre.
    let short = t.width_mm.min(t.height_mm);
    let ids: Vec<&str> = t.fiducials.iter().map(|f| f.id.as_str()).collect();
    assert_eq!(ids, ["tl", "tr", "br", "bl"]);
    for f in &t.fiducials {
        let d = f.diameter_mm;
        assert!((d - 0.04 * short).abs() < 1e-9);
        let cx = if f.id.ends_with('l') {
            d
        } else {
            t.width_mm - d
        };
        let cy = if f.id.starts_with('t') {
            d
        } else {
            t.height_mm - d
        };
        assert!((f.x_mm - cx).abs() < 1e-9 && (f.y_mm - cy).abs() < 1e-9);
        let centre = at(f.x_mm, f.y_mm);
        let ring = at(f.x_mm + 0.375 * d, f.y_mm);
        let outside = at(f.x_mm + 0.75 * d, f.y_mm + 0.75 * d);
        assert!(ring < 0.01 && outside > 0.99, "{}", f.id);
        if f.id == "tl" {
            assert!(centre > 0.99, "ring centre is white");
        } else {
            assert!(centre < 0.01, "disk centre is black");
        }
    }
}

#[test]
fn png_log_sweep_with_contrast_rows() {
    let dir = tempfile::tempdir().unwrap();
    let (png, t) = make(
        dir.path(),
        "log.png",
        &[
            "--law",
            "log",
            "--f-min",
            "0.25",
            "--f-max",
            "1.5",
            "--size",
            "A4",
            "--dpi",
            "150",
            "--contrasts",
            "0.8,0.4,0.2",
        ],
    );
    // Metadata via the png crate: size and pHYs.
    let dec = png::Decoder::new(std::io::BufReader::new(std::fs::File::open(&png).unwrap()));
    let reader = dec.read_info().unwrap();
    let info = reader.info();
    assert_eq!((info.width, info.height), (1754, 1240));
    assert_eq!(info.bit_depth, png::BitDepth::Sixteen);
    let dims = info.pixel_dims.unwrap();
    assert_eq!(dims.unit, png::Unit::Meter);
    let dpi = dims.xppu as f64 * 0.0254;
    // pHYs stores whole pixels per metre: 150 dpi = 5905.5/m is stored as 5906/m.
    assert!((dpi - DPI).abs() < 0.02 && dims.yppu == dims.xppu, "{dpi}");
    assert!((info.width as f64 / dpi * 25.4 - 297.0).abs() < 25.4 / dpi);
    // Pixels via the image crate.
    let img = load_luma16(&png);
    assert_eq!(t.sweeps.len(), 3);
    let c = check_sweeps(&img, &t);
    eprintln!(
        "log PNG: max frequency error {:.5} %, max modulation error {:.5} %",
        c.max_freq_err * 100.0,
        c.max_mod_err * 100.0
    );
    assert!(c.max_freq_err < 0.002, "{}", c.max_freq_err);
    assert!(c.max_mod_err < 0.005, "{}", c.max_mod_err);
    check_greys_and_fiducials(&img, &t);
    check_description_matches(&img, &t);
    // Preview exists and is small.
    let pv = image::open(dir.path().join("log.preview.png")).unwrap();
    assert!(pv.width() <= 1200 && pv.height() <= 1200 && pv.width() > 300);
}

#[test]
fn tiff_linear_sweep() {
    let dir = tempfile::tempdir().unwrap();
    let (tif, t) = make(
        dir.path(),
        "lin.tif",
        &[
            "--law",
            "linear",
            "--f-min",
            "0.2",
            "--f-max",
            "2",
            "--size",
            "200x150mm",
            "--dpi",
            "150",
            "--contrast",
            "0.6",
        ],
    );
    let mut dec = tiff::decoder::Decoder::new(std::fs::File::open(&tif).unwrap()).unwrap();
    let (w, h) = dec.dimensions().unwrap();
    assert_eq!((w, h), (1181, 886));
    use tiff::tags::Tag;
    let xr = dec.get_tag_u32_vec(Tag::XResolution).unwrap();
    let yr = dec.get_tag_u32_vec(Tag::YResolution).unwrap();
    assert_eq!(xr[0] as f64 / xr[1] as f64, DPI);
    assert_eq!(yr[0] as f64 / yr[1] as f64, DPI);
    assert_eq!(dec.get_tag_u32(Tag::ResolutionUnit).unwrap(), 2, "inch");
    assert_eq!(dec.colortype().unwrap(), tiff::ColorType::Gray(16));
    let img = load_luma16(&tif);
    let c = check_sweeps(&img, &t);
    eprintln!(
        "linear TIFF: max frequency error {:.5} %, max modulation error {:.5} %",
        c.max_freq_err * 100.0,
        c.max_mod_err * 100.0
    );
    assert!(c.max_freq_err < 0.002 && c.max_mod_err < 0.005);
    check_greys_and_fiducials(&img, &t);
    check_description_matches(&img, &t);
}

#[test]
fn png_patches_frequency_and_modulation() {
    let dir = tempfile::tempdir().unwrap();
    let (png, t) = make(
        dir.path(),
        "patches.png",
        &[
            "--law",
            "patches",
            "--f-min",
            "0.3",
            "--f-max",
            "2.4",
            "--patches",
            "8",
            "--dpi",
            "150",
        ],
    );
    assert_eq!(t.patches.len(), 8);
    // Log-spaced from f_min to f_max.
    let f: Vec<f64> = t.patches.iter().map(|p| p.freq_cy_mm).collect();
    assert_eq!(f[0], 0.3);
    assert_eq!(f[7], 2.4);
    for i in 1..7 {
        let want = 0.3 * 8f64.powf(i as f64 / 7.0);
        assert!((f[i] / want - 1.0).abs() < 0.005, "{} vs {want}", f[i]);
    }
    let img = load_luma16(&png);
    let pitch = 25.4 / DPI;
    let mut worst_f: f64 = 0.0;
    let mut worst_m: f64 = 0.0;
    for p in &t.patches {
        let j = ((p.rect.y_mm + p.rect.height_mm / 2.0) / pitch) as u32;
        let i0 = (p.rect.x_mm / pitch).ceil() as usize;
        let i1 = ((p.rect.x_mm + p.rect.width_mm) / pitch - 1.0).floor() as usize;
        let refl: Vec<f64> = (i0..i1)
            .map(|i| srgb_to_linear(img.get_pixel(i as u32, j)[0] as f64 / 65535.0))
            .collect();
        let x0 = p.rect.x_mm - i0 as f64 * pitch;
        let xs = crossings(&refl, p.mean, pitch, x0);
        let n = xs.len() - 1;
        let n = n - n % 2;
        let measured = (n as f64 / 2.0) / (xs[n] - xs[0]);
        worst_f = worst_f.max((measured / p.freq_cy_mm - 1.0).abs());
        let (mx, mn) = refl
            .iter()
            .fold((0.0f64, 1.0f64), |(a, b), &r| (a.max(r), b.min(r)));
        // Extremes are sampled exactly only when a dot centre meets a peak; use the fit instead.
        let mut m = [[0.0f64; 4]; 3];
        for (i, &r) in refl.iter().enumerate() {
            let ph = 2.0 * std::f64::consts::PI * p.freq_cy_mm * ((i as f64 + 0.5) * pitch - x0);
            let b = [1.0, ph.cos(), ph.sin()];
            for u in 0..3 {
                for v in 0..3 {
                    m[u][v] += b[u] * b[v];
                }
                m[u][3] += b[u] * r;
            }
        }
        let s = solve3(m);
        let modulation = s[1].hypot(s[2]) / s[0];
        assert!((mx - mn) / (mx + mn) <= p.contrast + 1e-4);
        worst_m = worst_m.max((modulation / p.contrast - 1.0).abs());
    }
    eprintln!(
        "patches: max frequency error {:.5} %, max modulation error {:.5} %",
        worst_f * 100.0,
        worst_m * 100.0
    );
    assert!(worst_f < 0.002, "{worst_f}");
    assert!(worst_m < 0.005, "{worst_m}");
    check_greys_and_fiducials(&img, &t);
    check_description_matches(&img, &t);
}

#[test]
fn pdf_page_size_and_image_match_png() {
    let dir = tempfile::tempdir().unwrap();
    let args = [
        "--law", "log", "--f-min", "0.3", "--f-max", "1.5", "--size", "A5", "--dpi", "100",
    ];
    let (pdf, _) = make(dir.path(), "c.pdf", &args);
    let (png, _) = make(dir.path(), "c.png", &args);
    let bytes = std::fs::read(&pdf).unwrap();
    assert!(bytes.starts_with(b"%PDF-1."));
    let text = String::from_utf8_lossy(&bytes);
    let mb = text.find("/MediaBox [").expect("MediaBox") + "/MediaBox [".len();
    let nums: Vec<f64> = text[mb..]
        .split(']')
        .next()
        .unwrap()
        .split_whitespace()
        .map(|t| t.parse().unwrap())
        .collect();
    assert_eq!(nums.len(), 4);
    let (w_pt, h_pt) = (nums[2] - nums[0], nums[3] - nums[1]);
    assert!((w_pt - 210.0 / 25.4 * 72.0).abs() < 0.01, "{w_pt}");
    assert!((h_pt - 148.0 / 25.4 * 72.0).abs() < 0.01, "{h_pt}");
    // The image dictionary and its placement: raster at 100 dpi.
    let num_after = |key: &str| -> f64 {
        let i = text.find(key).unwrap() + key.len();
        text[i..]
            .split_whitespace()
            .next()
            .unwrap()
            .parse()
            .unwrap()
    };
    let (wpx, hpx) = (num_after("/Width "), num_after("/Height "));
    assert_eq!((wpx, hpx), (827.0, 583.0));
    // Inflate the image stream, undo the PNG Up predictor, compare with the PNG.
    // Byte offsets (the lossy text above shifts them after the binary header line).
    let find = |needle: &[u8], from: usize| {
        bytes[from..]
            .windows(needle.len())
            .position(|w| w == needle)
            .map(|k| from + k)
            .unwrap()
    };
    let im = find(b"/Subtype /Image", 0);
    let s = find(b"stream\n", im) + 7;
    let mut z = flate2::read::ZlibDecoder::new(&bytes[s..]);
    let mut raw = Vec::new();
    use std::io::Read;
    z.read_to_end(&mut raw).unwrap();
    let row_len = 827 * 2 + 1;
    assert_eq!(raw.len(), row_len * 583);
    let img = load_luma16(&png);
    let mut prev = vec![0u8; 827 * 2];
    for (j, row) in raw.chunks_exact(row_len).enumerate() {
        assert_eq!(row[0], 2);
        for (k, b) in row[1..].iter().enumerate() {
            prev[k] = prev[k].wrapping_add(*b);
        }
        for i in (0..827).step_by(7) {
            let v = u16::from_be_bytes([prev[2 * i], prev[2 * i + 1]]);
            assert_eq!(v, img.get_pixel(i as u32, j as u32)[0]);
        }
    }
    // Content stream scales the unit image to the raster's physical size.
    let cm = text.find(" cm").unwrap();
    let line = text[..cm].rsplit('\n').next().unwrap();
    let m: Vec<f64> = line
        .split_whitespace()
        .map(|t| t.parse().unwrap())
        .collect();
    assert!((m[0] - 827.0 / 100.0 * 72.0).abs() < 0.01);
}

#[test]
fn setup_gives_chart_range_and_reports_cycles_per_pixel() {
    let dir = tempfile::tempdir().unwrap();
    let out = run(
        dir.path(),
        &[
            "--pixel-pitch",
            "4.3um",
            "--focal-length",
            "50mm",
            "--distance",
            "2m",
            "--cy-px",
            "0.005,0.1",
            "--dpi",
            "150",
            "-o",
            "s.png",
        ],
    );
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let t: Target = Target::load(&dir.path().join("s.toml")).unwrap();
    // Chart frequency = cy/px × m / pitch with m = f/(d − f).
    let m = 50.0 / 1950.0;
    let f_max = 0.1 * m / 0.0043;
    assert!((t.sweeps[0].f_max_cy_mm - f_max).abs() < 1e-9);
    assert!((t.sweeps[0].f_min_cy_mm - 0.005 * m / 0.0043).abs() < 1e-9);
    let stdout = String::from_utf8_lossy(&out.stdout);
    assert!(stdout.contains("0.005–0.1 cy/px"), "{stdout}");
    assert!(stdout.contains("0.596"), "{stdout}");
}

#[test]
fn bad_input_one_line_exit_code_no_files() {
    let dir = tempfile::tempdir().unwrap();
    let cases: &[(&[&str], i32)] = &[
        (&["--f-min", "2", "--f-max", "1", "-o", "a.png"], 2),
        (&["--f-min", "0", "--f-max", "1", "-o", "a.png"], 2),
        (&["--f-min=-1", "--f-max", "1", "-o", "a.png"], 2),
        (
            &[
                "--f-min",
                "1",
                "--f-max",
                "2",
                "--contrast",
                "1.5",
                "-o",
                "a.png",
            ],
            2,
        ),
        (
            &[
                "--f-min",
                "1",
                "--f-max",
                "2",
                "--contrast",
                "0",
                "-o",
                "a.png",
            ],
            2,
        ),
        (
            &[
                "--f-min", "1", "--f-max", "2", "--size", "10x8mm", "-o", "a.png",
            ],
            2,
        ),
        (
            &[
                "--f-min", "1", "--f-max", "20", "--dpi", "300", "-o", "a.png",
            ],
            2,
        ),
        (&["--f-min", "1", "--f-max", "2", "-o", "a.jpg"], 2),
        (
            &[
                "--f-min",
                "1",
                "--f-max",
                "2",
                "--size",
                "6000x300mm",
                "-o",
                "a.pdf",
            ],
            2,
        ),
        (
            &[
                "--f-min",
                "1",
                "--f-max",
                "2",
                "--printer-curve",
                "missing.csv",
                "-o",
                "a.png",
            ],
            3,
        ),
        (
            &[
                "--f-min",
                "0.5",
                "--f-max",
                "0.8",
                "--dpi",
                "100",
                "-o",
                "no/such/dir/a.png",
            ],
            6,
        ),
    ];
    for (args, code) in cases {
        let out = run(dir.path(), args);
        let err = String::from_utf8_lossy(&out.stderr);
        assert_eq!(out.status.code(), Some(*code), "{args:?}: {err}");
        assert_eq!(err.trim().lines().count(), 1, "{args:?}: {err}");
        assert!(err.starts_with("sweepmtf: "), "{err}");
        let left: Vec<_> = std::fs::read_dir(dir.path()).unwrap().collect();
        assert!(left.is_empty(), "{args:?} left {left:?}");
    }
    // A failure after the temporary files exist (the final name is a folder):
    // exit 6 and the temporary files are gone.
    std::fs::create_dir(dir.path().join("d.png")).unwrap();
    let out = run(
        dir.path(),
        &[
            "--f-min", "0.5", "--f-max", "0.8", "--dpi", "100", "-o", "d.png",
        ],
    );
    assert_eq!(
        out.status.code(),
        Some(6),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let names: Vec<String> = std::fs::read_dir(dir.path())
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().to_string())
        .collect();
    assert_eq!(names, ["d.png"], "temporary files left behind");
    std::fs::remove_dir(dir.path().join("d.png")).unwrap();
    // An unwritable existing folder: nothing half-written is left behind.
    let ro = dir.path().join("ro");
    std::fs::create_dir(&ro).unwrap();
    let mut perm = std::fs::metadata(&ro).unwrap().permissions();
    use std::os::unix::fs::PermissionsExt;
    perm.set_mode(0o555);
    std::fs::set_permissions(&ro, perm).unwrap();
    let probe = ro.join("probe");
    if std::fs::write(&probe, b"x").is_err() {
        // (root ignores permissions; only check where they apply)
        let out = run(
            dir.path(),
            &[
                "--f-min", "0.5", "--f-max", "0.8", "--dpi", "100", "-o", "ro/a.png",
            ],
        );
        assert_eq!(out.status.code(), Some(6));
        assert_eq!(std::fs::read_dir(&ro).unwrap().count(), 0);
    }
}

#[test]
fn printer_curve_is_precompensated() {
    let dir = tempfile::tempdir().unwrap();
    // A printer whose reflectance is 0.05 + 0.85·(v/255)^1.8 (paper white 0.9).
    let mut csv = String::from("value,reflectance\n");
    let curve = |v: f64| 0.05 + 0.85 * (v / 255.0).powf(1.8);
    for v in (0..=255).step_by(5) {
        csv.push_str(&format!("{v},{}\n", curve(v as f64)));
    }
    std::fs::write(dir.path().join("p.csv"), csv).unwrap();
    let (png, t) = make(
        dir.path(),
        "pc.png",
        &[
            "--law",
            "patches",
            "--f-min",
            "0.3",
            "--f-max",
            "1",
            "--patches",
            "4",
            "--dpi",
            "150",
            "--printer-curve",
            "p.csv",
        ],
    );
    let img = load_luma16(&png);
    let pitch = 25.4 / DPI;
    // Print each pixel through the printer model (relative to paper white) and fit the sine.
    let p = &t.patches[0];
    let j = ((p.rect.y_mm + p.rect.height_mm / 2.0) / pitch) as u32;
    let i0 = (p.rect.x_mm / pitch).ceil() as usize;
    let i1 = ((p.rect.x_mm + p.rect.width_mm) / pitch - 1.0).floor() as usize;
    let x0 = p.rect.x_mm - i0 as f64 * pitch;
    let mut m = [[0.0f64; 4]; 3];
    for i in i0..i1 {
        let v = img.get_pixel(i as u32, j)[0] as f64 / 65535.0 * 255.0;
        // The curve is sampled every 5 values and interpolated linearly by the chart;
        // model the printer the same way so the check is exact.
        let k = ((v / 5.0).floor() * 5.0).min(250.0);
        let r = curve(k) + (curve(k + 5.0) - curve(k)) * (v - k) / 5.0;
        let r = r / 0.9;
        let ph = 2.0
            * std::f64::consts::PI
            * p.freq_cy_mm
            * ((i - i0) as f64 * pitch + 0.5 * pitch - x0);
        let b = [1.0, ph.cos(), ph.sin()];
        for u in 0..3 {
            for w in 0..3 {
                m[u][w] += b[u] * b[w];
            }
            m[u][3] += b[u] * r;
        }
    }
    let s = solve3(m);
    assert!((s[0] - 0.5).abs() < 0.0025, "mean {}", s[0]);
    let modulation = s[1].hypot(s[2]) / s[0];
    assert!((modulation / 0.8 - 1.0).abs() < 0.005, "{modulation}");
    // A contrast the printer cannot reach (black 0.5·0.05 < 0.0556) is refused.
    let out = run(
        dir.path(),
        &[
            "--f-min",
            "0.3",
            "--f-max",
            "1",
            "--contrast",
            "0.95",
            "--printer-curve",
            "p.csv",
            "-o",
            "x.png",
        ],
    );
    assert_eq!(out.status.code(), Some(2));
}

#[test]
fn unreadable_description_is_reported() {
    let dir = tempfile::tempdir().unwrap();
    let p = dir.path().join("bad.toml");
    std::fs::write(&p, "name = 3").unwrap();
    assert!(matches!(Target::load(&p), Err(TargetError::Parse { .. })));
}

#[test]
fn gamma_encoding_gives_requested_modulation() {
    let dir = tempfile::tempdir().unwrap();
    let (png, t) = make(
        dir.path(),
        "g.png",
        &[
            "--law",
            "patches",
            "--f-min",
            "0.3",
            "--f-max",
            "1",
            "--patches",
            "4",
            "--dpi",
            "150",
            "--gamma",
            "2.2",
            "--contrast",
            "0.5",
        ],
    );
    let img = load_luma16(&png);
    let pitch = 25.4 / DPI;
    let refl = |i: usize, j: u32| (img.get_pixel(i as u32, j)[0] as f64 / 65535.0).powf(2.2);
    for g in &t.greys {
        let (i, j) = (
            ((g.rect.x_mm + g.rect.width_mm / 2.0) / pitch) as usize,
            ((g.rect.y_mm + g.rect.height_mm / 2.0) / pitch) as u32,
        );
        assert!((refl(i, j) - g.reflectance).abs() < 1e-4, "{}", g.id);
    }
    for p in &t.patches {
        let j = ((p.rect.y_mm + p.rect.height_mm / 2.0) / pitch) as u32;
        let i0 = (p.rect.x_mm / pitch).ceil() as usize;
        let i1 = ((p.rect.x_mm + p.rect.width_mm) / pitch - 1.0).floor() as usize;
        let mut m = [[0.0f64; 4]; 3];
        for i in i0..i1 {
            let ph = 2.0
                * std::f64::consts::PI
                * p.freq_cy_mm
                * ((i as f64 + 0.5) * pitch - p.rect.x_mm);
            let b = [1.0, ph.cos(), ph.sin()];
            for u in 0..3 {
                for w in 0..3 {
                    m[u][w] += b[u] * b[w];
                }
                m[u][3] += b[u] * refl(i, j);
            }
        }
        let s = solve3(m);
        let modulation = s[1].hypot(s[2]) / s[0];
        assert!(
            (modulation / 0.5 - 1.0).abs() < 0.005,
            "{}: {modulation}",
            p.id
        );
        assert!((s[0] - 0.5).abs() < 0.0025);
    }
}
