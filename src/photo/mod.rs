//! Photo decoding (JPEG, PNG, TIFF, camera raw), EXIF facts and linearisation
//! to linear light. The output of this layer is one or more [`Plane`]s of
//! linear values on known pixel sites, which the measurement bins without
//! resampling (a Bayer colour's sites are a sparse plane; no demosaicing).

pub mod decode;
pub mod exif;
pub(crate) mod hugebuf;
pub mod jpeg;
pub mod jpeg_check;
pub mod jpeg_quant;
pub mod linearise;
pub mod pitch;
pub mod plane_ref;
pub mod raw;
pub mod transfer;

pub use plane_ref::{PlaneData, PlaneRef};

/// One channel of linear-light samples on a regular lattice of image pixel sites.
///
/// Sample `(i, j)` (column i, row j) sits at the image pixel whose centre is
/// `(offset.0 + i·step.0 + 0.5, offset.1 + j·step.1 + 0.5)` in image pixel
/// coordinates (origin at the image's top-left corner, x right, y down). A full
/// grey image has step (1, 1) and offset (0, 0); the red sites of an RGGB
/// mosaic have step (2, 2) and offset (0, 0); its two green planes have
/// offsets (1, 0) and (0, 1).
#[derive(Debug, Clone, PartialEq)]
pub struct Plane {
    /// Samples in this lattice (columns).
    pub width: usize,
    /// Samples in this lattice (rows).
    pub height: usize,
    /// Lattice step in image pixels (x, y).
    pub step: (usize, usize),
    /// Image-pixel offset of sample (0, 0) (x, y).
    pub offset: (usize, usize),
    /// Linear values, row-major, `width × height`; 1.0 = white/clipping level.
    pub data: Vec<f32>,
}

impl Plane {
    /// A full-resolution plane (step 1, offset 0).
    pub fn full(width: usize, height: usize, data: Vec<f32>) -> Plane {
        Plane {
            width,
            height,
            step: (1, 1),
            offset: (0, 0),
            data,
        }
    }

    /// The value of sample (i, j).
    pub fn get(&self, i: usize, j: usize) -> f32 {
        self.data[j * self.width + i]
    }

    /// Image pixel coordinates (x, y) of the centre of sample (i, j).
    pub fn centre(&self, i: usize, j: usize) -> (f64, f64) {
        (
            (self.offset.0 + i * self.step.0) as f64 + 0.5,
            (self.offset.1 + j * self.step.1) as f64 + 0.5,
        )
    }
}
