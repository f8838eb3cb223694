//! DNG black-level deltas (BlackLevelDeltaH/V), which rawler 0.8.0 reads but
//! does not apply: read from the raw IFD and put into a frame's black levels.

use crate::photo::raw::frame::BlackLevels;
use rawler::rawsource::RawSource;

/// DNG BlackLevelDeltaH (per active-area column) and BlackLevelDeltaV (per
/// active-area row), in DN; rawler 0.8.0 does not apply them.
#[derive(Debug, Default)]
pub(in crate::photo::raw) struct Deltas {
    /// Per active-area column (DN).
    pub h: Vec<f64>,
    /// Per active-area row (DN).
    pub v: Vec<f64>,
}

impl Deltas {
    /// Puts the deltas of the frame `(x0, y0, w, h)` (decoded-buffer pixels)
    /// into `black`; `active` = (x, y, w, h) is the active area the deltas
    /// run over. Deltas of the wrong length are ignored with a warning.
    pub(in crate::photo::raw) fn apply(
        &self,
        black: &mut BlackLevels,
        (x0, y0, w, h): (usize, usize, usize, usize),
        (ax, ay, aw, ah): (usize, usize, usize, usize),
        warnings: &mut Vec<String>,
    ) {
        for (name, d, start, len, full, out) in [
            (
                "BlackLevelDeltaH",
                &self.h,
                x0 - ax.min(x0),
                w,
                aw,
                &mut black.delta_h,
            ),
            (
                "BlackLevelDeltaV",
                &self.v,
                y0 - ay.min(y0),
                h,
                ah,
                &mut black.delta_v,
            ),
        ] {
            if d.is_empty() {
                continue;
            }
            if d.len() == full && start + len <= full && d.iter().all(|v| v.is_finite()) {
                *out = d[start..start + len].to_vec();
            } else {
                warnings.push(format!(
                    "{name} has {} values for an active area {full} px across (or unreadable values): ignored",
                    d.len()
                ));
            }
        }
    }
}

/// Reads BlackLevelDeltaH/V (tags 50715/50716) of the raw IFD rawler decodes
/// (the first full-resolution IFD with a supported compression); none if absent.
pub(super) fn dng_black_deltas(src: &RawSource) -> Deltas {
    use rawler::formats::tiff::GenericTiffReader;
    use rawler::formats::tiff::reader::TiffReader;
    use rawler::tags::{DngTag, TiffCommonTag};
    let Ok(tiff) = GenericTiffReader::new(&mut src.reader(), 0, 0, None, &[]) else {
        return Deltas::default();
    };
    let raw = tiff
        .find_ifds_with_tag(TiffCommonTag::Compression)
        .into_iter()
        .find(|ifd| {
            let compression = ifd
                .get_entry(TiffCommonTag::Compression)
                .and_then(|e| e.value.get_u32(0).ok().flatten())
                .unwrap_or(0);
            let subsampled = ifd
                .get_entry(TiffCommonTag::NewSubFileType)
                .and_then(|e| e.value.get_u32(0).ok().flatten())
                .is_some_and(|t| t & 1 != 0);
            !subsampled && [1, 7, 8, 0x884c, 52546].contains(&compression)
        });
    let Some(raw) = raw else {
        return Deltas::default();
    };
    let read = |tag: DngTag| -> Vec<f64> {
        raw.get_entry(tag)
            .map(|e| {
                (0..e.count() as usize)
                    .map(|i| {
                        e.value
                            .get_f32(i)
                            .ok()
                            .flatten()
                            .map_or(f64::NAN, f64::from)
                    })
                    .collect()
            })
            .unwrap_or_default()
    };
    Deltas {
        h: read(DngTag::BlackLevelDeltaH),
        v: read(DngTag::BlackLevelDeltaV),
    }
}
