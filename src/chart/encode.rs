//! Output encodings: how a wanted linear reflectance (1 = paper white) becomes
//! a pixel value (0–1, quantised to 16 bits) so that the printed reflectance
//! is the wanted one. sRGB (default), a pure power law, or a measured printer
//! curve (CSV of pixel value → measured reflectance), inverted piecewise
//! linearly (pre-compensation).

use super::ChartError;
use std::path::Path;

/// How pixel values map to printed reflectance.
#[derive(Debug, Clone, PartialEq)]
pub enum Encoding {
    /// The sRGB transfer curve (what printers assume for untagged or sRGB-tagged images).
    Srgb,
    /// A power law: reflectance = value^gamma.
    Gamma(f64),
    /// A measured printer curve.
    Printer(PrinterCurve),
}

/// A measured printer response: strictly increasing pixel values (0–1) and
/// their reflectances relative to paper white (the brightest entry is 1).
#[derive(Debug, Clone, PartialEq)]
pub struct PrinterCurve {
    /// Pixel values (0–1), increasing.
    pub value: Vec<f64>,
    /// Reflectance relative to paper white at each value (0–1), increasing.
    pub reflectance: Vec<f64>,
}

/// sRGB encoding of a linear value (0–1).
pub fn srgb_from_linear(l: f64) -> f64 {
    if l <= 0.003_130_8 {
        12.92 * l
    } else {
        1.055 * l.powf(1.0 / 2.4) - 0.055
    }
}

/// Linear value (0–1) of an sRGB-encoded value.
pub fn linear_from_srgb(v: f64) -> f64 {
    if v <= 0.040_45 {
        v / 12.92
    } else {
        ((v + 0.055) / 1.055).powf(2.4)
    }
}

impl Encoding {
    /// Pixel value (0–1) that prints the given linear reflectance (clamped to the printable range).
    pub fn value(&self, reflectance: f64) -> f64 {
        let r = reflectance.clamp(0.0, 1.0);
        match self {
            Encoding::Srgb => srgb_from_linear(r),
            Encoding::Gamma(g) => r.powf(1.0 / g),
            Encoding::Printer(c) => interp(&c.reflectance, &c.value, r),
        }
    }

    /// Printed linear reflectance of a pixel value (0–1): the inverse of [`Encoding::value`].
    pub fn reflectance(&self, value: f64) -> f64 {
        let v = value.clamp(0.0, 1.0);
        match self {
            Encoding::Srgb => linear_from_srgb(v),
            Encoding::Gamma(g) => v.powf(*g),
            Encoding::Printer(c) => interp(&c.value, &c.reflectance, v),
        }
    }

    /// The 16-bit pixel value that prints the given reflectance.
    pub fn value_u16(&self, reflectance: f64) -> u16 {
        (self.value(reflectance) * 65535.0).round() as u16
    }

    /// The darkest reflectance the encoding can print (0 for sRGB and gamma).
    pub fn darkest(&self) -> f64 {
        match self {
            Encoding::Printer(c) => c.reflectance[0],
            _ => 0.0,
        }
    }

    /// A short description for labels and summaries ("sRGB", "gamma 2.2", "printer curve").
    pub fn describe(&self) -> String {
        match self {
            Encoding::Srgb => "sRGB".to_string(),
            Encoding::Gamma(g) => format!("gamma {g}"),
            Encoding::Printer(_) => "printer curve".to_string(),
        }
    }
}

/// Piecewise-linear interpolation of y(x) on increasing `xs`, clamped at the ends.
fn interp(xs: &[f64], ys: &[f64], x: f64) -> f64 {
    if x <= xs[0] {
        return ys[0];
    }
    let n = xs.len();
    if x >= xs[n - 1] {
        return ys[n - 1];
    }
    let i = xs.partition_point(|&v| v <= x).clamp(1, n - 1);
    let t = (x - xs[i - 1]) / (xs[i] - xs[i - 1]);
    ys[i - 1] + t * (ys[i] - ys[i - 1])
}

impl PrinterCurve {
    /// Builds a curve from (value, reflectance) pairs; values on 0–1, 0–255 or
    /// 0–65535 (by their maximum); reflectances are divided by the largest one.
    pub fn from_pairs(mut pairs: Vec<(f64, f64)>, source: &str) -> Result<Self, ChartError> {
        let bad = |m: String| ChartError::PrinterCurve(format!("{source}: {m}"));
        if pairs.len() < 2 {
            return Err(bad("needs at least two rows of value, reflectance".into()));
        }
        if pairs
            .iter()
            .any(|&(v, r)| !(v.is_finite() && r.is_finite() && v >= 0.0 && r >= 0.0))
        {
            return Err(bad(
                "values and reflectances must be finite and not negative".into(),
            ));
        }
        pairs.sort_by(|a, b| a.0.total_cmp(&b.0));
        let vmax = pairs.last().map(|p| p.0).unwrap_or(1.0);
        let scale = if vmax <= 1.0 {
            1.0
        } else if vmax <= 255.0 {
            255.0
        } else if vmax <= 65535.0 {
            65535.0
        } else {
            return Err(bad(format!(
                "pixel value {vmax} is beyond 16 bits; give values on 0–1, 0–255 or 0–65535"
            )));
        };
        let rmax = pairs.iter().map(|p| p.1).fold(0.0, f64::max);
        if rmax <= 0.0 {
            return Err(bad("all reflectances are zero".into()));
        }
        let value: Vec<f64> = pairs.iter().map(|p| p.0 / scale).collect();
        let reflectance: Vec<f64> = pairs.iter().map(|p| p.1 / rmax).collect();
        for i in 1..value.len() {
            if value[i] <= value[i - 1] || reflectance[i] <= reflectance[i - 1] {
                return Err(bad(format!(
                    "reflectance must rise strictly with pixel value (rows near value {})",
                    pairs[i].0
                )));
            }
        }
        Ok(PrinterCurve { value, reflectance })
    }

    /// Reads a CSV with a header naming a `value` column and a `reflectance` column.
    pub fn load(path: &Path) -> Result<Self, ChartError> {
        let src = path.display().to_string();
        let mut rdr = csv::ReaderBuilder::new()
            .trim(csv::Trim::All)
            .comment(Some(b'#'))
            .from_path(path)
            .map_err(|e| ChartError::PrinterCurve(format!("{src}: cannot read: {e}")))?;
        let headers = rdr
            .headers()
            .map_err(|e| ChartError::PrinterCurve(format!("{src}: {e}")))?
            .clone();
        let find = |key: &str| {
            headers
                .iter()
                .position(|h| h.to_ascii_lowercase().contains(key))
        };
        let (Some(iv), Some(ir)) = (find("value"), find("reflectance")) else {
            return Err(ChartError::PrinterCurve(format!(
                "{src}: needs a header with a 'value' and a 'reflectance' column"
            )));
        };
        let mut pairs = Vec::new();
        for (n, rec) in rdr.records().enumerate() {
            let rec = rec.map_err(|e| ChartError::PrinterCurve(format!("{src}: {e}")))?;
            let num = |i: usize| -> Result<f64, ChartError> {
                rec.get(i)
                    .and_then(|t| t.parse::<f64>().ok())
                    .ok_or_else(|| {
                        ChartError::PrinterCurve(format!("{src}: row {} is not numeric", n + 2))
                    })
            };
            pairs.push((num(iv)?, num(ir)?));
        }
        Self::from_pairs(pairs, &src)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn srgb_round_trip_and_reference_points() {
        // Reference values of the sRGB curve (IEC 61966-2-1): 18 % grey ≈ 0.4613.
        assert!((srgb_from_linear(0.18) - 0.461_356).abs() < 1e-5);
        assert!((srgb_from_linear(1.0) - 1.0).abs() < 1e-12);
        for i in 0..=1000 {
            let l = i as f64 / 1000.0;
            assert!((linear_from_srgb(srgb_from_linear(l)) - l).abs() < 1e-12);
        }
    }

    #[test]
    fn printer_curve_inverts_and_normalises() {
        let c = PrinterCurve::from_pairs(vec![(255.0, 0.85), (0.0, 0.034), (128.0, 0.17)], "t.csv")
            .unwrap();
        let e = Encoding::Printer(c);
        assert!((e.value(1.0) - 1.0).abs() < 1e-12);
        assert!((e.darkest() - 0.04).abs() < 1e-12);
        // 0.2 of paper white lies on the segment 128→255 (0.2 .. 1.0 relative).
        let v = e.value(0.6);
        assert!((e.reflectance(v) - 0.6).abs() < 1e-12);
        assert!((v - (128.0 + 127.0 * 0.5) / 255.0).abs() < 1e-12);
    }

    #[test]
    fn printer_curve_rejects_non_monotonic() {
        let r = PrinterCurve::from_pairs(vec![(0.0, 0.1), (0.5, 0.05), (1.0, 0.9)], "x");
        assert!(r.is_err());
    }
}
