//! The windowed decode ([`Job`]'s methods): the strips or tiles meeting the
//! wanted rectangle read and decoded in parallel bands, straight into the
//! frame buffer.

use super::{Codec, Job, Source};
use rawler::decompressors::Decompressor;
use rawler::decompressors::ljpeg::LjpegDecompressor;
use rawler::decompressors::packed::PackedDecompressor;
use rayon::prelude::*;

thread_local! {
    /// Per-thread buffers reused from unit to unit: the unit's bytes and its decoded samples.
    static SCRATCH: std::cell::RefCell<(Vec<u8>, Vec<u16>)> = const {
        std::cell::RefCell::new((Vec::new(), Vec::new()))
    };
}

/// Scratch capacity (elements) kept per thread between decodes: enough for
/// common strips and tiles (a 16-row strip of 6000 px is 96 k samples).
const SCRATCH_KEEP: usize = 1 << 20;

/// Rows of an uncompressed unit decoded per task.
const PACKED_ROWS: usize = 64;

impl Job<'_> {
    /// Decodes every unit meeting the wanted rectangle into `out` (the frame
    /// buffer), one band of unit rows per parallel task.
    pub(super) fn run(&self, source: &Source, out: &mut [u16]) -> Result<(), String> {
        let u = self.units;
        let (_, fy, fw) = self.frame;
        let (x0, y0, x1, y1) = self.want;
        let row_len = fw * self.spp;
        // Frame rows y0..y1 split at unit-row boundaries, each band with its
        // slice; uncompressed units (which can start at any row) also every
        // PACKED_ROWS rows, so that one big strip still decodes in parallel
        // through a small buffer.
        let step = match self.codec {
            Codec::Packed => PACKED_ROWS,
            Codec::Ljpeg => u.h,
        };
        let mut bands = Vec::new();
        let mut rest = &mut out[(y0 - fy) * row_len..(y1 - fy) * row_len];
        let mut y = y0;
        while y < y1 {
            let band = y / u.h;
            let end = ((band + 1) * u.h).min((y / step + 1) * step).min(y1);
            let (head, tail) = rest.split_at_mut((end - y) * row_len);
            bands.push((band, y, end, head));
            rest = tail;
            y = end;
        }
        let (c0, c1) = (x0 / u.w, (x1 - 1) / u.w + 1);
        bands.into_par_iter().try_for_each(|(band, ya, yb, dst)| {
            for col in c0..c1.min(u.across) {
                self.unit(source, band, col, (ya, yb), dst)?;
            }
            Ok::<(), String>(())
        })
    }

    /// Decodes image rows `rows` of unit (`band`, `col`) and copies the wanted
    /// columns into `dst` (the frame rows `rows`).
    fn unit(
        &self,
        source: &Source,
        band: usize,
        col: usize,
        rows: (usize, usize),
        dst: &mut [u16],
    ) -> Result<(), String> {
        let u = self.units;
        let i = band * u.across + col;
        let (ux, uy) = (col * u.w, band * u.h);
        let line = u.w * self.spp;
        let (r0, r1) = (rows.0 - uy, rows.1 - uy);
        let (offset, count) = (u.offsets[i], u.counts[i]);
        SCRATCH.with(|scratch| {
            let (bytes, samples) = &mut *scratch.borrow_mut();
            // `samples` from `first` on: the unit's rows r0..r1, `line` samples each.
            let first = match self.codec {
                Codec::Packed => {
                    let row_bits = line as u64 * self.bits as u64;
                    let need = (r1 as u64 * row_bits).div_ceil(8);
                    if need > count {
                        return Err(format!(
                            "unit {i} holds {count} bytes where {need} are needed"
                        ));
                    }
                    // Whole bytes up to the first wanted row are skipped when rows are byte aligned.
                    let (start, skip) = if row_bits.is_multiple_of(8) {
                        (r0 as u64 * row_bits / 8, 0)
                    } else {
                        (0, r0)
                    };
                    source.read_into(offset + start, need - start, bytes)?;
                    samples.resize((r1 - r0) * line, 0);
                    PackedDecompressor::new(self.bits, self.endian).decompress(
                        bytes,
                        skip,
                        samples.chunks_exact_mut(line),
                        line,
                    )?;
                    0
                }
                Codec::Ljpeg => {
                    source.read_into(offset, count, bytes)?;
                    // The whole unit is decoded (into the reused buffer); rows r0.. are kept.
                    let d = LjpegDecompressor::new(bytes)?;
                    let (w, h) = (d.width(), d.height());
                    if w != line || h < r1 {
                        return Err(format!(
                            "unit {i} decodes to {w}×{h} samples where {line}×{} are expected",
                            r1
                        ));
                    }
                    samples.resize(w * h, 0);
                    d.decode(samples, 0, w, w, h, false)?;
                    r0 * line
                }
            };
            self.place(&samples[first..first + (r1 - r0) * line], ux, dst);
            // Big units (one strip for the whole image) are not kept alive per thread.
            if samples.capacity() > SCRATCH_KEEP {
                *samples = Vec::new();
            }
            if bytes.capacity() > SCRATCH_KEEP {
                *bytes = Vec::new();
            }
            Ok(())
        })
    }

    /// Copies the unit rows in `rows` (unit width, starting at image column
    /// `ux`) into the frame rows `dst`, the columns inside the image, the
    /// frame and the wanted range only.
    fn place(&self, rows: &[u16], ux: usize, dst: &mut [u16]) {
        let u = self.units;
        let line = u.w * self.spp;
        // Columns of this unit inside the image, the frame and the wanted range.
        let (fx, _, fw) = self.frame;
        let xa = ux.max(self.want.0).max(fx);
        let xb = (ux + u.w).min(self.width).min(self.want.2).min(fx + fw);
        if xa >= xb {
            return;
        }
        let row_len = fw * self.spp;
        let n = (xb - xa) * self.spp;
        for (k, src_row) in rows.chunks_exact(line).enumerate() {
            let s = (xa - ux) * self.spp;
            let d = k * row_len + (xa - fx) * self.spp;
            dst[d..d + n].copy_from_slice(&src_row[s..s + n]);
        }
    }
}
