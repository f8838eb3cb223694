//! The tone curve a file declares (`photo::transfer`): ICC profiles written by
//! other software (testdata/icc, see its README), PNG chunks written by the
//! `png` crate, a JPEG APP2 ICC segment and a TIFF ICC tag; and what it
//! changes end to end: a 16-bit sRGB PNG used to be read as linear.

use assert_cmd::Command;
use std::path::Path;
use sweepmtf::photo::decode::decode_bytes;
use sweepmtf::photo::linearise::Tone;
use sweepmtf::photo::transfer::icc_tone;

fn icc(name: &str) -> Vec<u8> {
    std::fs::read(
        Path::new(env!("CARGO_MANIFEST_DIR"))
            .join("testdata/icc")
            .join(name),
    )
    .unwrap()
}

fn gamma_of(t: &Tone) -> f64 {
    match t {
        Tone::Gamma(g) => *g,
        other => panic!("not a power law: {other:?}"),
    }
}

#[test]
fn icc_profiles_from_other_software_give_their_curves() {
    assert_eq!(icc_tone(&icc("srgb-rel.icc")), Some(Tone::Srgb));
    assert_eq!(icc_tone(&icc("gray-d65-srgb-rel.icc")), Some(Tone::Srgb));
    assert!((gamma_of(&icc_tone(&icc("srgb-gamma22-rel.icc")).unwrap()) - 2.2).abs() < 1e-4);
    assert!((gamma_of(&icc_tone(&icc("gray-d65-linear-rel.icc")).unwrap()) - 1.0).abs() < 1e-4);
    // ProPhoto: a curv with one u8.8 entry, 461/256.
    assert_eq!(
        gamma_of(&icc_tone(&icc("prophoto-gamma18-rel.icc")).unwrap()),
        461.0 / 256.0
    );
    // BT.709 (ITU-R BT.709-6, the inverse of its OETF): a tabulated curve.
    let t = icc_tone(&icc("srgb-bt709-per.icc")).unwrap();
    assert!(matches!(t, Tone::Curve(_)), "{t:?}");
    for v in [0.0, 0.03, 0.081, 0.2, 0.5, 0.9, 1.0] {
        let want = if v < 0.081 {
            v / 4.5
        } else {
            ((v + 0.099) / 1.099f64).powf(1.0 / 0.45)
        };
        assert!(
            (t.apply(v) - want).abs() < 1e-3,
            "{v}: {} {want}",
            t.apply(v)
        );
    }
    // The ICC's own sRGB v4 profile has no TRC tag: nothing is claimed.
    assert_eq!(icc_tone(&icc("sRGB_v4.icc")), None);
    // Damaged profiles give nothing, never a panic.
    let good = icc("srgb-rel.icc");
    for cut in [0, 40, 131, 140, 200, good.len() - 1] {
        let _ = icc_tone(&good[..cut]);
    }
    let mut huge = good.clone();
    huge[128..132].copy_from_slice(&u32::MAX.to_be_bytes());
    let _ = icc_tone(&huge);
    let mut far = good.clone();
    let n = u32::from_be_bytes(good[128..132].try_into().unwrap()) as usize;
    for k in 0..n {
        far[136 + 12 * k..140 + 12 * k].copy_from_slice(&u32::MAX.to_be_bytes());
    }
    assert_eq!(icc_tone(&far), None);
}

/// A 4×2 16-bit grey PNG with the given extra chunks written by the `png` crate.
fn png16(set: impl FnOnce(&mut png::Encoder<&mut Vec<u8>>)) -> Vec<u8> {
    png16_icc(None, set)
}

/// [`png16`] with an iCCP chunk holding `icc`.
fn png16_icc(icc: Option<Vec<u8>>, set: impl FnOnce(&mut png::Encoder<&mut Vec<u8>>)) -> Vec<u8> {
    let mut out = Vec::new();
    {
        let mut info = png::Info::with_size(4, 2);
        info.icc_profile = icc.map(Into::into);
        let mut e = png::Encoder::with_info(&mut out, info).unwrap();
        e.set_color(png::ColorType::Grayscale);
        e.set_depth(png::BitDepth::Sixteen);
        set(&mut e);
        let mut w = e.write_header().unwrap();
        w.write_image_data(&[0x80u8; 16]).unwrap();
        w.finish().unwrap();
    }
    out
}

fn declared(bytes: &[u8]) -> Option<Tone> {
    decode_bytes(bytes, "t")
        .unwrap()
        .declared_tone
        .map(|d| d.tone)
}

#[test]
fn png_chunks_jpeg_segments_and_tiff_tags_are_read() {
    assert_eq!(declared(&png16(|_| {})), None);
    let srgb = png16(|e| e.set_source_srgb(png::SrgbRenderingIntent::Perceptual));
    assert_eq!(declared(&srgb), Some(Tone::Srgb));
    let g = declared(&png16(|e| {
        e.set_source_gamma(png::ScaledFloat::new(0.45455))
    }));
    assert!((gamma_of(&g.unwrap()) - 1.0 / 0.45455).abs() < 1e-4);
    // iCCP overrides gAMA (PNG spec 11.3.3.5).
    let pro = icc("prophoto-gamma18-rel.icc");
    let both = png16_icc(Some(pro.clone()), |e| {
        e.set_source_gamma(png::ScaledFloat::new(1.0))
    });
    assert_eq!(gamma_of(&declared(&both).unwrap()), 461.0 / 256.0);

    // JPEG: the profile in APP2 ICC_PROFILE segments (split in two, out of order).
    let mut jpeg = Vec::new();
    image::codecs::jpeg::JpegEncoder::new_with_quality(&mut jpeg, 90)
        .encode(&[128u8; 64], 8, 8, image::ExtendedColorType::L8)
        .unwrap();
    let p = icc("srgb-gamma22-rel.icc");
    let (a, b) = p.split_at(300);
    let seg = |n: u8, part: &[u8]| {
        let mut s = vec![0xFF, 0xE2];
        s.extend(((part.len() + 16) as u16).to_be_bytes());
        s.extend(b"ICC_PROFILE\0");
        s.extend([n, 2]);
        s.extend(part);
        s
    };
    let mut with = jpeg[..2].to_vec();
    with.extend(seg(2, b));
    with.extend(seg(1, a));
    with.extend(&jpeg[2..]);
    assert!((gamma_of(&declared(&with).unwrap()) - 2.2).abs() < 1e-4);
    assert_eq!(declared(&jpeg), None);

    // TIFF: tag 34675.
    let mut cur = std::io::Cursor::new(Vec::new());
    {
        let mut enc = tiff::encoder::TiffEncoder::new(&mut cur).unwrap();
        let mut im = enc
            .new_image::<tiff::encoder::colortype::Gray16>(4, 2)
            .unwrap();
        im.encoder()
            .write_tag(
                tiff::tags::Tag::Unknown(34675),
                &icc("gray-d65-srgb-rel.icc")[..],
            )
            .unwrap();
        im.write_data(&[30000u16; 8]).unwrap();
    }
    assert_eq!(declared(cur.get_ref()), Some(Tone::Srgb));

    // A damaged iCCP stream: the picture still decodes, no curve is claimed from it.
    let mut bad = png16_icc(Some(pro.clone()), |_| {});
    let at = bad.windows(4).position(|w| w == b"iCCP").unwrap();
    for b in &mut bad[at + 20..at + 40] {
        *b ^= 0x5A;
    }
    // (the chunk's CRC no longer matches: the png crate may refuse the file; either way no panic)
    let _ = decode_bytes(&bad, "bad");
}

/// End to end: a 16-bit sRGB PNG from the simulator carries an sRGB chunk, and
/// is measured through the sRGB curve (it used to be taken as linear: chart
/// modulation 0.42 for a printed 0.8, RMS 0.044).
#[test]
fn a_16_bit_srgb_png_is_measured_through_its_declared_curve() {
    let dir = tempfile::tempdir().unwrap();
    let photo = dir.path().join("s16.png");
    let sim = Command::cargo_bin("sweepmtf")
        .unwrap()
        .args([
            "simulate", "--target", "demo:log", "--size", "900x600", "--bits", "16", "-q",
        ])
        .args(["--gaussian", "sigma=2.4um", "-o"])
        .arg(&photo)
        .output()
        .unwrap();
    assert!(
        sim.status.success(),
        "{}",
        String::from_utf8_lossy(&sim.stderr)
    );
    let json: serde_json::Value =
        serde_json::from_slice(&std::fs::read(dir.path().join("s16.json")).unwrap()).unwrap();
    let roi: Vec<String> = json["roi"]
        .as_array()
        .unwrap()
        .iter()
        .map(|v| format!("{:.3}", v.as_f64().unwrap()))
        .collect();
    let out = dir.path().join("m");
    let m = Command::cargo_bin("sweepmtf")
        .unwrap()
        .arg("measure")
        .arg(&photo)
        .args(["--roi", &roi.join(","), "-v", "-o"])
        .arg(&out)
        .output()
        .unwrap();
    let err = String::from_utf8_lossy(&m.stderr);
    assert!(m.status.success(), "{err}");
    assert!(err.contains("tone from the PNG's sRGB chunk"), "{err}");
    assert!(!err.contains("taken as linear"), "{err}");
    let s: serde_json::Value =
        serde_json::from_slice(&std::fs::read(out.join("s16.summary.json")).unwrap()).unwrap();
    let cm = s["curves"][0]["chart_modulation"].as_f64().unwrap();
    assert!((cm / 0.8 - 1.0).abs() < 0.005, "chart modulation {cm}");
}

/// A real camera JPEG (Nikon D70, testdata/real/exif_jpeg) embeds HP's
/// "sRGB IEC61966-2.1" profile, whose green TRC is a 1024-entry `curv` table:
/// read as the sRGB curve itself. The other real samples embed no profile.
#[test]
fn a_real_camera_jpeg_declares_srgb_through_its_icc_table() {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("testdata/real/exif_jpeg");
    let d = decode_bytes(
        &std::fs::read(dir.join("nikon_d70_no_focalplane.jpg")).unwrap(),
        "d70",
    )
    .unwrap()
    .declared_tone
    .expect("an ICC profile");
    assert_eq!(d.tone, Tone::Srgb);
    assert_eq!(d.source, "the JPEG's ICC profile");
    for f in [
        "canon_powershot_s40_downscaled.jpg",
        "canon_powershot_sx60hs_hdr_NO.jpg",
    ] {
        let dec = decode_bytes(&std::fs::read(dir.join(f)).unwrap(), f).unwrap();
        assert_eq!(dec.declared_tone, None, "{f}");
    }
}
