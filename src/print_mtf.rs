//! Closed-form MTF models of a printed chart (the print's own blur, against
//! the frequency printed on the chart in cycles per millimetre of paper):
//! `gaussian:sigma=LENGTH` (exp(−2π²σ²f²), the usual fit to an inkjet or
//! photo print) and `dots:dpi=N` (a square printer dot of 1/N inch,
//! sinc(f·25.4/N), the nominal dot model).
//!
//! `measure --chart-mtf` divides these out of a measurement; `simulate
//! --print-blur` renders a chart whose printed sines have lost modulation by
//! them at their chart frequency.

use serde::{Deserialize, Deserializer, Serialize, Serializer};
use std::f64::consts::PI;
use std::fmt;
use std::str::FromStr;

/// A print's MTF in closed form.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum PrintMtf {
    /// Gaussian blur of σ (mm on the print): exp(−2π²σ²f²).
    Gaussian {
        /// σ of the blur, mm on the print.
        sigma_mm: f64,
    },
    /// Square printer dot of 1/dpi inch: sinc(f·25.4/dpi) (signed: contrast reverses past its first zero).
    Dots {
        /// Printer dots per inch.
        dpi: f64,
    },
}

/// sin(πx)/(πx), 1 at x = 0 (the series' next term is below 1e-16 within 1e-8 of it).
fn sinc(x: f64) -> f64 {
    if x.abs() < 1e-8 {
        1.0
    } else {
        (PI * x).sin() / (PI * x)
    }
}

impl PrintMtf {
    /// Signed transfer (the sine's printed modulation relative to the nominal one)
    /// at chart frequency `f_cy_mm` (cycles per mm of print).
    pub fn transfer(&self, f_cy_mm: f64) -> f64 {
        match *self {
            PrintMtf::Gaussian { sigma_mm } => {
                (-2.0 * PI * PI * (sigma_mm * f_cy_mm).powi(2)).exp()
            }
            PrintMtf::Dots { dpi } => sinc(f_cy_mm * 25.4 / dpi),
        }
    }

    /// The print's MTF (|transfer|, dimensionless) at `f_cy_mm` cycles/mm of print.
    pub fn mtf(&self, f_cy_mm: f64) -> f64 {
        self.transfer(f_cy_mm).abs()
    }

    /// Lowest chart frequency (cycles/mm) where the MTF falls to `level` (0 < level < 1).
    pub fn freq_at(&self, level: f64) -> f64 {
        match *self {
            PrintMtf::Gaussian { sigma_mm } => (-level.ln() / (2.0 * PI * PI)).sqrt() / sigma_mm,
            PrintMtf::Dots { dpi } => {
                // sinc falls monotonically on [0, 1]: bisection in x = f·25.4/dpi.
                let (mut a, mut b) = (0.0, 1.0);
                for _ in 0..80 {
                    let m = 0.5 * (a + b);
                    if sinc(m) > level {
                        a = m;
                    } else {
                        b = m;
                    }
                }
                0.5 * (a + b) * dpi / 25.4
            }
        }
    }
}

/// The print's MTF tabulated as a chart-MTF CSV (`freq_chart_cy_mm,mtf,mtf_err`,
/// `n` ≥ 2 rows evenly spaced from `f_hi_cy_mm`/`n` to `f_hi_cy_mm`, σ 0): a
/// starting file for `measure --chart-mtf` that a measured one can replace.
pub fn table_csv(p: &PrintMtf, f_hi_cy_mm: f64, n: usize) -> String {
    let n = n.max(2);
    let mut out = String::from("freq_chart_cy_mm,mtf,mtf_err\n");
    for i in 1..=n {
        let f = f_hi_cy_mm * i as f64 / n as f64;
        out.push_str(&format!("{f:.6},{:.6},0\n", p.mtf(f)));
    }
    out
}

impl fmt::Display for PrintMtf {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match *self {
            PrintMtf::Gaussian { sigma_mm } => write!(f, "gaussian:sigma={sigma_mm}mm"),
            PrintMtf::Dots { dpi } => write!(f, "dots:dpi={dpi}"),
        }
    }
}

impl FromStr for PrintMtf {
    type Err = String;

    /// `gaussian:sigma=LENGTH` (a unit is required: 0.02mm, 20um) or `dots:dpi=N`.
    fn from_str(s: &str) -> Result<Self, String> {
        let t = s.trim();
        let (kind, rest) = t.split_once(':').ok_or_else(|| {
            format!("'{s}': expected gaussian:sigma=LENGTH (e.g. 0.02mm) or dots:dpi=N")
        })?;
        let (key, value) = rest
            .split_once('=')
            .ok_or_else(|| format!("'{s}': expected KEY=VALUE after '{kind}:'"))?;
        match (kind.trim().to_ascii_lowercase().as_str(), key.trim()) {
            ("gaussian", "sigma") => {
                let sigma_mm = crate::units::parse_length_mm(value)
                    .map_err(|e| format!("'{s}': sigma: {e}"))?;
                if !(0.0..10.0).contains(&sigma_mm) {
                    return Err(format!("'{s}': sigma must be in [0, 10) mm"));
                }
                Ok(PrintMtf::Gaussian { sigma_mm })
            }
            ("dots", "dpi") => {
                let dpi: f64 = value
                    .trim()
                    .parse()
                    .map_err(|_| format!("'{s}': dpi '{value}' is not a number"))?;
                if !(10.0..=1e5).contains(&dpi) {
                    return Err(format!("'{s}': dpi must be in [10, 100000]"));
                }
                Ok(PrintMtf::Dots { dpi })
            }
            _ => Err(format!(
                "'{s}': expected gaussian:sigma=LENGTH (e.g. 0.02mm) or dots:dpi=N"
            )),
        }
    }
}

impl Serialize for PrintMtf {
    fn serialize<S: Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        s.serialize_str(&self.to_string())
    }
}

impl<'de> Deserialize<'de> for PrintMtf {
    fn deserialize<D: Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        let s = String::deserialize(d)?;
        s.parse().map_err(serde::de::Error::custom)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn parses_and_round_trips() {
        let g: PrintMtf = "gaussian:sigma=0.02mm".parse().unwrap();
        assert_eq!(g, PrintMtf::Gaussian { sigma_mm: 0.02 });
        let g2: PrintMtf = "gaussian:sigma=20um".parse().unwrap();
        assert!(matches!(g2, PrintMtf::Gaussian { sigma_mm } if (sigma_mm - 0.02).abs() < 1e-15));
        let d: PrintMtf = "dots:dpi=600".parse().unwrap();
        assert_eq!(d, PrintMtf::Dots { dpi: 600.0 });
        assert_eq!(d.to_string().parse::<PrintMtf>().unwrap(), d);
        assert_eq!(g.to_string().parse::<PrintMtf>().unwrap(), g);
        for bad in [
            "",
            "gaussian",
            "gaussian:sigma=0.02",
            "gaussian:sigma=-1mm",
            "gaussian:sigma=NaNmm",
            "dots:dpi=0",
            "dots:dpi=abc",
            "lorentz:gamma=1mm",
        ] {
            assert!(bad.parse::<PrintMtf>().is_err(), "{bad}");
        }
    }

    /// The starting table reads back as a chart table equal to the model at its rows.
    #[test]
    fn table_reads_back() {
        let d = PrintMtf::Dots { dpi: 600.0 };
        let text = table_csv(&d, 20.0, 200);
        let t =
            crate::measure::chart_mtf::ChartTable::from_csv_bytes(text.as_bytes(), "t").unwrap();
        assert_eq!(t.f_cy_mm.len(), 200);
        assert!((t.f_cy_mm[199] - 20.0).abs() < 1e-9);
        for (f, m) in t.f_cy_mm.iter().zip(&t.mtf) {
            assert!((m - d.mtf(*f)).abs() < 1e-6);
        }
        // Between rows, linear interpolation of the smooth sinc stays within 1e-4.
        let (m, e) = t.at(10.05).unwrap();
        assert!((m - d.mtf(10.05)).abs() < 1e-4 && e == 0.0);
    }

    /// Closed forms at known points, the singular point f = 0 and the inverse.
    #[test]
    fn closed_forms_and_their_inverse() {
        let g = PrintMtf::Gaussian { sigma_mm: 0.05 };
        assert_eq!(g.mtf(0.0), 1.0);
        // f = 1/(π σ √2): exponent −1.
        let f = 1.0 / (PI * 0.05 * 2f64.sqrt());
        assert!((g.mtf(f) - (-1f64).exp()).abs() < 1e-12);
        assert!((g.mtf(g.freq_at(0.3)) - 0.3).abs() < 1e-12);
        let d = PrintMtf::Dots { dpi: 600.0 };
        assert_eq!(d.mtf(0.0), 1.0);
        // First zero at 600/25.4 cy/mm; half a period there: 2/π.
        assert!(d.mtf(600.0 / 25.4).abs() < 1e-12);
        assert!((d.mtf(300.0 / 25.4) - 2.0 / PI).abs() < 1e-12);
        assert!(d.transfer(1.5 * 600.0 / 25.4) < 0.0);
        assert!((d.mtf(d.freq_at(0.5)) - 0.5).abs() < 1e-9);
        assert!(PrintMtf::Gaussian { sigma_mm: 0.0 }.mtf(1e6) == 1.0);
    }
}
