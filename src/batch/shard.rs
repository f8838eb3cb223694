//! `--shard K/N`: a deterministic split of the sorted file list into N parts,
//! shot i going to shard (i mod N) + 1, so parallel jobs of a job array
//! (Slurm, Kubernetes indexed Jobs, GNU parallel) share a folder without
//! talking to each other, and interleaved shots balance the parts.

use super::BatchError;
use std::fmt;
use std::str::FromStr;

/// Shard K of N (1 ≤ K ≤ N).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Shard {
    /// This shard's number, 1-based.
    pub k: usize,
    /// Number of shards.
    pub n: usize,
}

impl Shard {
    /// The whole list (shard 1 of 1).
    pub const ALL: Shard = Shard { k: 1, n: 1 };

    /// Whether the shot at `index` of the full list belongs to this shard.
    pub fn contains(&self, index: usize) -> bool {
        index % self.n == self.k - 1
    }
}

impl fmt::Display for Shard {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{}/{}", self.k, self.n)
    }
}

impl FromStr for Shard {
    type Err = BatchError;
    fn from_str(s: &str) -> Result<Self, Self::Err> {
        let bad = |why: &str| {
            BatchError::Usage(format!(
                "--shard '{s}': {why}; write K/N with 1 ≤ K ≤ N, e.g. 3/8"
            ))
        };
        let (k, n) = s.split_once('/').ok_or_else(|| bad("no '/'"))?;
        let k: usize = k
            .trim()
            .parse()
            .map_err(|_| bad("K is not a whole number"))?;
        let n: usize = n
            .trim()
            .parse()
            .map_err(|_| bad("N is not a whole number"))?;
        if n == 0 || k == 0 || k > n {
            return Err(bad("K out of range"));
        }
        Ok(Shard { k, n })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn shards_partition_the_list() {
        for n in 1..7 {
            let shards: Vec<Shard> = (1..=n).map(|k| Shard { k, n }).collect();
            for i in 0..50 {
                assert_eq!(shards.iter().filter(|s| s.contains(i)).count(), 1);
            }
        }
    }

    #[test]
    fn parses_and_rejects() {
        assert_eq!("3/8".parse::<Shard>().unwrap(), Shard { k: 3, n: 8 });
        for bad in ["0/4", "5/4", "1/0", "x/2", "3", "-1/2"] {
            assert!(bad.parse::<Shard>().is_err(), "{bad}");
        }
    }
}
