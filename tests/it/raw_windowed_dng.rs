//! The windowed DNG reader (`decode_raw`, `decode_raw_within`) against
//! rawler's own whole-file decode (`decode_raw_with_rawler`, other
//! software): the real Canon 550D DNG (uncompressed 14-bit, one strip) and
//! DNGs from the simulator stored uncompressed, as lossless-JPEG strips and
//! as lossless-JPEG tiles with padded edge tiles, with an odd masked
//! border, per-site black levels, BlackLevelDeltaH/V and an orientation.
//! Every sample, level and fact must agree; a window must hold exactly the
//! whole decode's samples inside it and nothing outside; damaged tiled
//! files must be errors naming the file; and `measure_raw` with corners
//! given, which decodes only the region's window, meets the bar against the
//! simulator's truth with a preview that equals the simulator's mosaic.

use std::path::{Path, PathBuf};
use sweepmtf::photo::raw::{
    RawError, RawFrame, decode_raw, decode_raw_with_rawler, decode_raw_within, read_raw_facts,
};
use sweepmtf::simulate::BayerOrder;
use sweepmtf::simulate::dng::{DngSettings, encode_mosaic};

fn realdata(rel: &str) -> PathBuf {
    Path::new(concat!(env!("CARGO_MANIFEST_DIR"), "/testdata/real")).join(rel)
}

/// Asserts that two frames hold the same data, levels and facts.
fn assert_same(ours: &RawFrame, theirs: &RawFrame, what: &str) {
    assert_eq!(
        (ours.width, ours.height),
        (theirs.width, theirs.height),
        "{what}"
    );
    assert_eq!(ours.cfa, theirs.cfa, "{what}: CFA");
    assert_eq!(ours.samples_per_pixel, theirs.samples_per_pixel, "{what}");
    assert_eq!(ours.black, theirs.black, "{what}: black levels");
    assert_eq!(ours.white, theirs.white, "{what}: white levels");
    assert_eq!(
        (&ours.make, &ours.model, &ours.format, ours.bits_per_sample),
        (
            &theirs.make,
            &theirs.model,
            &theirs.format,
            theirs.bits_per_sample
        ),
        "{what}"
    );
    assert_eq!(ours.facts, theirs.facts, "{what}: EXIF facts");
    for y in 0..ours.height {
        for x in 0..ours.width {
            for s in 0..ours.samples_per_pixel {
                assert_eq!(
                    ours.dn(x, y, s),
                    theirs.dn(x, y, s),
                    "{what}: DN at ({x}, {y})"
                );
            }
        }
    }
}

fn mosaic(w: usize, h: usize) -> Vec<f32> {
    (0..w * h)
        .map(|i| 0.02 + 0.95 * ((i * 7919 + i / w * 13) % 1000) as f32 / 1000.0)
        .collect()
}

/// Writes a simulated DNG with `settings` into `dir`.
fn simulated(dir: &Path, name: &str, w: usize, h: usize, settings: &DngSettings) -> PathBuf {
    let bytes = encode_mosaic(&mosaic(w, h), w, h, BayerOrder::Gbrg, 3.9, settings).unwrap();
    let p = dir.join(name);
    std::fs::write(&p, bytes).unwrap();
    p
}

fn kinds() -> Vec<(&'static str, DngSettings)> {
    let (w, h) = (150usize, 98usize);
    let base = DngSettings {
        margin_px: 7,
        orientation: 6,
        black_delta_h: (0..w).map(|x| 0.5 * x as f64 - 20.0).collect(),
        black_delta_v: (0..h).map(|y| 30.0 - 0.25 * y as f64).collect(),
        ..DngSettings::default()
    };
    vec![
        ("uncompressed.dng", base.clone()),
        (
            "ljpeg_strips.dng",
            DngSettings {
                lossless_jpeg: true,
                ..base.clone()
            },
        ),
        (
            "ljpeg_tiles.dng",
            DngSettings {
                lossless_jpeg: true,
                tile_px: 64,
                ..base
            },
        ),
    ]
}

#[test]
fn the_real_canon_dng_reads_windowed_as_rawler_reads_it() {
    let p = realdata("raw/tinydng_colorchart_canon550d_magiclantern.dng");
    let ours = decode_raw(&p).unwrap();
    assert!(ours.decoder.contains("windowed"), "{}", ours.decoder);
    let theirs = decode_raw_with_rawler(&p).unwrap();
    assert!(theirs.decoder.starts_with("rawler"), "{}", theirs.decoder);
    assert_same(&ours, &theirs, "Canon 550D");
    assert_eq!(
        read_raw_facts(&p).unwrap(),
        theirs.facts,
        "facts without decoding"
    );
    assert_eq!(ours.decoded_rect(), (0, 0, ours.width, ours.height));
}

#[test]
fn simulated_dngs_of_every_layout_read_windowed_as_rawler_reads_them() {
    let dir = tempfile::tempdir().unwrap();
    for (name, settings) in kinds() {
        let p = simulated(dir.path(), name, 150, 98, &settings);
        let ours = decode_raw(&p).unwrap();
        assert!(
            ours.decoder.contains("windowed"),
            "{name}: {}",
            ours.decoder
        );
        let theirs = decode_raw_with_rawler(&p).unwrap();
        assert_same(&ours, &theirs, name);
        assert_eq!(read_raw_facts(&p).unwrap(), theirs.facts, "{name}");
    }
}

#[test]
fn a_window_holds_the_whole_decode_inside_and_nothing_outside() {
    let dir = tempfile::tempdir().unwrap();
    for (name, settings) in kinds() {
        let p = simulated(dir.path(), name, 150, 98, &settings);
        let whole = decode_raw(&p).unwrap();
        // Windows across tile and strip borders, at the frame's edges, and empty.
        for want in [
            (37, 21, 101, 70),
            (0, 0, 5, 3),
            (140, 90, 150, 98),
            (60, 60, 400, 400),
            (20, 20, 20, 40),
        ] {
            let part = decode_raw_within(&p, Some(want)).unwrap();
            let clamp = (
                want.0.min(150),
                want.1.min(98),
                want.2.min(150),
                want.3.min(98),
            );
            let expect = if clamp.0 < clamp.2 && clamp.1 < clamp.3 {
                clamp
            } else {
                (0, 0, 0, 0)
            };
            assert_eq!(part.decoded_rect(), expect, "{name} {want:?}");
            let (x0, y0, x1, y1) = expect;
            for y in 0..98 {
                for x in 0..150 {
                    let inside = x >= x0 && x < x1 && y >= y0 && y < y1;
                    let want_dn = if inside { whole.dn(x, y, 0) } else { 0.0 };
                    assert_eq!(part.dn(x, y, 0), want_dn, "{name} {want:?} ({x}, {y})");
                }
            }
        }
    }
}

#[test]
fn damaged_tiled_dngs_are_errors_naming_the_file() {
    let dir = tempfile::tempdir().unwrap();
    let (name, settings) = kinds().pop().unwrap();
    let p = simulated(dir.path(), name, 150, 98, &settings);
    let bytes = std::fs::read(&p).unwrap();
    let mut seen = 0;
    // Cut short anywhere in the tiles, and tile bytes overwritten.
    for (i, cut) in [0.98, 0.9, 0.6].into_iter().enumerate() {
        let q = dir.path().join(format!("cut{i}.dng"));
        std::fs::write(&q, &bytes[..(bytes.len() as f64 * cut) as usize]).unwrap();
        match decode_raw(&q) {
            Err(e) => {
                assert!(e.to_string().contains(&format!("cut{i}.dng")), "{e}");
                seen += 1;
            }
            Ok(f) => panic!("a truncated file decoded ({})", f.decoder),
        }
    }
    let mut garbled = bytes.clone();
    let n = garbled.len();
    for b in &mut garbled[n / 2..n / 2 + 4000] {
        *b = 0xff;
    }
    let q = dir.path().join("garbled.dng");
    std::fs::write(&q, &garbled).unwrap();
    // Either refused with the file named, or decoded (lossless JPEG may resync); never a panic.
    if let Err(e) = decode_raw(&q) {
        assert!(
            matches!(e, RawError::Corrupt { .. } | RawError::DecoderPanic { .. }),
            "{e}"
        );
        assert!(e.to_string().contains("garbled.dng"), "{e}");
    }
    assert_eq!(seen, 3);
}

/// RMS |MTF − truth| of the measured curve `id` over the green lattice's unaliased band.
fn green_rms(
    m: &sweepmtf::measure::Measurement,
    truth: &sweepmtf::simulate::SweepTruth,
    id: &str,
) -> f64 {
    let rows: Vec<(f64, f64)> = truth.rows.iter().map(|r| (r.freq_cy_px, r.mtf)).collect();
    let at = |f: f64| {
        let i = rows.partition_point(|p| p.0 < f).clamp(1, rows.len() - 1);
        let (a, b) = (rows[i - 1], rows[i]);
        a.1 + (b.1 - a.1) * (f - a.0) / (b.0 - a.0)
    };
    let c = m.curves.iter().find(|c| c.sweep_id == id).expect("curve");
    let e: Vec<f64> = c
        .points
        .iter()
        .filter(|p| !p.aliased && (0.01..=0.24).contains(&p.freq_cy_px))
        .map(|p| p.mtf - at(p.freq_cy_px))
        .collect();
    assert!(e.len() > 20, "{} points", e.len());
    (e.iter().map(|v| v * v).sum::<f64>() / e.len() as f64).sqrt()
}

#[test]
fn a_region_measures_from_its_window_alone_within_the_bar() {
    use sweepmtf::measure::{MeasureOptions, measure_raw};
    use sweepmtf::photo::linearise::Channel;
    use sweepmtf::simulate::{self, Camera, demo::demo_target};
    use sweepmtf::target::SweepLaw;
    let target = demo_target(SweepLaw::Log);
    let camera = Camera {
        bayer: Some(BayerOrder::Rggb),
        ..Camera::noiseless(1200, 800)
    };
    let shot = simulate::render(&target, &sweepmtf::model::System::default(), &camera).unwrap();
    let dir = tempfile::tempdir().unwrap();
    let quad = |q: [f64; 8]| [[q[0], q[1]], [q[2], q[3]], [q[4], q[5]], [q[6], q[7]]];
    for (name, settings) in [
        ("plain.dng", DngSettings::default()),
        (
            "tiles.dng",
            DngSettings {
                lossless_jpeg: true,
                tile_px: 64,
                ..DngSettings::default()
            },
        ),
    ] {
        let bytes =
            encode_mosaic(&shot.linear, 1200, 800, BayerOrder::Rggb, 4.3, &settings).unwrap();
        let p = dir.path().join(name);
        std::fs::write(&p, bytes).unwrap();
        // The strip alone (no target, refined ends) and the target frame's corners.
        for (roi, t, id) in [
            (quad(shot.roi().unwrap()), None, "strip"),
            (
                quad(shot.target_corners),
                Some(&target),
                shot.sweeps[0].id.as_str(),
            ),
        ] {
            let opts = MeasureOptions {
                roi: Some(roi),
                refine_roi: true,
                channel: Channel::G,
                ..MeasureOptions::default()
            };
            let m = measure_raw(&p, name, t, &opts).unwrap();
            let rms = green_rms(&m, &shot.sweeps[0], id);
            eprintln!("{name} {id}: RMS {rms:.5}");
            assert!(rms <= 0.005, "{name} {id}: RMS {rms}");
            // Every preview pixel was decoded (a sample outside the window would
            // read 0 DN and show black): each equals the simulator's mosaic there.
            let pv = &m.preview;
            let srgb = |v: f64| {
                let v = v.clamp(0.0, 1.0);
                let c = if v <= 0.0031308 {
                    12.92 * v
                } else {
                    1.055 * v.powf(1.0 / 2.4) - 0.055
                };
                255.0 * c
            };
            for j in 0..pv.height {
                for i in 0..pv.width {
                    let x = (pv.x0 + i as f64 * pv.scale) as usize;
                    let y = (pv.y0 + j as f64 * pv.scale) as usize;
                    let want = srgb(shot.linear[y * 1200 + x] as f64);
                    let got = pv.rgb[3 * (j * pv.width + i)] as f64;
                    assert!(
                        (got - want).abs() <= 2.5,
                        "{name} {id}: preview ({x}, {y}) is {got}, the mosaic says {want:.1}"
                    );
                }
            }
        }
    }
}
