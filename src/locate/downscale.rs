//! The reduced search image: a k×k box average of the plane, so that the
//! search works on about 640 samples across the short side whatever the
//! sensor (a 24-megapixel frame is reduced 6×; small images are used as is).

use super::sample::Gray;
use crate::photo::Plane;
use rayon::prelude::*;
use std::borrow::Cow;

/// Short side (samples) the search image is reduced to, at most.
pub const SEARCH_SHORT_SIDE: usize = 640;

/// The box factor used for a plane of this size.
pub fn factor(width: usize, height: usize) -> usize {
    (width.min(height) / SEARCH_SHORT_SIDE).max(1)
}

/// The plane reduced by [`factor`] (borrowed when the factor is 1).
pub fn reduce_for_search(plane: &Plane) -> Gray<'_> {
    let k = factor(plane.width, plane.height);
    let full = Gray::of_plane(plane);
    if k == 1 {
        return full;
    }
    box_reduce(&full, k)
}

/// A k×k box average (trailing samples that do not fill a box are dropped).
pub fn box_reduce(g: &Gray<'_>, k: usize) -> Gray<'static> {
    let (w, h) = (g.w / k, g.h / k);
    let mut out = vec![0.0f32; w * h];
    let inv = 1.0 / (k * k) as f32;
    let src = &g.data;
    out.par_chunks_mut(w.max(1))
        .enumerate()
        .for_each(|(j, row)| {
            let mut acc = vec![0.0f32; w];
            for r in 0..k {
                let line = &src[(j * k + r) * g.w..(j * k + r) * g.w + w * k];
                add_box_sums(&mut acc, line, k);
            }
            for (o, a) in row.iter_mut().zip(acc) {
                *o = a * inv;
            }
        });
    Gray {
        w,
        h,
        data: Cow::Owned(out),
        origin: g.origin,
        scale: [g.scale[0] * k as f64, g.scale[1] * k as f64],
    }
}

/// Adds to each `acc[i]` the sum of `line[k·i .. k·i + k]`, summed left to
/// right (as `chunk.iter().sum()`), so every box average is the same to the bit
/// whichever way its rows are read. Unrolled for the usual factors.
#[inline]
pub fn add_box_sums(acc: &mut [f32], line: &[f32], k: usize) {
    match k {
        2 => add_sums::<2>(acc, line),
        3 => add_sums::<3>(acc, line),
        4 => add_sums::<4>(acc, line),
        5 => add_sums::<5>(acc, line),
        6 => add_sums::<6>(acc, line),
        7 => add_sums::<7>(acc, line),
        8 => add_sums::<8>(acc, line),
        _ => {
            for (a, chunk) in acc.iter_mut().zip(line.chunks_exact(k)) {
                *a += chunk.iter().sum::<f32>();
            }
        }
    }
}

#[inline(always)]
fn add_sums<const K: usize>(acc: &mut [f32], line: &[f32]) {
    for (a, chunk) in acc.iter_mut().zip(line.chunks_exact(K)) {
        let c: &[f32; K] = chunk.try_into().expect("chunks_exact gives K");
        let mut s = c[0];
        for &v in &c[1..] {
            s += v;
        }
        *a += s;
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn reduced_grid_maps_to_box_centres() {
        // A linear ramp in x: the reduced sample's value equals the ramp at its image position.
        let (w, h) = (2000, 1400);
        let data: Vec<f32> = (0..w * h).map(|i| (i % w) as f32 + 0.5).collect();
        let p = Plane::full(w, h, data);
        let g = reduce_for_search(&p);
        assert_eq!(g.scale, [2.0, 2.0]);
        for (i, j) in [(0, 0), (17, 5), (999, 699)] {
            let c = g.to_img([i as f64 + 0.5, j as f64 + 0.5]);
            assert!((g.at(i, j) as f64 - c[0]).abs() < 1e-3, "{i} {j}");
        }
    }
}
