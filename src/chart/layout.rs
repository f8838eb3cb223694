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

use super::labels::{Align, TextLabel, format_freq, text_size_mm};
use super::{ChartError, MIN_DOTS_PER_CYCLE, WARN_DOTS_PER_CYCLE};
use crate::target::{
    Direction, Fiducial, FiducialKind, GreyPatch, Rect, SinePatch, Sweep, SweepLaw, Target,
};

/// How frequency is laid out along the chart.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Law {
    /// Logarithmic sweep: f(s) = f_min·(f_max/f_min)^(s/L).
    Log,
    /// Linear sweep: f(s) = f_min + (f_max − f_min)·s/L.
    Linear,
    /// Discrete constant-frequency patches, log-spaced from f_min to f_max.
    Patches,
}

impl Law {
    /// The law's name as used on the command line.
    pub fn name(&self) -> &'static str {
        match self {
            Law::Log => "log",
            Law::Linear => "linear",
            Law::Patches => "patches",
        }
    }
}

/// Everything that defines a chart.
#[derive(Debug, Clone, PartialEq)]
pub struct ChartSpec {
    /// Name written into the description and the title.
    pub name: String,
    /// Frequency layout.
    pub law: Law,
    /// Lowest chart frequency (cycles/mm on the print).
    pub f_min_cy_mm: f64,
    /// Highest chart frequency (cycles/mm on the print).
    pub f_max_cy_mm: f64,
    /// Page width (mm); sweeps run along it.
    pub width_mm: f64,
    /// Page height (mm).
    pub height_mm: f64,
    /// Printer resolution (dots per inch).
    pub dpi: u32,
    /// Modulation of each row of sweeps/patches; the first is the main one (0–1].
    pub contrasts: Vec<f64>,
    /// Mean linear reflectance of the sines (0–1).
    pub mean: f64,
    /// Number of patches per contrast for [`Law::Patches`].
    pub patch_count: usize,
    /// Darkest reflectance the output encoding can print (0 for sRGB/gamma).
    pub darkest: f64,
    /// Encoding named in the title ("sRGB", "gamma 2.2", …).
    pub encoding_name: String,
}

impl ChartSpec {
    /// A default spec: log sweep on A4 landscape at 600 dpi, contrast 0.8, mean 0.5.
    pub fn new(law: Law, f_min_cy_mm: f64, f_max_cy_mm: f64) -> ChartSpec {
        ChartSpec {
            name: "sweepmtf chart".into(),
            law,
            f_min_cy_mm,
            f_max_cy_mm,
            width_mm: 297.0,
            height_mm: 210.0,
            dpi: 600,
            contrasts: vec![0.8],
            mean: 0.5,
            patch_count: 12,
            darkest: 0.0,
            encoding_name: "sRGB".into(),
        }
    }
}

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

fn check_spec(s: &ChartSpec) -> Result<(f64, Vec<String>), ChartError> {
    let inv = |m: String| Err(ChartError::Invalid(m));
    let fin = |v: f64| v.is_finite();
    if !(fin(s.f_min_cy_mm) && s.f_min_cy_mm > 0.0) {
        return inv(format!(
            "--f-min {} must be a positive frequency (cycles/mm)",
            s.f_min_cy_mm
        ));
    }
    if !(fin(s.f_max_cy_mm) && s.f_max_cy_mm > 0.0) {
        return inv(format!(
            "--f-max {} must be a positive frequency (cycles/mm)",
            s.f_max_cy_mm
        ));
    }
    if s.f_min_cy_mm >= s.f_max_cy_mm {
        return inv(format!(
            "--f-min {} must be below --f-max {}",
            s.f_min_cy_mm, s.f_max_cy_mm
        ));
    }
    if !(fin(s.width_mm) && fin(s.height_mm) && s.width_mm > 0.0 && s.height_mm > 0.0) {
        return inv(format!(
            "chart size {}×{} mm must be positive",
            s.width_mm, s.height_mm
        ));
    }
    if !(25..=10_000).contains(&s.dpi) {
        return inv(format!("--dpi {} must lie between 25 and 10000", s.dpi));
    }
    if s.contrasts.is_empty() {
        return inv("at least one contrast is needed".into());
    }
    if !(fin(s.mean) && s.mean > 0.0 && s.mean < 1.0) {
        return inv(format!("--mean {} must lie in (0, 1)", s.mean));
    }
    for &c in &s.contrasts {
        if !(fin(c) && c > 0.0 && c <= 1.0) {
            return inv(format!("contrast {c} must lie in (0, 1]"));
        }
        if s.mean * (1.0 + c) > 1.0 + 1e-12 {
            return inv(format!(
                "mean {} × (1 + contrast {c}) = {:.4} exceeds paper white (1); lower --mean or the contrast",
                s.mean,
                s.mean * (1.0 + c)
            ));
        }
        if s.mean * (1.0 - c) < s.darkest - 1e-12 {
            return inv(format!(
                "mean {} × (1 − contrast {c}) = {:.4} is darker than the printer's black ({:.4}); \
                 lower the contrast or raise --mean",
                s.mean,
                s.mean * (1.0 - c),
                s.darkest
            ));
        }
    }
    if s.law == Law::Patches && !(2..=60).contains(&s.patch_count) {
        return inv(format!(
            "--patches {} must lie between 2 and 60",
            s.patch_count
        ));
    }
    let dpc = s.dpi as f64 / 25.4 / s.f_max_cy_mm;
    let mut warnings = Vec::new();
    if dpc < MIN_DOTS_PER_CYCLE {
        return inv(format!(
            "--f-max {} cy/mm leaves {:.2} printer dots per cycle at {} dpi; at least {} are needed \
             (raise --dpi to {} or lower --f-max to {})",
            s.f_max_cy_mm,
            dpc,
            s.dpi,
            MIN_DOTS_PER_CYCLE,
            (MIN_DOTS_PER_CYCLE * 25.4 * s.f_max_cy_mm).ceil(),
            format_freq(s.dpi as f64 / 25.4 / MIN_DOTS_PER_CYCLE)
        ));
    }
    if dpc < WARN_DOTS_PER_CYCLE {
        warnings.push(format!(
            "only {:.2} printer dots per cycle at {} cy/mm ({} dpi): the printed highest frequencies \
             will not be clean sines; {} dots per cycle or more are advised",
            dpc, s.f_max_cy_mm, s.dpi, WARN_DOTS_PER_CYCLE
        ));
    }
    Ok((dpc, warnings))
}

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

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a4_log_layout_follows_conventions() {
        let c = layout(&ChartSpec::new(Law::Log, 0.5, 10.0)).unwrap();
        let t = &c.target;
        assert_eq!(t.fiducials.len(), 4);
        let d = 0.04 * 210.0;
        assert!((t.fiducials[0].diameter_mm - d).abs() < 1e-12);
        assert_eq!(t.fiducials[0].kind, FiducialKind::Ring);
        assert!((t.fiducials[2].x_mm - (297.0 - d)).abs() < 1e-12);
        let white = t.greys.iter().find(|g| g.id == "white").unwrap();
        assert!((white.reflectance - 0.9).abs() < 1e-12);
        // Nothing but background within one diameter of a fiducial (outside its own square).
        for s in &t.sweeps {
            for f in &t.fiducials {
                let r = &s.rect;
                let dx = (f.x_mm - (r.x_mm + r.width_mm).min(f.x_mm.max(r.x_mm))).abs();
                let dy = (f.y_mm - (r.y_mm + r.height_mm).min(f.y_mm.max(r.y_mm))).abs();
                assert!(dx.max(dy) >= d, "{} near {}", s.id, f.id);
            }
        }
        // Labels lie on background (away from every described region).
        for l in &c.texts {
            let r = l.rect();
            for (x, y) in [
                (r.x_mm, r.y_mm),
                (r.x_mm + r.width_mm, r.y_mm + r.height_mm),
                (r.x_mm + r.width_mm / 2.0, r.y_mm + r.height_mm / 2.0),
            ] {
                assert_eq!(t.reflectance(x, y), 1.0, "label '{}' at {x},{y}", l.text);
            }
        }
        assert!(c.ticks.len() >= 4);
    }

    #[test]
    fn marks_stay_on_background_for_many_layouts() {
        // Every label box and tick (sampled on a grid) lies inside the page, on
        // background, and outside every fiducial's keep-out square.
        for (w, h) in [
            (297.0, 210.0),
            (420.0, 297.0),
            (210.0, 148.0),
            (120.0, 80.0),
            (600.0, 200.0),
        ] {
            for law in [Law::Log, Law::Linear, Law::Patches] {
                for contrasts in [vec![0.8], vec![0.8, 0.4, 0.2]] {
                    let mut s = ChartSpec::new(law, 0.3, 4.0);
                    s.width_mm = w;
                    s.height_mm = h;
                    s.contrasts = contrasts;
                    let c = layout(&s).unwrap();
                    let t = &c.target;
                    let rects = c
                        .texts
                        .iter()
                        .map(|l| l.rect())
                        .chain(c.ticks.iter().copied());
                    for r in rects {
                        for a in 0..=8 {
                            for b in 0..=4 {
                                let x = r.x_mm + r.width_mm * a as f64 / 8.0;
                                let y = r.y_mm + r.height_mm * b as f64 / 4.0;
                                assert!(
                                    x >= 0.0 && x <= w && y >= 0.0 && y <= h,
                                    "{w}×{h} {law:?}"
                                );
                                assert_eq!(t.reflectance(x, y), 1.0, "{w}×{h} {law:?} at {x},{y}");
                                for f in &t.fiducials {
                                    let d = f.diameter_mm;
                                    assert!(
                                        (x - f.x_mm).abs() >= d || (y - f.y_mm).abs() >= d,
                                        "{w}×{h} {law:?}: mark at {x},{y} near {}",
                                        f.id
                                    );
                                }
                            }
                        }
                    }
                }
            }
        }
    }

    #[test]
    fn refuses_under_two_dots_and_warns_under_four() {
        let mut s = ChartSpec::new(Law::Linear, 1.0, 10.0);
        s.dpi = 100; // 3.94 dots/mm: 0.39 dots per cycle at 10 cy/mm
        assert!(layout(&s).is_err());
        s.dpi = 900; // 3.54 dots per cycle
        let c = layout(&s).unwrap();
        assert_eq!(c.warnings.len(), 1);
    }

    #[test]
    fn bad_inputs() {
        let mut s = ChartSpec::new(Law::Log, 2.0, 1.0);
        assert!(layout(&s).is_err());
        s.f_min_cy_mm = 0.0;
        assert!(layout(&s).is_err());
        let mut s = ChartSpec::new(Law::Log, 0.5, 5.0);
        s.contrasts = vec![1.2];
        assert!(layout(&s).is_err());
        s.contrasts = vec![0.8];
        s.width_mm = 10.0;
        s.height_mm = 8.0;
        assert!(matches!(layout(&s), Err(ChartError::TooLarge(_))));
    }
}
