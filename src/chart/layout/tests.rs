//! Unit tests of [`layout`](fn@super::layout): page conventions, marks on
//! background and refused inputs.

use super::*;

#[test]
fn a4_log_layout_follows_conventions() {
    let c = layout(&ChartSpec::new(Law::Log, 0.5, 10.0)).unwrap();
    let t = &c.target;
    assert_eq!(t.fiducials.len(), 4);
    let d = 0.04 * 210.0;
    assert!((t.fiducials[0].diameter_mm - d).abs() < 1e-12);
    assert_eq!(t.fiducials[0].kind, FiducialKind::Ring);
    assert!((t.fiducials[2].x_mm - (297.0 - d)).abs() < 1e-12);
    let white = t.greys.iter().find(|g| g.id == "white").unwrap();
    assert!((white.reflectance - 0.9).abs() < 1e-12);
    // Nothing but background within one diameter of a fiducial (outside its own square).
    for s in &t.sweeps {
        for f in &t.fiducials {
            let r = &s.rect;
            let dx = (f.x_mm - (r.x_mm + r.width_mm).min(f.x_mm.max(r.x_mm))).abs();
            let dy = (f.y_mm - (r.y_mm + r.height_mm).min(f.y_mm.max(r.y_mm))).abs();
            assert!(dx.max(dy) >= d, "{} near {}", s.id, f.id);
        }
    }
    // Labels lie on background (away from every described region).
    for l in &c.texts {
        let r = l.rect();
        for (x, y) in [
            (r.x_mm, r.y_mm),
            (r.x_mm + r.width_mm, r.y_mm + r.height_mm),
            (r.x_mm + r.width_mm / 2.0, r.y_mm + r.height_mm / 2.0),
        ] {
            assert_eq!(t.reflectance(x, y), 1.0, "label '{}' at {x},{y}", l.text);
        }
    }
    assert!(c.ticks.len() >= 4);
}

#[test]
fn marks_stay_on_background_for_many_layouts() {
    // Every label box and tick (sampled on a grid) lies inside the page, on
    // background, and outside every fiducial's keep-out square.
    for (w, h) in [
        (297.0, 210.0),
        (420.0, 297.0),
        (210.0, 148.0),
        (120.0, 80.0),
        (600.0, 200.0),
    ] {
        for law in [Law::Log, Law::Linear, Law::Patches] {
            for contrasts in [vec![0.8], vec![0.8, 0.4, 0.2]] {
                let mut s = ChartSpec::new(law, 0.3, 4.0);
                s.width_mm = w;
                s.height_mm = h;
                s.contrasts = contrasts;
                let c = layout(&s).unwrap();
                let t = &c.target;
                let rects = c
                    .texts
                    .iter()
                    .map(|l| l.rect())
                    .chain(c.ticks.iter().copied());
                for r in rects {
                    for a in 0..=8 {
                        for b in 0..=4 {
                            let x = r.x_mm + r.width_mm * a as f64 / 8.0;
                            let y = r.y_mm + r.height_mm * b as f64 / 4.0;
                            assert!(x >= 0.0 && x <= w && y >= 0.0 && y <= h, "{w}×{h} {law:?}");
                            assert_eq!(t.reflectance(x, y), 1.0, "{w}×{h} {law:?} at {x},{y}");
                            for f in &t.fiducials {
                                let d = f.diameter_mm;
                                assert!(
                                    (x - f.x_mm).abs() >= d || (y - f.y_mm).abs() >= d,
                                    "{w}×{h} {law:?}: mark at {x},{y} near {}",
                                    f.id
                                );
                            }
                        }
                    }
                }
            }
        }
    }
}

#[test]
fn refuses_under_two_dots_and_warns_under_four() {
    let mut s = ChartSpec::new(Law::Linear, 1.0, 10.0);
    s.dpi = 100; // 3.94 dots/mm: 0.39 dots per cycle at 10 cy/mm
    assert!(layout(&s).is_err());
    s.dpi = 900; // 3.54 dots per cycle
    let c = layout(&s).unwrap();
    assert_eq!(c.warnings.len(), 1);
}

#[test]
fn bad_inputs() {
    let mut s = ChartSpec::new(Law::Log, 2.0, 1.0);
    assert!(layout(&s).is_err());
    s.f_min_cy_mm = 0.0;
    assert!(layout(&s).is_err());
    let mut s = ChartSpec::new(Law::Log, 0.5, 5.0);
    s.contrasts = vec![1.2];
    assert!(layout(&s).is_err());
    s.contrasts = vec![0.8];
    s.width_mm = 10.0;
    s.height_mm = 8.0;
    assert!(matches!(layout(&s), Err(ChartError::TooLarge(_))));
}
