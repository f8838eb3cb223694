//! Refining user-given corners (±5 px off) to a strip's or target's edges.

use crate::locate_support;

use locate_support::*;
use sweepmtf::geometry::{Homography, Point, rect_corners};
use sweepmtf::locate;

fn shot(seed: u64) -> (sweepmtf::target::Target, Homography, sweepmtf::photo::Plane) {
    shot_blurred(seed, 0.8)
}

/// A shot of the test target under a Gaussian blur of σ `blur_px`.
fn shot_blurred(
    seed: u64,
    blur_px: f64,
) -> (sweepmtf::target::Target, Homography, sweepmtf::photo::Plane) {
    let t = test_target(200.0, 140.0);
    let mut rng = Rng(seed);
    let hom = random_pose(&t, 800, 600, 30.0, 0.6, &mut rng);
    let look = Look {
        blur_px,
        vignette: 0.2,
        gradient: [0.2, 0.1],
        noise: [0.003, 0.01],
        ..Look::default()
    };
    let plane = render(&[(&t, hom)], 800, 600, &look, &mut rng);
    (t, hom, plane)
}

fn jitter(c: [Point; 4], rng: &mut Rng, px: f64) -> [Point; 4] {
    c.map(|p| [p[0] + rng.range(-px, px), p[1] + rng.range(-px, px)])
}

fn max_err(a: &[Point; 4], b: &[Point; 4]) -> f64 {
    (0..4)
        .map(|i| (a[i][0] - b[i][0]).hypot(a[i][1] - b[i][1]))
        .fold(0.0, f64::max)
}

#[test]
fn target_corners_off_by_5px_are_refined_on_the_targets_edges() {
    for seed in [1, 2, 3] {
        let (t, hom, plane) = shot(seed);
        let truth = rect_corners(0.0, 0.0, t.width_mm, t.height_mm).map(|p| hom.apply(p));
        let mut rng = Rng(seed + 100);
        let given = jitter(truth, &mut rng, 5.0);
        let got = locate::refine_roi(&plane, given, Some(&t), 6.0).unwrap();
        let e = max_err(&got, &truth);
        assert!(
            e < 0.5,
            "seed {seed}: max corner error {e:.3} px (given {:.2})",
            max_err(&given, &truth)
        );
    }
}

#[test]
fn strip_corners_off_by_5px_are_refined_on_the_strips_long_edges() {
    for seed in [4, 5, 6] {
        let (t, hom, plane) = shot(seed);
        let sw = &t.sweeps[0];
        let truth = sw.rect.corners().map(|p| hom.apply(p));
        let mut rng = Rng(seed + 200);
        let given = jitter(truth, &mut rng, 5.0);
        let got = locate::refine_roi(&plane, given, None, 6.0).unwrap();
        // Distance of each refined corner from the true long edges (top and bottom sides).
        for (i, j, k) in [(0, 0, 1), (1, 0, 1), (2, 2, 3), (3, 2, 3)] {
            let d = line_dist(got[i], truth[j], truth[k]);
            assert!(
                d < 0.3,
                "seed {seed}: corner {i} is {d:.3} px off its long edge"
            );
        }
    }
}

/// Distance (px) of `p` from the line through `a` and `b`.
fn line_dist(p: Point, a: Point, b: Point) -> f64 {
    let (dx, dy) = (b[0] - a[0], b[1] - a[1]);
    ((p[0] - a[0]) * dy - (p[1] - a[1]) * dx).abs() / dx.hypot(dy)
}

/// Strip corners on a soft shot (Gaussian σ 1.5 px: the edges' gradient
/// spreads wider than the last pass's ±4 px window), given exactly or ±5 px
/// off, are refined onto the long edges. The narrow pass used to find a
/// chance peak on a few places per side or none: the corners were then kept
/// as given, or (with noise, on the independent camera's defocused shots)
/// moved 1 px off by lines through those few points. A pass that loses most
/// of a side's points is not used now.
#[test]
fn strip_corners_on_a_soft_shot_are_refined_onto_the_long_edges() {
    for seed in [4, 5, 6] {
        let (t, hom, plane) = shot_blurred(seed, 1.5);
        let truth = t.sweeps[0].rect.corners().map(|p| hom.apply(p));
        let mut rng = Rng(seed + 300);
        for given in [truth, jitter(truth, &mut rng, 5.0)] {
            let got = locate::refine_roi(&plane, given, None, 6.0)
                .unwrap_or_else(|e| panic!("seed {seed}: not refined: {e}"));
            for (i, j, k) in [(0, 0, 1), (1, 0, 1), (2, 2, 3), (3, 2, 3)] {
                let d = line_dist(got[i], truth[j], truth[k]);
                assert!(
                    d < 0.3,
                    "seed {seed}: corner {i} is {d:.3} px off its long edge"
                );
            }
        }
    }
}

#[test]
fn refine_rejects_a_region_without_edges() {
    let plane = sweepmtf::photo::Plane::full(200, 200, vec![0.5; 40_000]);
    let r = locate::refine_roi(
        &plane,
        [[50.0, 50.0], [150.0, 50.0], [150.0, 150.0], [50.0, 150.0]],
        None,
        5.0,
    );
    assert!(r.is_err());
}
