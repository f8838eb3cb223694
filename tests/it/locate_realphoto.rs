//! The real photo of a printed chart of another design (mtfmapper, in
//! perspective, uneven light) must give a clean "no chart found".

use crate::locate_support;

use locate_support::*;
use sweepmtf::locate::{self, LocateError};

/// The real photo of another chart design (testdata/real, BSD, MTF Mapper).
fn photo() -> String {
    concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/testdata/real/chart_photo/mtfmapper_perspective_chart_photo.jpg"
    )
    .to_string()
}

#[test]
fn other_chart_design_is_cleanly_not_found() {
    let plane = load_linear_luma(&photo());
    let t = test_target(200.0, 140.0);
    let s = locate::search(&plane, &t).unwrap();
    let dir = std::path::Path::new(env!("CARGO_TARGET_TMPDIR")).join("locate");
    std::fs::create_dir_all(&dir).unwrap();
    locate::debug_image(&plane, &s.candidates, &s.charts)
        .save(dir.join("realphoto.roi.png"))
        .unwrap();
    assert!(s.charts.is_empty(), "false detection: {:?}", s.charts);
    match locate::find_chart(&plane, &t, None) {
        Err(e @ LocateError::NotFound { .. }) => {
            let msg = e.to_string();
            eprintln!("{msg}");
            assert!(msg.contains("looked for") && !msg.contains('\n'), "{msg}");
        }
        other => panic!("expected NotFound, got {other:?}"),
    }
}
