//! Unit tests of the fiducial assignment: the affine guess, the pattern's
//! flat radii, the background clearance and the shape check.

use super::judge::shape_matches;
use super::*;
use crate::geometry::Point;

#[test]
fn affine_from_three_points_is_exact() {
    let src = [[0.0, 0.0], [10.0, 0.0], [10.0, 5.0]];
    let f = |p: Point| [3.0 + 2.0 * p[0] - 0.5 * p[1], 7.0 + 0.3 * p[0] + 1.7 * p[1]];
    let dst: Vec<Point> = src.iter().map(|&p| f(p)).collect();
    let h = affine3(&src, &dst).unwrap();
    for p in [[0.0, 5.0], [4.0, 3.0], [-2.0, 8.0]] {
        let (a, b) = (h.apply(p), f(p));
        assert!((a[0] - b[0]).abs() < 1e-9 && (a[1] - b[1]).abs() < 1e-9);
    }
    assert!(h.m[6].abs() < 1e-12 && h.m[7].abs() < 1e-12);
}

/// The flat radius by its plain definition: the ladder of offsets, each
/// of the 8 points evaluated, for every point.
fn plain_flat(target: &Target, p: Point, e: f64) -> f64 {
    let max_eps = 0.25 * target.width_mm.min(target.height_mm);
    let (mut flat, mut eps) = (0.0, 0.01);
    while eps <= max_eps {
        let offsets = [-eps, 0.0, eps];
        let ok = offsets
            .iter()
            .flat_map(|&a| offsets.iter().map(move |&b| [a, b]))
            .filter(|o| {
                *o != [0.0, 0.0] && (o[0] == 0.0 || o[1] == 0.0 || o[0] == o[1] || o[0] == -o[1])
            })
            .all(|o| (target.reflectance(p[0] + o[0], p[1] + o[1]) - e).abs() < 0.08);
        if !ok {
            break;
        }
        flat = eps;
        eps *= std::f64::consts::SQRT_2;
    }
    flat
}

#[test]
fn pattern_flat_radii_equal_the_plain_ladder() {
    // Every shipped target (fiducials, sweeps, sine and grey patches):
    // the background shortcut changes no radius, and points near the
    // regions' edges (where a rounding error would show) are included.
    for name in ["a4_log", "a4_linear", "a4_patches", "a3_log"] {
        let path = format!("{}/targets/{name}.toml", env!("CARGO_MANIFEST_DIR"));
        let target = Target::load(std::path::Path::new(&path)).unwrap();
        let pat = Pattern::new(&target);
        assert!(pat.pts.len() > 1200);
        for &(p, e, flat) in &pat.pts {
            assert_eq!(e, target.reflectance(p[0], p[1]));
            assert_eq!(flat, plain_flat(&target, p, e), "{name} at {p:?}");
        }
    }
}

#[test]
fn background_clearance_leaves_every_region_out() {
    // Random points: every point within the clearance (Chebyshev) of a
    // background point reads the background.
    let path = format!("{}/targets/a4_patches.toml", env!("CARGO_MANIFEST_DIR"));
    let target = Target::load(std::path::Path::new(&path)).unwrap();
    let mut st = 7u64;
    let mut u = || {
        st = st
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        (st >> 11) as f64 / (1u64 << 53) as f64
    };
    let mut checked = 0;
    for _ in 0..20_000 {
        let (x, y) = (u() * 320.0 - 10.0, u() * 230.0 - 10.0);
        let c = target.background_clearance(x, y);
        if target.reflectance(x, y) != target.background || c == 0.0 {
            continue;
        }
        for _ in 0..8 {
            let (dx, dy) = ((2.0 * u() - 1.0) * c, (2.0 * u() - 1.0) * c);
            assert_eq!(
                target.reflectance(x + dx * 0.999, y + dy * 0.999),
                target.background
            );
        }
        // Just beyond it, some region begins (the clearance is tight).
        let hit = (0..64).any(|k| {
            let a = k as f64 / 64.0 * std::f64::consts::TAU;
            let r = 1.001 * c * 1.5;
            target.reflectance(x + r * a.cos(), y + r * a.sin()) != target.background
        });
        checked += hit as usize;
    }
    assert!(checked > 1000, "{checked}");
}

#[test]
fn shape_check_accepts_rotated_equal_and_rejects_double_size() {
    assert!(shape_matches([4.0, 1.0, 2.0], [4.0, 1.0, 2.0], 0.4, 2.5));
    assert!(!shape_matches([4.0, 1.0, 2.0], [12.0, 3.0, 6.0], 0.4, 2.5));
}
