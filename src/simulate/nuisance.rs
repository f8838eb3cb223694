//! What real cameras and lights add to a shot beyond optics and sensor, each
//! with exact truth: unsharp-mask sharpening in linear light ([`Sharpen`]), an
//! illumination gradient across the frame ([`LightGradient`]), and the colour
//! of the light (an RGB photo; as JPEG with 4:2:0 or 4:4:4 chroma, [`Chroma`]).
//!
//! Sharpening is the linear operator x + a·(x − g∗x) with g a sampled,
//! normalised Gaussian applied separably (rows, then columns; edges
//! replicated). Its transfer at image frequency (u, v) cy/px is exactly
//! 1 + a·(1 − G(u)·G(v)) with G(f) = Σₙ g\[n\]·cos(2πfn), the kernel's discrete
//! Fourier transform: for radii near a pixel the sampled kernel aliases, so
//! the continuous exp(−2π²r²f²) would be off by up to 0.7 % of a at Nyquist.
//! The illumination and the light's colour multiply the signal and change no
//! modulation, so the truth is the optics' alone.

use rayon::prelude::*;
use serde::{Deserialize, Serialize};
use std::f64::consts::PI;
use std::fmt;
use std::str::FromStr;

/// Unsharp-mask sharpening in linear light: out = x + amount·(x − Gaussian(radius)∗x).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Sharpen {
    /// Amount a (dimensionless; the high-frequency gain tends to 1 + a).
    pub amount: f64,
    /// Standard deviation of the Gaussian, pixels.
    pub radius_px: f64,
}

impl Sharpen {
    /// Largest amount accepted.
    pub const MAX_AMOUNT: f64 = 5.0;
    /// Radii accepted, pixels.
    pub const RADIUS_PX: (f64, f64) = (0.3, 20.0);

    /// The sampled, normalised 1-D kernel g[−n..=n].
    pub fn kernel(&self) -> Vec<f64> {
        let n = (4.0 * self.radius_px).ceil().max(1.0) as i64;
        let mut k: Vec<f64> = (-n..=n)
            .map(|i| (-(i * i) as f64 / (2.0 * self.radius_px * self.radius_px)).exp())
            .collect();
        let s: f64 = k.iter().sum();
        k.iter_mut().for_each(|v| *v /= s);
        k
    }

    /// The 1-D kernel's transfer G(f) at `f` cycles/pixel (real: the kernel is symmetric).
    pub fn blur_transfer(&self, f: f64) -> f64 {
        transfer_of(&self.kernel(), f)
    }

    /// The sharpening's transfer at image frequency (u, v) cycles/pixel: 1 + a·(1 − G(u)·G(v)).
    pub fn gain(&self, u: f64, v: f64) -> f64 {
        let k = self.kernel();
        1.0 + self.amount * (1.0 - transfer_of(&k, u) * transfer_of(&k, v))
    }

    /// Checks the ranges.
    pub fn check(&self) -> Result<(), String> {
        let (lo, hi) = Self::RADIUS_PX;
        if !(self.amount.is_finite() && (0.0..=Self::MAX_AMOUNT).contains(&self.amount)) {
            return Err(format!(
                "sharpening amount {} must lie in 0–{}",
                self.amount,
                Self::MAX_AMOUNT
            ));
        }
        if !(self.radius_px.is_finite() && (lo..=hi).contains(&self.radius_px)) {
            return Err(format!(
                "sharpening radius {} px must lie in {lo}–{hi} px",
                self.radius_px
            ));
        }
        Ok(())
    }

    /// Sharpens a `width`-wide row-major plane in place (edges replicated).
    pub fn apply(&self, plane: &mut [f32], width: usize) {
        if width == 0 || plane.is_empty() || self.amount == 0.0 {
            return;
        }
        let height = plane.len() / width;
        let k: Vec<f32> = self.kernel().iter().map(|&v| v as f32).collect();
        let n = (k.len() / 2) as isize;
        let clampi = |i: isize, len: usize| i.clamp(0, len as isize - 1) as usize;
        // Rows.
        let mut rows = vec![0f32; plane.len()];
        rows.par_chunks_mut(width)
            .zip(plane.par_chunks(width))
            .for_each(|(o, src)| {
                for (x, o) in o.iter_mut().enumerate() {
                    let mut s = 0f32;
                    for (j, &g) in k.iter().enumerate() {
                        s += g * src[clampi(x as isize + j as isize - n, width)];
                    }
                    *o = s;
                }
            });
        // Columns, then x + a·(x − blurred).
        let a = self.amount as f32;
        let src = &rows;
        plane
            .par_chunks_mut(width)
            .enumerate()
            .for_each(|(y, out)| {
                let mut acc = vec![0f32; width];
                for (j, &g) in k.iter().enumerate() {
                    let r = clampi(y as isize + j as isize - n, height);
                    for (a, &v) in acc.iter_mut().zip(&src[r * width..(r + 1) * width]) {
                        *a += g * v;
                    }
                }
                for (o, b) in out.iter_mut().zip(acc) {
                    *o += a * (*o - b);
                }
            });
    }
}

/// The DFT of a symmetric kernel g[−n..=n] at `f` cycles/sample.
fn transfer_of(k: &[f64], f: f64) -> f64 {
    let n = (k.len() / 2) as f64;
    k.iter()
        .enumerate()
        .map(|(i, g)| g * (2.0 * PI * f * (i as f64 - n)).cos())
        .sum()
}

impl FromStr for Sharpen {
    type Err = String;
    /// Parses `amount=A,radius=R` (R in pixels).
    fn from_str(s: &str) -> Result<Self, String> {
        let mut amount = None;
        let mut radius = None;
        for part in s.split(',') {
            let (k, v) = part.split_once('=').ok_or_else(|| {
                format!("sharpening '{s}': write amount=A,radius=R (R in pixels)")
            })?;
            let v: f64 = v
                .trim()
                .parse()
                .map_err(|_| format!("sharpening '{s}': '{v}' is not a number"))?;
            match k.trim() {
                "amount" => amount = Some(v),
                "radius" => radius = Some(v),
                o => {
                    return Err(format!(
                        "sharpening '{s}': unknown key '{o}' (amount, radius)"
                    ));
                }
            }
        }
        let (Some(amount), Some(radius_px)) = (amount, radius) else {
            return Err(format!(
                "sharpening '{s}': give both amount=A and radius=R (pixels)"
            ));
        };
        let sh = Sharpen { amount, radius_px };
        sh.check()?;
        Ok(sh)
    }
}

impl fmt::Display for Sharpen {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "amount={},radius={}", self.amount, self.radius_px)
    }
}

/// Light that falls off exponentially across the frame: `ratio` times brighter
/// at one edge than at the opposite one, darkening towards `toward_deg`.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct LightGradient {
    /// Illumination at the bright edge / at the dark edge (≥ 1).
    pub ratio: f64,
    /// Direction in which the light falls, degrees (0 = towards the right, 90 = down).
    pub toward_deg: f64,
}

impl LightGradient {
    /// Largest ratio accepted.
    pub const MAX_RATIO: f64 = 100.0;

    /// Relative illumination at pixel centre (x, y) of a `width`×`height` frame (1 at the centre).
    pub fn gain(&self, x: f64, y: f64, width: usize, height: usize) -> f64 {
        let (c, s) = (
            self.toward_deg.to_radians().cos(),
            self.toward_deg.to_radians().sin(),
        );
        let extent = width as f64 * c.abs() + height as f64 * s.abs();
        let t = ((x - width as f64 / 2.0) * c + (y - height as f64 / 2.0) * s) / extent;
        self.ratio.powf(-t)
    }

    /// Checks the ranges.
    pub fn check(&self) -> Result<(), String> {
        if !(self.ratio.is_finite() && (1.0..=Self::MAX_RATIO).contains(&self.ratio)) {
            return Err(format!(
                "light gradient ratio {} must lie in 1–{} (bright edge / dark edge)",
                self.ratio,
                Self::MAX_RATIO
            ));
        }
        if !self.toward_deg.is_finite() {
            return Err("light gradient direction must be a finite angle".into());
        }
        Ok(())
    }
}

impl FromStr for LightGradient {
    type Err = String;
    /// Parses `R` or `R,DEG`.
    fn from_str(s: &str) -> Result<Self, String> {
        let (r, d) = s.split_once(',').unwrap_or((s, "0"));
        let num = |t: &str| {
            t.trim().parse::<f64>().map_err(|_| {
                format!("light gradient '{s}': write RATIO or RATIO,DEG ('{t}' is not a number)")
            })
        };
        let g = LightGradient {
            ratio: num(r)?,
            toward_deg: num(d)?,
        };
        g.check()?;
        Ok(g)
    }
}

impl fmt::Display for LightGradient {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{},{}", self.ratio, self.toward_deg)
    }
}

/// Chroma sampling of a colour JPEG.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize, Default)]
pub enum Chroma {
    /// Cb and Cr at half resolution both ways (what most cameras write).
    #[default]
    #[serde(rename = "4:2:0")]
    S420,
    /// Cb and Cr at half resolution horizontally.
    #[serde(rename = "4:2:2")]
    S422,
    /// Full-resolution chroma.
    #[serde(rename = "4:4:4")]
    S444,
}

impl FromStr for Chroma {
    type Err = String;
    fn from_str(s: &str) -> Result<Self, String> {
        match s.replace(':', "").as_str() {
            "420" => Ok(Chroma::S420),
            "422" => Ok(Chroma::S422),
            "444" => Ok(Chroma::S444),
            _ => Err(format!("chroma '{s}' is not one of 420, 422, 444")),
        }
    }
}

/// Parses light-colour gains `R,G,B` (each in (0, 1]).
pub fn parse_colour(s: &str) -> Result<[f64; 3], String> {
    let v: Vec<f64> = s
        .split(',')
        .map(|t| t.trim().parse::<f64>())
        .collect::<Result<_, _>>()
        .map_err(|_| format!("light colour '{s}': write three gains R,G,B"))?;
    let g: [f64; 3] = v
        .try_into()
        .map_err(|_| format!("light colour '{s}': write three gains R,G,B"))?;
    check_colour(&g)?;
    Ok(g)
}

/// Checks light-colour gains: each finite in (0, 1].
pub fn check_colour(g: &[f64; 3]) -> Result<(), String> {
    if g.iter().all(|v| v.is_finite() && *v > 0.0 && *v <= 1.0) {
        Ok(())
    } else {
        Err(format!(
            "light colour {g:?}: each gain must lie in (0, 1] (relative to the exposure)"
        ))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The sharpening applied to a sampled cosine scales it by the stated gain
    /// (measured by projecting the output on the cosine and sine: independent
    /// of `gain`'s formula), on and off axis, near and at Nyquist.
    #[test]
    fn sharpening_scales_a_cosine_by_its_stated_gain() {
        for (amount, radius) in [(1.0, 1.0), (0.6, 2.5), (3.0, 0.5)] {
            let sh = Sharpen {
                amount,
                radius_px: radius,
            };
            for (u, v) in [
                (0.05, 0.0),
                (0.25, 0.0),
                (0.125, 0.25),
                (0.5, 0.0),
                (0.3, 0.4),
            ] {
                let (w, h) = (256usize, 256usize);
                let mut img: Vec<f32> = (0..w * h)
                    .map(|i| {
                        let (x, y) = ((i % w) as f64, (i / w) as f64);
                        (0.5 + 0.25 * (2.0 * PI * (u * x + v * y)).cos()) as f32
                    })
                    .collect();
                sh.apply(&mut img, w);
                // Project the interior (away from replicated edges) on cos and sin.
                let (mut c, mut s, mut n) = (0.0, 0.0, 0.0);
                for y in 40..h - 40 {
                    for x in 40..w - 40 {
                        let ph = 2.0 * PI * (u * x as f64 + v * y as f64);
                        let d = img[y * w + x] as f64 - 0.5;
                        c += d * ph.cos();
                        s += d * ph.sin();
                        n += ph.cos().powi(2);
                    }
                }
                let got = (c / n).hypot(s / n) / 0.25;
                let want = sh.gain(u, v);
                assert!(
                    (got - want).abs() < 2e-3 * want,
                    "a={amount} r={radius} ({u},{v}): got {got}, want {want}"
                );
            }
        }
    }

    /// The camera JSON (the Python `simulate` camera dict) takes the nuisances by name.
    #[test]
    fn camera_json_takes_the_nuisances_by_name() {
        let c: crate::simulate::Camera = serde_json::from_str(
            r#"{"sharpen": {"amount": 0.8, "radius_px": 1.2},
                "light_gradient": {"ratio": 3, "toward_deg": 0},
                "light_colour": [1, 0.8, 0.6], "chroma": "4:2:0", "jpeg_quality": 75}"#,
        )
        .unwrap();
        c.validate().unwrap();
        assert_eq!(c.sharpen.unwrap().radius_px, 1.2);
        assert_eq!(c.light_gradient.unwrap().ratio, 3.0);
        assert_eq!(c.light_colour, Some([1.0, 0.8, 0.6]));
        assert_eq!(c.chroma, Chroma::S420);
        let bad: crate::simulate::Camera =
            serde_json::from_str(r#"{"sharpen": {"amount": 9, "radius_px": 1}}"#).unwrap();
        assert!(bad.validate().is_err());
    }

    #[test]
    fn sharpening_gain_approaches_the_continuous_form_for_wide_kernels() {
        let sh = Sharpen {
            amount: 1.0,
            radius_px: 3.0,
        };
        for f in [0.02, 0.1, 0.3] {
            let cont = (-2.0 * PI * PI * 9.0 * f * f).exp();
            // The kernel is cut at 4σ (6e-5 of its mass), which bounds the difference.
            assert!((sh.blur_transfer(f) - cont).abs() < 2e-4, "{f}");
        }
        assert!((sh.gain(0.0, 0.0) - 1.0).abs() < 1e-12);
    }

    #[test]
    fn gradient_ratio_holds_edge_to_edge_and_parsers_refuse_nonsense() {
        let g: LightGradient = "3,0".parse().unwrap();
        let (l, r) = (g.gain(0.0, 5.0, 100, 10), g.gain(100.0, 5.0, 100, 10));
        assert!((l / r - 3.0).abs() < 1e-12 && (g.gain(50.0, 5.0, 100, 10) - 1.0).abs() < 1e-12);
        let d: LightGradient = "2,90".parse().unwrap();
        assert!((d.gain(3.0, 0.0, 10, 40) / d.gain(3.0, 40.0, 10, 40) - 2.0).abs() < 1e-12);
        for bad in ["0.5", "1e9", "x", "2,y", "nan"] {
            assert!(bad.parse::<LightGradient>().is_err(), "{bad}");
        }
        for bad in [
            "amount=1",
            "amount=-1,radius=1",
            "amount=1,radius=0.1",
            "amount=1,radius=1e9",
            "a=1,radius=1",
        ] {
            assert!(bad.parse::<Sharpen>().is_err(), "{bad}");
        }
        assert!("amount=1.2,radius=1.5".parse::<Sharpen>().is_ok());
        assert!(parse_colour("1,0.8,0.5").is_ok());
        for bad in ["1,1", "1,1,0", "1,1,2", "a,b,c"] {
            assert!(parse_colour(bad).is_err(), "{bad}");
        }
        assert_eq!("4:2:0".parse::<Chroma>().unwrap(), Chroma::S420);
        assert!("411".parse::<Chroma>().is_err());
    }
}
