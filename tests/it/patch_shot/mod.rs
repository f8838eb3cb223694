//! The shared patch shot of the model-at-patches tests: the A4 patch chart
//! simulated through `targets/systems/aps_c_f4.toml`, turned 20°.

use assert_cmd::Command;
use std::path::{Path, PathBuf};

/// The system the shot is simulated through (and modelled with).
pub const SYSTEM: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/targets/systems/aps_c_f4.toml");
/// The A4 patch chart.
pub const TARGET: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/targets/a4_patches.toml");

/// Simulates the A4 patch chart turned 20° (1500×1100 px: 0.07 to 1.7 cy/px)
/// into `dir/shot.png`; returns the photo and the target corners as `--roi` text.
pub fn shot(dir: &Path) -> (PathBuf, String) {
    let photo = dir.join("shot.png");
    Command::cargo_bin("sweepmtf")
        .unwrap()
        .args(["simulate", "--target", TARGET, "--system", SYSTEM])
        .args(["--size", "1500x1100", "--rotate", "20", "-o"])
        .arg(&photo)
        .assert()
        .success();
    let meta: serde_json::Value =
        serde_json::from_slice(&std::fs::read(dir.join("shot.json")).unwrap()).unwrap();
    let roi: Vec<String> = meta["target_corners"]
        .as_array()
        .unwrap()
        .iter()
        .map(|v| format!("{}", v.as_f64().unwrap()))
        .collect();
    (photo, roi.join(","))
}
