use super::*;

/// ITU-T T.81's FDCT (A.3.3), summed directly over a block of
/// cos(2π(fx(x − 3.5) + fy(y − 3.5)) + φ): the coefficient (v rows, u columns).
fn t81_fdct(fx: f64, fy: f64, phi: f64, u: usize, v: usize) -> f64 {
    use std::f64::consts::{FRAC_1_SQRT_2, PI, TAU};
    let c = |k: usize| if k == 0 { FRAC_1_SQRT_2 } else { 1.0 };
    let mut s = 0.0;
    for y in 0..8 {
        for x in 0..8 {
            let value = (TAU * (fx * (x as f64 - 3.5) + fy * (y as f64 - 3.5)) + phi).cos();
            s += value
                * ((2 * x + 1) as f64 * u as f64 * PI / 16.0).cos()
                * ((2 * y + 1) as f64 * v as f64 * PI / 16.0).cos();
        }
    }
    0.25 * c(u) * c(v) * s
}

fn q75() -> [u16; 64] {
    // The IJG luma table at quality 75 (scale 50 %), natural order.
    const Q50: [u16; 64] = [
        16, 11, 10, 16, 24, 40, 51, 61, 12, 12, 14, 19, 26, 58, 60, 55, 14, 13, 16, 24, 40, 57, 69,
        56, 14, 17, 22, 29, 51, 87, 80, 62, 18, 22, 37, 56, 68, 109, 103, 77, 24, 35, 55, 64, 81,
        104, 113, 92, 49, 64, 78, 87, 103, 121, 120, 101, 72, 92, 95, 98, 112, 100, 103, 99,
    ];
    Q50.map(|q| ((q as u32 * 50 + 50) / 100).max(1) as u16)
}

/// The blocks' coefficients are the standard's FDCT of the sine, at each
/// phase, for a sine square to the blocks and one turned 20°.
#[test]
fn the_coefficients_are_the_standards_fdct() {
    for (f, angle) in [(0.4, 0.0), (0.23, 20f64.to_radians())] {
        let sine = PointSine {
            freq_cy_px: f,
            angle_rad: angle,
            codes_per_modulation: 1.0,
        };
        let b = Blocks::of(&block_coefficients(&sine), &q75(), 0.0);
        for (j, unit) in b.unit.iter().enumerate() {
            let phi = std::f64::consts::TAU * j as f64 / PHASES as f64;
            for k in 0..64 {
                let want = t81_fdct(f * angle.cos(), f * angle.sin(), phi, k % 8, k / 8);
                assert!(
                    (unit[k] - want).abs() < 1e-12,
                    "{f} {j} {k}: {} {want}",
                    unit[k]
                );
            }
        }
    }
}

/// A grey sine of 0.5–12 codes at 0.15–0.45 cy/px along the rows, written
/// by the image crate's JPEG encoder at q75 and decoded by zune-jpeg (via
/// the image crate), its amplitude read back by least squares over the
/// frame: inside the dead zone the model and the file both read (nearly)
/// nothing, and within two dead zones of it the error claimed covers the
/// file's (|z| ≤ 2.5). (Clear of it the file still reads up to ≈ 0.5 code
/// off, one dead zone at 0.15 cy/px: the blocks' ripple, which the coarse
/// JPEG's smoothing and its ripple term carry, `block_ripple`.)
#[test]
fn the_dead_zone_is_where_a_jpeg_encoder_and_decoder_lose_the_sine() {
    let (w, h) = (512usize, 64usize);
    let (mut in_zone, mut near) = (0, 0);
    for f in [0.3913, 0.2717, 0.4471, 0.1537] {
        let sine = PointSine {
            freq_cy_px: f,
            angle_rad: 0.0,
            codes_per_modulation: 1.0,
        };
        for a in (1..=24).map(|i| 0.5 * i as f64) {
            let img = image::GrayImage::from_fn(w as u32, h as u32, |x, _| {
                let v = 128.0 + a * (std::f64::consts::TAU * f * x as f64).cos();
                image::Luma([v.round() as u8])
            });
            let mut buf = Vec::new();
            image::codecs::jpeg::JpegEncoder::new_with_quality(&mut buf, 75)
                .encode_image(&img)
                .unwrap();
            let table = crate::photo::jpeg_quant::luma_table(&buf).unwrap();
            let dec = image::load_from_memory(&buf).unwrap().to_luma8().into_raw();
            assert_eq!(dec.len(), w * h);
            // Least squares on cos and sin at f over the whole frame (f·w
            // is far from a whole number of cycles, so both are fitted).
            let (mut cc, mut ss, mut cs, mut yc, mut ys) = (0.0, 0.0, 0.0, 0.0, 0.0);
            for y in 0..h {
                for x in 0..w {
                    let t = std::f64::consts::TAU * f * x as f64;
                    let (c, s) = (t.cos(), t.sin());
                    let v = dec[y * w + x] as f64 - 128.0;
                    cc += c * c;
                    ss += s * s;
                    cs += c * s;
                    yc += v * c;
                    ys += v * s;
                }
            }
            let det = cc * ss - cs * cs;
            let read = ((yc * ss - ys * cs) / det).hypot((ys * cc - yc * cs) / det);
            let z = block_coefficients(&sine);
            let (blocks, dz) = (Blocks::of(&z, &table, a), dead_zone(&z, &table));
            if a < 0.9 * dz {
                let model = blocks.read_back(a, &table);
                assert!(read < 0.1 * a && model < 0.1 * a, "{f} {a}: {read} {model}");
                in_zone += 1;
            }
            if a <= 2.0 * dz {
                let claimed = error_codes(&z, dz, &table, read, 0.05).hypot(0.05);
                let z = (read - a) / claimed;
                assert!(z.abs() <= 2.5, "{f} {a}: read {read}, claimed ± {claimed}");
                near += 1;
            }
        }
    }
    assert!(in_zone >= 6 && near >= 16, "{in_zone} {near}");
}

/// A point is flagged as the file's where the quantiser's error outweighs
/// the rest of its uncertainty or its sine is rounded away, and left
/// unflagged well clear of the dead zone or where noise outweighs the
/// quantiser. The dead zone is taken from the table directly (the largest
/// coefficient of the standard's FDCT of the sine, at its best phase,
/// reaching half its step), not from the code under test.
#[test]
fn points_the_quantiser_holds_are_flagged_as_the_files() {
    let (table, f) = (q75(), 0.3913);
    let dz = (1..64)
        .map(|k| {
            let best = (0..64)
                .map(|j| {
                    t81_fdct(
                        f,
                        0.0,
                        std::f64::consts::TAU * j as f64 / 64.0,
                        k % 8,
                        k / 8,
                    )
                })
                .fold(0.0f64, |m, c| m.max(c.abs()));
            table[k] as f64 / (2.0 * best)
        })
        .fold(f64::INFINITY, f64::min);
    assert!(dz > 0.5 && dz < 20.0, "{dz}");
    let point = |modulation: f64, mtf_err: f64| MtfPoint {
        s: 0.0,
        freq_cy_px: f,
        freq_chart: f,
        modulation,
        mtf: modulation,
        mtf_err,
        aliased: false,
        jpeg_limited: false,
    };
    // Modulation in codes here: one code per unit.
    let mut points = vec![
        point(20.0 * dz, 0.02 * dz), // far clear: untouched
        point(1.5 * dz, 0.02 * dz),  // near, quiet: the quantiser dominates
        point(1.5 * dz, 3.0 * dz),   // near, noisy: noise dominates
        point(0.0, 0.05 * dz),       // rounded away
    ];
    let before: Vec<f64> = points.iter().map(|p| p.mtf_err).collect();
    let sine_at = |p: &MtfPoint| {
        Some(PointSine {
            freq_cy_px: p.freq_cy_px,
            angle_rad: 0.0,
            codes_per_modulation: 1.0,
        })
    };
    let lost = widen(&mut points, &table, sine_at);
    let flags: Vec<bool> = points.iter().map(|p| p.jpeg_limited).collect();
    assert_eq!(flags, [false, true, false, true], "dz {dz}: {points:?}");
    assert_eq!(points[0].mtf_err, before[0]);
    assert!(points[1].mtf_err > 2.0 * before[1], "{points:?}");
    assert_eq!(lost, Some(f));
}
