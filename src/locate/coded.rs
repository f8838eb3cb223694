//! A decoded photo as the search's source: rows converted on demand as by
//! [`Converted`], but the reduced search image summed straight from the
//! integer codes through the conversion's table. The values and the order of
//! every sum are [`Converted::reduced`]'s (so the reduced image is the same to
//! the bit), without a row of linear values written and read back for each of
//! the frame's rows (issue 16: on a 24 MP JPEG the reduction was over half of
//! the search's CPU).

use super::downscale::factor;
use super::row_reduction::ReducedSearch;
use super::sample::Gray;
use super::source::{BAND, Converted, Source, Window};
use crate::photo::decode::{Decoded, Samples};
use crate::photo::linearise::{Channel, CodedTone, Crop, Tone, coded, row_converter};
use rayon::prelude::*;
use std::borrow::Cow;

/// A decoded photo searched as a [`Converted`] one, with the reduced image made from its codes.
pub struct Coded<'a, F> {
    /// Rows converted on demand (the windows, and the reduced image of floating-point samples).
    pub converted: Converted<F>,
    dec: &'a Decoded,
    /// The code → linear table and the channel weights ([`coded`]).
    table: Option<CodedTone>,
    /// The search image, if already summed while the photo was decoded.
    pre: Option<&'a ReducedSearch>,
}

/// `dec` as a search source: the linear values of `channel` through `tone`,
/// exactly as [`row_converter`] gives them.
pub fn of_decoded<'a>(
    dec: &'a Decoded,
    tone: &Tone,
    channel: Channel,
) -> Coded<'a, impl Fn(usize, usize, &mut [f32]) + Sync + use<'a>> {
    Coded {
        converted: Converted {
            width: dec.width,
            height: dec.height,
            convert: row_converter(dec, tone, channel),
        },
        dec,
        table: coded(dec, tone, channel),
        pre: None,
    }
}

impl<'a, F> Coded<'a, F> {
    /// Searches `pre` as the reduced image, when it was summed as
    /// [`Source::reduced`] would sum it (same factor, table and channel;
    /// else it is left aside).
    pub fn with_reduced(mut self, pre: Option<&'a ReducedSearch>) -> Self {
        self.pre = pre.filter(|p| {
            let k = factor(self.dec.width, self.dec.height);
            let one_channel = self.dec.channels == 1 && matches!(self.dec.samples, Samples::U8(_));
            let same_table = self.table.as_ref().is_some_and(|t| {
                t.mix() == [(0, 1.0)]
                    && t.table().len() == 256
                    && t.table()
                        .iter()
                        .zip(p.lut.iter())
                        .all(|(a, b)| a.to_bits() == b.to_bits())
            });
            one_channel
                && same_table
                && p.gray.scale == [k as f64, k as f64]
                && (p.gray.w, p.gray.h) == (self.dec.width / k, self.dec.height / k)
        });
        self
    }
}

impl<F: Fn(usize, usize, &mut [f32]) + Sync> Source for Coded<'_, F> {
    fn size(&self) -> (usize, usize) {
        self.converted.size()
    }

    fn reduced(&self) -> Gray<'_> {
        if let Some(p) = self.pre {
            return Gray {
                data: Cow::Borrowed(&p.gray.data),
                ..p.gray
            };
        }
        let k = factor(self.dec.width, self.dec.height);
        let fast = match (&self.table, &self.dec.samples) {
            (Some(t), Samples::U8(codes)) if k > 1 => {
                let lut: Option<&[f32; 256]> = t.table().try_into().ok();
                lut.and_then(|lut| self.reduced_from(codes, lut, t.mix(), k))
            }
            (Some(t), Samples::U16(codes)) if k > 1 => {
                let lut: Option<&[f32; 65536]> = t.table().try_into().ok();
                lut.and_then(|lut| self.reduced_from(codes, lut, t.mix(), k))
            }
            _ => None,
        };
        fast.unwrap_or_else(|| self.converted.reduced())
    }

    fn window(&self, want: Crop) -> Window<'_> {
        self.converted.window(want)
    }
}

impl<F> Coded<'_, F> {
    /// [`Converted::reduced`] summed from the codes; `None` for weights it does not handle.
    fn reduced_from<T: Copy + Into<usize> + Sync, const N: usize>(
        &self,
        codes: &[T],
        lut: &[f32; N],
        mix: &[(usize, f32)],
        k: usize,
    ) -> Option<Gray<'static>> {
        let (iw, nc) = (self.dec.width, self.dec.channels);
        if !matches!(mix.len(), 1 | 3) || mix.iter().any(|&(c, _)| c >= nc) {
            return None;
        }
        let (w, h) = (self.dec.width / k, self.dec.height / k);
        let inv = 1.0 / (k * k) as f32;
        let mut out = vec![0.0f32; w * h];
        out.par_chunks_mut((w * BAND).max(1))
            .enumerate()
            .for_each(|(b, rows)| {
                let mut acc = vec![0.0f32; w];
                for (jj, row) in rows.chunks_mut(w).enumerate() {
                    let j = b * BAND + jj;
                    acc.iter_mut().for_each(|a| *a = 0.0);
                    for r in 0..k {
                        let a = (j * k + r) * iw * nc;
                        add_code_sums(&mut acc, &codes[a..a + w * k * nc], k, nc, mix, lut);
                    }
                    for (o, a) in row.iter_mut().zip(&acc) {
                        *o = a * inv;
                    }
                }
            });
        Some(Gray {
            w,
            h,
            data: Cow::Owned(out),
            origin: [0.0, 0.0],
            scale: [k as f64, k as f64],
        })
    }
}

/// Adds to each `acc[i]` the sum, left to right, of the linear values of
/// pixels `k·i .. k·i + k` of `line` (as [`super::downscale::add_box_sums`]
/// sums a row of converted values). `mix` has one or three weights.
pub(super) fn add_code_sums<T: Copy + Into<usize>, const N: usize>(
    acc: &mut [f32],
    line: &[T],
    k: usize,
    nc: usize,
    mix: &[(usize, f32)],
    lut: &[f32; N],
) {
    match k {
        2 => code_sums::<T, N, 2>(acc, line, nc, mix, lut),
        3 => code_sums::<T, N, 3>(acc, line, nc, mix, lut),
        4 => code_sums::<T, N, 4>(acc, line, nc, mix, lut),
        5 => code_sums::<T, N, 5>(acc, line, nc, mix, lut),
        6 => code_sums::<T, N, 6>(acc, line, nc, mix, lut),
        7 => code_sums::<T, N, 7>(acc, line, nc, mix, lut),
        8 => code_sums::<T, N, 8>(acc, line, nc, mix, lut),
        _ => {
            let value = |p: &[T]| linear(p, mix, lut);
            for (a, px) in acc.iter_mut().zip(line.chunks_exact(k * nc)) {
                let mut s = value(px);
                for t in 1..k {
                    s += value(&px[t * nc..]);
                }
                *a += s;
            }
        }
    }
}

/// One pixel's linear value, as `convert_row` gives it (one or three weights).
#[inline(always)]
fn linear<T: Copy + Into<usize>, const N: usize>(
    p: &[T],
    mix: &[(usize, f32)],
    lut: &[f32; N],
) -> f32 {
    match *mix {
        [(c, _)] => lut[p[c].into()],
        [(c0, w0), (c1, w1), (c2, w2)] => {
            w0 * lut[p[c0].into()] + w1 * lut[p[c1].into()] + w2 * lut[p[c2].into()]
        }
        _ => unreachable!("one or three weights"),
    }
}

#[inline(always)]
fn code_sums<T: Copy + Into<usize>, const N: usize, const K: usize>(
    acc: &mut [f32],
    line: &[T],
    nc: usize,
    mix: &[(usize, f32)],
    lut: &[f32; N],
) {
    if nc == 1 {
        // Grey: the table straight (the one weight is channel 0's).
        for (a, px) in acc.iter_mut().zip(line.chunks_exact(K)) {
            let px: &[T; K] = px.try_into().expect("chunks_exact gives K");
            let mut s = lut[px[0].into()];
            for &c in &px[1..] {
                s += lut[c.into()];
            }
            *a += s;
        }
        return;
    }
    for (a, px) in acc.iter_mut().zip(line.chunks_exact(K * nc)) {
        let mut s = linear(px, mix, lut);
        for t in 1..K {
            s += linear(&px[t * nc..], mix, lut);
        }
        *a += s;
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn photo(w: usize, h: usize, nc: usize, sixteen: bool) -> Decoded {
        let code = |i: usize| (i * 7919 + (i / (w * nc)) * 104_729) % 65_536;
        let n = w * h * nc;
        Decoded {
            width: w,
            height: h,
            channels: nc,
            samples: if sixteen {
                Samples::U16((0..n).map(|i| code(i) as u16).collect())
            } else {
                Samples::U8((0..n).map(|i| (code(i) % 256) as u8).collect())
            },
            format: "png",
            rows: h,
            warnings: Vec::new(),
            declared_tone: None,
            jpeg_luma_quant: None,
        }
    }

    #[test]
    fn reduced_from_codes_equals_the_converted_rows_reduction() {
        // Factors 2, 3 and 6 with trailing rows and columns; grey and RGB (luma
        // and one channel); 8 and 16 bits.
        for (w, h) in [(1931, 1297), (2100, 1925), (3850, 3851)] {
            for (nc, channel) in [(1, Channel::Luma), (3, Channel::Luma), (3, Channel::G)] {
                for sixteen in [false, true] {
                    let dec = photo(w, h, nc, sixteen);
                    let src = of_decoded(&dec, &Tone::Srgb, channel);
                    let a = src.converted.reduced();
                    let b = src.reduced();
                    assert_eq!((a.w, a.h, a.scale, a.origin), (b.w, b.h, b.scale, b.origin));
                    assert!(
                        a.data
                            .iter()
                            .zip(b.data.iter())
                            .all(|(x, y)| x.to_bits() == y.to_bits()),
                        "{w}×{h}×{nc} {channel:?} 16-bit {sixteen}"
                    );
                }
            }
        }
    }
}
