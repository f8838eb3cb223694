//! Centrally symmetric polygons (zonogons: rectangle, rhomb, regular hexagon
//! and octagon) as tilings by parallelograms. The OTF is the area-weighted sum
//! of the parallelograms' transforms, sinc(q·e₁)·sinc(q·e₂)·cos(2πq·c): every
//! term is bounded by its weight and all weights are positive, so the sum has
//! no cancellation at low frequency and no 1/u or 1/v anywhere.

use crate::model::special::{sinc_from_sinpi, sincospi};

/// Most edge directions a zonogon may have (the octagon has 4).
const MAX_EDGES: usize = 8;

/// One parallelogram of the tiling: its share of the area, the indices of its
/// two edges, and its centre c as 2c = Σₖ signₖ·eₖ.
#[derive(Debug, Clone)]
struct Tile {
    weight: f64,
    i: usize,
    j: usize,
    signs: [i8; MAX_EDGES],
}

/// A zonogon centred on the origin, tiled by parallelograms.
#[derive(Debug, Clone)]
pub(crate) struct Zonogon {
    edges: Vec<[f64; 2]>,
    tiles: Vec<Tile>,
    #[cfg_attr(not(test), allow(dead_code))]
    area: f64,
}

impl Zonogon {
    /// Builds the zonogon whose counter-clockwise boundary starts with the edge
    /// vectors `edges` (mm, at most 8) and continues with their negatives; centred on 0.
    ///
    /// Tile (i, j), i < j, spans eᵢ, eⱼ from P₀ + Σ_{k<i} eₖ + Σ_{k>j} eₖ with
    /// P₀ = −Σeₖ/2, so twice its centre is Σ_{k<i or k>j} eₖ − Σ_{i<k<j} eₖ.
    pub(crate) fn from_edges(edges: &[[f64; 2]]) -> Zonogon {
        let n = edges.len();
        assert!((2..=MAX_EDGES).contains(&n), "zonogon needs 2..=8 edges");
        let mut raw = Vec::new();
        let mut area = 0.0;
        for i in 0..n {
            for j in i + 1..n {
                let mut signs = [0i8; MAX_EDGES];
                for (k, sk) in signs.iter_mut().enumerate().take(n) {
                    *sk = if k < i || k > j {
                        1
                    } else if k > i && k < j {
                        -1
                    } else {
                        0
                    };
                }
                let (a, b) = (edges[i], edges[j]);
                let w = (a[0] * b[1] - a[1] * b[0]).abs();
                area += w;
                raw.push((w, i, j, signs));
            }
        }
        let tiles = raw
            .into_iter()
            .map(|(w, i, j, signs)| Tile {
                weight: w / area,
                i,
                j,
                signs,
            })
            .collect();
        Zonogon {
            edges: edges.to_vec(),
            tiles,
            area,
        }
    }

    /// The area, mm².
    #[cfg(test)]
    pub(crate) fn area(&self) -> f64 {
        self.area
    }

    /// The (real) OTF at (u, v), cycles/mm: one `sincospi` per edge direction,
    /// the tiles' phases cos(2πq·c) = Re Πₖ e^(iπ·signₖ·q·eₖ) by products.
    pub(crate) fn otf(&self, u: f64, v: f64) -> f64 {
        let n = self.edges.len();
        let mut zc = [1.0f64; MAX_EDGES];
        let mut zs = [0.0f64; MAX_EDGES];
        let mut sc = [1.0f64; MAX_EDGES];
        for k in 0..n {
            let e = self.edges[k];
            let p = u * e[0] + v * e[1];
            let (s, c) = sincospi(p);
            zc[k] = c;
            zs[k] = s;
            sc[k] = sinc_from_sinpi(p, s);
        }
        let mut sum = 0.0;
        for t in &self.tiles {
            let (mut re, mut im) = (1.0f64, 0.0f64);
            for k in 0..n {
                let s = match t.signs[k] {
                    0 => continue,
                    1 => zs[k],
                    _ => -zs[k],
                };
                let c = zc[k];
                (re, im) = (re * c - im * s, re * s + im * c);
            }
            sum += t.weight * sc[t.i] * sc[t.j] * re;
        }
        sum
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn square_is_one_tile_and_hexagon_area_is_right() {
        let z = Zonogon::from_edges(&[[2.0, 0.0], [0.0, 3.0]]);
        assert_eq!(z.area(), 6.0);
        assert_eq!(z.otf(0.0, 0.0), 1.0);
        let s = 1.0 / 3f64.sqrt();
        let h = Zonogon::from_edges(&[[s / 2.0, 0.5], [-s / 2.0, 0.5], [-s, 0.0]]);
        assert!((h.area() - 3f64.sqrt() / 2.0).abs() < 1e-15);
    }
}
