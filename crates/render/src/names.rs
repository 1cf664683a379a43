//! Seeded randomness and anonymous animation names.
//!
//! Names are four lowercase consonants (`bcdfghjklmnpqrstvwxz`, no vowels and no `y`, so no name
//! spells a word that could suggest a judgement), drawn without repetition from a generator that
//! sees only the seed and the number of names: nothing about a configuration can leak into its
//! name. Assigning the names to configurations is the caller's business.

use crate::{RenderError, Result};
use std::collections::BTreeSet;

/// SplitMix64 (Steele, Lea, Flood 2014): tiny, fast, and fixed here so that the same seed gives
/// the same sequence whatever crate versions are around.
#[derive(Clone, Debug)]
pub struct SplitMix64 {
    state: u64,
}

impl SplitMix64 {
    /// A generator from a seed.
    pub fn new(seed: u64) -> Self {
        Self { state: seed }
    }

    /// A generator for one purpose (`stream`) derived from a user seed, so that, say, names and
    /// question order do not share draws.
    pub fn for_stream(seed: u64, stream: &str) -> Self {
        // FNV-1a of the stream name, mixed into the seed.
        let tag = stream.bytes().fold(0xcbf2_9ce4_8422_2325u64, |h, b| {
            (h ^ u64::from(b)).wrapping_mul(0x0000_0100_0000_01b3)
        });
        let mut g = Self::new(seed ^ tag);
        g.next_u64();
        g
    }

    /// The next 64 random bits.
    pub fn next_u64(&mut self) -> u64 {
        self.state = self.state.wrapping_add(0x9e37_79b9_7f4a_7c15);
        let mut z = self.state;
        z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
        z ^ (z >> 31)
    }

    /// A uniform integer in `0..n` (`n` > 0), without modulo bias (rejection sampling).
    pub fn below(&mut self, n: u64) -> u64 {
        assert!(n > 0, "below(0)");
        let zone = u64::MAX - (u64::MAX % n);
        loop {
            let x = self.next_u64();
            if x < zone {
                return x % n;
            }
        }
    }

    /// A fair coin.
    pub fn coin(&mut self) -> bool {
        self.next_u64() >> 63 == 1
    }

    /// Fisher-Yates shuffle.
    pub fn shuffle<T>(&mut self, items: &mut [T]) {
        for i in (1..items.len()).rev() {
            let j = self.below(i as u64 + 1) as usize;
            items.swap(i, j);
        }
    }
}

/// The letters names are made of.
pub const NAME_LETTERS: &[u8; 20] = b"bcdfghjklmnpqrstvwxz";
/// Letters per name.
pub const NAME_LENGTH: usize = 4;
/// At most this many names per call (a quarter of the 160 000 possible, so drawing stays fast).
pub const MAX_NAMES: usize = 40_000;

/// `count` distinct random names from `seed`.
pub fn random_names(count: usize, seed: u64) -> Result<Vec<String>> {
    if count > MAX_NAMES {
        return Err(RenderError::Questionnaire(format!(
            "{count} names requested, at most {MAX_NAMES} are available"
        )));
    }
    let mut rng = SplitMix64::for_stream(seed, "animation names");
    let mut seen = BTreeSet::new();
    let mut names = Vec::with_capacity(count);
    while names.len() < count {
        let name: String = (0..NAME_LENGTH)
            .map(|_| char::from(NAME_LETTERS[rng.below(NAME_LETTERS.len() as u64) as usize]))
            .collect();
        if seen.insert(name.clone()) {
            names.push(name);
        }
    }
    Ok(names)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn names_are_unique_four_lowercase_consonants_and_seeded() {
        let names = random_names(500, 7).unwrap();
        let set: BTreeSet<&String> = names.iter().collect();
        assert_eq!(set.len(), 500);
        for n in &names {
            assert_eq!(n.len(), 4);
            assert!(n.bytes().all(|b| NAME_LETTERS.contains(&b)), "{n}");
        }
        assert_eq!(names, random_names(500, 7).unwrap());
        assert_ne!(names, random_names(500, 8).unwrap());
        // A shorter list from the same seed is a prefix: names depend on nothing but the seed and
        // the position.
        assert_eq!(random_names(18, 7).unwrap(), names[..18]);
    }

    #[test]
    fn letters_are_used_evenly() {
        // Uninformative also means unbiased: each letter appears about 1/20 of the time.
        let names = random_names(5000, 1).unwrap();
        let mut counts = [0usize; 20];
        for b in names.iter().flat_map(|n| n.bytes()) {
            counts[NAME_LETTERS.iter().position(|&l| l == b).unwrap()] += 1;
        }
        let expected = 5000 * 4 / 20;
        for (l, c) in NAME_LETTERS.iter().zip(counts) {
            assert!(
                c.abs_diff(expected) < expected / 5,
                "{} x{c}",
                char::from(*l)
            );
        }
    }

    #[test]
    fn shuffle_is_a_permutation_and_below_stays_in_range() {
        let mut rng = SplitMix64::new(3);
        let mut v: Vec<u32> = (0..100).collect();
        rng.shuffle(&mut v);
        let mut sorted = v.clone();
        sorted.sort_unstable();
        assert_eq!(sorted, (0..100).collect::<Vec<_>>());
        assert_ne!(v, sorted);
        assert!((0..1000).all(|_| rng.below(7) < 7));
    }
}
