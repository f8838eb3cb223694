//! Demosaicking a simulated Bayer mosaic into an RGB photo, as a camera's
//! fast path does: bilinear interpolation of each colour from its own sites,
//! then white balance (division by the sites' gains, so a neutral chart stays
//! neutral).
//!
//! Bilinear demosaicking is the convolution of each colour's zero-filled
//! plane with a fixed kernel: red and blue (one site in four) with
//! [1 2 1; 2 4 2; 1 2 1]/4, green (one in two, a quincunx) with
//! [0 1 0; 1 4 1; 0 1 0]/4. Along a row, red and blue sampled every second
//! pixel and so interpolated pass a cosine of f cy/px with gain cos²(πf) and
//! add its alias at ½ − f with gain sin²(πf); the red and blue lattices are
//! one pixel apart, so their aliases have opposite signs — the false colour
//! of colour moiré, largest where the alias falls on the signal (f = ¼).
//! Image edges are mirrored about the edge pixel (index −1 reads 1), which
//! keeps the mosaic's parity.

use super::BayerOrder;
use rayon::prelude::*;
use serde::{Deserialize, Serialize};
use std::fmt;
use std::str::FromStr;

/// How a Bayer mosaic becomes an RGB photo.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum Demosaic {
    /// Bilinear interpolation of each colour from its own sites.
    Bilinear,
}

impl fmt::Display for Demosaic {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str("bilinear")
    }
}

impl FromStr for Demosaic {
    type Err = String;
    fn from_str(s: &str) -> Result<Self, String> {
        match s.trim().to_ascii_lowercase().as_str() {
            "bilinear" => Ok(Demosaic::Bilinear),
            _ => Err(format!("demosaicking '{s}' is not one of: bilinear")),
        }
    }
}

/// Mirrors index `i` (may be −1 or n) into 0..n about the edge samples.
fn mirror(i: isize, n: usize) -> usize {
    let n = n as isize;
    let j = if i < 0 {
        -i
    } else if i >= n {
        2 * n - 2 - i
    } else {
        i
    };
    j.clamp(0, n - 1) as usize
}

/// Bilinear demosaicking of `mosaic` (width `w`, row-major, linear) laid out
/// in `order`, each colour divided by its site gain (`gains` R, G, B) and
/// clipped to [0, 1]: the R, G, B planes.
pub fn bilinear(mosaic: &[f32], w: usize, order: BayerOrder, gains: [f64; 3]) -> [Vec<f32>; 3] {
    let h = mosaic.len().checked_div(w).unwrap_or(0);
    let plane = |c: usize| -> Vec<f32> {
        let mut out = vec![0f32; w * h];
        if w < 2 || h < 2 {
            return out;
        }
        let inv = 1.0 / gains[c];
        out.par_chunks_mut(w).enumerate().for_each(|(y, row)| {
            for (x, o) in row.iter_mut().enumerate() {
                let v = if order.colour_at(x, y) == c {
                    mosaic[y * w + x] as f64
                } else {
                    // The kernel's weights over the same-colour neighbours
                    // (the zero-filled plane makes the others vanish).
                    let mut acc = 0.0;
                    for dy in -1isize..=1 {
                        for dx in -1isize..=1 {
                            if dx == 0 && dy == 0 {
                                continue;
                            }
                            let (xx, yy) = (mirror(x as isize + dx, w), mirror(y as isize + dy, h));
                            if order.colour_at(xx, yy) != c {
                                continue;
                            }
                            let wgt = match (dx.abs() + dy.abs(), c) {
                                (1, 1) => 0.25, // green: the four edge neighbours
                                (_, 1) => 0.0,
                                (1, _) => 0.5, // red/blue: two edge neighbours …
                                _ => 0.25,     // … or four corners
                            };
                            acc += wgt * mosaic[yy * w + xx] as f64;
                        }
                    }
                    acc
                };
                *o = (v * inv).clamp(0.0, 1.0) as f32;
            }
        });
        out
    };
    [plane(0), plane(1), plane(2)]
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Amplitude of frequency `f` (cy/px) in row `y` of `p` by a direct DFT over the whole row.
    fn amp(p: &[f32], w: usize, y: usize, f: f64) -> (f64, f64) {
        let (mut c, mut s) = (0.0, 0.0);
        for x in 0..w {
            let a = std::f64::consts::TAU * f * x as f64;
            c += p[y * w + x] as f64 * a.cos();
            s += p[y * w + x] as f64 * a.sin();
        }
        (2.0 * c / w as f64, 2.0 * s / w as f64)
    }

    #[test]
    fn a_grey_scene_stays_grey_at_every_pixel_and_edge() {
        for order in [
            BayerOrder::Rggb,
            BayerOrder::Bggr,
            BayerOrder::Grbg,
            BayerOrder::Gbrg,
        ] {
            let (w, h) = (7, 5);
            let gains = [0.55, 1.0, 0.75];
            let m: Vec<f32> = (0..w * h)
                .map(|i| (0.4 * gains[order.colour_at(i % w, i / w)]) as f32)
                .collect();
            for p in bilinear(&m, w, order, gains) {
                assert!(p.iter().all(|&v| (v - 0.4).abs() < 1e-6), "{order} {p:?}");
            }
        }
    }

    #[test]
    fn red_and_blue_pass_cos2_and_alias_with_opposite_signs() {
        // A cosine along x, constant down the columns, on an RGGB mosaic: red
        // at even x (even rows), blue at odd x (odd rows). Closed form: gain
        // cos²(πf) at f, sin²(πf) at ½ − f, with + for red and − for blue;
        // green (quincunx, averaged over a pair of rows) 3/4 + cos(2πf)/4.
        // f = k/w with whole k so the DFT over a row is exact (w even).
        let (w, h) = (200, 4);
        for k in [20usize, 36, 44] {
            let f = k as f64 / w as f64;
            let scene = |x: usize| 0.5 + 0.3 * (std::f64::consts::TAU * f * x as f64).cos();
            let m: Vec<f32> = (0..w * h).map(|i| scene(i % w) as f32).collect();
            let [r, g, b] = bilinear(&m, w, BayerOrder::Rggb, [1.0; 3]);
            // Mean over the rows; the mirrored ends of a row disturb the DFT
            // only slightly (tolerance 0.01).
            let c2 = (std::f64::consts::PI * f).cos().powi(2);
            let sin2 = (std::f64::consts::PI * f).sin().powi(2);
            for (p, sign) in [(&r, 1.0), (&b, -1.0)] {
                let mut at_f = 0.0;
                let mut at_alias = 0.0;
                for y in 0..h {
                    at_f += amp(p, w, y, f).0 / h as f64;
                    at_alias += amp(p, w, y, 0.5 - f).0 / h as f64;
                }
                assert!(
                    (at_f - 0.3 * c2).abs() < 0.01,
                    "f {f}: {at_f} vs {}",
                    0.3 * c2
                );
                assert!(
                    (at_alias - sign * 0.3 * sin2).abs() < 0.01,
                    "f {f}: alias {at_alias} vs {}",
                    sign * 0.3 * sin2
                );
            }
            let gf: f64 = (0..h).map(|y| amp(&g, w, y, f).0).sum::<f64>() / h as f64;
            let want = 0.3 * (0.75 + 0.25 * (std::f64::consts::TAU * f).cos());
            assert!((gf - want).abs() < 0.01, "green {gf} vs {want}");
        }
    }

    #[test]
    fn tiny_and_empty_mosaics_do_not_panic() {
        for (w, n) in [(0usize, 0usize), (1, 1), (1, 3), (3, 3)] {
            let m = vec![0.5f32; n];
            let out = bilinear(&m, w, BayerOrder::Rggb, [1.0; 3]);
            assert_eq!(out[0].len(), if w == 0 { 0 } else { n });
        }
        assert_eq!("Bilinear".parse::<Demosaic>(), Ok(Demosaic::Bilinear));
        assert!("ahd".parse::<Demosaic>().is_err());
    }
}
