//! Tests of the binned profile: against sample-by-sample definitions, with and
//! without a lens, in either walk and build.

use super::*;
use crate::distortion::Lens;
use crate::geometry::Homography;

/// A deterministic uniform generator on [0, 1) from `seed`.
fn uniform(mut st: u64) -> impl FnMut() -> f64 {
    move || {
        st = st
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        (st >> 11) as f64 / (1u64 << 53) as f64
    }
}

fn strip_for(quad: [Point; 4], len: f64, wid: f64) -> Strip {
    let src = crate::geometry::rect_corners(0.0, 0.0, len, wid);
    Strip {
        lens: None,
        to_image: Homography::from_quads(&src, &quad).unwrap(),
        length: len,
        width: wid,
    }
}

/// Every bin of `p` as the plain definition `want` gives it: mean s and
/// value to 1e-9, counts exactly and, with `parity`, the pixel-parity
/// patterns exactly (`what` names the case in a failure).
fn assert_bins(p: &Profile, want: &[(f64, f64, f64, [f64; 3])], parity: bool, what: &str) {
    assert_eq!(p.s.len(), want.len(), "{what}");
    for (k, w) in want.iter().enumerate() {
        assert!((p.s[k] - w.0).abs() < 1e-9, "{what}, bin {k}");
        assert!(
            (p.y[k] - w.1).abs() < 1e-9,
            "{what}, bin {k}: {} vs {}",
            p.y[k],
            w.1
        );
        assert_eq!(p.count[k], w.2, "{what}, bin {k}");
        if parity {
            assert_eq!(p.parity[k], w.3, "{what}, bin {k}");
        }
    }
}

/// The random-geometry tests' photo: a smooth pattern over `w` × `h` px.
fn wavy_plane(w: usize, h: usize) -> Plane {
    let data: Vec<f32> = (0..w * h)
        .map(|k| (0.5 + 0.4 * ((k % w) as f64 * 0.37 + (k / w) as f64 * 0.11).sin()) as f32)
        .collect();
    Plane::full(w, h, data)
}

/// A random strip's corners in a `w` × `h` frame, and its length and width
/// (up to 1 + `max_wid` px): centred anywhere, 2–182 px long, turned any
/// way, one end up to 2× the other's height (six draws of `rnd`).
fn random_quad(
    rnd: &mut impl FnMut() -> f64,
    (w, h): (usize, usize),
    max_wid: f64,
) -> ([Point; 4], f64, f64) {
    let (cx, cy) = (w as f64 * rnd(), h as f64 * rnd());
    let (len, wid) = (2.0 + 180.0 * rnd(), 1.0 + max_wid * rnd());
    let a = std::f64::consts::TAU * rnd();
    let key = 0.5 + rnd();
    let (c, sn) = (a.cos(), a.sin());
    let quad = [
        [-0.5, -0.5],
        [0.5, -0.5 / key],
        [0.5, 0.5 / key],
        [-0.5, 0.5],
    ]
    .map(|[x, y]| {
        let (x, y) = (x * len, y * wid);
        [cx + c * x - sn * y, cy + sn * x + c * y]
    });
    (quad, len, wid)
}

#[test]
fn bins_a_linear_ramp_exactly_under_rotation() {
    // Image value = 0.001·s for a strip rotated by 30°: every bin mean must
    // equal 0.001 × the bin's mean s (brute force: linear data, no blur).
    let (w, h) = (300, 200);
    let a = 30f64.to_radians();
    let (c, sn) = (a.cos(), a.sin());
    let o = [40.0, 30.0];
    let len = 200.0;
    let wid = 40.0;
    let quad = [
        o,
        [o[0] + len * c, o[1] + len * sn],
        [o[0] + len * c - wid * sn, o[1] + len * sn + wid * c],
        [o[0] - wid * sn, o[1] + wid * c],
    ];
    let strip = strip_for(quad, len, wid);
    let mut data = vec![0f32; w * h];
    for j in 0..h {
        for i in 0..w {
            let (x, y) = (i as f64 + 0.5 - o[0], j as f64 + 0.5 - o[1]);
            data[j * w + i] = (0.001 * (x * c + y * sn)) as f32;
        }
    }
    let plane = Plane::full(w, h, data);
    let p = bin_plane(&plane, &strip, &BinOptions::default());
    assert!(p.s.len() > 600, "{}", p.s.len());
    for k in 0..p.s.len() {
        assert!((p.y[k] - 0.001 * p.s[k]).abs() < 1e-6, "{k}");
        assert!(p.var_s[k].sqrt() <= p.bin);
    }
    // Samples inside: 70% of the strip area (margins 15% + 15%) minus the end pixels.
    let area = len * wid * 0.7;
    assert!(
        (p.samples as f64 - area).abs() < 0.03 * area,
        "{}",
        p.samples
    );
    let sc = strip.scale_at(100.0);
    assert!((sc.s_per_px - 1.0).abs() < 1e-9);
    assert!((sc.angle_rad - a).abs() < 1e-9);
}

/// The first pass's bins as bits: sums, count and extremes.
fn acc_bits(acc: &[BinAcc]) -> Vec<u64> {
    acc.iter()
        .flat_map(|a| {
            [a.sum, a.sum2, a.ssum, a.ssum2]
                .map(f64::to_bits)
                .into_iter()
                .chain([a.n as u64])
                .chain(a.hi.iter().chain(&a.lo).map(|v| v.to_bits() as u64))
        })
        .collect()
}

#[test]
fn the_first_pass_equals_sample_by_sample_binning_in_either_walk_and_build() {
    // A turned, keystoned strip of 8-bit codes with noise, walked down the
    // columns and along the rows, in the baseline and (where the CPU has
    // it) the AVX2 build, against the plain per-sample reference: the
    // same counts and extremes; the sums in another order, so equal to
    // rounding.
    let (w, h) = (400, 300);
    let mut rnd = uniform(4242u64);
    let codes: Vec<u8> = (0..w * h)
        .map(|k| {
            let x = (k % w) as f64;
            (128.0 + 100.0 * (0.002 * x * x).sin() + 20.0 * (rnd() - 0.5)) as u8
        })
        .collect();
    let lut: Vec<f32> = (0..256).map(|c| (c as f32 / 255.0).powf(2.2)).collect();
    let mix = [(0usize, 1.0f32)];
    let plane = PlaneRef {
        width: w,
        height: h,
        step: (1, 1),
        offset: (0, 0),
        data: crate::photo::plane_ref::PlaneData::Codes8(crate::photo::plane_ref::Codes {
            codes: &codes,
            channels: 1,
            mix: &mix,
            lut: &lut,
        }),
    };
    let strip = strip_for(
        [[20.0, 40.0], [380.0, 60.0], [372.0, 260.0], [25.0, 230.0]],
        350.0,
        200.0,
    );
    let planes = [plane];
    let inv = positive_inverse(&strip, strip.to_image.inverse().unwrap().m);
    let quad = strip.image_quad(30.0, 170.0);
    assert!(sweeps_across_columns(&inv, &quad));
    let region = Region {
        planes: &planes,
        m: inv,
        ymin: quad.iter().map(|p| p[1]).fold(f64::INFINITY, f64::min),
        ymax: quad.iter().map(|p| p[1]).fold(f64::NEG_INFINITY, f64::max),
        t0: 30.0,
        t1: 170.0,
        s_lo: 1.0,
        s_hi: 349.0,
        bin: 0.25,
        nbins: 1400,
        by_columns: true,
        row_step: 1,
        col_step: 1,
    };
    // Every sample centre of the image (in rows at multiples of `rs`, at
    // multiples of `cs` along them), row by row, through the
    // region's own inside test (`Region::inside`'s arithmetic) and position
    // (`visit_band_lines`' arithmetic).
    let reference = |rs: usize, cs: usize| {
        let mut reference = vec![BinAcc::default(); 1400];
        let mut ref_count = [0usize; 3];
        let m = &region.m;
        for j in (0..h).step_by(rs) {
            let y = j as f64 + 0.5;
            if y < region.ymin || y > region.ymax {
                continue;
            }
            for i in (0..w).step_by(cs) {
                let x = i as f64 + 0.5;
                let rw = 1.0 / (m[6] * x + m[7] * y + m[8]);
                let (si, ti) = (
                    (m[0] * x + m[1] * y + m[2]) * rw,
                    (m[3] * x + m[4] * y + m[5]) * rw,
                );
                if !(ti >= region.t0 && ti <= region.t1 && si >= region.s_lo && si <= region.s_hi) {
                    continue;
                }
                let s = (m[0] * x + (m[1] * y + m[2])) / (m[6] * x + (m[7] * y + m[8]));
                let v = lut[codes[j * w + i] as usize];
                ref_count[0] += 1;
                ref_count[1] += (v >= 0.999) as usize;
                ref_count[2] += (v <= 0.0) as usize;
                let r = &mut reference[((s * 4.0) as usize).min(1399)];
                r.add(s, v);
                r.add_parity(i, j);
            }
        }
        (reference, ref_count)
    };
    let run = |by_columns: bool, steps: (usize, usize), avx2: bool| {
        let piece = Region {
            by_columns,
            row_step: steps.0,
            col_step: steps.1,
            ..region
        };
        let mut acc = vec![BinAcc::default(); 1400];
        let count = if avx2 {
            #[cfg(target_arch = "x86_64")]
            {
                // SAFETY: only called where the CPU has AVX2.
                unsafe { first_pass_avx2(&piece, 0, &mut acc, 0.999) }
            }
            #[cfg(not(target_arch = "x86_64"))]
            unreachable!()
        } else {
            first_pass_body::<false>(&piece, 0, &mut acc, 0.999)
        };
        (count, acc)
    };
    // Every sample, every third row, every fifth column (the steps a strip
    // taller across than `BinOptions::max_across` is binned with).
    for steps in [(1, 1), (3, 1), (1, 5), (3, 5)] {
        let (reference, ref_count) = reference(steps.0, steps.1);
        assert!(ref_count[0] > 30_000 / (steps.0 * steps.1), "{ref_count:?}");
        for by_columns in [true, false] {
            let (count, acc) = run(by_columns, steps, false);
            assert_eq!(count, ref_count, "steps {steps:?}");
            for (a, r) in acc.iter().zip(&reference) {
                assert_eq!((a.n, a.hi, a.lo), (r.n, r.hi, r.lo));
                // The pixel-parity sums, a run at a time, exactly.
                assert_eq!(
                    a.parity, r.parity,
                    "by columns {by_columns}, steps {steps:?}"
                );
                for (x, y) in [
                    (a.sum, r.sum),
                    (a.sum2, r.sum2),
                    (a.ssum, r.ssum),
                    (a.ssum2, r.ssum2),
                ] {
                    assert!((x - y).abs() <= 1e-12 * y.abs(), "{x} {y}");
                }
            }
            #[cfg(target_arch = "x86_64")]
            if std::arch::is_x86_feature_detected!("avx2") {
                let (count2, acc2) = run(by_columns, steps, true);
                assert_eq!(count2, count);
                assert!(acc_bits(&acc2) == acc_bits(&acc));
            }
        }
    }
}

#[test]
fn a_strip_taller_across_than_max_across_is_binned_from_every_kth_line_across_it() {
    // A keystoned strip sweeping along the rows and one sweeping down the
    // columns, each ≈ 84 px across inside its margins: with at most 30
    // lines across, every third row (along the rows) or every third
    // column (down the columns), as the plain definition over those
    // samples gives every bin; with no limit, every sample.
    let (w, h) = (260, 260);
    let mut rnd = uniform(31u64);
    let data: Vec<f32> = (0..w * h)
        .map(|k| {
            let (x, y) = ((k % w) as f64, (k / w) as f64);
            (0.5 + 0.3 * (0.002 * x * x + 0.0015 * y * y).sin() + 0.02 * (rnd() - 0.5)) as f32
        })
        .collect();
    let plane = Plane::full(w, h, data);
    let along_rows = [[10.0, 60.0], [250.0, 70.0], [248.0, 190.0], [12.0, 180.0]];
    let down_columns = along_rows.map(|p| [p[1], p[0]]);
    for (quad, steps) in [(along_rows, (3, 1)), (down_columns, (1, 3))] {
        let strip = strip_for(quad, 240.0, 120.0);
        for (max_across, steps) in [(0, (1, 1)), (30, steps)] {
            let o = BinOptions {
                max_across,
                ..BinOptions::default()
            };
            let p = bin_plane(&plane, &strip, &o);
            let want = brute_every(&plane, &strip, &o, steps);
            assert!(p.samples > 8_000 / (steps.0 * steps.1), "{}", p.samples);
            assert_bins(&p, &want, true, &format!("steps {steps:?}"));
        }
    }
}

#[test]
fn stepped_binning_holds_on_random_geometry() {
    // Strips turned any way, keystoned, partly outside the frame, tiny or
    // long, binned with at most 2, 5 or 17 lines across: no panic, and every
    // bin as the plain definition over the stepped lattice gives it (the
    // step as `across_step` chooses it; the samples are the check).
    let mut rnd = uniform(4041u64);
    let plane = wavy_plane(160, 120);
    let mut stepped = 0;
    for case in 0..300 {
        let (quad, len, wid) = random_quad(&mut rnd, (160, 120), 80.0);
        let Ok(to_image) =
            Homography::from_quads(&crate::geometry::rect_corners(0.0, 0.0, len, wid), &quad)
        else {
            continue;
        };
        let strip = Strip {
            lens: None,
            to_image,
            length: len,
            width: wid,
        };
        let o = BinOptions {
            max_across: [2, 5, 17][case % 3],
            ..BinOptions::default()
        };
        let p = bin_plane(&plane, &strip, &o);
        let Some(inv) = strip.to_image.inverse() else {
            continue;
        };
        let m = positive_inverse(&strip, inv.m);
        let (t0, t1) = (o.margin * wid, (1.0 - o.margin) * wid);
        let by_columns = sweeps_across_columns(&m, &strip.image_quad(t0, t1));
        let planes = [PlaneRef::from(&plane)];
        let steps = line_steps(&strip, t1 - t0, &planes, by_columns, o.max_across);
        let k = steps.0.max(steps.1);
        assert!(
            k % 2 == 1 && steps.0.min(steps.1) == 1,
            "case {case}: steps {steps:?}"
        );
        stepped += (k > 1) as usize;
        let want = brute_every(&plane, &strip, &o, steps);
        assert_bins(&p, &want, false, &format!("case {case}, steps {steps:?}"));
    }
    assert!(stepped >= 100, "{stepped}");
}

#[test]
fn sparse_plane_uses_its_own_sites() {
    // A Bayer-like plane with step 2 and offset (1, 0): site x = 2i + 1.5.
    let plane = Plane {
        width: 50,
        height: 20,
        step: (2, 2),
        offset: (1, 0),
        data: (0..1000).map(|k| (2 * (k % 50) + 1) as f32 + 0.5).collect(),
    };
    let strip = strip_for(
        crate::geometry::rect_corners(0.0, 0.0, 100.0, 40.0),
        100.0,
        40.0,
    );
    let p = bin_plane(&plane, &strip, &BinOptions::default());
    for k in 0..p.s.len() {
        assert!((p.y[k] - p.s[k]).abs() < 1e-9);
    }
}

/// The plain definition: every sample centre through the lens's exact
/// undistortion (if any) and the inverse homography, two passes, 3σ clip
/// about each bin's plain mean.
/// Every bin by definition, sample by sample: (mean s, robust mean,
/// count, mean pixel-parity patterns).
fn brute(plane: &Plane, strip: &Strip, o: &BinOptions) -> Vec<(f64, f64, f64, [f64; 3])> {
    brute_every(plane, strip, o, (1, 1))
}

/// [`brute`] over the samples in rows at multiples of `rs` and at
/// multiples of `cs` along them.
fn brute_every(
    plane: &Plane,
    strip: &Strip,
    o: &BinOptions,
    (rs, cs): (usize, usize),
) -> Vec<(f64, f64, f64, [f64; 3])> {
    let inv = strip.to_image.inverse().unwrap();
    let m = o.margin;
    let scale = [0.0, 0.5, 1.0]
        .iter()
        .map(|f| 1.0 / strip.scale_at(f * strip.length).s_per_px)
        .fold(0.0, f64::max);
    let (bin, end) = (o.bin_px / scale, o.end_px / scale);
    let nb = (strip.length / bin).ceil() as usize;
    let mut by_bin: Vec<Vec<(f64, f64, [f64; 3])>> = vec![Vec::new(); nb];
    for j in (0..plane.height).step_by(rs) {
        for i in (0..plane.width).step_by(cs) {
            let x = (plane.offset.0 + i * plane.step.0) as f64 + 0.5;
            let y = (plane.offset.1 + j * plane.step.1) as f64 + 0.5;
            let [x, y] = match &strip.lens {
                Some(l) => l.undistort([x, y]),
                None => [x, y],
            };
            let [s, t] = inv.apply([x, y]);
            if t >= m * strip.width
                && t <= (1.0 - m) * strip.width
                && s >= end
                && s <= strip.length - end
            {
                let b = ((s / bin) as usize).min(nb - 1);
                let (px, py) = (
                    parity_sign(plane.offset.0 + i * plane.step.0) as f64,
                    parity_sign(plane.offset.1 + j * plane.step.1) as f64,
                );
                by_bin[b].push((s, plane.data[j * plane.width + i] as f64, [px, py, px * py]));
            }
        }
    }
    by_bin
        .iter()
        .filter(|v| !v.is_empty())
        .map(|v| {
            let n = v.len() as f64;
            let ms = v.iter().map(|p| p.0).sum::<f64>() / n;
            let mu = v.iter().map(|p| p.1).sum::<f64>() / n;
            let var = v.iter().map(|p| (p.1 - mu).powi(2)).sum::<f64>() / n;
            let lim = 3.0 * var.sqrt() + 1e-6;
            let kept: Vec<f64> = v
                .iter()
                .map(|p| p.1)
                .filter(|y| v.len() < 4 || (y - mu).abs() <= lim)
                .collect();
            let par = |q: usize| v.iter().map(|p| p.2[q]).sum::<f64>() / n;
            (
                ms,
                kept.iter().sum::<f64>() / kept.len() as f64,
                kept.len() as f64,
                [par(0), par(1), par(2)],
            )
        })
        .collect()
}

#[test]
fn bins_through_a_lens_equal_the_plain_definition() {
    // A strip near a frame edge through strong barrel and pincushion
    // (its edges bow by pixels), noise with dust: every bin as the brute
    // force through the exact undistortion gives it.
    let (w, h) = (400, 300);
    for b in [-0.06, 0.05] {
        let lens = Lens::new(
            crate::distortion::Ptlens {
                a: 0.01,
                b,
                c: -0.01,
            },
            w,
            h,
        );
        lens.check().unwrap();
        let quad = [[15.0, 200.0], [385.0, 205.0], [380.0, 290.0], [20.0, 285.0]];
        let mut strip = strip_for(quad, 370.0, 85.0);
        strip.lens = Some(lens);
        let mut rnd = uniform(777u64);
        let data = (0..w * h)
            .map(|k| {
                let (x, y) = ((k % w) as f64, (k / w) as f64);
                let dust = (x - 200.0).hypot(y - 250.0) < 6.0;
                if dust {
                    0.01
                } else {
                    (0.5 + 0.3 * (0.004 * x * x).sin() + 0.03 * (rnd() - 0.5)) as f32
                }
            })
            .collect();
        let plane = Plane::full(w, h, data);
        // Every sample; then (at most 25 rows across the strip's 60 inside
        // its margins) every third row, as a taller strip is binned.
        for (bin_px, max_across, steps) in [(0.25, 0, (1, 1)), (2.0, 0, (1, 1)), (0.25, 25, (3, 1))]
        {
            let o = BinOptions {
                bin_px,
                max_across,
                ..BinOptions::default()
            };
            let p = bin_plane(&plane, &strip, &o);
            let want = brute_every(&plane, &strip, &o, steps);
            assert_bins(&p, &want, true, &format!("b {b} bin {bin_px}"));
        }
    }
}

#[test]
fn lens_binning_holds_on_random_geometry() {
    // Random lenses (a, b, c mixed, up to ±12 % at the corner), strips
    // turned any way, keystoned, partly outside the frame, tiny or long:
    // no panic, and every bin as the brute force gives it.
    let (w, h) = (160, 120);
    let mut rnd = uniform(99u64);
    let plane = wavy_plane(w, h);
    let (mut checked, mut lens_stepped) = (0, 0);
    for case in 0..400 {
        let b = 0.12 * (2.0 * rnd() - 1.0) / 2.25;
        let model = crate::distortion::Ptlens {
            a: 0.3 * b * (2.0 * rnd() - 1.0),
            b,
            c: 0.2 * b * (2.0 * rnd() - 1.0),
        };
        let lens = Lens::new(model, w, h);
        if lens.check().is_err() {
            continue;
        }
        let (quad, len, wid) = random_quad(&mut rnd, (w, h), 60.0);
        // As a measurement makes it: corners clicked inside the photo,
        // undistorted, the strip's edges then bowing between them.
        if quad
            .iter()
            .any(|p| !(0.0..=w as f64).contains(&p[0]) || !(0.0..=h as f64).contains(&p[1]))
        {
            continue;
        }
        let Ok(h_) = Homography::from_quads(
            &crate::geometry::rect_corners(0.0, 0.0, len, wid),
            &quad.map(|p| lens.undistort(p)),
        ) else {
            continue;
        };
        let strip = Strip {
            lens: Some(lens),
            to_image: h_,
            length: len,
            width: wid,
        };
        // Every line, then (every other case) at most 3 or 9 lines across.
        let o = BinOptions {
            bin_px: [0.25, 1.0, 2.0][case % 3],
            max_across: [0, 0, 3, 0, 9, 0][case % 6],
            ..BinOptions::default()
        };
        let p = bin_plane(&plane, &strip, &o);
        // The steps as `bin_planes` chooses them for a lens (the samples are the check).
        let (bin, _) = bin_and_end(&strip, &o);
        let planes = [PlaneRef::from(&plane)];
        let steps = line_steps(
            &strip,
            (1.0 - 2.0 * o.margin) * wid,
            &planes,
            lens_along_rows(&strip, bin),
            o.max_across,
        );
        lens_stepped += (steps != (1, 1)) as usize;
        let want = brute_every(&plane, &strip, &o, steps);
        assert_bins(&p, &want, false, &format!("case {case}"));
        checked += 1;
    }
    assert!(
        checked >= 40 && lens_stepped >= 10,
        "{checked} {lens_stepped}"
    );
}

#[test]
fn robust_bins_equal_the_plain_two_pass_definition() {
    // Perspective, a sparse (Bayer-like) lattice, noise with heavy tails and
    // dust specks that put many outliers into single bins; the strip swept
    // across the image (binned down the columns) and, transposed, down it
    // (binned along the rows).
    for down in [false, true] {
        robust_bins_case(down);
    }
}

fn robust_bins_case(down: bool) {
    let (w, h) = (180, 180);
    let mut quad = [[20.0, 30.0], [330.0, 12.0], [345.0, 250.0], [12.0, 200.0]];
    if down {
        quad.iter_mut().for_each(|p| p.swap(0, 1));
    }
    let strip = strip_for(quad, 300.0, 60.0);
    let inv = positive_inverse(&strip, strip.to_image.inverse().unwrap().m);
    assert_eq!(sweeps_across_columns(&inv, &quad), !down);
    let mut rnd = uniform(12345u64);
    let mut data = vec![0f32; w * h];
    for j in 0..h {
        for i in 0..w {
            let (x, y) = ((2 * i + 1) as f64 + 0.5, (2 * j) as f64 + 0.5);
            let mut v = 0.5 + 0.3 * (0.05 * x + 0.01 * y).sin() + 0.02 * (rnd() - 0.5);
            if rnd() < 0.01 {
                v += 0.4 * (rnd() - 0.3); // heavy tail
            }
            if (x - 150.0).hypot(y - 120.0) < 9.0 || (x - 260.0).hypot(y - 60.0) < 4.0 {
                v = 0.02; // dust
            }
            data[j * w + i] = v as f32;
        }
    }
    let plane = Plane {
        width: w,
        height: h,
        step: (2, 2),
        offset: (1, 0),
        data,
    };
    for bin_px in [0.25, 1.0, 3.0] {
        let o = BinOptions {
            bin_px,
            ..BinOptions::default()
        };
        let p = bin_plane(&plane, &strip, &o);
        let want = brute(&plane, &strip, &o);
        assert_bins(&p, &want, false, &format!("bin {bin_px}"));
    }
}
