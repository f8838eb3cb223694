//! EXIF facts and pixel pitch from real camera JPEGs (Wikimedia Commons
//! samples, see testdata/real/README.md): the expected numbers are the
//! rationals the README quotes from the files, and the stored sizes come
//! from the `image` crate's JPEG decoder.

use std::path::{Path, PathBuf};
use sweepmtf::photo::exif::{ResolutionUnit, read_facts};
use sweepmtf::photo::pitch::{self, PitchSource};

fn realdata(rel: &str) -> PathBuf {
    Path::new(concat!(env!("CARGO_MANIFEST_DIR"), "/testdata/real")).join(rel)
}

fn stored_size(p: &Path) -> (usize, usize) {
    let (w, h) = image::image_dimensions(p).unwrap();
    (w as usize, h as usize)
}

#[test]
fn sx60_gives_the_focal_plane_pitch() {
    let p = realdata("exif_jpeg/canon_powershot_sx60hs_hdr_NO.jpg");
    let f = read_facts(&p).unwrap();
    assert_eq!(f.make.as_deref(), Some("Canon"));
    assert_eq!(f.model.as_deref(), Some("Canon PowerShot SX60 HS"));
    assert_eq!(f.f_number, Some(5.6));
    assert!((f.focal_length_mm.unwrap() - 57.0).abs() < 0.05);
    assert_eq!(f.focal_plane_x_res_px_per_unit, Some(505679.0 / 60.0));
    assert_eq!(
        f.focal_plane_unit.unwrap_or(ResolutionUnit::Inch),
        ResolutionUnit::Inch
    );
    assert!(f.warnings.is_empty(), "{:?}", f.warnings);
    let (w, h) = stored_size(&p);
    assert_eq!((w, h), (2048, 1536));
    let r = pitch::resolve(&f, w, h, None);
    assert_eq!(r.source, PitchSource::Exif);
    let want = 25.4 / (505679.0 / 60.0);
    assert!((r.pitch_mm.unwrap() - want).abs() < 1e-15);
    assert!((r.pitch_um().unwrap() - 3.0138).abs() < 1e-4);
    assert!(r.warnings.is_empty(), "{:?}", r.warnings);
    let specs = pitch::auto_model_specs(&f, r.pitch_mm.unwrap(), 550e-6).unwrap();
    assert_eq!(
        specs[0],
        ("optics".into(), "diffraction:lambda=550nm,fnum=5.6".into())
    );
    assert_eq!(specs[1].0, "aperture");
    assert!(specs[1].1.starts_with("rect:A=3.0137696"), "{}", specs[1].1);
    // the model's own parser takes the aperture spec: a square pixel of the
    // pitch has MTF |sinc(1/2)| = 2/π at the Nyquist frequency 1/(2·pitch)
    let spec = specs[1].1.trim_start_matches("rect:");
    let aperture = sweepmtf::model::aperture::parse(&format!("rect:{spec}")).unwrap();
    let nyquist = 1.0 / (2.0 * want);
    let mtf = aperture.otf(nyquist, 0.0).norm();
    assert!((mtf - 2.0 / std::f64::consts::PI).abs() < 1e-9, "{mtf}");
}

#[test]
fn downscaled_s40_pitch_is_rescaled_to_the_stored_pixels_with_a_note() {
    let p = realdata("exif_jpeg/canon_powershot_s40_downscaled.jpg");
    let f = read_facts(&p).unwrap();
    assert_eq!(f.focal_plane_x_res_px_per_unit, Some(56800.0 / 7.0));
    assert_eq!(f.exif_width_px, Some(2272));
    let (w, h) = stored_size(&p);
    assert_eq!((w, h), (480, 360));
    let r = pitch::resolve(&f, w, h, None);
    assert_eq!(r.source, PitchSource::ExifRescaled);
    let sensor = 25.4 / (56800.0 / 7.0);
    assert!((r.sensor_pitch_mm.unwrap() - sensor).abs() < 1e-15);
    assert!((r.pitch_mm.unwrap() - sensor * 2272.0 / 480.0).abs() < 1e-15);
    // What was done (rescaled) is a note, not a warning.
    assert!(r.notes.iter().any(|w| w.contains("2272")), "{:?}", r.notes);
    assert!(r.warnings.is_empty(), "{:?}", r.warnings);
    // --pixel-pitch still wins
    let r = pitch::resolve(&f, w, h, Some(0.0148));
    assert_eq!(
        (r.pitch_mm, r.source),
        (Some(0.0148), PitchSource::Override)
    );
}

#[test]
fn d70_without_focal_plane_tags_falls_back_to_cycles_per_pixel() {
    let p = realdata("exif_jpeg/nikon_d70_no_focalplane.jpg");
    let f = read_facts(&p).unwrap();
    assert_eq!(f.model.as_deref(), Some("NIKON D70"));
    assert_eq!(f.f_number, Some(9.0));
    assert_eq!(f.focal_length_mm, Some(100.0));
    assert_eq!(f.focal_plane_x_res_px_per_unit, None);
    let (w, h) = stored_size(&p);
    let r = pitch::resolve(&f, w, h, None);
    assert_eq!((r.pitch_mm, r.source), (None, PitchSource::None));
    assert!(r.notes.iter().any(|w| w.contains("--pixel-pitch")));
    // auto model needs a pitch, which must come from --pixel-pitch here
    assert!(pitch::auto_model_specs(&f, 0.0078, 550e-6).is_ok());
}

#[test]
fn a_file_without_exif_gives_empty_facts() {
    let dir = tempfile::tempdir().unwrap();
    let p = dir.path().join("plain.png");
    image::GrayImage::new(4, 4).save(&p).unwrap();
    let f = read_facts(&p).unwrap();
    assert_eq!(f.make, None);
    assert_eq!(f.f_number, None);
    assert!(read_facts(&dir.path().join("missing.jpg")).is_err());
}
