//! Chart MTF compensation (`measure --chart-mtf`): the measured MTF divided
//! by the print's own MTF at each point's *chart* frequency (cycles per mm of
//! print), so a chart whose printed sines lose modulation at their finer
//! frequencies does not pass that loss on as the camera's.
//!
//! The print's MTF comes from a closed-form model ([`PrintMtf`]:
//! `gaussian:sigma=…mm`, `dots:dpi=…`) or from the `.mtf.csv` that `measure`
//! wrote for a scan or close, sharp capture of the same print
//! ([`ChartTable`], interpolated linearly in cycles/mm; never extrapolated).
//! Where the print's MTF is below [`MIN_CHART_MTF`] the quotient mostly
//! amplifies noise and any error of the chart MTF: those points get no camera
//! MTF (NaN) and are flagged, as are aliased points and points outside the
//! chart file's frequency range.
//!
//! The chart frequency of a point is known when the strip was measured in
//! chart millimetres (with a target description: its located geometry maps
//! image pixels to chart mm), or, without a target, when the printed length
//! of the strip between the region's short edges is given (the strip's
//! homography makes its units proportional to chart mm); otherwise the
//! compensation is refused ([`ChartMtfError::NoScale`]).

use super::Curve;
use crate::print_mtf::PrintMtf;
use std::path::Path;

/// Smallest print MTF (dimensionless) a point's camera MTF is given for.
pub const MIN_CHART_MTF: f64 = 0.3;

/// Why a chart MTF could not be read or used.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum ChartMtfError {
    /// The chart MTF file could not be read or holds no usable curve.
    #[error("--chart-mtf {path}: {cause}")]
    File {
        /// The file.
        path: String,
        /// The cause.
        cause: String,
    },
    /// A model string that does not parse.
    #[error("--chart-mtf {arg}: {cause}")]
    Spec {
        /// The argument as given.
        arg: String,
        /// The cause.
        cause: String,
    },
    /// The points' chart frequencies (cycles/mm of print) are unknown.
    #[error(
        "--chart-mtf: the chart frequency in cycles/mm of print is unknown without a target \
         description; give --target CHART.toml (the chart's description, which `chart` writes) \
         or --chart-length (the printed length of the strip between the --roi's short edges)"
    )]
    NoScale,
    /// The printed strip length is not a positive length.
    #[error("--chart-length must be a positive length (e.g. 200mm)")]
    BadLength,
}

/// The print's MTF, tabulated from a measurement of the print itself.
#[derive(Debug, Clone, PartialEq)]
pub struct ChartTable {
    /// The file it was read from.
    pub source: String,
    /// Which column gave the MTF (`mtf`, or `lens_mtf` when the file has it).
    pub column: &'static str,
    /// Chart frequencies, cycles/mm of print, strictly increasing.
    pub f_cy_mm: Vec<f64>,
    /// The print's MTF there (dimensionless).
    pub mtf: Vec<f64>,
    /// One-sigma uncertainty of `mtf` (0 where the file gives none).
    pub err: Vec<f64>,
}

impl ChartTable {
    /// Reads a `.mtf.csv` that `measure` wrote: the chart frequency from
    /// `freq_chart_cy_mm` (written with a target), else `freq_cy_mm` (cycles
    /// per mm of print when the pitch given was the scanner's sample spacing
    /// on the print, e.g. 10.583um for a 2400 dpi scan); the MTF from
    /// `lens_mtf` where `lens_flag` is `ok` when the file has those columns
    /// (the scanner's pixel aperture divided out), else `mtf`; `mtf_err` (or
    /// `lens_mtf_err`) as its uncertainty; aliased rows left out; with several
    /// curves, the first curve's rows.
    pub fn from_csv(path: &Path) -> Result<ChartTable, ChartMtfError> {
        let name = path.display().to_string();
        let bytes = std::fs::read(path).map_err(|e| ChartMtfError::File {
            path: name.clone(),
            cause: format!("cannot read: {e}"),
        })?;
        Self::from_csv_bytes(&bytes, &name)
    }

    /// [`ChartTable::from_csv`] for a file's bytes; `name` is used in messages.
    pub fn from_csv_bytes(bytes: &[u8], name: &str) -> Result<ChartTable, ChartMtfError> {
        let bad = |cause: String| ChartMtfError::File {
            path: name.to_string(),
            cause,
        };
        let mut r = csv::ReaderBuilder::new().from_reader(bytes);
        let head = r
            .headers()
            .map_err(|e| bad(format!("not a CSV file: {e}")))?
            .clone();
        let col = |n: &str| head.iter().position(|h| h.trim() == n);
        let fcol = col("freq_chart_cy_mm")
            .or(col("freq_cy_mm"))
            .ok_or_else(|| {
                bad(
                    "no chart frequency column (freq_chart_cy_mm, written when the print was \
                 measured with --target, or freq_cy_mm)"
                        .into(),
                )
            })?;
        let lens = col("lens_mtf").zip(col("lens_flag"));
        let (mcol, ecol, column) = match lens {
            Some((m, _)) => (m, col("lens_mtf_err"), "lens_mtf"),
            None => (
                col("mtf").ok_or_else(|| bad("no mtf column".into()))?,
                col("mtf_err"),
                "mtf",
            ),
        };
        let (acol, chcol, swcol) = (col("aliased"), col("channel"), col("sweep"));
        let mut first: Option<(String, String)> = None;
        let mut rows: Vec<(f64, f64, f64)> = Vec::new();
        for (i, rec) in r.records().enumerate() {
            let rec = rec.map_err(|e| bad(format!("row {}: {e}", i + 2)))?;
            let cell = |c: Option<usize>| c.and_then(|c| rec.get(c)).unwrap_or("").trim();
            let curve = (cell(chcol).to_string(), cell(swcol).to_string());
            if first.get_or_insert_with(|| curve.clone()) != &curve {
                continue;
            }
            if cell(acol) == "true" {
                continue;
            }
            if let Some((_, flag)) = lens
                && cell(Some(flag)) != "ok"
            {
                continue;
            }
            let num = |c: Option<usize>| cell(c).parse::<f64>().ok().filter(|v| v.is_finite());
            let (Some(f), Some(m)) = (num(Some(fcol)), num(Some(mcol))) else {
                continue;
            };
            let e = num(ecol).map_or(0.0, f64::abs);
            if f > 0.0 {
                rows.push((f, m, e));
            }
        }
        rows.sort_by(|a, b| a.0.total_cmp(&b.0));
        rows.dedup_by(|b, a| b.0 <= a.0);
        if rows.len() < 2 {
            return Err(bad(format!(
                "only {} usable row(s) (need at least 2 non-aliased rows with a chart frequency and an MTF)",
                rows.len()
            )));
        }
        Ok(ChartTable {
            source: name.to_string(),
            column,
            f_cy_mm: rows.iter().map(|r| r.0).collect(),
            mtf: rows.iter().map(|r| r.1).collect(),
            err: rows.iter().map(|r| r.2).collect(),
        })
    }

    /// (MTF, its σ) at `f_cy_mm` cycles/mm of print, interpolated linearly; `None` outside the table.
    pub fn at(&self, f_cy_mm: f64) -> Option<(f64, f64)> {
        let f = &self.f_cy_mm;
        if !(f_cy_mm >= f[0] && f_cy_mm <= f[f.len() - 1]) {
            return None;
        }
        let j = f.partition_point(|&x| x < f_cy_mm).clamp(1, f.len() - 1);
        let t = (f_cy_mm - f[j - 1]) / (f[j] - f[j - 1]);
        let lerp = |v: &[f64]| v[j - 1] + t * (v[j] - v[j - 1]);
        Some((lerp(&self.mtf), lerp(&self.err)))
    }
}

/// Where the print's MTF comes from.
#[derive(Debug, Clone, PartialEq)]
pub enum ChartMtf {
    /// A closed-form model (exact: no uncertainty).
    Model(PrintMtf),
    /// A measurement of the print.
    Table(ChartTable),
}

impl ChartMtf {
    /// `gaussian:…` or `dots:…` as a model, anything else as a `.mtf.csv` file.
    pub fn from_arg(arg: &str) -> Result<ChartMtf, ChartMtfError> {
        let t = arg.trim().to_ascii_lowercase();
        if t.starts_with("gaussian:") || t.starts_with("dots:") {
            return arg
                .parse()
                .map(ChartMtf::Model)
                .map_err(|cause| ChartMtfError::Spec {
                    arg: arg.to_string(),
                    cause,
                });
        }
        ChartTable::from_csv(Path::new(arg)).map(ChartMtf::Table)
    }

    /// One line naming the source (for the JSON summary and the plot legend).
    pub fn describe(&self) -> String {
        match self {
            ChartMtf::Model(p) => p.to_string(),
            ChartMtf::Table(t) => format!("{} ({})", t.source, t.column),
        }
    }

    /// (print MTF, its σ) at `f_cy_mm` cycles/mm of print; `None` outside a table's range.
    pub fn at(&self, f_cy_mm: f64) -> Option<(f64, f64)> {
        match self {
            ChartMtf::Model(p) => Some((p.mtf(f_cy_mm), 0.0)),
            ChartMtf::Table(t) => t.at(f_cy_mm),
        }
    }
}

/// Why a point has no camera MTF.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum ChartFlag {
    /// Camera MTF given.
    Ok,
    /// The print's MTF there is below [`MIN_CHART_MTF`].
    BelowFloor,
    /// The point's chart frequency lies outside the chart file's range.
    OutsideFile,
    /// The point is aliased (not an MTF to begin with).
    Aliased,
}

impl ChartFlag {
    /// The CSV word: `ok`, `chart_below_floor`, `outside_chart_file`, `aliased`.
    pub fn as_str(self) -> &'static str {
        match self {
            ChartFlag::Ok => "ok",
            ChartFlag::BelowFloor => "chart_below_floor",
            ChartFlag::OutsideFile => "outside_chart_file",
            ChartFlag::Aliased => "aliased",
        }
    }
}

/// The compensated (camera) MTF of one curve, one entry per point in the curve's order.
#[derive(Debug, Clone, PartialEq)]
pub struct ChartCurve {
    /// The print's MTF at each point's chart frequency (NaN outside a file's range).
    pub chart_mtf: Vec<f64>,
    /// Camera MTF = MTF / print MTF (NaN where flagged), dimensionless.
    pub camera_mtf: Vec<f64>,
    /// One-sigma uncertainty of the camera MTF: the MTF's and the print MTF's, propagated (NaN where flagged).
    pub camera_mtf_err: Vec<f64>,
    /// Why a point has no camera MTF (or `Ok`).
    pub flag: Vec<ChartFlag>,
}

impl ChartCurve {
    /// The (frequency cy/px, camera MTF) pairs that are given (flag `Ok`), for plots.
    pub fn given<'a>(&'a self, c: &'a Curve) -> impl Iterator<Item = (f64, f64)> + 'a {
        c.points
            .iter()
            .zip(self.camera_mtf.iter().zip(&self.flag))
            .filter(|(_, (_, f))| **f == ChartFlag::Ok)
            .map(|(p, (v, _))| (p.freq_cy_px, *v))
    }

    /// Where the print stops being sharp enough for the plain MTF: the first
    /// non-aliased point (cy/px) whose print MTF is below
    /// [`crate::chart::suitability::SHARP_ENOUGH`] (or unknown), and how many
    /// such points there are; None when the print is sharp enough along the
    /// whole measured curve.
    pub fn soft_from(&self, c: &Curve) -> Option<(f64, usize)> {
        let sharp = crate::chart::suitability::SHARP_ENOUGH;
        let soft: Vec<f64> = c
            .points
            .iter()
            .zip(&self.chart_mtf)
            .filter(|(p, d)| !p.aliased && !(**d >= sharp))
            .map(|(p, _)| p.freq_cy_px)
            .collect();
        soft.first().map(|&f| (f, soft.len()))
    }

    /// Number of points with flag `f`.
    pub fn count(&self, f: ChartFlag) -> usize {
        self.flag.iter().filter(|&&g| g == f).count()
    }
}

/// Divides a curve's MTF by the print's MTF at each point's chart frequency
/// (the curve must have been measured in chart millimetres, i.e. with a target).
///
/// σ(camera) = √((σ_M/C)² + (M·σ_C/C²)²) for MTF M ± σ_M and print MTF C ± σ_C.
pub fn chart_curve(c: &Curve, chart: &ChartMtf) -> Result<ChartCurve, ChartMtfError> {
    chart_curve_scaled(c, chart, None)
}

/// Chart millimetres per strip unit of a curve: 1 when it was measured in
/// chart mm (with a target); without one, the printed length of the strip
/// between the region's short edges (`strip_mm`, mm) over its length in px.
pub fn mm_per_strip_unit(c: &Curve, strip_mm: Option<f64>) -> Result<f64, ChartMtfError> {
    if c.strip_unit == "mm" {
        return Ok(1.0);
    }
    let l = strip_mm.ok_or(ChartMtfError::NoScale)?;
    if !(l.is_finite() && l > 0.0) {
        return Err(ChartMtfError::BadLength);
    }
    if !(c.strip_length.is_finite() && c.strip_length > 0.0) {
        return Err(ChartMtfError::NoScale);
    }
    Ok(l / c.strip_length)
}

/// [`chart_curve`] for a curve measured with or without a target: `strip_mm`
/// is the printed length (mm) of a target-less strip between the region's
/// short edges (ignored with a target).
pub fn chart_curve_scaled(
    c: &Curve,
    chart: &ChartMtf,
    strip_mm: Option<f64>,
) -> Result<ChartCurve, ChartMtfError> {
    let mm_per_unit = mm_per_strip_unit(c, strip_mm)?;
    let n = c.points.len();
    let mut out = ChartCurve {
        chart_mtf: Vec::with_capacity(n),
        camera_mtf: Vec::with_capacity(n),
        camera_mtf_err: Vec::with_capacity(n),
        flag: Vec::with_capacity(n),
    };
    for p in &c.points {
        // Cycles per strip unit → cycles per mm of print.
        let at = chart.at(p.freq_chart / mm_per_unit);
        let (d, de) = at.unwrap_or((f64::NAN, f64::NAN));
        let flag = if p.aliased {
            ChartFlag::Aliased
        } else if at.is_none() {
            ChartFlag::OutsideFile
        } else if !(d >= MIN_CHART_MTF) {
            ChartFlag::BelowFloor
        } else {
            ChartFlag::Ok
        };
        let ok = flag == ChartFlag::Ok;
        out.chart_mtf.push(d);
        out.camera_mtf.push(if ok { p.mtf / d } else { f64::NAN });
        out.camera_mtf_err.push(if ok {
            (p.mtf_err / d).hypot(p.mtf * de / (d * d))
        } else {
            f64::NAN
        });
        out.flag.push(flag);
    }
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;

    const SCAN: &str = "freq_cy_px,mtf,freq_lw_ph,modulation,mtf_err,aliased,freq_chart_cy_mm\n\
        0.01,1.0,1,0.8,0.001,false,1.0\n\
        0.02,0.8,2,0.64,0.002,false,3.0\n\
        0.03,0.5,3,0.4,0.004,false,5.0\n\
        0.04,0.2,4,0.16,0.004,false,7.0\n\
        0.6,0.9,60,0.7,0.01,true,9.0\n";

    #[test]
    fn table_interpolates_and_refuses_to_extrapolate() {
        let t = ChartTable::from_csv_bytes(SCAN.as_bytes(), "scan.mtf.csv").unwrap();
        assert_eq!(t.column, "mtf");
        assert_eq!(t.f_cy_mm, vec![1.0, 3.0, 5.0, 7.0], "aliased row left out");
        let (m, e) = t.at(4.0).unwrap();
        assert!((m - 0.65).abs() < 1e-12 && (e - 0.003).abs() < 1e-12);
        assert_eq!(t.at(1.0).unwrap().0, 1.0);
        assert_eq!(t.at(7.0).unwrap().0, 0.2);
        assert!(t.at(0.999).is_none() && t.at(7.001).is_none() && t.at(f64::NAN).is_none());
    }

    #[test]
    fn lens_columns_are_preferred_and_their_flags_respected() {
        let text = "freq_cy_px,mtf,mtf_err,aliased,freq_chart_cy_mm,sensor_mtf,lens_mtf,lens_mtf_err,lens_flag\n\
            0.01,0.99,0.001,false,1.0,0.99,1.0,0.001,ok\n\
            0.2,0.5,0.001,false,2.0,0.9,0.55,0.002,ok\n\
            0.45,0.1,0.001,false,3.0,0.1,,,small_divisor\n";
        let t = ChartTable::from_csv_bytes(text.as_bytes(), "s").unwrap();
        assert_eq!(t.column, "lens_mtf");
        assert_eq!(t.mtf, vec![1.0, 0.55]);
        assert_eq!(t.err, vec![0.001, 0.002]);
    }

    #[test]
    fn bad_files_are_refused_with_the_file_named() {
        for (text, want) in [
            ("", "chart frequency column"),
            ("freq_cy_px,mtf\n0.1,0.5\n0.2,0.4\n", "chart frequency"),
            ("freq_chart_cy_mm,mtf\n1,0.5\n", "only 1"),
            ("freq_chart_cy_mm,mtf\n1,NaN\n2,x\n", "only 0"),
            ("freq_chart_cy_mm,modulation\n1,0.5\n2,0.4\n", "no mtf"),
        ] {
            let e = ChartTable::from_csv_bytes(text.as_bytes(), "p.csv").unwrap_err();
            let s = e.to_string();
            assert!(s.contains("p.csv") && s.contains(want), "{text:?}: {s}");
        }
        let e = ChartMtf::from_arg("/nonexistent/x.mtf.csv").unwrap_err();
        assert!(e.to_string().contains("cannot read"), "{e}");
        let e = ChartMtf::from_arg("gaussian:sigma=2").unwrap_err();
        assert!(
            e.to_string().starts_with("--chart-mtf gaussian:sigma=2"),
            "{e}"
        );
    }

    fn curve(points: &[(f64, f64, f64, bool)], unit: &'static str) -> Curve {
        use crate::measure::{MtfPoint, PhaseLaw};
        Curve {
            channel: "luma".into(),
            sweep_id: "main".into(),
            law: PhaseLaw {
                kind: crate::measure::LawKind::Linear,
                c0: 0.0,
                c1: 1.0,
                c2: 0.0,
                persp: 0.0,
            },
            strip_unit: unit,
            strip_length: 100.0,
            points: points
                .iter()
                .map(|&(f, m, e, aliased)| MtfPoint {
                    s: 0.0,
                    freq_cy_px: f / 10.0,
                    freq_chart: f,
                    modulation: m,
                    mtf: m,
                    mtf_err: e,
                    aliased,
                    jpeg_limited: false,
                })
                .collect(),
            chart_modulation: 1.0,
            chart_modulation_err: 0.0,
            chart_modulation_source: String::new(),
            figures: Default::default(),
            aliasing_from_cy_px: None,
            rounded_away_from_cy_px: None,
            clipped_fraction: 0.0,
            region_px: [[0.0; 2]; 4],
            outline_px: Vec::new(),
            alias_line_px: None,
            measured_lines_px: [[[0.0; 2]; 2]; 2],
            paper_bands_px: Vec::new(),
            print_ends_inside_px: [None; 2],
            tone_fix: None,
        }
    }

    /// Division, the propagated σ, every flag, and the refusal without chart millimetres.
    #[test]
    fn compensation_flags_and_uncertainty() {
        let t = ChartTable::from_csv_bytes(SCAN.as_bytes(), "scan").unwrap();
        let chart = ChartMtf::Table(t);
        let c = curve(
            &[
                (4.0, 0.52, 0.01, false),
                (6.5, 0.1, 0.01, false),
                (8.0, 0.05, 0.01, false),
                (2.0, 0.7, 0.01, true),
            ],
            "mm",
        );
        let cc = chart_curve(&c, &chart).unwrap();
        assert_eq!(
            cc.flag,
            vec![
                ChartFlag::Ok,
                ChartFlag::BelowFloor,
                ChartFlag::OutsideFile,
                ChartFlag::Aliased
            ]
        );
        assert!((cc.camera_mtf[0] - 0.52 / 0.65).abs() < 1e-12);
        let want = (0.01f64 / 0.65).hypot(0.52 * 0.003 / (0.65 * 0.65));
        assert!((cc.camera_mtf_err[0] - want).abs() < 1e-12);
        assert!((cc.chart_mtf[1] - 0.275).abs() < 1e-12);
        assert!(cc.camera_mtf[1..].iter().all(|v| v.is_nan()));
        assert!(cc.camera_mtf_err[1..].iter().all(|v| v.is_nan()));
        assert!(cc.chart_mtf[2].is_nan());
        assert_eq!(cc.given(&c).count(), 1);
        // A model: exact (σ from the MTF alone).
        let g = ChartMtf::Model(PrintMtf::Gaussian { sigma_mm: 0.05 });
        let cc = chart_curve(&c, &g).unwrap();
        let d = (-2.0 * std::f64::consts::PI.powi(2) * (0.05f64 * 4.0).powi(2)).exp();
        assert!((cc.camera_mtf[0] - 0.52 / d).abs() < 1e-12);
        assert!((cc.camera_mtf_err[0] - 0.01 / d).abs() < 1e-12);
        assert_eq!(cc.flag[2], ChartFlag::BelowFloor, "{}", cc.chart_mtf[2]);
        let px = curve(&[(1.0, 0.5, 0.0, false)], "px");
        assert_eq!(chart_curve(&px, &g).unwrap_err(), ChartMtfError::NoScale);
        // 100 px of strip printed over 50 mm: 1 cy/px of strip = 2 cy/mm.
        let cc = chart_curve_scaled(&px, &g, Some(50.0)).unwrap();
        assert!((cc.chart_mtf[0] - g.at(2.0).unwrap().0).abs() < 1e-15);
        for bad in [0.0, -1.0, f64::NAN, f64::INFINITY] {
            assert_eq!(
                chart_curve_scaled(&px, &g, Some(bad)).unwrap_err(),
                ChartMtfError::BadLength
            );
        }
        // With a target the length is not needed (and not used).
        let cc = chart_curve_scaled(&c, &g, Some(1.0)).unwrap();
        assert!((cc.camera_mtf[0] - 0.52 / d).abs() < 1e-12);
    }
}
