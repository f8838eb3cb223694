//! The region of a strip under a plain homography, visited sample by sample
//! in cache-sized tiles (the fast path of binning).

use crate::geometry::Point;
use crate::photo::PlaneRef;

/// The sampled region of a strip, for visiting its samples.
#[derive(Clone, Copy)]
pub(super) struct Region<'a> {
    pub(super) planes: &'a [PlaneRef<'a>],
    /// Image → strip homography, scaled so its denominator is positive in the region.
    pub(super) m: [f64; 9],
    pub(super) ymin: f64,
    pub(super) ymax: f64,
    pub(super) t0: f64,
    pub(super) t1: f64,
    pub(super) s_lo: f64,
    pub(super) s_hi: f64,
    pub(super) bin: f64,
    pub(super) nbins: usize,
    /// Whether `s` changes faster across the columns than across the rows
    /// (then [`Region::visit_band_lines`] walks down the columns).
    pub(super) by_columns: bool,
    /// Sample rows visited: every `row_step`th (odd, so that a line down a
    /// column still alternates its pixel parity; 1 = all).
    pub(super) row_step: usize,
    /// Samples visited along a row: those at multiples of `col_step` (odd,
    /// likewise; 1 = all).
    pub(super) col_step: usize,
}

impl Region<'_> {
    /// Whether the sample centre (x, y) lies inside the region; its s if so.
    #[inline]
    fn inside(&self, x: f64, y: f64) -> Option<f64> {
        let m = &self.m;
        let rw = 1.0 / (m[6] * x + m[7] * y + m[8]);
        let s = (m[0] * x + m[1] * y + m[2]) * rw;
        let t = (m[3] * x + m[4] * y + m[5]) * rw;
        (t >= self.t0 && t <= self.t1 && s >= self.s_lo && s <= self.s_hi).then_some(s)
    }

    /// Sample indices [i0, i1) of a row at height y (sample x = ox + i·sx)
    /// inside the region. Along a row each bound is a linear inequality in x.
    fn row_range(&self, y: f64, ox: f64, sx: f64, width: usize) -> (usize, usize) {
        let m = &self.m;
        let (ns, nt, w) = (m[1] * y + m[2], m[4] * y + m[5], m[7] * y + m[8]);
        // a·x + b ≥ 0 for each bound.
        let bounds = [
            (m[3] - self.t0 * m[6], nt - self.t0 * w),
            (self.t1 * m[6] - m[3], self.t1 * w - nt),
            (m[0] - self.s_lo * m[6], ns - self.s_lo * w),
            (self.s_hi * m[6] - m[0], self.s_hi * w - ns),
            // The denominator itself stays positive.
            (m[6], w),
        ];
        let (mut lo, mut hi) = (f64::NEG_INFINITY, f64::INFINITY);
        for (a, b) in bounds {
            if a > 0.0 {
                lo = lo.max(-b / a);
            } else if a < 0.0 {
                hi = hi.min(-b / a);
            } else if b < 0.0 {
                return (0, 0);
            }
        }
        if !(lo <= hi) {
            return (0, 0);
        }
        let idx = |x: f64| ((x - ox) / sx).clamp(-1.0, width as f64 + 1.0);
        let mut i0 = idx(lo).ceil() as i64;
        let mut i1 = idx(hi).floor() as i64 + 1;
        i0 = i0.clamp(0, width as i64);
        i1 = i1.clamp(i0, width as i64);
        // Make the ends agree exactly with the per-sample test.
        let at = |i: i64| self.inside(ox + i as f64 * sx, y).is_some();
        while i0 < i1 && !at(i0) {
            i0 += 1;
        }
        while i1 > i0 && !at(i1 - 1) {
            i1 -= 1;
        }
        while i0 > 0 && at(i0 - 1) {
            i0 -= 1;
        }
        while i1 < width as i64 && i1 > i0 && at(i1) {
            i1 += 1;
        }
        (i0 as usize, i1 as usize)
    }

    /// Calls f(bin, s, value) for every sample inside the region that falls
    /// in one of `bins` (sorted, few): on each row only the samples around
    /// those bins' ends are looked at.
    pub(super) fn visit_bins<F: FnMut(usize, f64, f32)>(&self, bins: &[usize], mut f: F) {
        let m = &self.m;
        let inv_bin = 1.0 / self.bin;
        let last = self.nbins - 1;
        for band in self.bands() {
            let plane = self.planes[band.plane];
            let (ox, oy, sx, sy) = plane.centres();
            for (dj, &(i0, i1)) in band.rows.iter().enumerate() {
                if i0 >= i1 {
                    continue;
                }
                let j = band.row(dj);
                let y = oy + j as f64 * sy;
                let (ns0, w0) = (m[1] * y + m[2], m[7] * y + m[8]);
                let s_of = |i: usize| {
                    let x = ox + i as f64 * sx;
                    (m[0] * x + ns0) / (m[6] * x + w0)
                };
                let bin_of = |s: f64| ((s * inv_bin) as usize).min(last);
                let (sa, sb) = (s_of(i0), s_of(i1 - 1));
                let (ba, bb) = (bin_of(sa.min(sb)), bin_of(sa.max(sb)));
                let from = bins.partition_point(|&b| b < ba);
                for &b in bins[from..].iter().take_while(|&&b| b <= bb) {
                    // x where s crosses the bin's ends (s is a Möbius function of x).
                    let x_at = |s: f64| (s * w0 - ns0) / (m[0] - s * m[6]);
                    let (xa, xb) = (x_at(b as f64 * self.bin), x_at((b + 1) as f64 * self.bin));
                    let (xa, xb) = (xa.min(xb), xa.max(xb));
                    let ia = (((xa - ox) / sx).floor() - 1.0).max(i0 as f64) as usize;
                    let ib = (((xb - ox) / sx).ceil() + 2.0).min(i1 as f64) as usize;
                    for i in ia.max(i0)..ib.min(i1) {
                        if i % self.col_step.max(1) != 0 {
                            continue;
                        }
                        let s = s_of(i);
                        if bin_of(s) == b {
                            f(b, s, plane.at(i, j));
                        }
                    }
                }
            }
        }
    }

    /// The region's sample rows in bands of TILE rows, with each row's sample range.
    pub(super) fn bands(&self) -> Vec<Band> {
        let mut out = Vec::new();
        for (p, plane) in self.planes.iter().enumerate() {
            let (ox, oy, sx, sy) = plane.centres();
            // Sample rows whose centres lie within the region's vertical extent.
            let j0 = ((self.ymin - oy) / sy).ceil().max(0.0) as usize;
            let j1 =
                (((self.ymax - oy) / sy).floor() + 1.0).clamp(0.0, plane.height as f64) as usize;
            // Rows at multiples of the step (the same lattice whatever the region).
            let step = self.row_step.max(1);
            let j0 = j0.next_multiple_of(step);
            let ranges: Vec<(usize, usize)> = (j0..j1)
                .step_by(step)
                .map(|j| self.row_range(oy + j as f64 * sy, ox, sx, plane.width))
                .collect();
            for (k, rows) in ranges.chunks(TILE).enumerate() {
                if rows.iter().any(|r| r.0 < r.1) {
                    out.push(Band {
                        plane: p,
                        first: j0 + k * TILE * step,
                        step,
                        rows: rows.to_vec(),
                    });
                }
            }
        }
        out
    }

    /// Calls f(bin, s, value) for every sample inside the region, row by
    /// row within each tile (the order the sums of a revisit have always
    /// had, whatever `by_columns` says).
    pub(super) fn visit<F: FnMut(usize, f64, f32)>(&self, f: F) {
        let rows = Region {
            by_columns: false,
            ..*self
        };
        let mut each = EachSample(f);
        for band in self.bands() {
            rows.visit_band_lines(&band, &mut each);
        }
    }
}

/// A [`LineSink`] that hands each sample on to a closure: (bin, s, value).
struct EachSample<F>(F);

impl<F: FnMut(usize, f64, f32)> LineSink for EachSample<F> {
    #[inline(always)]
    fn line(&mut self, b: &[u32], s: &[f64], v: &[f32], _: LineStart) {
        for ((&b, &s), &v) in b.iter().zip(s).zip(v) {
            (self.0)(b as usize, s, v);
        }
    }
}

impl Region<'_> {
    /// The bin of position `s` (strip units): `((s / bin) as usize).min(last)`
    /// written so that it vectorises (the same value for every `s`, NaN included).
    #[inline(always)]
    fn bin_index(s: f64, inv_bin: f64, last: f64) -> u32 {
        let t = (s * inv_bin).max(0.0).min(last);
        // SAFETY: t is finite and within [0, last], and last < 2³²
        // (`bin_planes` refuses more bins).
        unsafe { t.to_int_unchecked::<u32>() }
    }

    /// Hands every sample of one band to `f` a line at a time: down each
    /// column of a tile when `self.by_columns` (a sweep across the columns:
    /// a column's samples share a bin for many rows), else along each row.
    /// Each bin gets its samples in increasing row order within a column
    /// (or column order within a row). The region has fewer than 2³² bins
    /// ([`super::bin_planes`] checks).
    #[inline(always)]
    pub(super) fn visit_band_lines<F: LineSink>(&self, band: &Band, f: &mut F) {
        let m = &self.m;
        let inv_bin = 1.0 / self.bin;
        let last = (self.nbins - 1) as f64;
        let plane = self.planes[band.plane];
        let (ox, oy, sx, sy) = plane.centres();
        let rows = &band.rows;
        let lo = rows.iter().filter(|r| r.0 < r.1).map(|r| r.0).min();
        let hi = rows.iter().map(|r| r.1).max().unwrap_or(0);
        let Some(lo) = lo else { return };
        let mut s_buf = [0.0f64; TILE];
        let mut b_buf = [0u32; TILE];
        let mut v_buf = [0.0f32; TILE];
        if !self.by_columns {
            for c0 in (lo..hi).step_by(TILE) {
                let c1 = (c0 + TILE).min(hi);
                for (dj, &(i0, i1)) in rows.iter().enumerate() {
                    let (i0, i1) = (i0.max(c0), i1.min(c1));
                    if i0 >= i1 {
                        continue;
                    }
                    let j = band.row(dj);
                    let y = oy + j as f64 * sy;
                    plane.prefetch(c1, j);
                    let (ns0, w0) = (m[1] * y + m[2], m[7] * y + m[8]);
                    let (n, i0, cs) = if self.col_step > 1 {
                        // Every col_step-th sample (those at multiples of it).
                        let first = i0.next_multiple_of(self.col_step);
                        if first >= i1 {
                            continue;
                        }
                        let mut row = [0.0f32; TILE];
                        plane.read_into(j, first, &mut row[..i1 - first]);
                        let n = (i1 - first).div_ceil(self.col_step);
                        for (q, v) in v_buf[..n].iter_mut().enumerate() {
                            *v = row[q * self.col_step];
                        }
                        (n, first, self.col_step)
                    } else {
                        let n = i1 - i0;
                        plane.read_into(j, i0, &mut v_buf[..n]);
                        (n, i0, 1)
                    };
                    for (k, s) in s_buf[..n].iter_mut().enumerate() {
                        let x = ox + (i0 + k * cs) as f64 * sx;
                        *s = (m[0] * x + ns0) / (m[6] * x + w0);
                    }
                    let start = LineStart::of(&plane, i0, j, true);
                    hand_out_line(n, &s_buf, &mut b_buf, &v_buf, inv_bin, last, start, f);
                }
            }
            return;
        }
        // Down the columns: each tile's values are read row by row first.
        let nr = rows.len();
        let mut tile = [[0.0f32; TILE]; TILE];
        let (mut ns, mut w) = ([0.0f64; TILE], [0.0f64; TILE]);
        let (mut ns_c, mut w_c) = ([0.0f64; TILE], [0.0f64; TILE]);
        for (dj, n) in ns.iter_mut().zip(&mut w).enumerate().take(nr) {
            let y = oy + band.row(dj) as f64 * sy;
            *n.0 = m[1] * y + m[2];
            *n.1 = m[7] * y + m[8];
        }
        for c0 in (lo..hi).step_by(TILE) {
            let c1 = (c0 + TILE).min(hi);
            for (dj, &(i0, i1)) in rows.iter().enumerate() {
                let (i0, i1) = (i0.max(c0), i1.min(c1));
                if i0 < i1 {
                    let j = band.row(dj);
                    plane.prefetch(c1, j);
                    plane.read_into(j, i0, &mut tile[dj][i0 - c0..i1 - c0]);
                }
            }
            // Whether every row holds the whole tile (then no packing).
            let full = rows.iter().all(|&(i0, i1)| i0 <= c0 && i1 >= c1);
            for k in (c0.next_multiple_of(self.col_step.max(1))..c1).step_by(self.col_step.max(1)) {
                let x = ox + k as f64 * sx;
                let (a0, a6) = (m[0] * x, m[6] * x);
                if full {
                    for q in 0..nr {
                        s_buf[q] = (a0 + ns[q]) / (a6 + w[q]);
                        v_buf[q] = tile[q][k - c0];
                    }
                    let start = LineStart::of(&plane, k, band.first, false);
                    hand_out_line(nr, &s_buf, &mut b_buf, &v_buf, inv_bin, last, start, f);
                    continue;
                }
                // The rows whose range holds column k, packed (one run of
                // rows: the region is convex).
                let mut n = 0;
                let mut first = usize::MAX;
                for (dj, &(i0, i1)) in rows.iter().enumerate() {
                    ns_c[n] = ns[dj];
                    w_c[n] = w[dj];
                    v_buf[n] = tile[dj][k - c0];
                    let holds = i0 <= k && k < i1;
                    if holds && first == usize::MAX {
                        first = dj;
                    }
                    n += holds as usize;
                }
                for q in 0..n {
                    s_buf[q] = (a0 + ns_c[q]) / (a6 + w_c[q]);
                }
                let start = LineStart::of(&plane, k, band.row(first.min(nr)), false);
                hand_out_line(n, &s_buf, &mut b_buf, &v_buf, inv_bin, last, start, f);
            }
        }
    }
}

/// Hands the first `n` samples of one line (positions `s`, values `v`) to
/// `f` with their bins (`b` is scratch for them).
#[inline(always)]
#[allow(clippy::too_many_arguments)]
fn hand_out_line<F: LineSink>(
    n: usize,
    s: &[f64; TILE],
    b: &mut [u32; TILE],
    v: &[f32; TILE],
    inv_bin: f64,
    last: f64,
    start: LineStart,
    f: &mut F,
) {
    for q in 0..n {
        b[q] = Region::bin_index(s[q], inv_bin, last);
    }
    f.line(&b[..n], &s[..n], &v[..n], start);
}

/// Where a line of samples starts in the photo and which way it runs: its
/// first sample's pixel (x, y) and whether it runs along x (a row) or along
/// y (a column); its samples are an odd number of pixels apart (one, or the
/// region's step), so their coordinate along it alternates in parity.
#[derive(Clone, Copy, Debug)]
pub(super) struct LineStart {
    pub(super) x: usize,
    pub(super) y: usize,
    pub(super) along_x: bool,
}

impl LineStart {
    /// The line from sample (i, j) of `plane`, along its rows or its columns.
    #[inline(always)]
    fn of(plane: &PlaneRef, i: usize, j: usize, along_x: bool) -> LineStart {
        LineStart {
            x: plane.offset.0 + i * plane.step.0,
            y: plane.offset.1 + j * plane.step.1,
            along_x,
        }
    }
}

/// What takes the samples of [`Region::visit_band_lines`]: one line of
/// samples at a time (down a column or along a row), in which consecutive
/// samples mostly share a bin.
pub(super) trait LineSink {
    /// Takes a line's samples: their bins `b`, positions `s` (strip units),
    /// linear values `v`, and where the line starts in the photo.
    fn line(&mut self, b: &[u32], s: &[f64], v: &[f32], start: LineStart);
}

/// Rows and columns of a tile in [`Region::visit_band_lines`] (and of the lens
/// path's tiles).
pub(super) const TILE: usize = 64;

/// Up to TILE sample rows of one plane, `step` apart, with each row's [i0, i1) range.
pub(super) struct Band {
    plane: usize,
    first: usize,
    step: usize,
    rows: Vec<(usize, usize)>,
}

impl Band {
    /// The sample row of the band's `dj`th row.
    #[inline(always)]
    fn row(&self, dj: usize) -> usize {
        self.first + dj * self.step
    }
}

/// The x-extent where the horizontal line at `y` crosses a closed polygon
/// (a strip's corner quadrilateral, or its curved outline under a lens).
pub fn row_span(q: &[Point], y: f64) -> Option<(f64, f64)> {
    let mut lo = f64::INFINITY;
    let mut hi = f64::NEG_INFINITY;
    for k in 0..q.len() {
        let (a, b) = (q[k], q[(k + 1) % q.len()]);
        let (ya, yb) = (a[1].min(b[1]), a[1].max(b[1]));
        if y < ya || y > yb {
            continue;
        }
        if (b[1] - a[1]).abs() < 1e-12 {
            lo = lo.min(a[0].min(b[0]));
            hi = hi.max(a[0].max(b[0]));
        } else {
            let x = a[0] + (b[0] - a[0]) * (y - a[1]) / (b[1] - a[1]);
            lo = lo.min(x);
            hi = hi.max(x);
        }
    }
    (lo <= hi).then_some((lo, hi))
}
