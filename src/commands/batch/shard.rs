//! Shards: `--shard I/N` runs the I-th of N parts of a batch. The partition depends only on
//! the order of the cases (the inputs as given): case p (0-based) belongs to shard
//! (p mod N) + 1, so the shards' sizes differ by at most one, every case is in exactly one
//! shard, and every machine computes the same partition. Shards with I > number of cases are
//! empty.

use std::fmt;
use std::str::FromStr;

/// The I-th of N shards (1 ≤ I ≤ N).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Shard {
    /// I, from 1.
    pub index: usize,
    /// N ≥ 1.
    pub count: usize,
}

impl Shard {
    /// The positions (0-based, increasing) of the cases of this shard among `n_cases` cases.
    pub fn positions(&self, n_cases: usize) -> Vec<usize> {
        (self.index - 1..n_cases).step_by(self.count).collect()
    }

    /// The shard (of `count`) holding the case at position `p`.
    pub fn of_position(p: usize, count: usize) -> Shard {
        Shard {
            index: p % count + 1,
            count,
        }
    }
}

impl fmt::Display for Shard {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{}/{}", self.index, self.count)
    }
}

impl FromStr for Shard {
    type Err = String;

    /// `I/N` with 1 ≤ I ≤ N.
    fn from_str(s: &str) -> Result<Shard, String> {
        let bad = || format!("--shard {s:?}: expected I/N with 1 ≤ I ≤ N (e.g. 2/8)");
        let (i, n) = s.split_once('/').ok_or_else(bad)?;
        let index: usize = i.trim().parse().map_err(|_| bad())?;
        let count: usize = n.trim().parse().map_err(|_| bad())?;
        if count == 0 || index == 0 || index > count {
            return Err(bad());
        }
        Ok(Shard { index, count })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// For every case count up to 12 and every N from 1 to more than the case count: the union
    /// of the shards is the batch, each case exactly once, sizes within one of each other, in
    /// increasing order, and `of_position` names the shard holding each case.
    #[test]
    fn shards_partition_the_batch() {
        for n_cases in 0..=12 {
            for count in 1..=n_cases + 3 {
                let mut seen = vec![0usize; n_cases];
                let mut sizes = Vec::new();
                for index in 1..=count {
                    let shard = Shard { index, count };
                    let ps = shard.positions(n_cases);
                    assert!(ps.windows(2).all(|w| w[0] < w[1]));
                    for &p in &ps {
                        seen[p] += 1;
                        assert_eq!(Shard::of_position(p, count), shard);
                    }
                    sizes.push(ps.len());
                }
                assert!(
                    seen.iter().all(|&c| c == 1),
                    "{n_cases} cases, {count} shards: {seen:?}"
                );
                let (lo, hi) = (sizes.iter().min().unwrap(), sizes.iter().max().unwrap());
                assert!(hi - lo <= 1, "{n_cases} cases, {count} shards: {sizes:?}");
                assert_eq!(sizes.iter().sum::<usize>(), n_cases);
            }
        }
    }

    #[test]
    fn shard_specs_are_checked() {
        assert_eq!("3/8".parse::<Shard>(), Ok(Shard { index: 3, count: 8 }));
        assert_eq!(Shard { index: 3, count: 8 }.to_string(), "3/8");
        for bad in ["0/4", "5/4", "1/0", "2", "a/b", "-1/3", ""] {
            let e = bad.parse::<Shard>().unwrap_err();
            assert!(e.contains("expected I/N"), "{bad}: {e}");
        }
    }
}
