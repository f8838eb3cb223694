//! Writes the two shots behind the README's "MTF50 vs MTF50P" and "Lens MTF"
//! pictures into DIR (default `target/docs_peak_lens`) and prints the
//! `sweepmtf measure` command for each:
//! `usm.png` (reference renderer, Gaussian σ 0.9 px with an unsharp mask of
//! amount 1, radius 1.5 px: peak ≈ 1.15, SNR 50) and `lens.png` (camera
//! simulator, Gaussian optics σ 2.58 µm × 4.3 µm square pixel, SNR 50, JPEG q90).

use sweepmtf::measure::synth::nuisance_cases;
use sweepmtf::model::{System, spec::parse_factor};
use sweepmtf::simulate::demo::demo_target_for;
use sweepmtf::simulate::{Camera, encode::PhotoFormat, render};
use sweepmtf::target::SweepLaw;

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let dir = std::path::PathBuf::from(
        std::env::args()
            .nth(1)
            .unwrap_or_else(|| "target/docs_peak_lens".into()),
    );
    std::fs::create_dir_all(&dir)?;
    let roi = |q: &[f64]| {
        q.iter()
            .map(|v| format!("{v:.2}"))
            .collect::<Vec<_>>()
            .join(",")
    };
    let usm = nuisance_cases(7)
        .into_iter()
        .find(|s| s.name == "usm_peak1.15")
        .ok_or("no USM case")?;
    let p = dir.join("usm.png");
    std::fs::write(&p, usm.encode(107))?;
    let q: Vec<f64> = usm.quad.iter().flatten().copied().collect();
    println!("sweepmtf measure {} --roi {}", p.display(), roi(&q));
    let cam = Camera {
        width_px: 1000,
        height_px: 600,
        chart_px: Some(840.0),
        full_well_e: Some(6000.0),
        read_noise_e: 5.0,
        seed: 11,
        jpeg_quality: Some(90),
        ..Camera::default()
    };
    let t = demo_target_for(&cam, SweepLaw::Log, 0.006, 0.6)?;
    let sys = System {
        factors: vec![parse_factor("gaussian", "sigma=2.58um")?],
    };
    let shot = render(&t, &sys, &cam)?;
    let p = dir.join("lens.jpg");
    std::fs::write(&p, shot.encode(PhotoFormat::Jpeg)?)?;
    println!(
        "sweepmtf measure {} --roi {} --pixel-pitch 4.3um --lens-mtf",
        p.display(),
        roi(&shot.roi().ok_or("no sweep")?)
    );
    Ok(())
}
