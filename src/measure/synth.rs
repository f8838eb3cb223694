//! A small reference renderer for tests and the accuracy report, independent
//! of the measurement code: a sine sweep strip seen through a homography and
//! blurred by an isotropic Gaussian of known σ, whose MTF exp(−2π²σ²f²) is the
//! truth. The blur is applied analytically as a locally plane wave (the
//! sweep's local frequency vector at each pixel centre, from the exact
//! derivative of the chart coordinate), then optional shot and read noise,
//! the sRGB curve, 8-bit quantisation and optional JPEG compression.
//!
//! The full camera simulator (`crate::simulate`) supersedes this for optics
//! and sensor effects; this renderer only needs to be exact for a Gaussian.

#![allow(clippy::needless_range_loop, clippy::neg_cmp_op_on_partial_ord)]

use super::law::PhaseLaw;
use crate::geometry::{Homography, Point, rect_corners};
use crate::photo::linearise::linear_to_srgb;
use crate::simulate::nuisance::Sharpen;
use std::f64::consts::PI;
use std::io::Cursor;

/// A synthetic shot of one sweep strip.
#[derive(Debug, Clone)]
pub struct SynthShot {
    /// Name of the case.
    pub name: String,
    /// Image size (pixels).
    pub width: usize,
    /// Image height (pixels).
    pub height: usize,
    /// Strip corners in the image (corners 1 and 4 on the low-frequency edge).
    pub quad: [Point; 4],
    /// Strip length and width (strip units).
    pub length: f64,
    /// Strip width (strip units).
    pub strip_width: f64,
    /// Phase law in strip units.
    pub law: PhaseLaw,
    /// Mean linear level (0–1).
    pub mean: f64,
    /// Printed modulation (0–1].
    pub contrast: f64,
    /// Gaussian blur σ (pixels).
    pub sigma_px: f64,
    /// Electrons at linear level 1 (shot noise), and read noise (electrons); None = noiseless.
    pub noise: Option<(f64, f64)>,
    /// JPEG quality; None = lossless PNG.
    pub jpeg_quality: Option<u8>,
    /// What real lenses, lights and cameras add (all off by default).
    pub nuisance: Nuisances,
}

/// Nuisances of real shots, each rendered with exact truth.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Nuisances {
    /// Illumination ratio between the strip's low- and high-frequency ends
    /// (1 = even; 3 = the low end 3× brighter), exponential in the image
    /// position projected on the strip's axis.
    pub light_ratio: f64,
    /// Vignetting: relative illumination at the frame corner (1 = none,
    /// 0.5 = 50 % falloff), shaped (1 + k r²)⁻² about the frame centre.
    pub vignette_corner: f64,
    /// Unsharp mask in linear light, (amount a, Gaussian radius σ in px):
    /// the MTF becomes truth × (1 + a(1 − exp(−2π²σ²f²))).
    pub usm: Option<(f64, f64)>,
    /// Colour of the light as gains of R, G, B (the shot is then RGB); None = grey.
    pub rgb_gains: Option<[f64; 3]>,
    /// JPEG with 4:2:0 chroma subsampling (else 4:4:4 through `image`).
    pub chroma_420: bool,
    /// A camera's picture style on top of sRGB: the code c becomes
    /// ½ + ½·tanh(k(c − ½))/tanh(k/2), strength k (0 = none; 2 is a
    /// "standard" style's contrast). The file still reads as sRGB.
    pub picture_style: f64,
    /// The strip printed on white paper, as charts are: the surround reads
    /// twice the strip's mean (the strip spans 0.1–0.9 of the paper at
    /// contrast 0.8); else the surround is the strip's mean.
    pub paper_surround: bool,
    /// A camera's unsharp mask on the code, after the picture style (see
    /// [`super::synth_code_sharpen`]; its truth assumes even light).
    pub code_sharpen: Option<Sharpen>,
}

/// A picture style's S-curve of strength `k` on a code (0–1); `k` = 0 leaves it.
pub fn picture_style(c: f64, k: f64) -> f64 {
    if k == 0.0 {
        c
    } else {
        0.5 + 0.5 * (k * (c - 0.5)).tanh() / (0.5 * k).tanh()
    }
}

impl Default for Nuisances {
    fn default() -> Self {
        Nuisances {
            light_ratio: 1.0,
            vignette_corner: 1.0,
            usm: None,
            rgb_gains: None,
            chroma_420: false,
            picture_style: 0.0,
            paper_surround: false,
            code_sharpen: None,
        }
    }
}

impl SynthShot {
    /// The true MTF at `f` cycles/pixel (with the code sharpened, the
    /// modulation transfer a sine of the chart's contrast reads).
    pub fn truth(&self, f: f64) -> f64 {
        let t = self.linear_transfer(f);
        match self.nuisance.code_sharpen {
            Some(cs) => {
                let q = self.quad;
                let angle = (q[1][1] - q[0][1]).atan2(q[1][0] - q[0][0]);
                super::synth_code_sharpen::truth(
                    &cs,
                    f,
                    angle,
                    t,
                    self.mean,
                    self.contrast,
                    self.nuisance.picture_style,
                )
            }
            None => t,
        }
    }

    /// The transfer in linear light at `f` cycles/pixel: the blur and any
    /// unsharp mask in linear light.
    fn linear_transfer(&self, f: f64) -> f64 {
        let blur = (-2.0 * PI * PI * self.sigma_px * self.sigma_px * f * f).exp();
        match self.nuisance.usm {
            Some((a, r)) => blur * (1.0 + a * (1.0 - (-2.0 * PI * PI * r * r * f * f).exp())),
            None => blur,
        }
    }

    /// Relative illumination (1 at the strip's low-frequency end on the frame's centre) at pixel centre `p`.
    pub fn light_at(&self, p: Point) -> f64 {
        let n = &self.nuisance;
        let mut l = 1.0;
        if n.light_ratio != 1.0 && n.light_ratio > 0.0 {
            let q = self.quad;
            let a = [0.5 * (q[0][0] + q[3][0]), 0.5 * (q[0][1] + q[3][1])];
            let b = [0.5 * (q[1][0] + q[2][0]), 0.5 * (q[1][1] + q[2][1])];
            let (dx, dy) = (b[0] - a[0], b[1] - a[1]);
            let t = ((p[0] - a[0]) * dx + (p[1] - a[1]) * dy) / (dx * dx + dy * dy);
            l *= n.light_ratio.powf(-t);
        }
        if n.vignette_corner < 1.0 && n.vignette_corner > 0.0 {
            let (cx, cy) = (0.5 * self.width as f64, 0.5 * self.height as f64);
            let rc2 = cx * cx + cy * cy;
            let k = (n.vignette_corner.powf(-0.5) - 1.0) / rc2;
            let r2 = (p[0] - cx).powi(2) + (p[1] - cy).powi(2);
            l /= (1.0 + k * r2).powi(2);
        }
        l
    }

    fn homography(&self) -> Homography {
        Homography::from_quads(
            &rect_corners(0.0, 0.0, self.length, self.strip_width),
            &self.quad,
        )
        .expect("synthetic quads are valid")
    }

    /// True image frequency (cycles/pixel) at distance `s` along the strip's centre line.
    pub fn freq_px_at(&self, s: f64) -> f64 {
        let inv = self.homography().inverse().expect("invertible");
        let p = self.homography().apply([s, 0.5 * self.strip_width]);
        let j = inv.jacobian(p);
        self.law.freq(s) * j[0][0].hypot(j[0][1])
    }

    /// Renders linear values (no noise, no encoding), row-major.
    pub fn render_linear(&self) -> Vec<f64> {
        let inv = self.homography().inverse().expect("invertible");
        let surround = if self.nuisance.paper_surround {
            2.0 * self.mean
        } else {
            self.mean
        };
        let mut out = vec![surround; self.width * self.height];
        for y in 0..self.height {
            for x in 0..self.width {
                let p = [x as f64 + 0.5, y as f64 + 0.5];
                let light = self.light_at(p);
                out[y * self.width + x] = surround * light;
                let q = inv.apply(p);
                let (s, t) = (q[0], q[1]);
                if !(0.0..=self.length).contains(&s) || !(0.0..=self.strip_width).contains(&t) {
                    continue;
                }
                let j = inv.jacobian(p);
                let f = self.law.freq(s) * j[0][0].hypot(j[0][1]);
                let m = self.contrast * self.linear_transfer(f);
                out[y * self.width + x] =
                    light * self.mean * (1.0 + m * (2.0 * PI * self.law.phase(s)).cos());
            }
        }
        out
    }

    /// Renders the shot and encodes it (8-bit sRGB grey PNG, or RGB JPEG); `seed` drives the noise.
    pub fn encode(&self, seed: u64) -> Vec<u8> {
        let lin = self.render_linear();
        let mut st = seed.wrapping_mul(0x9E37_79B9_7F4A_7C15).wrapping_add(1);
        let gains = self.nuisance.rgb_gains.unwrap_or([1.0; 3]);
        let channels = if self.nuisance.rgb_gains.is_some() {
            3
        } else {
            1
        };
        let mut code = |v: f64| -> f64 {
            let v = match self.noise {
                Some((full, read)) => {
                    let e = v * full;
                    (e + (e.max(0.0) + read * read).sqrt() * normal(&mut st)) / full
                }
                None => v,
            };
            picture_style(
                linear_to_srgb(v.clamp(0.0, 1.0)),
                self.nuisance.picture_style,
            )
        };
        // Per channel, a plane of codes (0–1), sharpened where the camera does.
        let mut planes = vec![Vec::with_capacity(lin.len()); channels];
        for &v in &lin {
            for (c, plane) in planes.iter_mut().enumerate() {
                plane.push(code(v * gains[c]));
            }
        }
        if let Some(cs) = self.nuisance.code_sharpen {
            for plane in &mut planes {
                super::synth_code_sharpen::apply(&cs, plane, self.width);
            }
        }
        let codes: Vec<u8> = (0..lin.len())
            .flat_map(|i| {
                planes
                    .iter()
                    .map(move |p| (255.0 * p[i].clamp(0.0, 1.0)).round() as u8)
            })
            .collect();
        let mut buf = Cursor::new(Vec::new());
        let (w, h) = (self.width as u32, self.height as u32);
        let rgb = || -> Vec<u8> {
            if channels == 3 {
                codes.clone()
            } else {
                codes.iter().flat_map(|&c| [c, c, c]).collect()
            }
        };
        match self.jpeg_quality {
            None if channels == 1 => {
                let img = image::GrayImage::from_raw(w, h, codes).expect("size");
                img.write_to(&mut buf, image::ImageFormat::Png)
                    .expect("PNG encoding in memory");
            }
            None => {
                let img = image::RgbImage::from_raw(w, h, codes).expect("size");
                img.write_to(&mut buf, image::ImageFormat::Png)
                    .expect("PNG encoding in memory");
            }
            Some(q) if self.nuisance.chroma_420 => {
                let mut out = Vec::new();
                let mut enc = jpeg_encoder::Encoder::new(&mut out, q);
                enc.set_sampling_factor(jpeg_encoder::SamplingFactor::R_4_2_0);
                enc.encode(&rgb(), w as u16, h as u16, jpeg_encoder::ColorType::Rgb)
                    .expect("JPEG encoding in memory");
                return out;
            }
            Some(q) => {
                let mut enc = image::codecs::jpeg::JpegEncoder::new_with_quality(&mut buf, q);
                enc.encode(&rgb(), w, h, image::ExtendedColorType::Rgb8)
                    .expect("JPEG encoding in memory");
            }
        }
        buf.into_inner()
    }
}

/// A deterministic standard normal (LCG + Box–Muller).
fn normal(state: &mut u64) -> f64 {
    let mut u = || {
        *state = state
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        ((*state >> 11) as f64 + 0.5) / (1u64 << 53) as f64
    };
    let (a, b) = (u(), u());
    (-2.0 * a.ln()).sqrt() * (2.0 * PI * b).cos()
}

/// A strip of `len`×`wid` pixels centred at (cx, cy), turned by `rot_deg`, with its far
/// (high-frequency) end tilted away: `tilt_deg` foreshortens the strip progressively
/// like a chart turned about its vertical axis.
pub fn strip_quad(cx: f64, cy: f64, len: f64, wid: f64, rot_deg: f64, tilt_deg: f64) -> [Point; 4] {
    // Perspective: the far end shrinks by cos(tilt)-like factor.
    let k = 1.0 - 0.5 * tilt_deg.to_radians().sin();
    let pts = [
        [-len / 2.0, -wid / 2.0],
        [len / 2.0 * k.sqrt(), -wid / 2.0 * k],
        [len / 2.0 * k.sqrt(), wid / 2.0 * k],
        [-len / 2.0, wid / 2.0],
    ];
    let (c, s) = (rot_deg.to_radians().cos(), rot_deg.to_radians().sin());
    pts.map(|[x, y]| [cx + c * x - s * y, cy + s * x + c * y])
}

/// The fixed set of cases of the accuracy report: (name, shot).
pub fn standard_cases() -> Vec<SynthShot> {
    use super::law::LawKind;
    let len = 1800.0;
    // Log sweep 0.004 → 0.6 cycles per unit over the strip (units ≈ pixels when not tilted).
    let k = (0.6f64 / 0.004).ln() / len;
    let law = PhaseLaw {
        kind: LawKind::Log,
        c0: 0.0,
        c1: 0.004,
        c2: k,
        persp: 0.0,
    };
    let base = SynthShot {
        name: "noiseless".into(),
        width: 1900,
        height: 200,
        quad: strip_quad(950.0, 100.0, len, 120.0, 0.0, 0.0),
        length: len,
        strip_width: 120.0,
        law,
        mean: 0.45,
        contrast: 0.8,
        sigma_px: 0.8,
        noise: None,
        jpeg_quality: None,
        nuisance: Nuisances::default(),
    };
    let noisy = |name: &str, rot: f64, tilt: f64| {
        let big = rot.abs() > 1.0 || tilt > 1.0;
        let (w, h) = if big { (1900, 1400) } else { (1900, 200) };
        SynthShot {
            name: name.into(),
            width: w,
            height: h,
            quad: strip_quad(
                w as f64 / 2.0,
                h as f64 / 2.0,
                if big { 1500.0 } else { len },
                120.0,
                rot,
                tilt,
            ),
            // SNR ≈ 50 at the mean level: 0.45·full/√(0.45·full) = 50 → full ≈ 5560 e⁻.
            noise: Some((5560.0, 3.0)),
            jpeg_quality: Some(90),
            ..base.clone()
        }
    };
    vec![
        base.clone(),
        noisy("snr50_jpeg90", 0.0, 0.0),
        noisy("rot20_snr50_jpeg90", 20.0, 0.0),
        noisy("rot45_snr50_jpeg90", 45.0, 0.0),
        noisy("tilt30_rot10_snr50_jpeg90", 10.0, 30.0),
        SynthShot {
            name: "dark_c0.2_noisy".into(),
            mean: 0.08,
            contrast: 0.2,
            noise: Some((5560.0, 3.0)),
            jpeg_quality: Some(90),
            ..base.clone()
        },
    ]
}

/// The 24-megapixel shot of the speed check (bench/benches/measure.rs, examples/accuracy.rs):
/// 6000×4000, a 5600×400 px log sweep 0.004→0.6 cy/px turned 3°, SNR ≈ 50, JPEG q90.
pub fn big_shot() -> SynthShot {
    let base = standard_cases().remove(1);
    SynthShot {
        name: "big".into(),
        width: 6000,
        height: 4000,
        quad: strip_quad(3000.0, 2000.0, 5600.0, 400.0, 3.0, 0.0),
        length: 5600.0,
        strip_width: 400.0,
        law: super::PhaseLaw {
            c2: (0.6f64 / 0.004).ln() / 5600.0,
            persp: 0.0,
            ..base.law
        },
        ..base
    }
}

/// The 24-megapixel shot of the libjpeg-turbo comparison (issue 16,
/// examples/djpeg_ratio.rs): 6000×4000, a 5200×1700 px log sweep
/// 0.004→0.6 cy/px turned 1° (its corners cover ≈ 37 % of the frame),
/// SNR ≈ 50, JPEG q92.
pub fn wide_strip_shot() -> SynthShot {
    let big = big_shot();
    SynthShot {
        name: "wide".into(),
        quad: strip_quad(3000.0, 2000.0, 5200.0, 1700.0, 1.0, 0.0),
        length: 5200.0,
        strip_width: 1700.0,
        law: super::PhaseLaw {
            c2: (0.6f64 / 0.004).ln() / 5200.0,
            persp: 0.0,
            ..big.law
        },
        jpeg_quality: Some(92),
        ..big
    }
}

/// The shots of issue 15's nuisances, with exact truth: illumination 3:1 along
/// the strip with 50 % vignetting, a keystoned linear sweep (one end 1.5× the
/// other's height), unsharp-mask sharpening peaking near 1.15, a camera's
/// picture style (an S-curve of strength 2 on top of sRGB; also under uneven
/// light on paper), RGB JPEG q75 with 4:2:0 chroma and noise, and the sRGB
/// code sharpened as a camera does. `variant` moves the strip, its size, turn
/// and blur a little (0 is the set the report uses; tests use others).
pub fn nuisance_cases(variant: u64) -> Vec<SynthShot> {
    use super::law::LawKind;
    // A small deterministic spread of geometry per variant.
    let mut st = variant.wrapping_mul(0x2545_F491_4F6C_DD1D).wrapping_add(17);
    let mut u = || {
        st = st
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        ((st >> 11) as f64 + 0.5) / (1u64 << 53) as f64 * 2.0 - 1.0
    };
    let (w, h) = (2400usize, 1600usize);
    let len = 1800.0 + 150.0 * u();
    let wid = 130.0 + 30.0 * u();
    let (cx, cy) = (1200.0 + 150.0 * u(), 800.0 + 300.0 * u());
    let rot = 4.0 * u();
    let sigma = 0.8 + 0.08 * u();
    let (f0, f1) = (0.004 + 0.001 * u(), 0.6);
    let log = PhaseLaw {
        kind: LawKind::Log,
        c0: 0.0,
        c1: f0,
        c2: (f1 / f0).ln() / len,
        persp: 0.0,
    };
    let base = SynthShot {
        name: String::new(),
        width: w,
        height: h,
        quad: strip_quad(cx, cy, len, wid, rot, 0.0),
        length: len,
        strip_width: wid,
        law: log,
        mean: 0.45,
        contrast: 0.8,
        sigma_px: sigma,
        noise: Some((5560.0, 3.0)),
        jpeg_quality: None,
        nuisance: Nuisances::default(),
    };
    // Keystone: the high-frequency end 1/1.5 the height of the low one, as a
    // chart turned about its vertical axis (true perspective through the homography).
    let key = {
        let (c, s) = (rot.to_radians().cos(), rot.to_radians().sin());
        let (hl, hr) = (0.5 * wid, 0.5 * wid / 1.5);
        let half = 0.5 * len * 0.85;
        [[-half, -hl], [half, -hr], [half, hr], [-half, hl]]
            .map(|[x, y]| [cx + c * x - s * y, cy + s * x + c * y])
    };
    vec![
        SynthShot {
            name: "light3_vignette50".into(),
            // Brighter at the low-frequency end; a light level that keeps the
            // brightest part (centre, low end) below clipping.
            mean: 0.3,
            nuisance: Nuisances {
                light_ratio: 3.0,
                vignette_corner: 0.5,
                ..Nuisances::default()
            },
            ..base.clone()
        },
        SynthShot {
            name: "keystone1.5_linear".into(),
            quad: key,
            law: PhaseLaw {
                kind: LawKind::Linear,
                c0: 0.0,
                c1: f0,
                c2: (0.4 - f0) / (2.0 * len),
                persp: 0.0,
            },
            ..base.clone()
        },
        SynthShot {
            name: "usm_peak1.15".into(),
            sigma_px: 0.92 + 0.02 * u(),
            nuisance: Nuisances {
                usm: Some((1.0, 1.5)),
                ..Nuisances::default()
            },
            ..base.clone()
        },
        SynthShot {
            name: "picture_style2".into(),
            // Paper white at 0.66 of clipping: the sine about a third, where
            // a picture style bends the modulation most.
            mean: 0.33,
            nuisance: Nuisances {
                picture_style: 2.0,
                ..Nuisances::default()
            },
            ..base.clone()
        },
        SynthShot {
            name: "rgb_jpeg75_420".into(),
            jpeg_quality: Some(75),
            nuisance: Nuisances {
                // A slight colour cast left after white balance.
                rgb_gains: Some([0.95, 1.0, 0.9]),
                chroma_420: true,
                ..Nuisances::default()
            },
            ..base.clone()
        },
        SynthShot {
            name: "picture_style2_light2".into(),
            // A picture style under light falling 2:1 along the strip, with
            // vignetting, on white paper: the curve's black level, which the
            // shape cannot show, then bends the MTF; the paper gives it.
            mean: 0.3,
            nuisance: Nuisances {
                picture_style: 2.0,
                light_ratio: 2.0,
                vignette_corner: 0.7,
                paper_surround: true,
                ..Nuisances::default()
            },
            ..base.clone()
        },
        SynthShot {
            name: "code_usm0.8".into(),
            // A camera's sharpening of its sRGB code (JPEG engines sharpen
            // after the tone curve): not linear, and not a tone curve.
            nuisance: Nuisances {
                code_sharpen: Some(Sharpen {
                    amount: 0.8,
                    radius_px: 1.2,
                }),
                ..Nuisances::default()
            },
            ..base
        },
    ]
}
