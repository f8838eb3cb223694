//! The 2-D model MTF as an image (`sweepmtf model --map`): |OTF(u,v)| on a
//! square grid −f_max..f_max in both axes (u right, v up, cycles/mm), drawn
//! with the viridis colour map, a colour bar, axes in lp/mm, contour lines at
//! MTF = 0.1 and 0.5, and the Nyquist rectangle when the system has a grid.
//! The grid is evaluated in parallel (rayon).

use super::model_io::{OutputError, encode_png, write_atomic};
use crate::model::System;
use crate::plot::{FONT, ensure_font};
use plotters::prelude::*;
use rayon::prelude::*;
use std::ops::Range;
use std::path::Path;

/// A square map of the system MTF.
#[derive(Debug, Clone)]
pub struct MtfMap {
    /// Samples per side.
    pub size: usize,
    /// Half-width of the map, cycles/mm: u, v ∈ [−f_max, f_max].
    pub f_max: f64,
    /// MTF, row-major; row 0 is the top (v = +f_max), column 0 the left (u = −f_max).
    pub mtf: Vec<f64>,
    /// Nyquist frequencies (u, v) of the system's grid, cycles/mm.
    pub nyquist: Option<(f64, f64)>,
}

impl MtfMap {
    /// Frequency of pixel centre `i` (0..size) along an axis, cycles/mm.
    pub fn coord(&self, i: usize) -> f64 {
        self.f_max * ((2 * i + 1) as f64 / self.size as f64 - 1.0)
    }
}

/// Evaluates |OTF| of `system` on a `size`×`size` grid of pixel centres spanning ±f_max.
pub fn compute_map(system: &System, f_max: f64, size: usize) -> MtfMap {
    let size = size.max(2);
    let mut map = MtfMap {
        size,
        f_max,
        mtf: vec![0.0; size * size],
        nyquist: system.nyquist(),
    };
    // Pixel centres symmetric about 0 exactly, so that row size−1−r is row r
    // reversed: every real PSF has OTF(−u,−v) = conj OTF(u,v), hence equal MTF.
    let mut coords: Vec<f64> = (0..size).map(|i| map.coord(i)).collect();
    for i in 0..size / 2 {
        coords[size - 1 - i] = -coords[i];
    }
    if size % 2 == 1 {
        coords[size / 2] = 0.0;
    }
    let half = size.div_ceil(2);
    map.mtf[..half * size]
        .par_chunks_mut(size)
        .enumerate()
        .for_each(|(row, out)| {
            let v = coords[size - 1 - row];
            for (o, &u) in out.iter_mut().zip(&coords) {
                *o = system.mtf(u, v);
            }
        });
    let (top, bottom) = map.mtf.split_at_mut(half * size);
    for (k, dst) in bottom.chunks_mut(size).enumerate() {
        // bottom row k is image row half + k, the mirror of row size − 1 − (half + k).
        let src_row = size - 1 - (half + k);
        let src = &top[src_row * size..(src_row + 1) * size];
        for (d, s) in dst.iter_mut().zip(src.iter().rev()) {
            *d = *s;
        }
    }
    map
}

/// Viridis colour map at t ∈ [0, 1] (piecewise linear through 9 anchors).
pub fn viridis(t: f64) -> [u8; 3] {
    const A: [[f64; 3]; 9] = [
        [68.0, 1.0, 84.0],
        [71.0, 44.0, 122.0],
        [59.0, 81.0, 139.0],
        [44.0, 113.0, 142.0],
        [33.0, 144.0, 141.0],
        [39.0, 173.0, 129.0],
        [92.0, 200.0, 99.0],
        [170.0, 220.0, 50.0],
        [253.0, 231.0, 37.0],
    ];
    let t = if t.is_nan() { 0.0 } else { t.clamp(0.0, 1.0) } * 8.0;
    let i = (t.floor() as usize).min(7);
    let f = t - i as f64;
    let mut c = [0u8; 3];
    for k in 0..3 {
        c[k] = (A[i][k] + f * (A[i + 1][k] - A[i][k])).round() as u8;
    }
    c
}

/// Contour levels drawn on the map.
pub const CONTOURS: [f64; 2] = [0.1, 0.5];

/// Width of the colour-bar area to the right of the map, pixels.
const BAR_AREA: u32 = 160;

struct Layout {
    width: u32,
    height: u32,
    map_px: (Range<i32>, Range<i32>),
    bar_px: (Range<i32>, Range<i32>),
}

fn draw_frame(buf: &mut [u8], map: &MtfMap, title: &str, w: u32, h: u32) -> Result<Layout, String> {
    let root = BitMapBackend::with_buffer(buf, (w, h)).into_drawing_area();
    let e = |e: DrawingAreaErrorKind<_>| format!("{e}");
    root.fill(&WHITE).map_err(e)?;
    let (left, right) = root.split_horizontally(w as i32 - BAR_AREA as i32);
    let f = map.f_max;
    let mut chart = ChartBuilder::on(&left)
        .caption(title, (FONT, 24))
        .margin(12)
        .x_label_area_size(56)
        .y_label_area_size(76)
        .build_cartesian_2d(-f..f, -f..f)
        .map_err(e)?;
    chart
        .configure_mesh()
        .disable_mesh()
        .x_desc("u (lp/mm)")
        .y_desc("v (lp/mm)")
        .label_style((FONT, 16))
        .axis_desc_style((FONT, 18))
        .draw()
        .map_err(e)?;
    let map_px = chart.plotting_area().get_pixel_range();
    // The colour bar spans exactly the map's height.
    let mut bar = ChartBuilder::on(&right)
        .margin_top(map_px.1.start as u32)
        .margin_bottom(h.saturating_sub(map_px.1.end as u32))
        .margin_left(8)
        .margin_right(BAR_AREA - 8 - 50 - 36)
        .y_label_area_size(50)
        .build_cartesian_2d(0.0..1.0f64, 0.0..1.0f64)
        .map_err(e)?;
    bar.configure_mesh()
        .disable_mesh()
        .disable_x_axis()
        .y_desc("MTF")
        .y_labels(11)
        .y_label_formatter(&|v| format!("{v:.1}"))
        .label_style((FONT, 15))
        .axis_desc_style((FONT, 16))
        .draw()
        .map_err(e)?;
    let note = (FONT, 14).into_font().color(&RGBColor(60, 60, 60));
    let y0 = map_px.1.end + 14;
    right
        .draw(&Text::new("white: MTF 0.1, 0.5", (8, y0), note.clone()))
        .map_err(e)?;
    if map.nyquist.is_some() {
        right
            .draw(&Text::new("dashed: Nyquist", (8, y0 + 18), note))
            .map_err(e)?;
    }
    let bar_px = bar.plotting_area().get_pixel_range();
    root.present().map_err(e)?;
    Ok(Layout {
        width: w,
        height: h,
        map_px,
        bar_px,
    })
}

fn put(buf: &mut [u8], w: u32, x: i32, y: i32, c: [u8; 3]) {
    let i = (y as usize * w as usize + x as usize) * 3;
    buf[i..i + 3].copy_from_slice(&c);
}

/// Renders the map as PNG bytes (plot area one pixel per sample, at least 512 pixels wide).
pub fn render_map(map: &MtfMap, title: &str) -> Result<Vec<u8>, String> {
    ensure_font();
    // Small maps are shown enlarged (nearest sample) so the frame stays legible.
    let n = (map.size as u32).max(512);
    // Chart margins around an n×n plot area (see draw_frame): left 12+76,
    // right 12 + colour bar area, top 12 + caption, bottom 12+56.
    let w = n + 12 + 76 + 12 + BAR_AREA;
    let h = n + 12 + 40 + 12 + 56;
    let mut buf = vec![255u8; (w * h * 3) as usize];
    let lay = draw_frame(&mut buf, map, title, w, h)?;
    let (xr, yr) = (lay.map_px.0.clone(), lay.map_px.1.clone());
    let (pw, ph) = ((xr.end - xr.start).max(1), (yr.end - yr.start).max(1));
    let at = |px: i32, py: i32| -> (usize, usize) {
        let col = (((px - xr.start) as f64 + 0.5) / pw as f64 * map.size as f64) as usize;
        let row = (((py - yr.start) as f64 + 0.5) / ph as f64 * map.size as f64) as usize;
        (col.min(map.size - 1), row.min(map.size - 1))
    };
    let value = |c: usize, r: usize| map.mtf[r * map.size + c];
    for py in yr.clone() {
        for px in xr.clone() {
            let (c, r) = at(px, py);
            let v = value(c, r);
            let mut colour = viridis(v);
            // Contours: a level between this pixel's sample and that of the
            // pixel to its right or below (1 pixel wide, also when enlarged).
            let (cr, rr) = at((px + 1).min(xr.end - 1), py);
            let (cd, rd) = at(px, (py + 1).min(yr.end - 1));
            let right = value(cr, rr);
            let down = value(cd, rd);
            for lev in CONTOURS {
                let cross = |a: f64, b: f64| (a - lev) * (b - lev) < 0.0;
                if cross(v, right) || cross(v, down) {
                    colour = [255, 255, 255];
                }
            }
            put(&mut buf, lay.width, px, py, colour);
        }
    }
    // Nyquist rectangle, dashed light grey.
    if let Some((nu, nv)) = map.nyquist {
        let to_px = |u: f64| xr.start as f64 + (u + map.f_max) / (2.0 * map.f_max) * pw as f64;
        let to_py = |v: f64| yr.start as f64 + (map.f_max - v) / (2.0 * map.f_max) * ph as f64;
        let (x0, x1) = (to_px(-nu).round() as i32, to_px(nu).round() as i32);
        let (y0, y1) = (to_py(nv).round() as i32, to_py(-nv).round() as i32);
        let grey = [230, 230, 230];
        let inside = |x: i32, y: i32| xr.contains(&x) && yr.contains(&y);
        for x in x0..=x1 {
            if (x - x0) % 12 < 7 {
                for y in [y0, y1] {
                    if inside(x, y) {
                        put(&mut buf, lay.width, x, y, grey);
                    }
                }
            }
        }
        for y in y0..=y1 {
            if (y - y0) % 12 < 7 {
                for x in [x0, x1] {
                    if inside(x, y) {
                        put(&mut buf, lay.width, x, y, grey);
                    }
                }
            }
        }
    }
    // Colour bar, with white ticks at the contour levels.
    let (bx, by) = (lay.bar_px.0.clone(), lay.bar_px.1.clone());
    let bh = (by.end - by.start).max(1) as f64;
    for py in by.clone() {
        let t = 1.0 - ((py - by.start) as f64 + 0.5) / bh;
        let mut c = viridis(t);
        if CONTOURS
            .iter()
            .any(|&l| ((1.0 - l) * bh).round() as i32 == py - by.start)
        {
            c = [255, 255, 255];
        }
        for px in bx.clone() {
            put(&mut buf, lay.width, px, py, c);
        }
    }
    encode_png(&buf, lay.width, lay.height)
}

/// Renders the map and writes it to `path` (PNG), atomically.
pub fn write_map_png(map: &MtfMap, title: &str, path: &Path) -> Result<(), OutputError> {
    let bytes = render_map(map, title).map_err(|c| OutputError::new(path, c))?;
    write_atomic(path, &bytes)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn map_matches_direct_evaluation_including_the_mirrored_half() {
        use crate::model::spec::parse_factor;
        let system = System {
            factors: vec![
                parse_factor("aperture", "L:A=5um,B=5um,a=2um,b=1um").unwrap(),
                parse_factor("cte", "n=100,cti=0.01,pitch=5um,model=exact").unwrap(),
            ],
        };
        for size in [7, 8] {
            let m = compute_map(&system, 300.0, size);
            for r in 0..size {
                for c in 0..size {
                    let (u, v) = (m.coord(c), m.coord(size - 1 - r));
                    let want = system.mtf(u, v);
                    assert!((m.mtf[r * size + c] - want).abs() < 1e-14, "{size} {r} {c}");
                }
            }
        }
    }

    #[test]
    fn viridis_ends() {
        assert_eq!(viridis(0.0), [68, 1, 84]);
        assert_eq!(viridis(1.0), [253, 231, 37]);
        assert_eq!(viridis(f64::NAN), [68, 1, 84]);
    }
}
