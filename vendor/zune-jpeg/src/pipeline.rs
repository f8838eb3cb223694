/*
 * sweepmtf: added to the vendored zune-jpeg 0.5.15 (see SWEEPMTF.md).
 *
 * Licensed as the rest of the crate: MIT, Apache-2.0 or Zlib.
 */

//! The baseline decode to `Luma` on two threads.
//!
//! For a sequential JPEG whose one scan holds every component, decoded to
//! `Luma` (only component 0's samples are kept), this thread does the entropy
//! decoding and a worker thread the rest: each MCU row's needed blocks (their
//! dequantised coefficients, the `len` that picks the 1x1/4x4/full IDCT, and
//! where they go) are collected in an [`IdctBatch`], sent to the worker, which
//! runs the same IDCT functions into the same row buffer (component 0's
//! `raw_coeff`, moved to the worker) in the same order, then the same copy of
//! that row into the output as `post_process` (its `Luma` branch). The output
//! is the same byte for byte, also for damaged files: the rows reach the
//! worker in order, one buffer, and every early return (errors, premature end,
//! a marker that ends the scan) first waits for the rows sent before it, as
//! the inline decoder would have processed them.

use alloc::boxed::Box;
use alloc::vec::Vec;

/// sweepmtf: sees the rows of a pipelined decode as they are written, on the
/// thread that writes them: (index of the first row, those rows' samples,
/// `width` bytes each). Rows that a damaged or cut-short file leaves filled
/// with 128 are not shown.
pub type RowObserver = Box<dyn FnMut(usize, &[u8]) + Send>;

/// The IDCT inputs of the needed blocks of some MCU rows, in decoding order.
#[derive(Default)]
pub(crate) struct IdctBatch {
    /// Where each MCU row ends in `blocks` (and in `coeffs`).
    rows: Vec<(usize, usize)>,
    /// Each block's coefficients, back to back: only those its IDCT reads,
    /// 1 (DC: the 1x1 IDCT), 32 (rows 0-3: the 4x4 IDCT; the other rows are
    /// zero) or 64.
    coeffs: Vec<i32>,
    /// Each block's place in the row buffer and the `len` from
    /// `decode_mcu_block` (in zig-zag order: which IDCT runs).
    blocks: Vec<(usize, u16)>
}

/// How many of a block's coefficients are kept for an IDCT picked by `len`.
#[inline(always)]
fn kept(len: u16) -> usize {
    if len <= 1 {
        1
    } else if len <= 10 {
        32
    } else {
        64
    }
}

impl IdctBatch {
    /// A zeroed block after those kept, for `decode_mcu_block` to fill; then
    /// [`Self::commit`]. (The inline path decodes into `tmp`, whose entries
    /// are all zero then, except those the block sets; see SWEEPMTF.md.)
    #[inline(always)]
    pub(crate) fn slot(&mut self) -> &mut [i32; 64] {
        let at = self.coeffs.len();
        self.coeffs.resize(at + 64, 0);
        (&mut self.coeffs[at..]).try_into().unwrap()
    }

    /// Keeps the block decoded into [`Self::slot`] for its IDCT (chosen by
    /// `len`), to be written at `position`.
    #[inline(always)]
    pub(crate) fn commit(&mut self, len: u16, position: usize) {
        let at = self.coeffs.len() - 64;
        self.coeffs.truncate(at + kept(len));
        self.blocks.push((position, len));
    }

    /// The blocks since the last [`Self::end_row`] make a row.
    fn end_row(&mut self) {
        self.rows.push((self.blocks.len(), self.coeffs.len()));
    }

    /// Drops the blocks since the last [`Self::end_row`].
    fn drop_partial_row(&mut self) {
        let (b, c) = self.rows.last().copied().unwrap_or((0, 0));
        self.blocks.truncate(b);
        self.coeffs.truncate(c);
    }

    /// An empty batch with room for `blocks` blocks of up to `per_block`
    /// coefficients (its memory not yet written).
    #[cfg(feature = "std")]
    fn with_capacity(blocks: usize, per_block: usize) -> IdctBatch {
        IdctBatch {
            rows: Vec::new(),
            coeffs: Vec::with_capacity(blocks * per_block),
            blocks: Vec::with_capacity(blocks)
        }
    }

    /// An empty batch whose memory for `blocks` blocks of up to `per_block`
    /// coefficients is already written once (its pages faulted in), so the
    /// thread that fills it does not take those faults.
    #[cfg(feature = "std")]
    fn touched(blocks: usize, per_block: usize) -> IdctBatch {
        // Written with `resize`, not made by `vec![0; n]`: that asks the
        // allocator for zeroed memory, which fresh memory already is, so
        // nothing was written and the pages still faulted in on the thread
        // that filled the batch.
        let mut b = IdctBatch::with_capacity(blocks, per_block);
        b.coeffs.resize(blocks * per_block, 0);
        b.blocks.resize(blocks, (0, 0));
        b.clear();
        b
    }

    fn clear(&mut self) {
        self.rows.clear();
        self.coeffs.clear();
        self.blocks.clear();
    }
}

#[cfg(feature = "std")]
mod threaded {
    #![allow(clippy::std_instead_of_alloc, clippy::alloc_instead_of_core)]

    use std::sync::mpsc;
    use std::thread;

    use zune_core::bytestream::ZByteReaderTrait;
    use zune_core::colorspace::ColorSpace;
    use zune_core::log::{error, trace, warn};

    use super::{kept, IdctBatch};
    use crate::bitstream::BitStream;
    use crate::components::SampleRatios;
    use crate::decoder::{ColorConvert16Ptr, IDCTPtr, MAX_COMPONENTS};
    use crate::errors::DecodeErrors;
    use crate::mcu::McuContinuation;
    use crate::mcu_prog::get_marker;
    use crate::worker::color_convert;
    use crate::JpegDecoder;

    /// Batches in flight: one being filled, the others queued or in the IDCT.
    const BATCHES: usize = 3;

    /// Blocks per batch (at most 2 MiB of coefficients): a handover costs a
    /// thread wake-up (tens of µs here), one per MCU row cost all the gain.
    const BLOCKS: usize = 8192;

    /// Coefficients per block made ready in a new batch: the most a block
    /// keeps, so that no batch grows while it is filled (growing one
    /// reallocates it: a copy, and fresh pages faulted in, on the entropy
    /// decoding's thread; 48 grew the three batches of a 24 MP q92 photo
    /// once each, ≈ 1 600 page faults on that thread).
    const TOUCHED_PER_BLOCK: usize = 64;

    /// Images with fewer pixels are decoded inline unless forced.
    const MIN_PIXELS: usize = 512 * 512;

    /// The worker's state: component 0's row buffer and the output.
    struct RowSink<'a> {
        idct: IDCTPtr,
        idct_4x4: IDCTPtr,
        idct_1x1: IDCTPtr,
        /// Component 0's `width_stride`.
        stride: usize,
        /// Component 0's `raw_coeff` (one MCU row of samples).
        row: Vec<i16>,
        pixels: &'a mut [u8],
        pixels_written: usize,
        /// Output rows per MCU row (`post_process`, `Luma` branch).
        rows_per_mcu: usize,
        width: usize,
        padded_width: usize,
        color_convert_16: ColorConvert16Ptr,
        input_colorspace: ColorSpace,
        output_colorspace: ColorSpace,
        /// Shown each MCU row's output rows once written.
        observer: Option<&'a mut (dyn FnMut(usize, &[u8]) + Send)>
    }

    impl RowSink<'_> {
        /// The MCU rows of `batch`.
        fn run(&mut self, batch: &IdctBatch) -> Result<(), DecodeErrors> {
            let (mut b, mut c) = (0, 0);
            for &(b_end, c_end) in &batch.rows {
                self.run_row(&batch.blocks[b..b_end], &batch.coeffs[c..c_end])?;
                (b, c) = (b_end, c_end);
            }
            Ok(())
        }

        /// One MCU row: the IDCTs of its blocks, then the copy into the output.
        fn run_row(&mut self, blocks: &[(usize, u16)], coeffs: &[i32]) -> Result<(), DecodeErrors> {
            let mut tmp = [0_i32; 64];
            // Whether tmp[32..] may be non-zero (after a full block).
            let mut upper_dirty = false;
            let mut at = 0;
            for &(position, len) in blocks {
                let n = kept(len);
                if n == 32 && upper_dirty {
                    tmp[32..].fill(0);
                    upper_dirty = false;
                }
                tmp[..n].copy_from_slice(&coeffs[at..at + n]);
                at += n;
                let idct_pos = self.row.get_mut(position..).unwrap();
                if len <= 1 {
                    (self.idct_1x1)(&mut tmp, idct_pos, self.stride);
                } else if len <= 10 {
                    (self.idct_4x4)(&mut tmp, idct_pos, self.stride);
                } else {
                    (self.idct)(&mut tmp, idct_pos, self.stride);
                    upper_dirty = true;
                }
            }
            // As `post_process` for a `Luma` output (only component 0).
            let (width, padded_width) = (self.width, self.padded_width);
            let first = self.pixels_written;
            for (pos, output) in self.pixels[self.pixels_written..]
                .chunks_exact_mut(width)
                .take(self.rows_per_mcu)
                .enumerate()
            {
                let mut raw_samples: [&[i16]; MAX_COMPONENTS] = [&[], &[], &[], &[]];
                raw_samples[0] = self
                    .row
                    .get(pos * padded_width..(pos + 1) * padded_width)
                    .ok_or(DecodeErrors::FormatStatic("Missing samples"))?;
                color_convert(
                    &raw_samples,
                    self.color_convert_16,
                    self.input_colorspace,
                    self.output_colorspace,
                    output,
                    width,
                    padded_width
                )?;
                self.pixels_written += width;
            }
            if let Some(f) = self.observer.as_mut() {
                f(first / width.max(1), &self.pixels[first..self.pixels_written]);
            }
            Ok(())
        }
    }

    /// Why the row loop stopped.
    enum Exit {
        /// Every MCU row was decoded.
        Done,
        /// The stream was over-read before this row (premature end).
        Overread,
        /// The entropy decoding failed (strict mode).
        Failed(DecodeErrors),
        /// The row was decoded, then this (not `Ok`) came.
        After(McuContinuation),
        /// The worker stopped early (its error is returned).
        WorkerGone
    }

    impl<T: ZByteReaderTrait> JpegDecoder<T> {
        /// Whether `decode_mcu_ycbcr_baseline` (all components in the first
        /// scan) may use [`Self::decode_baseline_luma_pipelined`].
        pub(crate) fn pipeline_applies(&self) -> bool {
            let wanted = match self.pipeline {
                Some(on) => on,
                None => {
                    usize::from(self.info.width) * usize::from(self.info.height) >= MIN_PIXELS
                }
            };
            wanted
                && self.options.jpeg_get_out_colorspace() == ColorSpace::Luma
                && matches!(self.input_colorspace, ColorSpace::YCbCr | ColorSpace::Luma)
                && self.components.first().is_some_and(|c| c.needed)
                && self.components.iter().skip(1).all(|c| !c.needed)
        }

        /// The `'sos` loop of `decode_mcu_ycbcr_baseline` (all components in
        /// the first scan, `Luma` out) and its end, with the IDCT and the row
        /// copy on a worker thread. Every exit matches the inline loop's.
        /// `None` when no thread could be started (nothing was decoded: the
        /// caller decodes inline).
        #[allow(clippy::too_many_arguments)]
        pub(crate) fn decode_baseline_luma_pipelined(
            &mut self, pixels: &mut [u8], mcu_width: usize, mcu_height: usize, width: usize,
            padded_width: usize, stream: &mut BitStream, tmp: &mut [i32; 64]
        ) -> Option<Result<(), DecodeErrors>> {
            let mut pixels_written = 0;
            let mut first_scan = true;
            'sos: loop {
                // MCU rows per batch: about BLOCKS blocks (fewer handovers).
                let blocks_per_row = self.components[0].width_stride / 8
                    * self.components[0].vertical_sample;
                let rows_per_batch = (BLOCKS / blocks_per_row.max(1)).max(1);
                // The blocks a batch can hold: a whole batch, or the whole
                // image when it is smaller (no memory made for rows it lacks).
                let batch_blocks = (rows_per_batch.min(mcu_height) * blocks_per_row).max(1);
                let rows_per_mcu = if let SampleRatios::Generic(_, v) = self.info.sample_ratio {
                    8 * v * self.coeff
                } else {
                    8 * self.coeff
                };
                let mut observer = self.row_observer.take();
                let ran = thread::scope(|s| {
                    let (give_sink, take_sink) = mpsc::sync_channel::<RowSink>(1);
                    let (to_worker, from_main) = mpsc::sync_channel::<IdctBatch>(BATCHES);
                    let (to_main, from_worker) = mpsc::sync_channel::<IdctBatch>(BATCHES);
                    let worker = thread::Builder::new().spawn_scoped(s, move || {
                        let mut sink = take_sink.recv().ok()?;
                        // The main thread fills its first batch meanwhile;
                        // the others are made here, their pages faulted in
                        // off the entropy decoding's path.
                        for _ in 1..BATCHES {
                            let _ =
                                to_main.send(IdctBatch::touched(batch_blocks, TOUCHED_PER_BLOCK));
                        }
                        let mut sunk = Ok(());
                        for mut batch in from_main {
                            if let Err(e) = sink.run(&batch) {
                                sunk = Err(e);
                                break;
                            }
                            batch.clear();
                            // The main thread may have stopped taking them.
                            let _ = to_main.send(batch);
                        }
                        Some((sunk, sink.row, sink.pixels_written))
                    });
                    // No thread: nothing is taken yet, the caller decodes inline.
                    let worker = worker.ok()?;
                    let sink = RowSink {
                        idct: self.idct_func,
                        idct_4x4: self.idct_4x4_func,
                        idct_1x1: self.idct_1x1_func,
                        stride: self.components[0].width_stride,
                        row: core::mem::take(&mut self.components[0].raw_coeff),
                        pixels: &mut *pixels,
                        pixels_written,
                        rows_per_mcu,
                        width,
                        padded_width,
                        color_convert_16: self.color_convert_16,
                        input_colorspace: self.input_colorspace,
                        output_colorspace: self.options.jpeg_get_out_colorspace(),
                        observer: observer.as_deref_mut().map(|f| f as _)
                    };
                    // (The worker waits for it: this cannot fail.)
                    let _ = give_sink.send(sink);
                    // The first batch with room for a whole batch (its pages
                    // fault in as it fills; it is not reallocated).
                    let mut spare: Vec<IdctBatch> =
                        alloc::vec![IdctBatch::with_capacity(batch_blocks, TOUCHED_PER_BLOCK)];
                    let mut exit = Exit::Done;
                    let mut batch = spare.pop();
                    for i in 0..mcu_height {
                        if stream.overread_by > 0 {
                            exit = Exit::Overread;
                            break;
                        }
                        let Some(b) = batch.as_mut() else {
                            exit = Exit::WorkerGone;
                            break;
                        };
                        match self.decode_mcu_width_deferred(mcu_width, i, tmp, stream, b) {
                            Err(e) => {
                                // Not this row (the inline path stops before
                                // its IDCT), but those before it.
                                b.drop_partial_row();
                                exit = Exit::Failed(e);
                                break;
                            }
                            Ok(next) => {
                                b.end_row();
                                if !matches!(next, McuContinuation::Ok) {
                                    exit = Exit::After(next);
                                    break;
                                }
                                if b.rows.len() >= rows_per_batch {
                                    let full = batch.take().unwrap();
                                    if to_worker.send(full).is_err() {
                                        exit = Exit::WorkerGone;
                                        break;
                                    }
                                    batch = spare.pop().or_else(|| from_worker.recv().ok());
                                }
                            }
                        }
                    }
                    if let Some(b) = batch.filter(|b| !b.rows.is_empty()) {
                        // (Fails only when the worker has stopped on an error.)
                        let _ = to_worker.send(b);
                    }
                    // The worker finishes the rows sent, then stops.
                    drop(to_worker);
                    match worker.join() {
                        Ok(Some((sunk, row, written))) => Some((exit, sunk, row, written)),
                        // (Not met: the worker was given its sink.)
                        Ok(None) => Some((
                            exit,
                            Err(DecodeErrors::FormatStatic("IDCT thread without its rows")),
                            Vec::new(),
                            0
                        )),
                        Err(panic) => std::panic::resume_unwind(panic)
                    }
                });
                self.row_observer = observer;
                let Some((exit, sunk, row, written)) = ran else {
                    // No second thread: inline, unless a scan was decoded here.
                    return if first_scan {
                        None
                    } else {
                        Some(Err(DecodeErrors::FormatStatic("could not start the IDCT thread")))
                    };
                };
                first_scan = false;
                self.components[0].raw_coeff = row;
                pixels_written = written;
                // The worker's error came first in the inline order (its row
                // was decoded before anything the loop met after it).
                if let Err(e) = sunk {
                    return Some(Err(e));
                }
                match exit {
                    Exit::Done => break 'sos,
                    Exit::Overread => {
                        pixels.get_mut(pixels_written..).map(|v| v.fill(128));
                        if self.options.strict_mode() {
                            return Some(Err(DecodeErrors::FormatStatic("Premature end of buffer")));
                        };

                        error!("Premature end of buffer");
                        break 'sos;
                    }
                    Exit::Failed(e) => return Some(Err(e)),
                    Exit::WorkerGone => {
                        return Some(Err(DecodeErrors::FormatStatic("IDCT worker stopped")));
                    }
                    // (Not made: the loop goes on after `Ok`.)
                    Exit::After(McuContinuation::Ok) => break 'sos,
                    Exit::After(McuContinuation::AnotherSos) => {
                        warn!("More than one SOS despite already having all components");
                        return Some(Ok(()));
                    }
                    Exit::After(McuContinuation::InterScanMarker(marker)) => {
                        match self.advance_to_next_sos(marker, stream) {
                            Ok(true) => continue 'sos,
                            Ok(false) => break 'sos,
                            Err(e) => return Some(Err(e))
                        }
                    }
                    Exit::After(McuContinuation::Terminate) => {
                        warn!("Got terminate signal, will not process further");
                        pixels.get_mut(pixels_written..).map(|v| v.fill(128));
                        return Some(Ok(()));
                    }
                }
            }

            // As the end of `decode_mcu_ycbcr_baseline`: read up to EOI.
            if !stream.seen_eoi {
                let marker = get_marker(&mut self.stream, stream);
                match marker {
                    Ok(_m) => {
                        trace!("Found marker {:?}", _m);
                    }
                    Err(_) => {
                        // ignore error
                    }
                }
            }

            trace!("Finished decoding image");

            Some(Ok(()))
        }
    }
}
