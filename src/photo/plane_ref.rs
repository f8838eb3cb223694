//! A read-only view of one lattice of linear samples, held either as linear
//! values ([`super::Plane`]) or as the decoded photo's own integer codes read
//! through the tone's table, so a measurement bins a JPEG's bytes in place:
//! no converted copy of the region (on a 24 MP strip that copy was 35 MB
//! written once and read once).

use super::Plane;

/// One lattice of linear samples; the geometry is [`Plane`]'s.
#[derive(Debug, Clone, Copy)]
pub struct PlaneRef<'a> {
    /// Samples in this lattice (columns).
    pub width: usize,
    /// Samples in this lattice (rows).
    pub height: usize,
    /// Lattice step in image pixels (x, y).
    pub step: (usize, usize),
    /// Image-pixel offset of sample (0, 0) (x, y).
    pub offset: (usize, usize),
    /// Where the values come from.
    pub data: PlaneData<'a>,
}

/// Where a [`PlaneRef`]'s values come from.
#[derive(Debug, Clone, Copy)]
pub enum PlaneData<'a> {
    /// Linear values, row-major, `width × height`.
    Linear(&'a [f32]),
    /// 8-bit codes converted where read.
    Codes8(Codes<'a, u8>),
    /// 16-bit codes converted where read.
    Codes16(Codes<'a, u16>),
}

/// Integer codes, `channels` per sample, row-major; a sample's linear value
/// is Σ w · lut\[code of channel c\] over `mix` (c, w), summed in `mix`'s
/// order, exactly as [`super::linearise::planes`] converts it.
#[derive(Debug, Clone, Copy)]
pub struct Codes<'a, T> {
    /// The codes, `width × height × channels`.
    pub codes: &'a [T],
    /// Codes per sample.
    pub channels: usize,
    /// (channel, weight) pairs of the mix.
    pub mix: &'a [(usize, f32)],
    /// Linear value of each code.
    pub lut: &'a [f32],
}

impl<'a> From<&'a Plane> for PlaneRef<'a> {
    fn from(p: &'a Plane) -> Self {
        PlaneRef {
            width: p.width,
            height: p.height,
            step: p.step,
            offset: p.offset,
            data: PlaneData::Linear(&p.data),
        }
    }
}

impl<'a> PlaneRef<'a> {
    /// The image-pixel centre of sample (0, 0) and the lattice step, as
    /// (ox, oy, sx, sy): sample (i, j) sits at (ox + i·sx, oy + j·sy).
    pub fn centres(&self) -> (f64, f64, f64, f64) {
        (
            self.offset.0 as f64 + 0.5,
            self.offset.1 as f64 + 0.5,
            self.step.0 as f64,
            self.step.1 as f64,
        )
    }

    /// The values of samples i0 .. i0 + out.len() of row j: a slice of the
    /// plane itself for linear data, else `out` filled with the converted codes.
    #[inline(always)]
    pub fn values<'b>(&'b self, j: usize, i0: usize, out: &'b mut [f32]) -> &'b [f32]
    where
        'a: 'b,
    {
        let k = j * self.width + i0;
        let n = out.len();
        match self.data {
            PlaneData::Linear(d) => &d[k..k + n],
            PlaneData::Codes8(c) => {
                c.convert(k, out);
                out
            }
            PlaneData::Codes16(c) => {
                c.convert(k, out);
                out
            }
        }
    }

    /// Writes the values of samples i0 .. i0 + out.len() of row j into `out`
    /// (copied for linear data, converted from the codes otherwise).
    #[inline(always)]
    pub fn read_into(&self, j: usize, i0: usize, out: &mut [f32]) {
        let k = j * self.width + i0;
        match self.data {
            PlaneData::Linear(d) => out.copy_from_slice(&d[k..k + out.len()]),
            PlaneData::Codes8(c) => c.convert(k, out),
            PlaneData::Codes16(c) => c.convert(k, out),
        }
    }

    /// Asks the CPU to bring sample (i, j)'s cache line in ahead of its use
    /// (a hint: no effect on any value, nothing read if (i, j) is outside).
    #[inline(always)]
    pub fn prefetch(&self, i: usize, j: usize) {
        #[cfg(target_arch = "x86_64")]
        {
            let k = j * self.width + i;
            let p: Option<*const i8> = match self.data {
                PlaneData::Linear(d) => d.get(k).map(|v| (v as *const f32).cast()),
                PlaneData::Codes8(c) => {
                    c.codes.get(k * c.channels).map(|v| (v as *const u8).cast())
                }
                PlaneData::Codes16(c) => c
                    .codes
                    .get(k * c.channels)
                    .map(|v| (v as *const u16).cast()),
            };
            if let Some(p) = p {
                // SAFETY: a prefetch never faults and changes nothing the
                // program can see; `p` points into the plane besides.
                unsafe { std::arch::x86_64::_mm_prefetch::<{ std::arch::x86_64::_MM_HINT_T0 }>(p) };
            }
        }
        #[cfg(not(target_arch = "x86_64"))]
        let _ = (i, j);
    }

    /// The value of sample (i, j).
    #[inline]
    pub fn at(&self, i: usize, j: usize) -> f32 {
        let mut v = [0.0f32];
        self.values(j, i, &mut v)[0]
    }
}

impl<T: Copy + Into<usize>> Codes<'_, T> {
    /// Converts the samples from index `k` on into `out`.
    #[inline(always)]
    fn convert(&self, k: usize, out: &mut [f32]) {
        let nc = self.channels;
        let codes = &self.codes[k * nc..(k + out.len()) * nc];
        super::linearise::convert_row(out, codes, nc, self.mix, self.lut);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn codes_read_in_place_equal_the_converted_plane() {
        // Two rows of three RGB samples; luma-like mix with a gamma-ish table.
        let codes: Vec<u8> = (0..18).map(|i| (i * 13 % 256) as u8).collect();
        let lut: Vec<f32> = (0..256).map(|c| (c as f32 / 255.0).powf(2.2)).collect();
        let mix = [(0, 0.2126f32), (1, 0.7152), (2, 0.0722)];
        let view = PlaneRef {
            width: 3,
            height: 2,
            step: (1, 1),
            offset: (0, 0),
            data: PlaneData::Codes8(Codes {
                codes: &codes,
                channels: 3,
                mix: &mix,
                lut: &lut,
            }),
        };
        for j in 0..2 {
            for i in 0..3 {
                let p = &codes[(j * 3 + i) * 3..][..3];
                let want = 0.2126 * lut[p[0] as usize]
                    + 0.7152 * lut[p[1] as usize]
                    + 0.0722 * lut[p[2] as usize];
                assert_eq!(view.at(i, j), want);
            }
        }
        let mut buf = [0.0f32; 2];
        assert_eq!(view.values(1, 1, &mut buf), &[view.at(1, 1), view.at(2, 1)]);
        let plane = Plane::full(2, 1, vec![0.25, 0.5]);
        let lin = PlaneRef::from(&plane);
        assert_eq!(lin.at(1, 0), 0.5);
    }
}
