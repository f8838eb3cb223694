//! The exact truth of a shot: for every sweep, the presampling MTF the image
//! should show along the sweep direction, sampled along the strip's centre
//! line; for every sine patch, its image frequency and MTF.
//!
//! A chart phase φ(X) appears in the image as ψ(x) = φ(H⁻¹(x)), so the image's
//! local frequency vector is ∇ψ = J⁻ᵀ·∇φ, J the homography's Jacobian at the
//! chart point (image px per chart mm). The MTF is |OTF| at that vector (with
//! perspective it changes along the strip and is evaluated on the centre line).
//! With lens distortion D (photo = D(undistorted)), J becomes J_D·J_H (the
//! distortion's Jacobian at the undistorted point times the homography's), and
//! every position is reported where it lands in the photo: distortion moves
//! the pattern and changes its local frequency, never the OTF.

use super::nuisance::Sharpen;
use super::render::Optics;
use crate::distortion::Lens;
use crate::geometry::{Homography, Point};
use crate::print_mtf::PrintMtf;
use crate::target::{Direction, Rect, Target};
use serde::Serialize;

/// One row of a sweep's truth curve.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct TruthRow {
    /// Image frequency along the sweep, cycles/pixel.
    pub freq_cy_px: f64,
    /// Presampling MTF at that frequency vector.
    pub mtf: f64,
    /// Distance along the sweep from its low-frequency edge, chart mm.
    pub s_mm: f64,
    /// Frequency on the sensor, cycles/mm.
    pub freq_cy_mm: f64,
    /// Frequency printed on the chart, cycles/mm of chart.
    pub chart_freq_cy_mm: f64,
    /// Image x of the point on the strip's centre line, pixels.
    pub x_px: f64,
    /// Image y of the point on the strip's centre line, pixels.
    pub y_px: f64,
    /// The print's MTF at `chart_freq_cy_mm` (shots with a print blur only;
    /// the image's modulation is `mtf` × this × the chart contrast).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub print_mtf: Option<f64>,
}

/// The truth's MTF at `f` cycles/pixel: linear between `rows` (sorted by
/// frequency, at least two), continued along the end segments beyond them.
pub fn mtf_at(rows: &[TruthRow], f: f64) -> f64 {
    let i = rows
        .partition_point(|r| r.freq_cy_px < f)
        .clamp(1, rows.len() - 1);
    let (a, b) = (&rows[i - 1], &rows[i]);
    a.mtf + (b.mtf - a.mtf) * (f - a.freq_cy_px) / (b.freq_cy_px - a.freq_cy_px)
}

/// The truth of one sweep strip.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct SweepTruth {
    /// The sweep's id in the target.
    pub id: String,
    /// The strip's corners in image pixels, corners 1 and 4 on the low-frequency edge, going round.
    pub roi: [f64; 8],
    /// The printed modulation of the sweep.
    pub chart_contrast: f64,
    /// The curve, in order of rising `s_mm`.
    pub rows: Vec<TruthRow>,
}

/// The truth of one constant-frequency sine patch.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct PatchTruth {
    /// The patch's id in the target.
    pub id: String,
    /// The patch's corners in image pixels (its rectangle's corners, going round).
    pub corners: [f64; 8],
    /// Image frequency vector at the patch centre, cycles/pixel (x right, y down).
    pub freq_vec_cy_px: [f64; 2],
    /// Its length, cycles/pixel.
    pub freq_cy_px: f64,
    /// Presampling MTF there.
    pub mtf: f64,
    /// The printed modulation.
    pub chart_contrast: f64,
    /// The modulation the (noiseless, unclipped) image shows: mtf × chart contrast (× the print's MTF).
    pub modulation: f64,
}

/// The image frequency vector (cy/px, x right, y down) of a chart phase gradient `g` (cy/mm) at chart point `p`.
pub fn image_freq(h: &Homography, p: Point, g: [f64; 2]) -> [f64; 2] {
    image_freq_lens(h, None, p, g)
}

/// As [`image_freq`], in the photo of a lens with distortion `lens` (chart → H → undistorted → photo).
pub fn image_freq_lens(h: &Homography, lens: Option<&Lens>, p: Point, g: [f64; 2]) -> [f64; 2] {
    let mut j = h.jacobian(p);
    if let Some(l) = lens {
        let d = l.jacobian(h.apply(p));
        j = [
            [
                d[0][0] * j[0][0] + d[0][1] * j[1][0],
                d[0][0] * j[0][1] + d[0][1] * j[1][1],
            ],
            [
                d[1][0] * j[0][0] + d[1][1] * j[1][0],
                d[1][0] * j[0][1] + d[1][1] * j[1][1],
            ],
        ];
    }
    let det = j[0][0] * j[1][1] - j[0][1] * j[1][0];
    [
        (j[1][1] * g[0] - j[1][0] * g[1]) / det,
        (-j[0][1] * g[0] + j[0][0] * g[1]) / det,
    ]
}

fn flat(q: [Point; 4]) -> [f64; 8] {
    [
        q[0][0], q[0][1], q[1][0], q[1][1], q[2][0], q[2][1], q[3][0], q[3][1],
    ]
}

/// A rectangle's corners going round, starting on the edge where `s` = 0 (corners 1 and 4 on it).
fn strip_corners(r: &Rect, dir: Direction) -> [Point; 4] {
    let (x0, y0, x1, y1) = (r.x_mm, r.y_mm, r.x_mm + r.width_mm, r.y_mm + r.height_mm);
    match dir {
        Direction::X => [[x0, y0], [x1, y0], [x1, y1], [x0, y1]],
        Direction::Y => [[x1, y0], [x1, y1], [x0, y1], [x0, y0]],
    }
}

/// The corners of a chart quadrilateral mapped to image pixels, flattened.
pub fn quad_px(h: &Homography, q: [Point; 4]) -> [f64; 8] {
    quad_px_lens(h, None, q)
}

/// Where a chart point lands in the photo: the homography, then the lens's distortion.
pub fn photo_point(h: &Homography, lens: Option<&Lens>, p: Point) -> Point {
    let q = h.apply(p);
    lens.map_or(q, |l| l.distort(q))
}

/// The corners of a chart quadrilateral where they land in the photo, flattened.
pub fn quad_px_lens(h: &Homography, lens: Option<&Lens>, q: [Point; 4]) -> [f64; 8] {
    flat(q.map(|p| photo_point(h, lens, p)))
}

/// Truth curves of every sweep in `target` and truths of every sine patch.
pub fn truths(
    target: &Target,
    h: &Homography,
    lens: Option<&Lens>,
    optics: &Optics,
    sharpen: Option<&Sharpen>,
    print: Option<&PrintMtf>,
) -> (Vec<SweepTruth>, Vec<PatchTruth>) {
    let gain = |k: [f64; 2]| sharpen.map_or(1.0, |s| s.gain(k[0], k[1]));
    let pitch = optics.pitch_mm;
    let sweeps = target
        .sweeps
        .iter()
        .map(|sw| {
            let r = sw.rect;
            let len = sw.length_mm();
            let a = h.apply(strip_corners(&r, sw.direction)[0]);
            let b = h.apply(strip_corners(&r, sw.direction)[1]);
            let n = ((a[0] - b[0]).hypot(a[1] - b[1]).ceil() as usize + 1).clamp(65, 4001);
            let rows = (0..n)
                .map(|i| {
                    let s = len * i as f64 / (n - 1) as f64;
                    let f = sw.freq_at(s);
                    let (p, g) = match sw.direction {
                        Direction::X => ([r.x_mm + s, r.y_mm + r.height_mm / 2.0], [f, 0.0]),
                        Direction::Y => ([r.x_mm + r.width_mm / 2.0, r.y_mm + s], [0.0, f]),
                    };
                    let k = image_freq_lens(h, lens, p, g);
                    let q = photo_point(h, lens, p);
                    let fpx = k[0].hypot(k[1]);
                    TruthRow {
                        freq_cy_px: fpx,
                        mtf: optics.otf_cy_px(k[0], k[1]).norm() * gain(k),
                        s_mm: s,
                        freq_cy_mm: fpx / pitch,
                        chart_freq_cy_mm: f,
                        x_px: q[0],
                        y_px: q[1],
                        print_mtf: print.map(|p| p.mtf(f)),
                    }
                })
                .collect();
            SweepTruth {
                id: sw.id.clone(),
                roi: quad_px_lens(h, lens, strip_corners(&r, sw.direction)),
                chart_contrast: sw.contrast,
                rows,
            }
        })
        .collect();
    let patches = target
        .patches
        .iter()
        .map(|p| {
            let r = p.rect;
            let c = [r.x_mm + r.width_mm / 2.0, r.y_mm + r.height_mm / 2.0];
            let g = match p.direction {
                Direction::X => [p.freq_cy_mm, 0.0],
                Direction::Y => [0.0, p.freq_cy_mm],
            };
            let k = image_freq_lens(h, lens, c, g);
            let mtf = optics.otf_cy_px(k[0], k[1]).norm() * gain(k);
            PatchTruth {
                id: p.id.clone(),
                corners: quad_px_lens(h, lens, r.corners()),
                freq_vec_cy_px: k,
                freq_cy_px: k[0].hypot(k[1]),
                mtf,
                chart_contrast: p.contrast,
                modulation: mtf * p.contrast * print.map_or(1.0, |q| q.mtf(p.freq_cy_mm)),
            }
        })
        .collect();
    (sweeps, patches)
}

/// A sweep's truth curve as CSV text: `freq_cy_px,mtf,s_mm,freq_cy_mm,chart_freq_cy_mm,x_px,y_px`
/// (+ `print_mtf` for a shot with a print blur).
pub fn truth_csv(t: &SweepTruth) -> Result<Vec<u8>, csv::Error> {
    let mut w = csv::Writer::from_writer(Vec::new());
    for r in &t.rows {
        w.serialize(r)?;
    }
    w.into_inner().map_err(|e| e.into_error().into())
}

/// One row of the sine patches' truth table.
#[derive(Debug, Serialize)]
struct PatchRow<'a> {
    id: &'a str,
    freq_cy_px: f64,
    mtf: f64,
    freq_cy_mm: f64,
    chart_contrast: f64,
    modulation: f64,
    x_px: f64,
    y_px: f64,
}

/// The sine patches' truth as CSV text:
/// `id,freq_cy_px,mtf,freq_cy_mm,chart_contrast,modulation,x_px,y_px` (x, y: the patch centre).
pub fn patches_csv(patches: &[PatchTruth], pitch_mm: f64) -> Result<Vec<u8>, csv::Error> {
    let mut w = csv::Writer::from_writer(Vec::new());
    for p in patches {
        let c = &p.corners;
        w.serialize(PatchRow {
            id: &p.id,
            freq_cy_px: p.freq_cy_px,
            mtf: p.mtf,
            freq_cy_mm: p.freq_cy_px / pitch_mm,
            chart_contrast: p.chart_contrast,
            modulation: p.modulation,
            x_px: (c[0] + c[2] + c[4] + c[6]) / 4.0,
            y_px: (c[1] + c[3] + c[5] + c[7]) / 4.0,
        })?;
    }
    w.into_inner().map_err(|e| e.into_error().into())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn image_frequency_of_a_scaled_rotated_chart() {
        // 4 px/mm, rotated 90° counter-clockwise: chart +x goes to image −y.
        let src = crate::geometry::rect_corners(0.0, 0.0, 10.0, 10.0);
        let dst = [[0.0, 40.0], [0.0, 0.0], [40.0, 0.0], [40.0, 40.0]];
        let h = Homography::from_quads(&src, &dst).unwrap();
        let k = image_freq(&h, [5.0, 5.0], [1.0, 0.0]);
        assert!(k[0].abs() < 1e-12 && (k[1] + 0.25).abs() < 1e-12, "{k:?}");
    }
}
