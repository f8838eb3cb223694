//! DNGs written here by the library's minimal TIFF/DNG writer
//! (`simulate::dng`), with known samples: an odd active-area offset, a default
//! crop, a 2×2 per-site black-level pattern (all anchored at the active area,
//! as DNG says), BlackLevelDeltaH/V (which rawler does not apply: the adapter
//! reads them itself), and a linear (demosaiced, no CFA) DNG, which must come
//! out as R, G, B planes.

use std::path::Path;
use sweepmtf::photo::raw::{CfaPattern, RawChannel, decode_raw};
use sweepmtf::simulate::dng::{TagValue as V, tiff_bytes};

/// A little-endian TIFF with `tags` and one strip of u16 `data`, by the library's DNG writer.
fn write_tiff(path: &Path, tags: Vec<(u16, V)>, data: &[u16]) {
    let strip: Vec<u8> = data.iter().flat_map(|v| v.to_le_bytes()).collect();
    std::fs::write(path, tiff_bytes(&tags, &[], &strip)).unwrap();
}

fn common(w: u32, h: u32, spp: u16, photometric: u16) -> Vec<(u16, V)> {
    vec![
        (254, V::Long(vec![0])),
        (256, V::Long(vec![w])),
        (257, V::Long(vec![h])),
        (258, V::Short(vec![16; spp as usize])),
        (259, V::Short(vec![1])),
        (262, V::Short(vec![photometric])),
        (271, V::Ascii("Testmaker".into())),
        (272, V::Ascii("Synthetic One".into())),
        (277, V::Short(vec![spp])),
        (278, V::Long(vec![h])),
        (284, V::Short(vec![1])),
        (50706, V::Byte(vec![1, 4, 0, 0])),
    ]
}

const W: usize = 10;
const H: usize = 8;
/// Active area top, left, bottom, right (odd left and top shift the CFA phase).
const ACTIVE: [usize; 4] = [1, 3, 7, 9];
const BLACK: [u32; 4] = [100, 110, 120, 130];
const WHITE: u32 = 4000;

fn dn(x: usize, y: usize) -> u16 {
    (1000 + 37 * x + 101 * y) as u16
}

fn cfa_dng(path: &Path, crop: Option<([u32; 2], [u32; 2])>) {
    let mut tags = common(W as u32, H as u32, 1, 32803);
    tags.push((33421, V::Short(vec![2, 2])));
    tags.push((33422, V::Byte(vec![1, 0, 2, 1]))); // GRBG from the active area's corner
    tags.push((50713, V::Short(vec![2, 2])));
    tags.push((50714, V::Long(BLACK.to_vec())));
    tags.push((50717, V::Long(vec![WHITE])));
    tags.push((50829, V::Long(ACTIVE.iter().map(|&a| a as u32).collect())));
    if let Some((origin, size)) = crop {
        tags.push((50719, V::Long(origin.to_vec())));
        tags.push((50720, V::Long(size.to_vec())));
    }
    let data: Vec<u16> = (0..H).flat_map(|y| (0..W).map(move |x| dn(x, y))).collect();
    write_tiff(path, tags, &data);
}

/// Colour letter and black level of full-image pixel (x, y), from the DNG rules.
fn site(x: usize, y: usize) -> (char, f64) {
    let (ax, ay) = (x - ACTIVE[1], y - ACTIVE[0]);
    let colour = [['G', 'R'], ['B', 'G']][ay % 2][ax % 2];
    (colour, BLACK[(ay % 2) * 2 + ax % 2] as f64)
}

fn check_cfa_frame(path: &Path, origin: (usize, usize), size: (usize, usize)) {
    let f = decode_raw(path).unwrap();
    assert_eq!((f.width, f.height), size);
    assert_eq!(f.make, "Testmaker");
    assert_eq!(f.model, "Synthetic One");
    let pattern: String = (0..2)
        .flat_map(|y| (0..2).map(move |x| (x, y)))
        .map(|(x, y)| site(origin.0 + x, origin.1 + y).0)
        .collect();
    assert_eq!(f.cfa, CfaPattern::parse(&pattern), "{pattern}");
    for (ch, letter) in [
        (RawChannel::R, 'R'),
        (RawChannel::G, 'G'),
        (RawChannel::B, 'B'),
    ] {
        let planes = f.channel_planes(ch);
        assert_eq!(planes.len(), if letter == 'G' { 2 } else { 1 });
        let mut count = 0;
        for p in &planes {
            for j in 0..p.height {
                for i in 0..p.width {
                    let (cx, cy) = p.centre(i, j);
                    let (x, y) = (origin.0 + cx as usize, origin.1 + cy as usize);
                    let (c, black) = site(x, y);
                    assert_eq!(c, letter, "({x},{y})");
                    let want = (dn(x, y) as f64 - black) / (WHITE as f64 - black);
                    assert!((p.get(i, j) as f64 - want).abs() < 1e-6, "({x},{y})");
                    count += 1;
                }
            }
        }
        let all = (0..size.1)
            .flat_map(|y| (0..size.0).map(move |x| (x, y)))
            .filter(|&(x, y)| site(origin.0 + x, origin.1 + y).0 == letter)
            .count();
        assert_eq!(count, all, "{letter}: every site once");
    }
}

#[test]
fn odd_active_area_keeps_cfa_phase_and_per_site_black_levels() {
    let dir = tempfile::tempdir().unwrap();
    let p = dir.path().join("cfa.dng");
    cfa_dng(&p, None);
    check_cfa_frame(&p, (ACTIVE[1], ACTIVE[0]), (6, 6));
}

#[test]
fn default_crop_inside_the_active_area_shifts_phase_and_black_pattern() {
    let dir = tempfile::tempdir().unwrap();
    let p = dir.path().join("crop.dng");
    cfa_dng(&p, Some(([1, 1], [4, 3])));
    check_cfa_frame(&p, (ACTIVE[1] + 1, ACTIVE[0] + 1), (4, 3));
}

#[test]
fn linear_dng_without_cfa_gives_rgb_planes() {
    let (w, h) = (5usize, 4usize);
    let black = [10u32, 20, 30];
    let white = [1000u32, 2000, 3000];
    let v = |x: usize, y: usize, s: usize| (50 + 7 * x + 13 * y + 300 * s) as u16;
    let mut tags = common(w as u32, h as u32, 3, 34892);
    tags.push((50714, V::Long(black.to_vec())));
    tags.push((50717, V::Long(white.to_vec())));
    let data: Vec<u16> = (0..h)
        .flat_map(|y| (0..w).flat_map(move |x| (0..3).map(move |s| v(x, y, s))))
        .collect();
    let dir = tempfile::tempdir().unwrap();
    let p = dir.path().join("linear.dng");
    write_tiff(&p, tags, &data);
    let f = decode_raw(&p).unwrap();
    assert_eq!(f.cfa, None);
    assert_eq!(f.samples_per_pixel, 3);
    let groups = f.channel_groups(RawChannel::All);
    assert_eq!(
        groups.iter().map(|g| g.0).collect::<Vec<_>>(),
        ["r", "g", "b"]
    );
    for (s, (_, planes)) in groups.iter().enumerate() {
        assert_eq!(planes.len(), 1);
        let p = &planes[0];
        assert_eq!(
            (p.width, p.height, p.step, p.offset),
            (w, h, (1, 1), (0, 0))
        );
        for y in 0..h {
            for x in 0..w {
                let want = (v(x, y, s) as f64 - black[s] as f64) / (white[s] - black[s]) as f64;
                assert!((p.get(x, y) as f64 - want).abs() < 1e-6);
            }
        }
    }
    assert_eq!(f.channel_planes(RawChannel::G).len(), 1);
}

#[test]
fn clipped_sites_are_counted_per_sample_white_level() {
    let mut tags = common(4, 2, 1, 32803);
    tags.push((33421, V::Short(vec![2, 2])));
    tags.push((33422, V::Byte(vec![0, 1, 1, 2])));
    tags.push((50714, V::Long(vec![64])));
    tags.push((50717, V::Long(vec![1000])));
    let data = [999u16, 1000, 1001, 5, 65535, 0, 64, 1000];
    let dir = tempfile::tempdir().unwrap();
    let p = dir.path().join("clip.dng");
    write_tiff(&p, tags, &data);
    let f = decode_raw(&p).unwrap();
    assert_eq!(f.clipped_sites(), 4);
    assert_eq!(f.clipped_fraction(), 0.5);
    // a clipped sample reads ≥ 1, black reads 0, below black reads < 0 (not clamped)
    assert!(f.value(1, 0, 0) >= 1.0);
    assert_eq!(f.value(2, 1, 0), 0.0);
    assert!(f.value(1, 1, 0) < 0.0);
}

/// Linear values 0.05–0.95 that change at every pixel, `w × h` row-major.
fn ramp(w: usize, h: usize) -> Vec<f32> {
    (0..w * h)
        .map(|i| 0.05 + 0.9 * ((i * 7919) % 1000) as f32 / 1000.0)
        .collect()
}

#[test]
fn black_level_deltas_per_column_and_row_are_applied() {
    use sweepmtf::simulate::BayerOrder;
    use sweepmtf::simulate::dng::{DngSettings, encode_mosaic};
    let (w, h) = (10usize, 6usize);
    let lin = ramp(w, h);
    // Deltas of tens to hundreds of DN: ignoring them would err by up to 0.005.
    let settings = DngSettings {
        margin_px: 3,
        black_delta_h: (0..w).map(|x| 25.0 * x as f64 - 60.0).collect(),
        black_delta_v: (0..h).map(|y| 40.0 * y as f64 + 12.5).collect(),
        ..DngSettings::default()
    };
    let bytes = encode_mosaic(&lin, w, h, BayerOrder::Grbg, 4.3, &settings).unwrap();
    let dir = tempfile::tempdir().unwrap();
    let p = dir.path().join("deltas.dng");
    std::fs::write(&p, bytes).unwrap();
    let f = decode_raw(&p).unwrap();
    assert_eq!((f.width, f.height), (w, h));
    assert_eq!(f.cfa, CfaPattern::parse("GRBG"));
    assert_eq!(f.black.delta_h, settings.black_delta_h);
    assert_eq!(f.black.delta_v, settings.black_delta_v);
    // Per DNG: black(x, y) = BlackLevel[site] + DeltaH[x] + DeltaV[y]; white − black spans [0, 1].
    let white = settings.white as f64;
    for y in 0..h {
        for x in 0..w {
            let b = settings.black[(y % 2) * 2 + x % 2] as f64
                + settings.black_delta_h[x]
                + settings.black_delta_v[y];
            assert!((f.black.at(x, y, 0) - b).abs() < 1e-9);
            let dn = (b + lin[y * w + x] as f64 * (white - b)).round();
            let want = (dn - b) / (white - b);
            assert!((f.value(x, y, 0) as f64 - want).abs() < 1e-6, "({x},{y})");
            assert!(
                (f.value(x, y, 0) - lin[y * w + x]).abs() < 1e-4,
                "({x},{y})"
            );
        }
    }
    // Planes take the deltas too (no constant-black shortcut along a row).
    for p in f.channel_planes(RawChannel::All) {
        for j in 0..p.height {
            for i in 0..p.width {
                let (cx, cy) = p.centre(i, j);
                let (x, y) = (cx as usize, cy as usize);
                assert!((p.get(i, j) - lin[y * w + x]).abs() < 1e-4, "({x},{y})");
            }
        }
    }
}

#[test]
fn deltas_of_the_wrong_length_are_ignored_with_a_warning() {
    let mut tags = common(4, 2, 1, 32803);
    tags.push((33421, V::Short(vec![2, 2])));
    tags.push((33422, V::Byte(vec![0, 1, 1, 2])));
    tags.push((50714, V::Long(vec![64])));
    tags.push((50715, V::SRational(vec![(5, 1); 3])));
    tags.push((50717, V::Long(vec![1000])));
    let dir = tempfile::tempdir().unwrap();
    let p = dir.path().join("bad_delta.dng");
    write_tiff(&p, tags, &[100u16; 8]);
    let f = decode_raw(&p).unwrap();
    assert!(f.black.delta_h.is_empty());
    assert!(
        f.facts
            .warnings
            .iter()
            .any(|w| w.contains("BlackLevelDeltaH") && w.contains("ignored")),
        "{:?}",
        f.facts.warnings
    );
}

#[test]
fn lossless_jpeg_strips_decode_to_the_same_samples_as_the_uncompressed_strip() {
    use sweepmtf::simulate::BayerOrder;
    use sweepmtf::simulate::dng::{DngSettings, encode_mosaic};
    // 276 rows: the last 16-row strip is short; odd margin: shifted CFA phase.
    let (w, h) = (300usize, 270usize);
    let lin = ramp(w, h);
    let dir = tempfile::tempdir().unwrap();
    let mut frames = Vec::new();
    for lossless_jpeg in [false, true] {
        let settings = DngSettings {
            margin_px: 3,
            lossless_jpeg,
            ..DngSettings::default()
        };
        let bytes = encode_mosaic(&lin, w, h, BayerOrder::Bggr, 4.3, &settings).unwrap();
        let p = dir.path().join(format!("ljpeg_{lossless_jpeg}.dng"));
        std::fs::write(&p, &bytes).unwrap();
        frames.push((bytes.len(), decode_raw(&p).unwrap()));
    }
    // (This ramp is noise-like: compressed, it does not get smaller.)
    let ((_, plain), (_, packed)) = (&frames[0], &frames[1]);
    assert_eq!((packed.width, packed.height), (w, h));
    assert_eq!(packed.cfa, CfaPattern::parse("BGGR"));
    for y in 0..h {
        for x in 0..w {
            assert_eq!(packed.dn(x, y, 0), plain.dn(x, y, 0), "({x},{y})");
            assert!((packed.value(x, y, 0) - lin[y * w + x]).abs() < 1e-4);
        }
    }
}
