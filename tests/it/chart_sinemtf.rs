//! The MITRE sineMTF target description (real file from the sineMTF
//! distribution) read into a `Target`.

use std::path::Path;
use sweepmtf::target::{Direction, Target};

const TGT: &str = concat!(
    env!("CARGO_MANIFEST_DIR"),
    "/testdata/real/sine_target_scan/mitre_sinemtf_tgt.txt"
);
fn tgt() -> &'static Path {
    Path::new(TGT)
}

#[test]
fn reads_mitre_test_target() {
    let t = Target::load(tgt()).unwrap();
    assert_eq!(t.name, "sineMTF test");
    assert_eq!((t.width_mm, t.height_mm), (70.0, 47.5));
    assert_eq!(t.greys.len(), 14);
    assert_eq!(t.patches.len(), 15);
    // Patch F: density .148 (whitest), at (50, 0), 9.95 × 11.45 mm.
    let f = t.greys.iter().find(|g| g.id == "F").unwrap();
    assert_eq!(f.density, Some(0.148));
    assert!((f.reflectance - 10f64.powf(-0.148)).abs() < 1e-15);
    assert_eq!((f.rect.x_mm, f.rect.y_mm), (50.0, 0.0));
    assert_eq!((f.rect.width_mm, f.rect.height_mm), (9.95, 11.45));
    // Patch G has its own height (11.40); I is the darkest (1.124).
    let g = t.greys.iter().find(|g| g.id == "G").unwrap();
    assert_eq!(g.rect.height_mm, 11.40);
    let darkest = t
        .greys
        .iter()
        .max_by(|a, b| a.density.partial_cmp(&b.density).unwrap())
        .unwrap();
    assert_eq!(darkest.id, "I");
    // Sine patterns: frequency, manufacturer modulation, along x. Pattern 7 is typed 'S'.
    let freqs: Vec<f64> = t.patches.iter().map(|p| p.freq_cy_mm).collect();
    assert_eq!(
        freqs,
        [
            0.1875, 0.25, 0.375, 0.5, 0.75, 1.0, 1.5, 2.0, 3.0, 4.0, 5.0, 6.0, 8.0, 10.0, 12.0
        ]
    );
    let p7 = t.patches.iter().find(|p| p.id == "7").unwrap();
    assert_eq!((p7.contrast, p7.freq_cy_mm), (0.6022, 1.5));
    assert_eq!(
        (p7.rect.x_mm, p7.rect.y_mm, p7.rect.width_mm),
        (20.0, 12.0, 9.9)
    );
    let p15 = t.patches.iter().find(|p| p.id == "15").unwrap();
    assert_eq!((p15.contrast, p15.rect.x_mm), (0.3589, 65.0));
    assert!(t.patches.iter().all(|p| p.direction == Direction::X));
    // Every region inside the 70 × 47.5 mm frame, no overlaps between patterns.
    t.validate().unwrap();
    // The description round-trips through TOML.
    let back: Target = toml::from_str(&t.to_toml()).unwrap();
    assert_eq!(back, t);
}
