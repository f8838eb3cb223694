//! Centrally symmetric polygons (zonogons: rectangle, rhomb, regular hexagon
//! and octagon) as tilings by parallelograms. The OTF is the area-weighted sum
//! of the parallelograms' transforms, sinc(q·e₁)·sinc(q·e₂)·cos(2πq·c): every
//! term is bounded by its weight and all weights are positive, so the sum has
//! no cancellation at low frequency and no 1/u or 1/v anywhere.

use crate::model::special::{cospi, sinc};

/// One parallelogram of the tiling: its share of the area, edges and centre (mm).
#[derive(Debug, Clone)]
struct Tile {
    weight: f64,
    e1: [f64; 2],
    e2: [f64; 2],
    centre: [f64; 2],
}

/// A zonogon centred on the origin, tiled by parallelograms.
#[derive(Debug, Clone)]
pub(crate) struct Zonogon {
    tiles: Vec<Tile>,
    #[cfg_attr(not(test), allow(dead_code))]
    area: f64,
}

fn dot(u: f64, v: f64, p: [f64; 2]) -> f64 {
    u * p[0] + v * p[1]
}

impl Zonogon {
    /// Builds the zonogon whose counter-clockwise boundary starts with the edge
    /// vectors `edges` (mm) and continues with their negatives; centred on 0.
    ///
    /// Tile (i, j), i < j, spans eᵢ, eⱼ from P₀ + Σ_{k<i} eₖ + Σ_{k>j} eₖ.
    pub(crate) fn from_edges(edges: &[[f64; 2]]) -> Zonogon {
        let n = edges.len();
        let sum = edges
            .iter()
            .fold([0.0, 0.0], |s, e| [s[0] + e[0], s[1] + e[1]]);
        let p0 = [-0.5 * sum[0], -0.5 * sum[1]];
        let mut raw = Vec::new();
        let mut area = 0.0;
        for i in 0..n {
            for j in i + 1..n {
                let mut base = p0;
                for (k, e) in edges.iter().enumerate() {
                    if k < i || k > j {
                        base[0] += e[0];
                        base[1] += e[1];
                    }
                }
                let (a, b) = (edges[i], edges[j]);
                let w = (a[0] * b[1] - a[1] * b[0]).abs();
                area += w;
                let centre = [base[0] + 0.5 * (a[0] + b[0]), base[1] + 0.5 * (a[1] + b[1])];
                raw.push((w, a, b, centre));
            }
        }
        let tiles = raw
            .into_iter()
            .map(|(w, e1, e2, centre)| Tile {
                weight: w / area,
                e1,
                e2,
                centre,
            })
            .collect();
        Zonogon { tiles, area }
    }

    /// The area, mm².
    #[cfg(test)]
    pub(crate) fn area(&self) -> f64 {
        self.area
    }

    /// The (real) OTF at (u, v), cycles/mm.
    pub(crate) fn otf(&self, u: f64, v: f64) -> f64 {
        self.tiles
            .iter()
            .map(|t| {
                t.weight
                    * sinc(dot(u, v, t.e1))
                    * sinc(dot(u, v, t.e2))
                    * cospi(2.0 * dot(u, v, t.centre))
            })
            .sum()
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
