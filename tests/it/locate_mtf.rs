//! Issue 7's bar in small: shots of the shipped A4 log chart from the project's
//! camera simulator (rotation, tilt up to 45°, small and large charts, fall-off,
//! a light gradient, noise at SNR ≈ 50, defocus, JPEG q90) are measured with no
//! corners given; corners and every sweep's MTF are checked against the
//! simulator's own truth. The 200-shot version is `examples/locate_sweep.rs`.

use crate::locate_support::sweep;

use sweep::{Pose, bar};

fn pose(rot: f64, tilt: f64, axis: f64, cover: f64, seed: u64) -> Pose {
    Pose {
        size: (900, 620),
        rotate_deg: rot,
        tilt_deg: tilt,
        tilt_axis_deg: axis,
        cover,
        shift: [0.6, -0.5],
        falloff: 0.35,
        gradient: [0.25, -0.2],
        exposure: 0.7,
        full_well_e: 7000.0,
        w020: 0.3,
        seed,
    }
}

#[test]
fn located_shots_measure_within_the_measure_bars() {
    let target = sweep::a4_log();
    let poses = [
        pose(0.0, 0.0, 90.0, 0.6, 1),
        pose(37.0, 45.0, 90.0, 0.5, 2),
        pose(128.0, 30.0, 20.0, 0.9, 3),
        pose(200.0, 44.0, 160.0, 0.35, 4),
        pose(271.0, 15.0, 0.0, 0.25, 5),
        pose(333.0, 40.0, 110.0, 0.7, 6),
    ];
    let mut errs = Vec::new();
    for (i, p) in poses.iter().enumerate() {
        let o = sweep::run(&target, p);
        assert!(o.error.is_none(), "shot {i}: {:?}", o.error);
        errs.extend(o.corner_err_px.iter().copied());
        for s in &o.sweeps {
            eprintln!(
                "shot {i} {}: RMS {:.4} over {} points (worst {:.3} at {:.3} cy/px)",
                s.id, s.rms, s.n, s.worst.0, s.worst.1
            );
            assert!(s.n >= 10, "shot {i} {}: only {} points", s.id, s.n);
            assert!(
                s.rms <= bar(s.contrast),
                "shot {i} {}: RMS {:.4} > {}",
                s.id,
                s.rms,
                bar(s.contrast)
            );
        }
    }
    let rms = (errs.iter().map(|e| e * e).sum::<f64>() / errs.len() as f64).sqrt();
    let max = errs.iter().cloned().fold(0.0, f64::max);
    eprintln!("corner error RMS {rms:.3} px, max {max:.3} px");
    assert!(
        rms <= 0.5 && max <= 1.0,
        "corner RMS {rms:.3}, max {max:.3}"
    );
}
