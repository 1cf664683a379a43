//! Splitting a plan's work into shards (`experiments run M.toml --shard I/N`), so that one
//! manifest can run as N independent jobs (a Slurm array, see [`crate::slurm`]) and be merged
//! back into one run ([`crate::merge`]).
//!
//! **Work units.** A work unit is a configuration with a block of its timed repetitions
//! (`first..=last`, numbered as in an unsharded run). The split is a pure function of the
//! configuration ids in plan order, the repetition count and N:
//!
//! - N <= configurations: every configuration is one unit with all its repetitions (timings
//!   compare within one machine); configuration k goes to shard `k mod N + 1` (round robin, so
//!   objects of different cost spread over the shards);
//! - N > configurations: every configuration gets at least one block, the extra N - C blocks go
//!   round robin to configurations that still have repetitions to split; each configuration's
//!   repetitions are cut into that many contiguous blocks of nearly equal size, and the units
//!   (configuration order, then block order) go one per shard. The split is then
//!   [`Split::RepetitionBlocks`], recorded in the shard's `run.json`;
//! - N > configurations x repetitions is refused (a shard would have nothing to do).
//!
//! Every unit lands on exactly one shard for any N (tested below, property test included).

use std::fmt;
use std::str::FromStr;

use serde::{Deserialize, Serialize};
use sha2::{Digest, Sha256};

/// Why a shard cannot be made.
#[derive(Debug, thiserror::Error, PartialEq, Eq)]
pub enum ShardError {
    /// `--shard` is not `I/N` with 1 <= I <= N.
    #[error("--shard `{0}`: expected I/N with 1 <= I <= N (for example 2/8)")]
    Syntax(String),
    /// More shards than work units.
    #[error(
        "{count} shards but only {units} work units ({configurations} configurations x \
         {repetitions} repetitions): a shard would have nothing to do; use at most {units} shards"
    )]
    TooMany {
        /// N.
        count: usize,
        /// Configurations x repetitions.
        units: usize,
        /// Configurations in the plan.
        configurations: usize,
        /// Timed repetitions per configuration.
        repetitions: usize,
    },
}

/// `I/N`: shard I (1-based) of N.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub struct ShardSpec {
    /// 1-based index.
    pub index: usize,
    /// Number of shards.
    pub count: usize,
}

impl FromStr for ShardSpec {
    type Err = ShardError;
    fn from_str(s: &str) -> Result<Self, ShardError> {
        let bad = || ShardError::Syntax(s.to_string());
        let (i, n) = s.split_once('/').ok_or_else(bad)?;
        let index: usize = i.trim().parse().map_err(|_| bad())?;
        let count: usize = n.trim().parse().map_err(|_| bad())?;
        if index == 0 || count == 0 || index > count {
            return Err(bad());
        }
        Ok(ShardSpec { index, count })
    }
}

impl fmt::Display for ShardSpec {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{}/{}", self.index, self.count)
    }
}

/// How a plan was split.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum Split {
    /// Whole configurations per shard.
    Configurations,
    /// Some configurations' repetitions are split in blocks over several shards.
    RepetitionBlocks,
}

/// A configuration and a block of its timed repetitions.
#[derive(Clone, Debug, PartialEq, Eq, Hash, PartialOrd, Ord, Serialize, Deserialize)]
pub struct WorkUnit {
    /// Configuration id.
    pub id: String,
    /// First timed repetition (1-based).
    pub first: usize,
    /// Last timed repetition (inclusive).
    pub last: usize,
}

impl WorkUnit {
    /// The whole configuration: repetitions `1..=repetitions`.
    pub fn whole(id: &str, repetitions: usize) -> Self {
        WorkUnit {
            id: id.to_string(),
            first: 1,
            last: repetitions,
        }
    }

    /// The unit's key in `progress.json`: the id for a whole configuration (as in unsharded
    /// runs), `id:first-last` for a block.
    pub fn key(&self, repetitions: usize) -> String {
        if self.first == 1 && self.last == repetitions {
            self.id.clone()
        } else {
            format!("{}:{}-{}", self.id, self.first, self.last)
        }
    }

    /// Number of repetitions.
    pub fn len(&self) -> usize {
        self.last + 1 - self.first
    }

    /// Whether the block is empty (never, for units made here).
    pub fn is_empty(&self) -> bool {
        self.last < self.first
    }
}

/// What `run.json` records of a shard (`"shard"`), and what [`crate::merge`] checks.
#[derive(Clone, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub struct ShardRecord {
    /// 1-based index.
    pub index: usize,
    /// Number of shards.
    pub count: usize,
    /// SHA-256 of the manifest text (hex).
    pub manifest_sha256: String,
    /// How the plan was split.
    pub split: Split,
    /// The units this shard runs, in order.
    pub units: Vec<WorkUnit>,
}

/// SHA-256 of a manifest's text, lower-case hex.
pub fn manifest_hash(text: &str) -> String {
    let digest = Sha256::digest(text.as_bytes());
    digest.iter().map(|b| format!("{b:02x}")).collect()
}

/// The units of every shard (index 0 is shard 1) for configurations `ids` (plan order) with
/// `repetitions` each, split `count` ways; see the [module documentation](self).
pub fn split(
    ids: &[String],
    repetitions: usize,
    count: usize,
) -> Result<(Split, Vec<Vec<WorkUnit>>), ShardError> {
    let c = ids.len();
    let total = c.saturating_mul(repetitions);
    if count == 0 || count > total {
        return Err(ShardError::TooMany {
            count,
            units: total,
            configurations: c,
            repetitions,
        });
    }
    let mut shards = vec![Vec::new(); count];
    if count <= c {
        for (k, id) in ids.iter().enumerate() {
            shards[k % count].push(WorkUnit::whole(id, repetitions));
        }
        return Ok((Split::Configurations, shards));
    }
    // Blocks per configuration: one each, the extra ones round robin over configurations that
    // can still be cut (at most `repetitions` blocks each).
    let mut blocks = vec![1usize; c];
    let mut extra = count - c;
    while extra > 0 {
        for b in blocks.iter_mut() {
            if extra == 0 {
                break;
            }
            if *b < repetitions {
                *b += 1;
                extra -= 1;
            }
        }
    }
    let mut units = Vec::with_capacity(count);
    for (id, &b) in ids.iter().zip(&blocks) {
        let mut first = 1;
        for j in 0..b {
            let len = repetitions / b + usize::from(j < repetitions % b);
            units.push(WorkUnit {
                id: id.clone(),
                first,
                last: first + len - 1,
            });
            first += len;
        }
    }
    for (shard, unit) in shards.iter_mut().zip(units) {
        shard.push(unit);
    }
    Ok((Split::RepetitionBlocks, shards))
}

/// The units of shard `spec` (see [`split`]).
pub fn units_of(
    ids: &[String],
    repetitions: usize,
    spec: ShardSpec,
) -> Result<(Split, Vec<WorkUnit>), ShardError> {
    let (how, mut all) = split(ids, repetitions, spec.count)?;
    Ok((how, all.swap_remove(spec.index - 1)))
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;
    use std::collections::BTreeMap;

    fn ids(n: usize) -> Vec<String> {
        (0..n).map(|i| format!("c{i}")).collect()
    }

    /// Every (configuration, repetition) exactly once over all shards, each configuration's
    /// repetitions on one shard when N <= configurations, no shard empty.
    fn check(c: usize, reps: usize, n: usize) {
        let names = ids(c);
        let (how, shards) = split(&names, reps, n).unwrap();
        assert_eq!(shards.len(), n);
        let mut seen: BTreeMap<(String, usize), usize> = BTreeMap::new();
        for (s, units) in shards.iter().enumerate() {
            assert!(!units.is_empty(), "shard {} of {n} is empty", s + 1);
            for u in units {
                assert!(u.first >= 1 && u.last <= reps && !u.is_empty(), "{u:?}");
                for r in u.first..=u.last {
                    assert!(
                        seen.insert((u.id.clone(), r), s).is_none(),
                        "{}#{r} twice",
                        u.id
                    );
                }
            }
        }
        assert_eq!(seen.len(), c * reps);
        if n <= c {
            assert_eq!(how, Split::Configurations);
            for id in &names {
                let homes: std::collections::BTreeSet<usize> = seen
                    .iter()
                    .filter(|((i, _), _)| i == id)
                    .map(|(_, &s)| s)
                    .collect();
                assert_eq!(homes.len(), 1, "{id} on shards {homes:?}");
            }
        } else {
            assert_eq!(how, Split::RepetitionBlocks);
        }
        // Deterministic.
        assert_eq!(split(&names, reps, n).unwrap().1, shards);
    }

    #[test]
    fn parses_i_of_n() {
        assert_eq!(
            "2/8".parse::<ShardSpec>().unwrap(),
            ShardSpec { index: 2, count: 8 }
        );
        for bad in ["0/4", "5/4", "1/0", "1", "a/b", "1/2/3", "-1/4"] {
            assert!(bad.parse::<ShardSpec>().is_err(), "{bad}");
        }
    }

    #[test]
    fn small_cases_cover_every_unit_once() {
        for c in 1..8 {
            for reps in 1..6 {
                for n in 1..=c * reps {
                    check(c, reps, n);
                }
            }
        }
    }

    #[test]
    fn round_robin_and_blocks_are_as_documented() {
        let (_, s) = split(&ids(5), 3, 2).unwrap();
        let on = |k: usize| s[k].iter().map(|u| u.id.as_str()).collect::<Vec<_>>();
        assert_eq!(on(0), ["c0", "c2", "c4"]);
        assert_eq!(on(1), ["c1", "c3"]);
        let (how, s) = split(&ids(2), 10, 5).unwrap();
        assert_eq!(how, Split::RepetitionBlocks);
        let got: Vec<(&str, usize, usize)> = s
            .iter()
            .map(|u| (u[0].id.as_str(), u[0].first, u[0].last))
            .collect();
        assert_eq!(
            got,
            [
                ("c0", 1, 4),
                ("c0", 5, 7),
                ("c0", 8, 10),
                ("c1", 1, 5),
                ("c1", 6, 10)
            ]
        );
        assert_eq!(s[0][0].key(10), "c0:1-4");
        assert_eq!(WorkUnit::whole("c0", 10).key(10), "c0");
    }

    #[test]
    fn too_many_shards_are_refused_with_the_limit() {
        let err = split(&ids(2), 3, 7).unwrap_err();
        assert!(err.to_string().contains("use at most 6 shards"), "{err}");
        assert!(split(&ids(0), 3, 1).is_err());
    }

    #[test]
    fn manifest_hash_is_sha256() {
        assert_eq!(
            manifest_hash("abc"),
            "ba7816bf8f01cfea414140de5dae2223b00361a396177a9cb410ff61f20015ad"
        );
    }

    proptest! {
        #[test]
        fn every_unit_exactly_once_for_any_n(c in 1usize..40, reps in 1usize..12, n_seed in 1usize..1000) {
            let n = 1 + n_seed % (c * reps);
            check(c, reps, n);
        }
    }
}
