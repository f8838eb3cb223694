//! The search image summed from a decoder's rows as they are written
//! (issue 16): a pipelined JPEG decode hands each MCU row's luma to its
//! second thread's observer, which adds it into the reduced image, so the
//! search does not read the whole frame again after decoding. The sums and
//! their order are [`super::coded`]'s, so the image is the same to the bit;
//! [`super::coded::Coded`] takes it only when it was made with the table and
//! factor the search would use, from every row.

use super::coded::add_code_sums;
use super::downscale::factor;
use super::sample::Gray;
use std::borrow::Cow;
use std::sync::{Arc, Mutex};

/// The reduced search image of an 8-bit one-channel photo, built row by row.
pub struct RowReduction {
    /// Reduction factor (image px per search-image px).
    k: usize,
    /// Search-image columns and rows.
    w: usize,
    h: usize,
    /// Image columns.
    width: usize,
    /// Code → linear table.
    lut: Box<[f32; 256]>,
    /// The current search row's sums.
    acc: Vec<f32>,
    /// The search image, row-major.
    out: Vec<f32>,
    /// The next image row expected; rows out of order spoil the image.
    next: usize,
    spoilt: bool,
}

/// A finished search image and the table it was summed through.
pub struct ReducedSearch {
    /// The search image (as [`super::Source::reduced`] gives it).
    pub gray: Gray<'static>,
    /// Code → linear table used.
    pub lut: Box<[f32; 256]>,
}

impl RowReduction {
    /// A reduction of a `width` × `height` photo through `lut` (256 entries);
    /// `None` when the search reads the photo unreduced.
    pub fn new(width: usize, height: usize, lut: &[f32]) -> Option<RowReduction> {
        let k = factor(width, height);
        let lut: Box<[f32; 256]> = Box::new(lut.try_into().ok()?);
        (k > 1).then(|| {
            let (w, h) = (width / k, height / k);
            RowReduction {
                k,
                w,
                h,
                width,
                lut,
                acc: vec![0.0; w],
                out: vec![0.0; w * h],
                next: 0,
                spoilt: false,
            }
        })
    }

    /// Adds image rows `first ..` (`width` samples each, back to back).
    pub fn rows(&mut self, first: usize, rows: &[u8]) {
        if first != self.next || self.width == 0 || !rows.len().is_multiple_of(self.width) {
            self.spoilt = true;
        }
        if self.spoilt {
            return;
        }
        let (k, w) = (self.k, self.w);
        let inv = 1.0 / (k * k) as f32;
        for (r, line) in rows.chunks_exact(self.width).enumerate() {
            let j = first + r;
            if j >= self.h * k {
                break;
            }
            add_code_sums(&mut self.acc, &line[..w * k], k, 1, &[(0, 1.0)], &self.lut);
            if (j + 1).is_multiple_of(k) {
                let o = &mut self.out[(j / k) * w..(j / k + 1) * w];
                for (o, a) in o.iter_mut().zip(&mut self.acc) {
                    *o = *a * inv;
                    *a = 0.0;
                }
            }
        }
        self.next = first + rows.len() / self.width;
    }

    /// The search image, if every row it needs was added in order.
    pub fn finish(self) -> Option<ReducedSearch> {
        if self.spoilt || self.next < self.h * self.k {
            return None;
        }
        Some(ReducedSearch {
            gray: Gray {
                w: self.w,
                h: self.h,
                data: Cow::Owned(self.out),
                origin: [0.0, 0.0],
                scale: [self.k as f64, self.k as f64],
            },
            lut: self.lut,
        })
    }
}

/// A row reduction handed to a decoder as its row observer (it runs on the
/// decoder's thread) and taken back when the decode is over.
#[derive(Default, Clone)]
pub struct SharedReduction(Arc<Mutex<Option<RowReduction>>>);

impl SharedReduction {
    /// The row observer summing a `width` × `height` photo's 8-bit rows
    /// through `lut` (256 entries) into the search image; `None` when the
    /// search reads the photo unreduced.
    pub fn observer(
        &self,
        width: usize,
        height: usize,
        lut: &[f32],
    ) -> Option<zune_jpeg::RowObserver> {
        *self.0.lock().ok()? = Some(RowReduction::new(width, height, lut)?);
        let shared = Arc::clone(&self.0);
        Some(Box::new(move |first: usize, rows: &[u8]| {
            if let Ok(mut r) = shared.lock()
                && let Some(r) = r.as_mut()
            {
                r.rows(first, rows);
            }
        }))
    }

    /// The search image, if every row it needs was shown, in order.
    pub fn finish(&self) -> Option<ReducedSearch> {
        self.0.lock().ok()?.take()?.finish()
    }
}
