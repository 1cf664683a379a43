//! The configurations of a study, the pairs it asks, and each participant's questions.
//!
//! **Balanced subsets.** The pairs are put in one seeded random cycle; participant `p` answers
//! the `q` pairs that start at position `p·q` of the cycle (wrapping). Consecutive participants
//! take consecutive windows, so after `N` participants every pair has been seen `⌊Nq/P⌋` or
//! `⌈Nq/P⌉` times, and nobody sees a pair twice (`q ≤ P`).
//!
//! **Sides.** The `k`-th showing of a pair is swapped when `k + flip(pair)` is odd (`flip` a
//! seeded coin per pair), so each pair is shown each way equally often, up to one.
//!
//! **Order.** Each participant's questions, controls included, are shuffled by a generator
//! seeded with the study's seed and the participant's number. Controls show one configuration
//! on both sides, the configurations taken in a seeded cycle.

use crate::stats::SplitMix64;

/// The configurations of a study: every object x method x shading, item
/// `(object * methods + method) * shadings + shading`.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct StudyItems {
    /// Object names.
    pub objects: Vec<String>,
    /// Method names (the study's own labels).
    pub methods: Vec<String>,
    /// Shading names.
    pub shadings: Vec<String>,
}

impl StudyItems {
    /// Number of configurations.
    pub fn len(&self) -> usize {
        self.objects.len() * self.methods.len() * self.shadings.len()
    }

    /// Whether there are none.
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// The item of (object, method, shading).
    pub fn item(&self, object: usize, method: usize, shading: usize) -> usize {
        (object * self.methods.len() + method) * self.shadings.len() + shading
    }

    /// (object, method, shading) of an item.
    pub fn parts(&self, item: usize) -> (usize, usize, usize) {
        let s = item % self.shadings.len();
        let rest = item / self.shadings.len();
        (rest / self.methods.len(), rest % self.methods.len(), s)
    }

    /// A file-name-safe id: `object_method_shading`.
    pub fn id(&self, item: usize) -> String {
        let (o, m, s) = self.parts(item);
        format!(
            "{}_{}_{}",
            self.objects[o], self.methods[m], self.shadings[s]
        )
    }
}

/// Which variable a pair varies.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum PairKind {
    /// Two methods, same object and shading.
    Method,
    /// Two shadings, same object and method.
    Shading,
}

impl PairKind {
    /// `method` or `shading`.
    pub fn as_str(self) -> &'static str {
        match self {
            PairKind::Method => "method",
            PairKind::Shading => "shading",
        }
    }
}

/// One pair the study asks: its canonical left (`first`) and right (`second`).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct StudyPair {
    /// Canonical left item.
    pub first: usize,
    /// Canonical right item.
    pub second: usize,
    /// What differs.
    pub kind: PairKind,
}

/// The pairs of a study, in order: per object, per shading the method pairs (`method_pairs`, as
/// method indices, or every pair when `None`), then per method the shading pairs when
/// `shading_pairs`.
pub fn study_pairs(
    items: &StudyItems,
    method_pairs: Option<&[(usize, usize)]>,
    shading_pairs: bool,
) -> Vec<StudyPair> {
    let m = items.methods.len();
    let all: Vec<(usize, usize)> = (0..m)
        .flat_map(|a| (a + 1..m).map(move |b| (a, b)))
        .collect();
    let method_pairs = method_pairs.unwrap_or(&all);
    let mut pairs = Vec::new();
    for o in 0..items.objects.len() {
        for s in 0..items.shadings.len() {
            for &(a, b) in method_pairs {
                pairs.push(StudyPair {
                    first: items.item(o, a, s),
                    second: items.item(o, b, s),
                    kind: PairKind::Method,
                });
            }
        }
        if shading_pairs {
            for method in 0..m {
                for s in 0..items.shadings.len() {
                    for t in s + 1..items.shadings.len() {
                        pairs.push(StudyPair {
                            first: items.item(o, method, s),
                            second: items.item(o, method, t),
                            kind: PairKind::Shading,
                        });
                    }
                }
            }
        }
    }
    pairs
}

/// One question as a participant sees it.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Shown {
    /// The pair (index into the study's pairs), `None` for a control.
    pub pair: Option<usize>,
    /// Item on the left screen.
    pub left: usize,
    /// Item on the right screen.
    pub right: usize,
    /// Whether the pair's canonical sides are swapped on screen.
    pub swapped: bool,
}

/// A participant's questions in the order shown.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct ParticipantPlan {
    /// The questions, first shown first.
    pub questions: Vec<Shown>,
}

/// Every participant's questions: `per_participant` pairs (at most all of them) and `controls`
/// controls each (see the module documentation).
pub fn assign(
    items: &StudyItems,
    pairs: &[StudyPair],
    per_participant: usize,
    controls: usize,
    participants: usize,
    seed: u64,
) -> Vec<ParticipantPlan> {
    let p = pairs.len();
    let q = per_participant.min(p);
    let mut rng = SplitMix64::new(seed ^ 0x05EE_D0FC_7C1E);
    let mut cycle: Vec<usize> = (0..p).collect();
    shuffle(&mut cycle, &mut rng);
    let flip: Vec<bool> = (0..p).map(|_| rng.next_u64() & 1 == 1).collect();
    let mut shown_times = vec![0usize; p];
    let mut control_pool: Vec<usize> = Vec::new();
    let mut control_rng = SplitMix64::new(seed ^ 0x0C04_7201);
    let mut plans = Vec::with_capacity(participants);
    for participant in 0..participants {
        let mut questions = Vec::with_capacity(q + controls);
        for k in 0..q {
            let pair = cycle[(participant * q + k) % p.max(1)];
            let swapped = (shown_times[pair] + usize::from(flip[pair])) % 2 == 1;
            shown_times[pair] += 1;
            let StudyPair { first, second, .. } = pairs[pair];
            let (left, right) = if swapped {
                (second, first)
            } else {
                (first, second)
            };
            questions.push(Shown {
                pair: Some(pair),
                left,
                right,
                swapped,
            });
        }
        for _ in 0..controls {
            if control_pool.is_empty() {
                control_pool = (0..items.len()).collect();
                shuffle(&mut control_pool, &mut control_rng);
            }
            if let Some(c) = control_pool.pop() {
                questions.push(Shown {
                    pair: None,
                    left: c,
                    right: c,
                    swapped: false,
                });
            }
        }
        let mut order_rng =
            SplitMix64::new(seed.wrapping_mul(0x9E37_79B9_7F4A_7C15) ^ (participant as u64 + 1));
        shuffle(&mut questions, &mut order_rng);
        plans.push(ParticipantPlan { questions });
    }
    plans
}

/// Fisher-Yates with the crate's generator.
pub fn shuffle<T>(v: &mut [T], rng: &mut SplitMix64) {
    for i in (1..v.len()).rev() {
        let j = rng.next_index(i + 1);
        v.swap(i, j);
    }
}

#[cfg(test)]
pub(crate) mod tests {
    use super::*;

    /// Three objects, four methods, two shadings (the simulation's tests use them too).
    pub(crate) fn items() -> StudyItems {
        StudyItems {
            objects: vec!["asteroid".into(), "bunny".into(), "chunk".into()],
            methods: vec!["rmt".into(), "rmt-s".into(), "nets".into(), "mc".into()],
            shadings: vec!["smooth".into(), "flat".into()],
        }
    }

    #[test]
    fn items_and_pairs_of_the_peers_design() {
        let it = items();
        assert_eq!(it.len(), 24);
        for i in 0..24 {
            let (o, m, s) = it.parts(i);
            assert_eq!(it.item(o, m, s), i);
        }
        assert_eq!(it.id(it.item(1, 2, 1)), "bunny_nets_flat");
        let pairs = study_pairs(&it, None, true);
        // Per object: 2 shadings x 6 method pairs + 4 shading pairs.
        assert_eq!(pairs.len(), 3 * (12 + 4));
        for p in &pairs {
            let (a, b) = (it.parts(p.first), it.parts(p.second));
            assert_eq!(a.0, b.0, "same object");
            match p.kind {
                PairKind::Method => assert!(a.1 != b.1 && a.2 == b.2),
                PairKind::Shading => assert!(a.1 == b.1 && a.2 != b.2),
            }
        }
        let only = study_pairs(&it, Some(&[(0, 2), (0, 3)]), false);
        assert_eq!(only.len(), 3 * 2 * 2);
    }

    #[test]
    fn subsets_are_balanced_per_pair_and_sides_per_pair() {
        let it = items();
        let pairs = study_pairs(&it, None, true);
        for (n, q) in [(100, 20), (37, 48), (5, 7)] {
            let plans = assign(&it, &pairs, q, 2, n, 11);
            let mut seen = vec![0usize; pairs.len()];
            let mut swapped = vec![0usize; pairs.len()];
            for plan in &plans {
                assert_eq!(plan.questions.len(), q.min(pairs.len()) + 2);
                let mut mine: Vec<usize> = plan.questions.iter().filter_map(|s| s.pair).collect();
                let before = mine.len();
                mine.sort_unstable();
                mine.dedup();
                assert_eq!(mine.len(), before, "a pair twice for one participant");
                for s in &plan.questions {
                    match s.pair {
                        Some(k) => {
                            seen[k] += 1;
                            swapped[k] += usize::from(s.swapped);
                            let pr = pairs[k];
                            let expect = if s.swapped {
                                (pr.second, pr.first)
                            } else {
                                (pr.first, pr.second)
                            };
                            assert_eq!((s.left, s.right), expect);
                        }
                        None => assert_eq!(s.left, s.right),
                    }
                }
            }
            let (lo, hi) = (*seen.iter().min().unwrap(), *seen.iter().max().unwrap());
            assert!(hi - lo <= 1, "n {n} q {q}: seen {lo}..{hi}");
            assert_eq!(seen.iter().sum::<usize>(), n * q.min(pairs.len()));
            for (s, w) in seen.iter().zip(&swapped) {
                assert!((2 * w).abs_diff(*s) <= 1, "pair seen {s}, swapped {w}");
            }
        }
        // Same seed, same plans; another seed, other plans.
        assert_eq!(
            assign(&it, &pairs, 20, 2, 10, 3),
            assign(&it, &pairs, 20, 2, 10, 3)
        );
        assert_ne!(
            assign(&it, &pairs, 20, 2, 10, 3),
            assign(&it, &pairs, 20, 2, 10, 4)
        );
    }
}
