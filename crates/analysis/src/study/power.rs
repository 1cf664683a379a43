//! The power table of a study design: participants needed for 80% power to detect a given
//! preference (60/40 of decided answers) between the reference method and each peer, per
//! shading.
//!
//! A pair question needs `n` answers for a two-sided sign test at level alpha and 80% power
//! ([`crate::effects::participants_needed`]: the normal approximation, ties at the design's tie
//! rate taking answers away). Each participant answers `q` of the `P` pairs, so a given pair
//! question is answered by the share `q / P` of participants. The comparison "reference
//! against peer in one shading" is asked on every object: pooled over the `O` objects it needs
//! `ceil(n / (O q / P))` participants by the normal approximation, then as many more as the
//! exact sign test on the pooled answers needs to reach 80% (its exact power is given beside
//! it); on each object alone `ceil(n / (q / P))` (normal approximation).

use super::design::{PairKind, StudyItems, StudyPair};
use crate::effects::{participants_needed, sign_test_power, TARGET_POWER};

/// One row: the reference against one peer in one shading.
#[derive(Clone, Debug, PartialEq)]
pub struct PowerRow {
    /// Peer method index.
    pub peer: usize,
    /// Shading index.
    pub shading: usize,
    /// Pair questions of this comparison (one per object where it is asked).
    pub questions: usize,
    /// Answers one question needs.
    pub answers_needed: Option<u64>,
    /// Participants needed, answers pooled over objects (exact sign test).
    pub pooled: Option<u64>,
    /// Participants needed for each object alone.
    pub per_object: Option<u64>,
    /// Exact sign-test power of the pooled answers at `pooled` participants.
    pub exact_power: f64,
}

/// The power table.
#[derive(Clone, Debug, PartialEq)]
pub struct PowerTable {
    /// The reference method.
    pub reference: usize,
    /// Decided share for the preferred side (0.6).
    pub effect: f64,
    /// Tie rate assumed.
    pub tie_rate: f64,
    /// Test level.
    pub alpha: f64,
    /// Share of participants who answer a given pair question.
    pub share_per_pair: f64,
    /// Rows, per shading then peer.
    pub rows: Vec<PowerRow>,
}

impl PowerTable {
    /// The participants the design asks for: the largest pooled figure (every comparison
    /// reaches 80% power).
    pub fn participants(&self) -> Option<u64> {
        self.rows
            .iter()
            .map(|r| r.pooled)
            .collect::<Option<Vec<u64>>>()
            .and_then(|v| v.into_iter().max())
    }
}

/// The power table of a design whose participants answer `per_participant` of `pairs`.
pub fn power_table(
    items: &StudyItems,
    pairs: &[StudyPair],
    per_participant: usize,
    reference: usize,
    effect: f64,
    tie_rate: f64,
    alpha: f64,
) -> PowerTable {
    let share = if pairs.is_empty() {
        0.0
    } else {
        per_participant.min(pairs.len()) as f64 / pairs.len() as f64
    };
    let answers_needed = participants_needed(effect, tie_rate, alpha);
    let mut rows = Vec::new();
    for shading in 0..items.shadings.len() {
        for peer in (0..items.methods.len()).filter(|&m| m != reference) {
            let questions = pairs
                .iter()
                .filter(|p| p.kind == PairKind::Method)
                .filter(|p| {
                    let (a, b) = (items.parts(p.first), items.parts(p.second));
                    a.2 == shading
                        && ((a.1, b.1) == (reference, peer) || (a.1, b.1) == (peer, reference))
                })
                .count();
            let need = |per: f64| -> Option<u64> {
                let n = answers_needed? as f64;
                (per > 0.0).then(|| (n / per).ceil() as u64)
            };
            let approximate = need(share * questions as f64);
            let per_object = if questions > 0 { need(share) } else { None };
            // The exact sign test on the pooled answers: from the normal approximation's
            // figure, add participants until the exact power reaches the target.
            let exact = |n: u64| {
                let answers = (n as f64 * share * questions as f64).round() as u64;
                if answers <= 20_000 {
                    sign_test_power(answers, effect, tie_rate, alpha)
                } else {
                    f64::NAN
                }
            };
            let (pooled, exact_power) = match approximate {
                Some(start) => {
                    let mut n = start;
                    let mut p = exact(n);
                    while p < TARGET_POWER && n < 2 * start {
                        n += 1;
                        p = exact(n);
                    }
                    (Some(n), p)
                }
                None => (None, f64::NAN),
            };
            rows.push(PowerRow {
                peer,
                shading,
                questions,
                answers_needed,
                pooled,
                per_object,
                exact_power,
            });
        }
    }
    PowerTable {
        reference,
        effect,
        tie_rate,
        alpha,
        share_per_pair: share,
        rows,
    }
}

#[cfg(test)]
mod tests {
    use super::super::design::study_pairs;
    use super::*;

    #[test]
    fn pooled_and_per_object_figures_follow_the_share_of_pairs() {
        let items = StudyItems {
            objects: vec!["a".into(), "b".into(), "c".into()],
            methods: vec!["rmt".into(), "x".into(), "y".into(), "z".into()],
            shadings: vec!["smooth".into(), "flat".into()],
        };
        let pairs = study_pairs(&items, None, true);
        assert_eq!(pairs.len(), 48);
        let t = power_table(&items, &pairs, 24, 0, 0.6, 0.2, 0.05);
        assert_eq!(t.rows.len(), 6);
        // n = ((1.96 * 0.5 + 0.8416 * sqrt(0.24)) / 0.1)^2 = 193.8; / 0.8 -> 243 answers.
        let n = t.rows[0].answers_needed.unwrap();
        assert_eq!(n, 243);
        for r in &t.rows {
            assert_eq!(r.questions, 3);
            // Half of the participants see a pair; three objects pooled.
            assert_eq!(r.per_object, Some(486));
            // 162 by the normal approximation (243 / 1.5); the exact test needs a few more.
            let n = r.pooled.unwrap();
            assert!((162..=175).contains(&n), "{n}");
            assert!(
                r.exact_power >= 0.8 && r.exact_power < 0.85,
                "{}",
                r.exact_power
            );
            let fewer = (((n - 1) as f64) * 1.5).round() as u64;
            assert!(sign_test_power(fewer, 0.6, 0.2, 0.05) < 0.8);
        }
        assert_eq!(t.participants(), t.rows[0].pooled);
        // A comparison that is never asked has no figure.
        let only = study_pairs(&items, Some(&[(0, 1)]), false);
        let t = power_table(&items, &only, 6, 0, 0.6, 0.2, 0.05);
        assert_eq!(t.rows.iter().filter(|r| r.pooled.is_none()).count(), 4);
        assert_eq!(t.participants(), None);
    }
}
