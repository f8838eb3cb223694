//! Reading the values of TIFF tags from an IFD: counts, integers, numbers and bytes.

use rawler::formats::tiff::{IFD, Value};

pub(super) fn count(ifd: &IFD, tag: impl rawler::tags::TiffTag) -> usize {
    ifd.get_entry(tag).map_or(0, |e| e.count() as usize)
}

pub(super) fn usize_at(ifd: &IFD, tag: impl rawler::tags::TiffTag, i: usize) -> Option<usize> {
    ifd.get_entry(tag)
        .and_then(|e| e.value.get_usize(i).ok().flatten())
}

/// n / d, NaN for a zero denominator.
fn ratio(n: f64, d: f64) -> f64 {
    if d == 0.0 { f64::NAN } else { n / d }
}

pub(super) fn f64s(ifd: &IFD, tag: impl rawler::tags::TiffTag) -> Option<Vec<f64>> {
    let e = ifd.get_entry(tag)?;
    let v: Option<Vec<f64>> = match &e.value {
        Value::Short(v) => Some(v.iter().map(|&x| x as f64).collect()),
        Value::Long(v) => Some(v.iter().map(|&x| x as f64).collect()),
        Value::Rational(v) => Some(v.iter().map(|r| ratio(r.n as f64, r.d as f64)).collect()),
        Value::SRational(v) => Some(v.iter().map(|r| ratio(r.n as f64, r.d as f64)).collect()),
        Value::Float(v) => Some(v.iter().map(|&x| x as f64).collect()),
        Value::Double(v) => Some(v.clone()),
        _ => None,
    };
    v
}

pub(super) fn bytes(ifd: &IFD, tag: impl rawler::tags::TiffTag) -> Option<Vec<u8>> {
    match &ifd.get_entry(tag)?.value {
        Value::Byte(v) | Value::Undefined(v) => Some(v.clone()),
        Value::Short(v) => v.iter().map(|&x| u8::try_from(x).ok()).collect(),
        _ => None,
    }
}
