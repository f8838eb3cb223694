//! Far-field guard shared by the apertures: beyond |f|·size > 1e250 the true
//! |OTF| of any aperture here is below 1e-250, so 0 is returned there, which
//! keeps every product of a frequency and a length finite.

/// Frequencies (cycles/mm) times the aperture's smallest size (mm) beyond which the OTF is 0.
pub(crate) const FAR: f64 = 1e250;

/// Whether (u, v) lies so far out that the OTF is returned as 0 (`size` in mm);
/// max(|u|, |v|) stands in for |f| (within √2, immaterial at 1e250).
pub(crate) fn far(u: f64, v: f64, size: f64) -> bool {
    u.abs().max(v.abs()) * size > FAR
}

/// Smallest and largest lengths accepted for an aperture or pitch, mm (1 pm and 1 km).
pub(crate) const LENGTH_RANGE_MM: (f64, f64) = (1e-9, 1e6);

/// Checks that a length (mm) is finite, positive and within [`LENGTH_RANGE_MM`].
pub(crate) fn check_length(
    factor: &str,
    key: &str,
    value: f64,
) -> Result<f64, crate::model::ModelError> {
    let (lo, hi) = LENGTH_RANGE_MM;
    if value.is_finite() && value > 0.0 && (lo..=hi).contains(&value) {
        Ok(value)
    } else {
        let why = if !value.is_finite() {
            "must be finite".to_string()
        } else if value <= 0.0 {
            "must be a positive length".to_string()
        } else {
            "must lie between 1 pm and 1 km".to_string()
        };
        Err(crate::model::ModelError::Parameter {
            factor: factor.to_string(),
            message: format!("{key} {why}, got {value} mm"),
        })
    }
}
