//! What binning takes and gives: the binning options and the binned profile
//! along a strip, with its queries.

/// How the strip is binned.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct BinOptions {
    /// Bin width in image pixels (at the strip's most magnified end).
    pub bin_px: f64,
    /// Fraction of the strip width left out along each long edge (0–0.45).
    pub margin: f64,
    /// Pixels left out at each short end of the strip.
    pub end_px: f64,
    /// Linear value at or above which a sample counts as clipped.
    pub clip_level: f32,
    /// Most sample rows binned across a strip that sweeps along the rows
    /// (evenly spaced; 0 = every row).
    pub max_across: usize,
}

impl Default for BinOptions {
    fn default() -> Self {
        BinOptions {
            bin_px: 0.25,
            margin: 0.15,
            end_px: 1.0,
            clip_level: 0.999,
            max_across: 0,
        }
    }
}

/// A binned profile along a strip (only non-empty bins, in increasing `s`).
#[derive(Debug, Clone, Default)]
pub struct Profile {
    /// Mean `s` of each bin's samples (strip units).
    pub s: Vec<f64>,
    /// Robust mean linear value of each bin.
    pub y: Vec<f64>,
    /// Samples averaged in each bin.
    pub count: Vec<f64>,
    /// Variance of the samples' `s` within each bin (strip units²).
    pub var_s: Vec<f64>,
    /// Bin width (strip units).
    pub bin: f64,
    /// Strip length (strip units).
    pub length: f64,
    /// Samples that fell inside the region.
    pub samples: usize,
    /// Samples at or above the clipping level.
    pub clipped_high: usize,
    /// Samples at or below zero (black clipping).
    pub clipped_low: usize,
    /// Whether each bin holds a clipped sample (at the clip level or at or
    /// below zero); empty when no sample of the profile is clipped.
    pub clipped: Vec<bool>,
    /// Each bin's mean of the pixel-parity patterns (−1)^x, (−1)^y and
    /// (−1)^(x+y) over its samples (x, y the photo pixel), for a single plane
    /// of step 1, where a demosaicked colour filter array leaves aliases
    /// locked to the pixel grid (see `wants_parity`); empty otherwise.
    pub parity: Vec<[f64; 3]>,
}

impl Profile {
    /// The indices of the bins whose `s` lies in [a, b) (strip units).
    pub fn bins_within(&self, a: f64, b: f64) -> std::ops::Range<usize> {
        let lo = self.s.partition_point(|&s| s < a);
        lo..self.s.partition_point(|&s| s < b).max(lo)
    }

    /// The mean of `g(value)` over the bins with `s` in [a, b); None when none.
    pub fn mean_within(&self, a: f64, b: f64, g: impl Fn(f64) -> f64) -> Option<f64> {
        let r = self.bins_within(a, b);
        (!r.is_empty())
            .then(|| self.y[r.clone()].iter().map(|&y| g(y)).sum::<f64>() / r.len() as f64)
    }

    /// Whether bin `k` holds a clipped sample: its mean is not the light's.
    pub fn is_clipped(&self, k: usize) -> bool {
        self.clipped.get(k).copied().unwrap_or(false)
    }

    /// Fraction of the region's samples that are clipped (white or black).
    pub fn clipped_fraction(&self) -> f64 {
        if self.samples == 0 {
            0.0
        } else {
            (self.clipped_high + self.clipped_low) as f64 / self.samples as f64
        }
    }
}
