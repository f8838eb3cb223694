//! Chart layout: where sweeps, sine patches, grey patches, fiducials, ticks
//! and labels go on a landscape page, as a [`Target`] description plus the
//! human-readable marks, all in the chart frame (mm, origin top-left).
//!
//! Conventions other modules rely on: four fiducials centred one diameter in
//! from both edges (ids tl, tr, br, bl; tl is a ring, the rest disks),
//! diameter 4 % of the short side, the square within one diameter of each
//! centre left to the fiducial; sweeps and patches vary along x (frequency
//! rising left to right); grey patches "white" = mean·(1+c) and "black" =
//! mean·(1−c) of the main (first) contrast, plus grey steps. Labels and
//! ticks lie only in bands the description leaves as background.

mod spec;
#[cfg(test)]
mod tests;

use super::ChartError;
use super::labels::{Align, TextLabel, format_freq, text_size_mm};
use crate::target::{
    Direction, Fiducial, FiducialKind, GreyPatch, Rect, SinePatch, Sweep, SweepLaw, Target,
};

use spec::check_spec;
pub use spec::{ChartSpec, Law};

/// A laid-out chart: the description plus human-readable marks and the raster size.
#[derive(Debug, Clone)]
pub struct Chart {
    /// The target description (what `measure` and `simulate` read).
    pub target: Target,
    /// Text labels (title, frequency numbers), all on background.
    pub texts: Vec<TextLabel>,
    /// Tick marks (filled black rectangles, mm), all on background.
    pub ticks: Vec<Rect>,
    /// Printer resolution (dots per inch).
    pub dpi: u32,
    /// Raster width (pixels).
    pub width_px: usize,
    /// Raster height (pixels).
    pub height_px: usize,
    /// Printer dots per cycle at the highest frequency.
    pub dots_per_cycle: f64,
    /// Things the user should know (few dots per cycle, few cycles in a patch).
    pub warnings: Vec<String>,
}

/// Grey steps (linear reflectance) besides white and black.
pub const GREY_STEPS: [f64; 6] = [0.05, 0.1, 0.2, 0.35, 0.5, 0.7];

/// Candidate tick frequencies in [lo, hi], most important first.
fn tick_candidates(law: Law, lo: f64, hi: f64) -> Vec<f64> {
    let mut out = vec![lo, hi];
    let inside = |f: f64| f >= lo * (1.0 - 1e-9) && f <= hi * (1.0 + 1e-9);
    match law {
        Law::Linear => {
            let raw = (hi - lo) / 8.0;
            let mag = 10f64.powf(raw.log10().floor());
            let step = [1.0, 2.0, 5.0, 10.0]
                .iter()
                .map(|m| m * mag)
                .find(|&s| s >= raw)
                .unwrap_or(10.0 * mag);
            let mut f = (lo / step).ceil() * step;
            while f <= hi * (1.0 + 1e-12) {
                out.push(f);
                f += step;
            }
        }
        _ => {
            for mants in [&[1.0][..], &[2.0, 5.0], &[3.0], &[1.5, 4.0, 6.0, 8.0]] {
                let k0 = lo.log10().floor() as i32 - 1;
                let k1 = hi.log10().ceil() as i32 + 1;
                for k in k0..=k1 {
                    for m in mants {
                        let f = m * 10f64.powi(k);
                        if inside(f) {
                            out.push(f);
                        }
                    }
                }
            }
        }
    }
    out
}

struct Builder {
    texts: Vec<TextLabel>,
    ticks: Vec<Rect>,
}

impl Builder {
    /// Places tick marks and numbers under a sweep (x positions from the sweep law).
    #[allow(clippy::too_many_arguments)]
    fn sweep_ticks(
        &mut self,
        sw: &Sweep,
        law: Law,
        band_y: f64,
        th: f64,
        caption: &str,
        caption_above: bool,
        w: f64,
    ) {
        let tick_w = 0.3f64.max(th * 0.08);
        let tick_len = 0.6 * th;
        let num_y = band_y + tick_len + 0.15 * th;
        let mut taken: Vec<(f64, f64)> = vec![];
        if caption_above {
            // In the free gap above the strip, left-aligned.
            let h = text_size_mm(caption, th).1;
            self.texts.push(TextLabel {
                text: caption.to_string(),
                x_mm: sw.rect.x_mm,
                y_mm: sw.rect.y_mm - 0.25 * th - h,
                height_mm: th,
                align: Align::Left,
            });
        } else {
            // Right-aligned at the sweep's end, among the numbers.
            let cap = TextLabel {
                text: caption.to_string(),
                x_mm: sw.rect.x_mm + sw.rect.width_mm,
                y_mm: num_y,
                height_mm: th,
                align: Align::Right,
            };
            let cr = cap.rect();
            taken.push((cr.x_mm, cr.x_mm + cr.width_mm));
            self.texts.push(cap);
        }
        let sep = 0.6 * th;
        let mut n = 0;
        for f in tick_candidates(law, sw.f_min_cy_mm, sw.f_max_cy_mm) {
            if n >= 30 {
                break;
            }
            let x = sw.rect.x_mm + sw.s_at_freq(f);
            let label = TextLabel {
                text: format_freq(f),
                x_mm: x,
                y_mm: num_y,
                height_mm: th,
                align: Align::Center,
            };
            let r = label.rect();
            let (a, b) = (r.x_mm - sep, r.x_mm + r.width_mm + sep);
            if r.x_mm < 0.5 || r.x_mm + r.width_mm > w - 0.5 {
                continue;
            }
            if taken.iter().any(|&(p, q)| a < q && b > p) {
                continue;
            }
            taken.push((r.x_mm, r.x_mm + r.width_mm));
            self.texts.push(label);
            self.ticks.push(Rect {
                x_mm: x - tick_w / 2.0,
                y_mm: band_y,
                width_mm: tick_w,
                height_mm: tick_len,
            });
            n += 1;
        }
    }
}

/// Lays out a chart; checks every parameter and that the page is big enough.
pub fn layout(spec: &ChartSpec) -> Result<Chart, ChartError> {
    let (dpc, mut warnings) = check_spec(spec)?;
    let (w, h) = (spec.width_mm, spec.height_mm);
    let px = |mm: f64| (mm * spec.dpi as f64 / 25.4).round();
    let (wpx, hpx) = (px(w), px(h));
    if wpx > u32::MAX as f64 || hpx > u32::MAX as f64 {
        return Err(ChartError::TooLarge(format!(
            "{w}×{h} mm at {} dpi is {wpx}×{hpx} pixels, beyond 2^32 per side",
            spec.dpi
        )));
    }
    let short = w.min(h);
    let d = 0.04 * short;
    let th = (0.0125 * short).clamp(1.2, 6.0);
    let text_h = text_size_mm("0123456789.", th).1;
    let mx = d;
    let top = 2.5 * d;
    let bottom = h - 2.5 * d;
    let tick_len = 0.6 * th;
    let band = 0.4 * th + tick_len + 0.15 * th + text_h + 0.3 * th;
    let grey_label_band = 0.3 * th + text_h + 0.3 * th;
    let per_contrast = if spec.law == Law::Patches { 2 } else { 1 };
    let n_rows = spec.contrasts.len() * per_contrast;
    let grey_h = (0.1 * h).clamp(4.0, 30.0);
    let min_gap = (0.01 * h).max(1.0);
    // Sweeps carry a caption line above the strip (patches caption their first label).
    let cap_h = if spec.law == Law::Patches {
        0.0
    } else {
        text_h + 0.5 * th
    };
    let fixed = grey_h + grey_label_band + n_rows as f64 * (band + cap_h + min_gap);
    let avail = bottom - top - fixed;
    let sh = (avail / n_rows as f64).min(0.3 * h);
    if sh < 3.0 || w - 2.0 * mx < 20.0 {
        return Err(ChartError::TooLarge(format!(
            "a {w}×{h} mm chart is too small for {n_rows} row(s) of sines, the grey patches and \
             the fiducials; use a larger --size or fewer --contrasts"
        )));
    }
    // Spread the leftover height evenly between the blocks.
    let gap = min_gap + (avail - sh * n_rows as f64).max(0.0) / (n_rows as f64 + 1.0);
    let strip_w = w - 2.0 * mx;

    let mut target = Target {
        name: spec.name.clone(),
        width_mm: w,
        height_mm: h,
        background: 1.0,
        sweeps: vec![],
        patches: vec![],
        greys: vec![],
        fiducials: vec![],
    };
    let mut b = Builder {
        texts: vec![],
        ticks: vec![],
    };
    let cid = |i: usize, c: f64| {
        if i == 0 {
            "main".to_string()
        } else {
            format!("c{c}")
        }
    };
    let mut y = top + gap / 2.0;
    // Patch frequencies: log-spaced, inner ones rounded to three digits.
    let n = spec.patch_count;
    let freqs: Vec<f64> = (0..n)
        .map(|i| {
            if i == 0 {
                spec.f_min_cy_mm
            } else if i + 1 == n {
                spec.f_max_cy_mm
            } else {
                let f = spec.f_min_cy_mm
                    * (spec.f_max_cy_mm / spec.f_min_cy_mm).powf(i as f64 / (n - 1) as f64);
                format_freq(f).parse().unwrap_or(f)
            }
        })
        .collect();
    for (ci, &c) in spec.contrasts.iter().enumerate() {
        match spec.law {
            Law::Log | Law::Linear => {
                y += cap_h;
                let sw = Sweep {
                    id: cid(ci, c),
                    rect: Rect {
                        x_mm: mx,
                        y_mm: y,
                        width_mm: strip_w,
                        height_mm: sh,
                    },
                    direction: Direction::X,
                    law: if spec.law == Law::Log {
                        SweepLaw::Log
                    } else {
                        SweepLaw::Linear
                    },
                    f_min_cy_mm: spec.f_min_cy_mm,
                    f_max_cy_mm: spec.f_max_cy_mm,
                    mean: spec.mean,
                    contrast: c,
                };
                let caption = format!("contrast {c}, frequency in lp/mm");
                b.sweep_ticks(&sw, spec.law, y + sh + 0.4 * th, th, &caption, true, w);
                target.sweeps.push(sw);
                y += sh + band + gap;
            }
            Law::Patches => {
                let k1 = n.div_ceil(2);
                let pg = (0.4 * th).max(1.0);
                let pw = (strip_w - (k1 as f64 - 1.0) * pg) / k1 as f64;
                for (row, chunk) in freqs.chunks(k1).enumerate() {
                    for (j, &f) in chunk.iter().enumerate() {
                        let x = mx + j as f64 * (pw + pg);
                        let idx = row * k1 + j;
                        target.patches.push(SinePatch {
                            id: format!("{}_f{}", cid(ci, c), idx),
                            rect: Rect {
                                x_mm: x,
                                y_mm: y,
                                width_mm: pw,
                                height_mm: sh,
                            },
                            direction: Direction::X,
                            freq_cy_mm: f,
                            mean: spec.mean,
                            contrast: c,
                        });
                        if f * pw < 3.0 {
                            warnings.push(format!(
                                "patch at {} cy/mm holds only {:.1} cycles in its {:.1} mm",
                                format_freq(f),
                                f * pw,
                                pw
                            ));
                        }
                        let mut text = format_freq(f);
                        if j == 0 {
                            let long = format!("{text} lp/mm, contrast {c}");
                            if text_size_mm(&long, th).0 < pw {
                                text = long;
                            }
                        }
                        b.texts.push(TextLabel {
                            text,
                            x_mm: if j == 0 { x } else { x + pw / 2.0 },
                            y_mm: y + sh + 0.4 * th,
                            height_mm: th,
                            align: if j == 0 { Align::Left } else { Align::Center },
                        });
                    }
                    y += sh + band + gap;
                }
            }
        }
    }
    // Grey row: black, steps, white.
    let c0 = spec.contrasts[0];
    let (black, white) = (spec.mean * (1.0 - c0), spec.mean * (1.0 + c0));
    let mut greys: Vec<(String, f64)> = vec![("black".into(), black), ("white".into(), white)];
    for &g in &GREY_STEPS {
        // Steps the printer can make and that do not repeat black or white.
        if g > spec.darkest && (g - black).abs() > 0.015 && (g - white).abs() > 0.015 {
            greys.push((format!("grey{g}"), g));
        }
    }
    greys.sort_by(|a, b| a.1.total_cmp(&b.1));
    let k = greys.len();
    let gg = (0.4 * th).max(1.0);
    let gw = (strip_w - (k as f64 - 1.0) * gg) / k as f64;
    for (i, (id, r)) in greys.into_iter().enumerate() {
        let x = mx + i as f64 * (gw + gg);
        let text = match id.as_str() {
            "black" | "white" => format!("{id} {}", format_freq(r)),
            _ => format_freq(r),
        };
        b.texts.push(TextLabel {
            text,
            x_mm: x + gw / 2.0,
            y_mm: y + grey_h + 0.3 * th,
            height_mm: th,
            align: Align::Center,
        });
        target.greys.push(GreyPatch {
            id,
            rect: Rect {
                x_mm: x,
                y_mm: y,
                width_mm: gw,
                height_mm: grey_h,
            },
            reflectance: r,
            density: None,
        });
    }
    // Fiducials.
    for (id, fx, fy, kind) in [
        ("tl", d, d, FiducialKind::Ring),
        ("tr", w - d, d, FiducialKind::Disk),
        ("br", w - d, h - d, FiducialKind::Disk),
        ("bl", d, h - d, FiducialKind::Disk),
    ] {
        target.fiducials.push(Fiducial {
            id: id.into(),
            x_mm: fx,
            y_mm: fy,
            diameter_mm: d,
            kind,
        });
    }
    // Title (top band) and note (bottom band), between the fiducial squares.
    let room = w - 4.0 * d - 2.0 * th;
    let contrasts: Vec<String> = spec.contrasts.iter().map(|c| c.to_string()).collect();
    let what = match spec.law {
        Law::Patches => format!("{} sine patches", spec.patch_count),
        l => format!("{} sweep", l.name()),
    };
    let title = format!(
        "{}: {what} {}–{} lp/mm, contrast {}, mean {}",
        spec.name,
        format_freq(spec.f_min_cy_mm),
        format_freq(spec.f_max_cy_mm),
        contrasts.join("/"),
        spec.mean
    );
    let note = format!(
        "{}×{} mm at {} dpi, {}. Print at 100 % (no scaling, no fit-to-page) on matte paper.",
        format_freq(w),
        format_freq(h),
        spec.dpi,
        spec.encoding_name
    );
    for (text, cy) in [(title, d), (note, h - d)] {
        let tw = text_size_mm(&text, th).0;
        let size = if tw > room { th * room / tw } else { th };
        let hh = text_size_mm(&text, size).1;
        if size >= 0.8 {
            b.texts.push(TextLabel {
                text,
                x_mm: w / 2.0,
                y_mm: cy - hh / 2.0,
                height_mm: size,
                align: Align::Center,
            });
        }
    }
    target
        .validate()
        .map_err(|e| ChartError::Invalid(format!("internal layout error: {e}")))?;
    Ok(Chart {
        target,
        texts: b.texts,
        ticks: b.ticks,
        dpi: spec.dpi,
        width_px: wpx as usize,
        height_px: hpx as usize,
        dots_per_cycle: dpc,
        warnings,
    })
}
