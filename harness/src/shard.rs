//! `--shard K/N`: a deterministic share of a run's case-runs, so CI can run one selection on N
//! machines and `harness merge` can join the N report folders into the unsharded run's reports.
//!
//! The unsharded order numbers every case-run (profile-major, cases in load order, after the
//! `--filter`) from 0; case-run `seq` belongs to shard `seq mod N + 1`. Round robin rather than
//! contiguous blocks, so each shard gets a similar mix of profiles and slow cases.

use serde::{Deserialize, Serialize};
use std::fmt;
use std::str::FromStr;

/// One shard of a run: `index` of `count` (1-based, as written on the command line), and how
/// many case-runs the unsharded run has, so a merge can tell when a shard is missing.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
pub struct Shard {
    /// K, 1..=`count`.
    pub index: usize,
    /// N, at least 1.
    pub count: usize,
    /// Case-runs of the whole (unsharded) selection; 0 until the runner has counted them.
    #[serde(default)]
    pub of: usize,
}

/// A `--shard` value that is not `K/N` with 1 ≤ K ≤ N.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
#[error("`{given}`: give the shard as K/N with 1 ≤ K ≤ N (e.g. 2/3)")]
pub struct ShardError {
    /// What was given.
    pub given: String,
}

impl FromStr for Shard {
    type Err = ShardError;

    fn from_str(s: &str) -> Result<Self, Self::Err> {
        let err = || ShardError { given: s.into() };
        let (k, n) = s.split_once('/').ok_or_else(err)?;
        let (index, count): (usize, usize) = (
            k.trim().parse().map_err(|_| err())?,
            n.trim().parse().map_err(|_| err())?,
        );
        if index == 0 || index > count {
            return Err(err());
        }
        Ok(Shard {
            index,
            count,
            of: 0,
        })
    }
}

impl fmt::Display for Shard {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{}/{}", self.index, self.count)
    }
}

impl Shard {
    /// Whether case-run `seq` of the unsharded order is this shard's.
    pub fn selects(&self, seq: usize) -> bool {
        seq % self.count == self.index - 1
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use rstest::rstest;

    #[rstest]
    #[case("1/1", 1, 1)]
    #[case("2/3", 2, 3)]
    #[case(" 3 / 3 ", 3, 3)]
    fn parses_k_of_n(#[case] s: &str, #[case] index: usize, #[case] count: usize) {
        assert_eq!(
            s.parse(),
            Ok(Shard {
                index,
                count,
                of: 0
            })
        );
    }

    #[rstest]
    #[case("0/3")]
    #[case("4/3")]
    #[case("1/0")]
    #[case("3")]
    #[case("a/b")]
    #[case("-1/3")]
    #[case("")]
    fn refuses_anything_else(#[case] s: &str) {
        let e = s.parse::<Shard>().unwrap_err();
        assert_eq!(e.given, s);
        assert!(e.to_string().contains("1 ≤ K ≤ N"), "{e}");
    }

    #[test]
    fn every_case_run_goes_to_exactly_one_shard_round_robin() {
        let shards: Vec<Shard> = (1..=3).map(|k| format!("{k}/3").parse().unwrap()).collect();
        for seq in 0..20 {
            let owners: Vec<usize> = shards
                .iter()
                .filter(|s| s.selects(seq))
                .map(|s| s.index)
                .collect();
            assert_eq!(owners, vec![seq % 3 + 1], "seq {seq}");
        }
        let first: Vec<usize> = (0..8).filter(|&i| shards[0].selects(i)).collect();
        assert_eq!(first, [0, 3, 6]);
        assert!((0..5).all(|i| "1/1".parse::<Shard>().unwrap().selects(i)));
    }
}
