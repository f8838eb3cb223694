//! The issue-7 bar on the project's real camera simulator: random shots of a
//! target (any rotation, tilt up to 45°, the chart's bounding box covering
//! 10–95 % of the frame's area, radial fall-off, a linear light gradient,
//! photon + read noise at SNR ≈ 50, mild wave-optics defocus, 8-bit sRGB JPEG
//! q90) are located with no corners given and measured; each sweep's MTF is
//! compared with the simulator's own truth curve (RMS |MTF − truth| over
//! 0.01–0.45 cy/px, non-aliased points) and the located target corners with
//! the simulator's exact ones. Shared by `examples/locate_sweep.rs` (200
//! shots, release) and `tests/locate_mtf.rs` (a few shots).
//!
//! Included with `#[path]`, so it is self-contained (own RNG).
#![allow(dead_code)]

use std::time::Instant;
use sweepmtf::geometry::rect_corners;
use sweepmtf::measure::{MeasureOptions, measure_decoded};
use sweepmtf::model::{System, spec::parse_factor};
use sweepmtf::photo::decode::decode_bytes;
use sweepmtf::simulate::{self, Camera, PhotoFormat, placement};
use sweepmtf::target::Target;

/// SplitMix64.
pub struct Rng(pub u64);

impl Rng {
    /// Next 64 random bits.
    pub fn next_u64(&mut self) -> u64 {
        self.0 = self.0.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        z ^ (z >> 31)
    }
    /// Uniform in [a, b).
    pub fn range(&mut self, a: f64, b: f64) -> f64 {
        a + (b - a) * ((self.next_u64() >> 11) as f64 / (1u64 << 53) as f64)
    }
}

/// One shot's random settings.
#[derive(Debug, Clone)]
pub struct Pose {
    /// Frame width and height, px.
    pub size: (usize, usize),
    /// Rotation on screen, degrees counter-clockwise.
    pub rotate_deg: f64,
    /// Perspective tilt, degrees.
    pub tilt_deg: f64,
    /// Direction of the tilt axis in the chart plane, degrees.
    pub tilt_axis_deg: f64,
    /// Fraction of the frame's area covered by the chart's bounding box.
    pub cover: f64,
    /// Offset of the chart centre, as a fraction (−1…1) of the room left in x and y.
    pub shift: [f64; 2],
    /// Radial fall-off (light lost at the frame corners).
    pub falloff: f64,
    /// Linear light gradient: relative gain change across the frame in x and y.
    pub gradient: [f64; 2],
    /// Paper white at the frame centre, fraction of clipping.
    pub exposure: f64,
    /// Full-well capacity, electrons (photon noise); read noise is 4 e⁻.
    pub full_well_e: f64,
    /// Defocus wavefront W020, waves (f/4, 550 nm, with diffraction).
    pub w020: f64,
    /// Noise seed.
    pub seed: u64,
}

impl Pose {
    /// A random pose within the ranges; `(w_lo, w_hi)` bounds the frame width
    /// (height = 0.6875 × width).
    pub fn random(rng: &mut Rng, width: (usize, usize), seed: u64) -> Pose {
        let w = rng.range(width.0 as f64, width.1 as f64 + 1.0) as usize;
        Pose {
            size: (w, (w as f64 * 0.6875).round() as usize),
            rotate_deg: rng.range(0.0, 360.0),
            tilt_deg: rng.range(0.0, 45.0),
            tilt_axis_deg: rng.range(0.0, 180.0),
            cover: rng.range(0.10, 0.95),
            shift: [rng.range(-1.0, 1.0), rng.range(-1.0, 1.0)],
            falloff: rng.range(0.0, 0.5),
            gradient: [rng.range(-0.3, 0.3), rng.range(-0.3, 0.3)],
            exposure: rng.range(0.6, 0.8),
            full_well_e: rng.range(6000.0, 12000.0),
            w020: rng.range(0.0, 0.5),
            seed,
        }
    }

    /// Signal-to-noise ratio of mid grey (reflectance 0.5) at the frame centre.
    pub fn snr(&self) -> f64 {
        let e = 0.5 * self.exposure * self.full_well_e;
        e / (e + 16.0).sqrt()
    }
}

/// The simulated camera for a pose: the chart scaled so that its bounding box covers
/// `pose.cover` of the frame's area, shifted within the room left.
pub fn camera(target: &Target, pose: &Pose) -> Result<Camera, String> {
    let (w, h) = (pose.size.0 as f64, pose.size.1 as f64);
    let base = Camera {
        width_px: pose.size.0,
        height_px: pose.size.1,
        rotate_deg: pose.rotate_deg,
        tilt_deg: pose.tilt_deg,
        tilt_axis_deg: pose.tilt_axis_deg,
        focal_px: Some(w.hypot(h)),
        falloff: pose.falloff,
        exposure: pose.exposure,
        full_well_e: Some(pose.full_well_e),
        read_noise_e: 4.0,
        seed: pose.seed,
        jpeg_quality: Some(90),
        ..Camera::default()
    };
    // Bounding box of the placed chart for a chart width of `px` pixels (frame made
    // large so that it always fits; the perspective depends on the focal length only).
    let bbox = |px: f64| -> Result<[f64; 4], String> {
        let big = Camera {
            width_px: 40_000,
            height_px: 40_000,
            chart_px: Some(px),
            ..base.clone()
        };
        let p = placement::place(&big, target).map_err(|e| e.to_string())?;
        let c = rect_corners(0.0, 0.0, target.width_mm, target.height_mm)
            .map(|q| p.chart_to_image.apply(q));
        let (mut lo, mut hi) = ([f64::INFINITY; 2], [f64::NEG_INFINITY; 2]);
        for q in c {
            for a in 0..2 {
                lo[a] = lo[a].min(q[a] - 20_000.0);
                hi[a] = hi[a].max(q[a] - 20_000.0);
            }
        }
        Ok([lo[0], lo[1], hi[0], hi[1]])
    };
    // Area cover → linear fill of the tighter direction (at least 2 px to spare).
    let fill = pose.cover.sqrt();
    let mut px = 0.5 * w;
    for _ in 0..6 {
        let b = bbox(px)?;
        let q = ((b[2] - b[0]) / (fill * w)).max((b[3] - b[1]) / (fill * h));
        px /= q;
    }
    let b = bbox(px)?;
    let room = [
        (w - (b[2] - b[0])) / 2.0 - 4.0,
        (h - (b[3] - b[1])) / 2.0 - 4.0,
    ];
    let centre = [(b[0] + b[2]) / 2.0, (b[1] + b[3]) / 2.0];
    Ok(Camera {
        chart_px: Some(px),
        offset_px: [
            pose.shift[0] * room[0].max(0.0) - centre[0],
            pose.shift[1] * room[1].max(0.0) - centre[1],
        ],
        ..base
    })
}

/// The optics: wave-optics defocus at f/4, 550 nm (includes diffraction), a 100 %
/// fill-factor 4.3 µm pixel aperture (the simulator's default pitch).
pub fn system(pose: &Pose) -> System {
    System {
        factors: vec![
            parse_factor(
                "defocus",
                &format!("wave:lambda=550nm,fnum=4,w020={}", pose.w020),
            )
            .unwrap(),
            parse_factor("aperture", "rect:A=4.3um,B=4.3um").unwrap(),
        ],
    }
}

/// A rendered shot: the simulator's output with the light gradient applied, and its JPEG.
pub fn shoot(target: &Target, pose: &Pose) -> Result<(simulate::Shot, Vec<u8>), String> {
    let cam = camera(target, pose)?;
    let mut shot = simulate::render(target, &system(pose), &cam).map_err(|e| e.to_string())?;
    // A linear light gradient across the frame (a gain on the recorded light: it
    // scales signal and noise together), clipped like the sensor.
    let (w, h) = (shot.width, shot.height);
    for (i, v) in shot.linear.iter_mut().enumerate() {
        let (x, y) = ((i % w) as f64 + 0.5, (i / w) as f64 + 0.5);
        let g =
            1.0 + pose.gradient[0] * (x / w as f64 - 0.5) + pose.gradient[1] * (y / h as f64 - 0.5);
        *v = (*v as f64 * g).clamp(0.0, 1.0) as f32;
    }
    let jpeg = shot.encode(PhotoFormat::Jpeg).map_err(|e| e.to_string())?;
    Ok((shot, jpeg))
}

/// Printed contrast → the `measure` accuracy bar (issue 5): 0.015 for noise + JPEG q90,
/// 0.04 for a chart modulation of 0.2.
pub fn bar(chart_contrast: f64) -> f64 {
    if chart_contrast < 0.3 { 0.04 } else { 0.015 }
}

/// One sweep's accuracy.
#[derive(Debug, Clone)]
pub struct SweepScore {
    /// Sweep id.
    pub id: String,
    /// Printed contrast.
    pub contrast: f64,
    /// RMS |MTF − truth| over 0.01–0.45 cy/px (non-aliased points); NaN if none.
    pub rms: f64,
    /// Largest |MTF − truth| there, and its frequency (cy/px).
    pub worst: (f64, f64),
    /// Points scored.
    pub n: usize,
    /// Highest non-aliased measured frequency, cy/px.
    pub f_top: f64,
}

/// The outcome of one shot.
#[derive(Debug, Clone)]
pub struct Outcome {
    /// The settings.
    pub pose: Pose,
    /// Chart width in the image before tilt, px.
    pub chart_px: f64,
    /// Error message when location or measurement failed.
    pub error: Option<String>,
    /// Distance of each located target corner from the truth, px.
    pub corner_err_px: Vec<f64>,
    /// Per-sweep accuracy.
    pub sweeps: Vec<SweepScore>,
    /// Time to render and encode, ms.
    pub sim_ms: f64,
    /// Time to decode, locate and measure, ms.
    pub measure_ms: f64,
}

/// Linear interpolation of `rows` (frequency, MTF; rising frequency) at `f`.
pub fn truth_at(rows: &[(f64, f64)], f: f64) -> f64 {
    let i = rows.partition_point(|p| p.0 < f).clamp(1, rows.len() - 1);
    let (a, b) = (rows[i - 1], rows[i]);
    a.1 + (b.1 - a.1) * (f - a.0) / (b.0 - a.0)
}

/// Renders, locates (no corners) and measures one shot; scores it against the truth.
pub fn run(target: &Target, pose: &Pose) -> Outcome {
    run_with(target, pose, |_| MeasureOptions::default())
}

/// Like [`run`], with the measurement options made from the shot (e.g. its exact
/// target corners as `roi`, to tell location's errors from measurement's).
pub fn run_with(
    target: &Target,
    pose: &Pose,
    options: impl Fn(&simulate::Shot) -> MeasureOptions,
) -> Outcome {
    let mut out = Outcome {
        pose: pose.clone(),
        chart_px: f64::NAN,
        error: None,
        corner_err_px: vec![],
        sweeps: vec![],
        sim_ms: 0.0,
        measure_ms: 0.0,
    };
    let t0 = Instant::now();
    let (shot, jpeg) = match shoot(target, pose) {
        Ok(s) => s,
        Err(e) => {
            out.error = Some(format!("simulate: {e}"));
            return out;
        }
    };
    out.chart_px = shot.camera.chart_px.unwrap_or(f64::NAN);
    out.sim_ms = t0.elapsed().as_secs_f64() * 1e3;
    let t1 = Instant::now();
    let measured = decode_bytes(&jpeg, "shot.jpg")
        .map_err(|e| e.to_string())
        .and_then(|dec| {
            measure_decoded(&dec, "shot.jpg", Some(target), &options(&shot))
                .map_err(|e| e.to_string())
        });
    out.measure_ms = t1.elapsed().as_secs_f64() * 1e3;
    let m = match measured {
        Ok(m) => m,
        Err(e) => {
            out.error = Some(e);
            return out;
        }
    };
    out.corner_err_px = (0..4)
        .map(|k| {
            let (x, y) = (shot.target_corners[2 * k], shot.target_corners[2 * k + 1]);
            (m.roi[k][0] - x).hypot(m.roi[k][1] - y)
        })
        .collect();
    for truth in &shot.sweeps {
        let rows: Vec<(f64, f64)> = truth.rows.iter().map(|r| (r.freq_cy_px, r.mtf)).collect();
        let mut score = SweepScore {
            id: truth.id.clone(),
            contrast: truth.chart_contrast,
            rms: f64::NAN,
            worst: (0.0, f64::NAN),
            n: 0,
            f_top: 0.0,
        };
        if let Some(c) = m.curves.iter().find(|c| c.sweep_id == truth.id) {
            let mut se = 0.0;
            for p in c.points.iter().filter(|p| !p.aliased) {
                score.f_top = score.f_top.max(p.freq_cy_px);
                if (0.01..=0.45).contains(&p.freq_cy_px) {
                    let e = p.mtf - truth_at(&rows, p.freq_cy_px);
                    se += e * e;
                    score.n += 1;
                    if e.abs() > score.worst.0 {
                        score.worst = (e.abs(), p.freq_cy_px);
                    }
                }
            }
            if score.n > 0 {
                score.rms = (se / score.n as f64).sqrt();
            }
        }
        out.sweeps.push(score);
    }
    out
}

/// The shot's exact target corners as measurement options (no location).
pub fn exact_corners(shot: &simulate::Shot) -> MeasureOptions {
    let c = shot.target_corners;
    MeasureOptions {
        roi: Some([[c[0], c[1]], [c[2], c[3]], [c[4], c[5]], [c[6], c[7]]]),
        ..MeasureOptions::default()
    }
}

/// The A4 log chart shipped in `targets/`.
pub fn a4_log() -> Target {
    let p = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("targets/a4_log.toml");
    Target::load(&p).expect("targets/a4_log.toml")
}

/// RMS |MTF − truth| of one sweep's measured curve over 0.01–0.45 cy/px (non-aliased).
pub fn curve_rms(
    m: &sweepmtf::measure::Measurement,
    truth: &simulate::SweepTruth,
    id: &str,
) -> f64 {
    let rows: Vec<(f64, f64)> = truth.rows.iter().map(|r| (r.freq_cy_px, r.mtf)).collect();
    let Some(c) = m.curves.iter().find(|c| c.sweep_id == id) else {
        return f64::NAN;
    };
    let e: Vec<f64> = c
        .points
        .iter()
        .filter(|p| !p.aliased && (0.01..=0.45).contains(&p.freq_cy_px))
        .map(|p| p.mtf - truth_at(&rows, p.freq_cy_px))
        .collect();
    if e.is_empty() {
        return f64::NAN;
    }
    (e.iter().map(|v| v * v).sum::<f64>() / e.len() as f64).sqrt()
}

/// `--roi` refinement on one shot: the main sweep's MTF RMS against the truth with
/// the exact corners and with corners off by up to ±`off_px` in x and y, each
/// without and with refinement, plus how far refinement left the corners from the
/// truth (px, largest). `strip`: the corners are the main sweep strip's, without a
/// target; else the target frame's, with the target.
#[derive(Debug, Clone)]
pub struct RefineTrial {
    /// RMS: exact corners, no refinement.
    pub exact: f64,
    /// RMS: exact corners, refined.
    pub exact_refined: f64,
    /// RMS: jittered corners, no refinement (NaN when that measurement fails).
    pub jittered: f64,
    /// RMS: jittered corners, refined.
    pub jittered_refined: f64,
    /// Largest corner error given, px.
    pub given_err_px: f64,
    /// Largest corner error after refinement, px.
    pub refined_err_px: f64,
    /// Warnings of the refined jittered run that mention the region.
    pub notes: Vec<String>,
    /// Slant of the refined region's two ends against the printed bars: how far
    /// (px along the strip) the end's v = 1 corner lies beyond the bar through its
    /// v = 0 corner, by the simulator's exact strip corners (strip trials; else 0).
    pub ends_slant_px: [f64; 2],
    /// Time of the refinement alone (`locate::refine_roi` on the luminance plane of
    /// the region's bounding box + 16 px, as `measure` converts it), ms.
    pub refine_ms: f64,
}

/// Runs one refinement trial on the main sweep (see [`RefineTrial`]).
pub fn refine_trial(
    target: &Target,
    pose: &Pose,
    strip: bool,
    off_px: f64,
    rng: &mut Rng,
) -> Result<RefineTrial, String> {
    refine_trial_on(target, pose, 0, strip, off_px, rng)
}

/// Runs one refinement trial scored on the target's `sweep`-th sweep (with `strip`,
/// that sweep's strip is the region).
pub fn refine_trial_on(
    target: &Target,
    pose: &Pose,
    sweep: usize,
    strip: bool,
    off_px: f64,
    rng: &mut Rng,
) -> Result<RefineTrial, String> {
    let (shot, jpeg) = shoot(target, pose)?;
    let dec = decode_bytes(&jpeg, "shot.jpg").map_err(|e| e.to_string())?;
    let truth = shot.sweeps.get(sweep).ok_or("no such sweep")?;
    let flat = if strip {
        truth.roi
    } else {
        shot.target_corners
    };
    let exact = [0, 1, 2, 3].map(|k| [flat[2 * k], flat[2 * k + 1]]);
    let given = exact.map(|p| {
        [
            p[0] + rng.range(-off_px, off_px),
            p[1] + rng.range(-off_px, off_px),
        ]
    });
    let t = (!strip).then_some(target);
    let measure = |roi: [[f64; 2]; 4], refine: bool| {
        let o = MeasureOptions {
            roi: Some(roi),
            refine_roi: refine,
            ..MeasureOptions::default()
        };
        measure_decoded(&dec, "shot.jpg", t, &o).map_err(|e| e.to_string())
    };
    let id = if strip { "strip" } else { truth.id.as_str() };
    let err = |a: &[[f64; 2]; 4]| {
        (0..4)
            .map(|k| (a[k][0] - exact[k][0]).hypot(a[k][1] - exact[k][1]))
            .fold(0.0, f64::max)
    };
    let refined = measure(given, true)?;
    let refine_ms = {
        use sweepmtf::photo::linearise::{Channel, Crop, default_tone, planes};
        let pad = sweepmtf::measure::REFINE_SEARCH_PX + 8.0;
        let lo = |a: usize| {
            (given.iter().map(|p| p[a]).fold(f64::INFINITY, f64::min) - pad).max(0.0) as usize
        };
        let hi = |a: usize, n: usize| {
            ((given.iter().map(|p| p[a]).fold(0.0, f64::max) + pad).ceil() as usize).min(n)
        };
        let crop = Crop {
            x0: lo(0),
            y0: lo(1),
            x1: hi(0, dec.width),
            y1: hi(1, dec.height),
        };
        let grey = planes(&dec, crop, &default_tone(dec.bits()).0, Channel::Luma);
        let t0 = Instant::now();
        let _ =
            sweepmtf::locate::refine_roi(&grey[0], given, t, sweepmtf::measure::REFINE_SEARCH_PX);
        t0.elapsed().as_secs_f64() * 1e3
    };
    // The refined corners in the true strip frame (unit square): a slant is a u difference.
    let ends_slant_px = if strip {
        let unit = rect_corners(0.0, 0.0, 1.0, 1.0);
        let to_true =
            sweepmtf::geometry::Homography::from_quads(&exact, &unit).map_err(|e| e.to_string())?;
        let q = refined.roi.map(|p| to_true.apply(p));
        let len = |a: [f64; 2], b: [f64; 2]| (a[0] - b[0]).hypot(a[1] - b[1]);
        let px = 0.5 * (len(exact[0], exact[1]) + len(exact[3], exact[2]));
        [(q[3][0] - q[0][0]) * px, (q[2][0] - q[1][0]) * px]
    } else {
        [0.0, 0.0]
    };
    Ok(RefineTrial {
        exact: curve_rms(&measure(exact, false)?, truth, id),
        exact_refined: curve_rms(&measure(exact, true)?, truth, id),
        // Corners given off may leave too little sweep to measure: NaN, not a failed trial.
        jittered: measure(given, false)
            .map(|m| curve_rms(&m, truth, id))
            .unwrap_or(f64::NAN),
        jittered_refined: curve_rms(&refined, truth, id),
        given_err_px: err(&given),
        refined_err_px: err(&refined.roi),
        notes: refined
            .notes
            .iter()
            .filter(|w| w.contains("region"))
            .cloned()
            .collect(),
        ends_slant_px,
        refine_ms,
    })
}
