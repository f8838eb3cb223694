//! Cutting a [`RawFrame`] into linear [`Plane`]s: the colour planes of a
//! channel (whole or windowed), the chart-finding plane and lattice planes,
//! each converted from DN only where it is read.

use super::{CfaColour, RawChannel, RawFrame, Samples};
use crate::photo::Plane;
use rayon::prelude::*;

impl RawFrame {
    /// Linear planes of `channel`. A mosaic gives one sparse plane per site
    /// of the CFA repeat with that colour (Bayer: step (2, 2); `G` gives both
    /// greens, `All` gives R, G…, B in that order); linear RGB gives full
    /// planes of the chosen samples (R, G, B for `All`); a monochrome raw
    /// gives its one plane for any channel.
    pub fn channel_planes(&self, channel: RawChannel) -> Vec<Plane> {
        self.channel_groups(channel)
            .into_iter()
            .flat_map(|(_, planes)| planes)
            .collect()
    }

    /// Planes of `channel` grouped by colour, named "r", "g", "b" (or "grey"
    /// for a monochrome raw): one group per CSV column / plot curve.
    pub fn channel_groups(&self, channel: RawChannel) -> Vec<(&'static str, Vec<Plane>)> {
        let all = (0, 0, self.width, self.height);
        self.channel_groups_within(channel, all, &|_| (0, self.width))
    }

    /// Like [`RawFrame::channel_groups`], but the planes cover only the frame
    /// rectangle `rect` = (x0, y0, x1, y1) (pixels, end exclusive), and in frame
    /// row y only the columns `span(y)` = [a, b) are converted; other samples
    /// stay 0 (their memory is never touched). A measurement region's rows are
    /// all a measurement reads, so a whole-frame f32 copy is never made.
    pub fn channel_groups_within(
        &self,
        channel: RawChannel,
        rect: (usize, usize, usize, usize),
        span: &(dyn Fn(usize) -> (usize, usize) + Sync),
    ) -> Vec<(&'static str, Vec<Plane>)> {
        let name = |c: CfaColour| match c {
            CfaColour::Red => "r",
            CfaColour::Green => "g",
            CfaColour::Blue => "b",
        };
        let rect = (
            rect.0.min(self.width),
            rect.1.min(self.height),
            rect.2.min(self.width),
            rect.3.min(self.height),
        );
        let site = |offset, step, s| self.site_plane(offset, step, s, rect, span);
        match (&self.cfa, self.samples_per_pixel) {
            (Some(cfa), _) => {
                let (pw, ph) = cfa.size();
                channel
                    .colours()
                    .iter()
                    .map(|&c| {
                        let planes = (0..ph)
                            .flat_map(|y| (0..pw).map(move |x| (x, y)))
                            .filter(|&(x, y)| cfa.colour_at(x, y) == c)
                            .map(|(x, y)| site((x, y), (pw, ph), 0))
                            .filter(|p| p.width > 0 && p.height > 0)
                            .collect();
                        (name(c), planes)
                    })
                    .filter(|(_, planes): &(&str, Vec<Plane>)| !planes.is_empty())
                    .collect()
            }
            (None, 3) => channel
                .colours()
                .iter()
                .map(|&c| {
                    let s = match c {
                        CfaColour::Red => 0,
                        CfaColour::Green => 1,
                        CfaColour::Blue => 2,
                    };
                    (name(c), vec![site((0, 0), (1, 1), s)])
                })
                .collect(),
            (None, _) => vec![("grey", vec![site((0, 0), (1, 1), 0)])],
        }
    }

    /// One whole-frame plane for finding the chart: on a Bayer mosaic the
    /// first green lattice (a quarter of the pixels, at their true positions);
    /// on other mosaics every site (colours unbalanced); on linear RGB the G
    /// samples; on a monochrome raw its one plane.
    pub fn location_plane(&self) -> Plane {
        self.location_plane_within((0, 0, self.width, self.height))
    }

    /// [`RawFrame::location_plane`] over the frame rectangle `rect` = (x0, y0,
    /// x1, y1) only (pixels, end exclusive), e.g. around given corners.
    pub fn location_plane_within(&self, rect: (usize, usize, usize, usize)) -> Plane {
        let all = rect;
        let span = |_| (0, self.width);
        match (&self.cfa, self.samples_per_pixel) {
            (Some(cfa), _) if cfa.size() == (2, 2) => {
                let g = self.green_site().unwrap_or((0, 0));
                self.site_plane(g, (2, 2), 0, all, &span)
            }
            (None, 3) => self.site_plane((0, 0), (1, 1), 1, all, &span),
            _ => self.site_plane((0, 0), (1, 1), 0, all, &span),
        }
    }

    /// The position (x, y) in the CFA repeat of a Bayer mosaic's first green
    /// site (the one [`RawFrame::location_plane`] uses); `None` without a 2×2 CFA.
    pub fn green_site(&self) -> Option<(usize, usize)> {
        let cfa = self.cfa.as_ref().filter(|c| c.size() == (2, 2))?;
        [(0, 0), (1, 0), (0, 1), (1, 1)]
            .into_iter()
            .find(|&(x, y)| cfa.colour_at(x, y) == CfaColour::Green)
    }

    /// The linear plane of sample `s` on the lattice of frame pixels
    /// `offset + k·step` inside the frame rectangle `rect` = (x0, y0, x1, y1)
    /// (pixels, end exclusive), e.g. a preview's sparse grid.
    pub fn lattice_plane(
        &self,
        offset: (usize, usize),
        step: (usize, usize),
        s: usize,
        rect: (usize, usize, usize, usize),
    ) -> Plane {
        let rect = (
            rect.0.min(self.width),
            rect.1.min(self.height),
            rect.2.min(self.width),
            rect.3.min(self.height),
        );
        self.site_plane(
            offset,
            step,
            s.min(self.samples_per_pixel - 1),
            rect,
            &|_| (0, self.width),
        )
    }

    /// The plane of sample `s` on the lattice with `step` and `offset` (frame
    /// pixels), over the sites inside `rect`, converting only columns `span(y)`.
    fn site_plane(
        &self,
        offset: (usize, usize),
        step: (usize, usize),
        s: usize,
        rect: (usize, usize, usize, usize),
        span: &(dyn Fn(usize) -> (usize, usize) + Sync),
    ) -> Plane {
        // First lattice index at or after `lo`, and the count of sites in [lo, hi).
        let range = |off: usize, st: usize, lo: usize, hi: usize| {
            let first = if lo > off { (lo - off).div_ceil(st) } else { 0 };
            let start = off + first * st;
            let n = if start < hi {
                (hi - start).div_ceil(st)
            } else {
                0
            };
            (start, n)
        };
        let (x0, pw) = range(offset.0, step.0, rect.0, rect.2);
        let (y0, ph) = range(offset.1, step.1, rect.1, rect.3);
        let spp = self.samples_per_pixel;
        let mut data = crate::photo::hugebuf::zeroed::<f32>(pw * ph);
        // Constant black along the plane when the black repeat divides the lattice step.
        let constant = step.0.is_multiple_of(self.black.width)
            && step.1.is_multiple_of(self.black.height)
            && self.black.delta_h.is_empty();
        let fill_row = |j: usize, out: &mut [f32]| {
            let y = y0 + j * step.1;
            let (a, b) = span(y);
            let (a, b) = (a.max(x0), b.min(rect.2));
            if a >= b {
                return;
            }
            // Lattice columns i with x = x0 + i·step in [a, b).
            let i0 = (a - x0).div_ceil(step.0);
            let i1 = ((b - x0).div_ceil(step.0)).min(pw);
            if i0 >= i1 {
                return;
            }
            let out = &mut out[i0..i1];
            let row = self.row_range(y);
            let first = (x0 + i0 * step.0) * spp + s;
            let stride = step.0 * spp;
            if constant {
                let b = self.black.at(x0, y, s);
                let scale = 1.0 / (self.white[s] - b);
                let (b, scale) = (b as f32, scale as f32);
                match &self.samples {
                    Samples::U16(v) => {
                        for (o, &d) in out
                            .iter_mut()
                            .zip(v[row].iter().skip(first).step_by(stride))
                        {
                            *o = (d as f32 - b) * scale;
                        }
                    }
                    Samples::F32(v) => {
                        for (o, &d) in out
                            .iter_mut()
                            .zip(v[row].iter().skip(first).step_by(stride))
                        {
                            *o = (d - b) * scale;
                        }
                    }
                }
            } else {
                for (k, o) in out.iter_mut().enumerate() {
                    *o = self.value(x0 + (i0 + k) * step.0, y, s);
                }
            }
        };
        if pw > 0 {
            data.par_chunks_mut(pw)
                .enumerate()
                .for_each(|(j, out)| fill_row(j, out));
        }
        Plane {
            width: pw,
            height: ph,
            step,
            offset: (x0, y0),
            data,
        }
    }
}
