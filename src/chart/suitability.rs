//! Chart suitability (`sweepmtf chart-check`): up to which image frequency a
//! print is sharp enough for a given camera set-up.
//!
//! The print's MTF C(f) (a model or a measured `.mtf.csv`, as for
//! `measure --chart-mtf`) is read at the chart frequency f = image frequency ×
//! image pixels per chart mm. Dividing C out changes a measured MTF
//! M = M_camera·C by M/C − M = M_camera·(1 − C): where C ≥ [`SHARP_ENOUGH`]
//! (0.99) that is ≤ 0.01 for any camera whose MTF does not exceed 1 (no
//! sharpening peak), so compensation is not needed there.
//! The levels 0.9 and 0.5 are the usual quality marks of a chart;
//! [`crate::measure::chart_mtf::MIN_CHART_MTF`] (0.3) is where `measure
//! --chart-mtf` stops compensating.

use crate::measure::chart_mtf::{ChartMtf, MIN_CHART_MTF};

/// Print MTF above which the chart counts as sharp enough: the camera MTF changes by ≤ 0.01 when divided out.
pub const SHARP_ENOUGH: f64 = 0.99;

/// The levels reported, highest first: sharp enough, 0.9, 0.5, the compensation floor.
pub const LEVELS: [f64; 4] = [SHARP_ENOUGH, 0.9, 0.5, MIN_CHART_MTF];

/// Where the print's MTF first falls below one level.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct LevelReach {
    /// The print MTF level (dimensionless).
    pub level: f64,
    /// Lowest chart frequency (cycles/mm of print) where the print's MTF falls
    /// below `level`; `None` when it does not within what is known (a file's range).
    pub chart_cy_mm: Option<f64>,
    /// The same as an image frequency (cycles/pixel).
    pub cy_px: Option<f64>,
    /// With `None`: the highest chart frequency known (a file's last row; infinite for a model).
    pub known_to_cy_mm: f64,
    /// The same as an image frequency (cycles/pixel).
    pub known_to_cy_px: f64,
}

impl LevelReach {
    /// Whether the print stays at or above the level up to Nyquist (0.5 cy/px),
    /// as far as is known (a file that never falls below it must reach Nyquist).
    pub fn covers_nyquist(&self) -> bool {
        match self.cy_px {
            Some(f) => f >= 0.5,
            None => self.known_to_cy_px >= 0.5,
        }
    }
}

/// The print's reach at every level of [`LEVELS`] for a camera seeing
/// `px_per_chart_mm` image pixels per mm of print.
pub fn check(chart: &ChartMtf, px_per_chart_mm: f64) -> Vec<LevelReach> {
    LEVELS
        .iter()
        .map(|&level| {
            let (f, known) = fall_below(chart, level);
            LevelReach {
                level,
                chart_cy_mm: f,
                cy_px: f.map(|f| f / px_per_chart_mm),
                known_to_cy_mm: known,
                known_to_cy_px: known / px_per_chart_mm,
            }
        })
        .collect()
}

/// Lowest chart frequency (cy/mm) where the print's MTF falls below `level`,
/// and how far the print's MTF is known (cy/mm).
pub fn fall_below(chart: &ChartMtf, level: f64) -> (Option<f64>, f64) {
    match chart {
        ChartMtf::Model(p) => (Some(p.freq_at(level)), f64::INFINITY),
        ChartMtf::Table(t) => {
            let (f, m) = (&t.f_cy_mm, &t.mtf);
            let known = f[f.len() - 1];
            if m[0] < level {
                return (Some(f[0]), known);
            }
            for i in 1..f.len() {
                if m[i] < level {
                    let u = (m[i - 1] - level) / (m[i - 1] - m[i]);
                    return (Some(f[i - 1] + u * (f[i] - f[i - 1])), known);
                }
            }
            (None, known)
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::measure::chart_mtf::ChartTable;
    use crate::print_mtf::PrintMtf;

    #[test]
    fn gaussian_levels_in_closed_form() {
        let g = ChartMtf::Model(PrintMtf::Gaussian { sigma_mm: 0.05 });
        let r = check(&g, 20.0);
        assert_eq!(r.len(), 4);
        for x in &r {
            // exp(−2π²σ²f²) = level ⇔ f = √(−ln level / 2π²) / σ.
            let want = (-x.level.ln() / (2.0 * std::f64::consts::PI.powi(2))).sqrt() / 0.05;
            assert!((x.chart_cy_mm.unwrap() - want).abs() < 1e-9);
            assert!((x.cy_px.unwrap() - want / 20.0).abs() < 1e-12);
        }
        // 0.99 at 0.4513 cy/mm, 0.3 at 4.939 cy/mm.
        assert!((r[0].chart_cy_mm.unwrap() - 0.4513).abs() < 1e-3);
        assert!((r[3].chart_cy_mm.unwrap() - 4.939).abs() < 1e-3);
        assert!(!r[0].covers_nyquist());
        // A perfect print reaches every level nowhere (infinite frequency: past Nyquist).
        let p = check(&ChartMtf::Model(PrintMtf::Gaussian { sigma_mm: 0.0 }), 20.0);
        assert!(p.iter().all(|x| x.covers_nyquist()));
    }

    #[test]
    fn table_crossings_and_a_table_that_never_falls() {
        let t = ChartTable {
            source: "t".into(),
            column: "mtf",
            f_cy_mm: vec![1.0, 2.0, 3.0],
            mtf: vec![1.0, 0.8, 0.4],
            err: vec![0.0; 3],
        };
        let r = check(&ChartMtf::Table(t.clone()), 10.0);
        assert!((r[0].chart_cy_mm.unwrap() - 1.05).abs() < 1e-12);
        assert!((r[1].chart_cy_mm.unwrap() - 1.5).abs() < 1e-12);
        assert!((r[2].chart_cy_mm.unwrap() - 2.75).abs() < 1e-12);
        assert_eq!(r[3].chart_cy_mm, None);
        assert_eq!(r[3].known_to_cy_mm, 3.0);
        assert!(!r[3].covers_nyquist(), "known to 0.3 cy/px only");
        assert!(check(&ChartMtf::Table(t.clone()), 5.0)[3].covers_nyquist());
        let low = ChartTable {
            mtf: vec![0.95, 0.9, 0.9],
            ..t
        };
        let r = check(&ChartMtf::Table(low), 10.0);
        assert_eq!(
            r[0].chart_cy_mm,
            Some(1.0),
            "below at the first row already"
        );
    }
}
