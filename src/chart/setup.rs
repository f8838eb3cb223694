//! The intended shooting set-up (pixel pitch, focal length, distance) and the
//! conversion between chart frequencies (cycles/mm on the print) and image
//! frequencies (cycles/pixel), with thin-lens magnification m = f/(d − f).

use super::ChartError;

/// Camera set-up the chart is made for.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Setup {
    /// Sensor pixel pitch (mm).
    pub pixel_pitch_mm: f64,
    /// Lens focal length (mm).
    pub focal_length_mm: f64,
    /// Distance from the lens to the chart (mm).
    pub distance_mm: f64,
}

impl Setup {
    /// Checks the set-up is physical (positive values, chart beyond the focal length).
    pub fn new(
        pixel_pitch_mm: f64,
        focal_length_mm: f64,
        distance_mm: f64,
    ) -> Result<Setup, ChartError> {
        let pos = |v: f64| v.is_finite() && v > 0.0;
        if !(pos(pixel_pitch_mm) && pos(focal_length_mm) && pos(distance_mm)) {
            return Err(ChartError::Invalid(
                "--pixel-pitch, --focal-length and --distance must be positive".into(),
            ));
        }
        if distance_mm <= focal_length_mm {
            return Err(ChartError::Invalid(format!(
                "--distance {distance_mm} mm must exceed --focal-length {focal_length_mm} mm \
                 (the chart must lie beyond the focal length to be imaged)"
            )));
        }
        Ok(Setup {
            pixel_pitch_mm,
            focal_length_mm,
            distance_mm,
        })
    }

    /// Image-to-chart magnification m = f/(d − f) (image size / chart size).
    pub fn magnification(&self) -> f64 {
        self.focal_length_mm / (self.distance_mm - self.focal_length_mm)
    }

    /// Chart frequency (cycles/mm on the print) that images at `cy_px` cycles/pixel.
    pub fn chart_cy_mm(&self, cy_px: f64) -> f64 {
        cy_px * self.magnification() / self.pixel_pitch_mm
    }

    /// Image frequency (cycles/pixel) of a chart frequency (cycles/mm on the print).
    pub fn cy_px(&self, chart_cy_mm: f64) -> f64 {
        chart_cy_mm * self.pixel_pitch_mm / self.magnification()
    }

    /// Size on the chart (mm) of one sensor pixel projected onto it.
    pub fn pixel_on_chart_mm(&self) -> f64 {
        self.pixel_pitch_mm / self.magnification()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn magnification_by_hand() {
        // 50 mm lens at 2 m: m = 50/1950; 4.3 µm pixels see 0.1677 mm on the chart.
        let s = Setup::new(0.0043, 50.0, 2000.0).unwrap();
        assert!((s.pixel_on_chart_mm() - 0.0043 * 39.0).abs() < 1e-12);
        // 0.5 cy/px = one cycle every two projected pixels.
        assert!((s.chart_cy_mm(0.5) - 0.5 / (0.0043 * 39.0)).abs() < 1e-12);
        assert!((s.cy_px(s.chart_cy_mm(0.123)) - 0.123).abs() < 1e-12);
        assert!(Setup::new(0.0043, 50.0, 40.0).is_err());
        assert!(Setup::new(0.0, 50.0, 400.0).is_err());
    }
}
