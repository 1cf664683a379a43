//! The dissertation's analysis (method.md, "Analysis"), exactly:
//!
//! - in a comparison group, a configuration's preference factor = votes for it / all responses in
//!   the group; "No preference" counts for nobody, so a group's factors sum to at most 1;
//! - the same group on different objects is combined by the arithmetic mean;
//! - a configuration's overall preference weight = the sum of its (mean) factors over the groups
//!   it appears in (its clustering group plus its lattice group in the paper's design).

use crate::data::{Answer, Question};
use crate::design::Design;

/// Answers to one question, by screen side.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct QuestionCounts {
    /// "Prefer left" answers (votes for the left configuration, W).
    pub left: u64,
    /// "No preference" answers (ties, T).
    pub none: u64,
    /// "Prefer right" answers (votes for the right configuration, L).
    pub right: u64,
}

impl QuestionCounts {
    /// All answers, N = W + T + L.
    pub fn total(&self) -> u64 {
        self.left + self.none + self.right
    }

    /// Decided answers, n = W + L.
    pub fn decided(&self) -> u64 {
        self.left + self.right
    }

    /// Adds one answer.
    pub fn add(&mut self, answer: Answer) {
        match answer {
            Answer::Left => self.left += 1,
            Answer::NoPreference => self.none += 1,
            Answer::Right => self.right += 1,
        }
    }

    /// Counts in [`Answer::ALL`] order.
    pub fn as_array(&self) -> [u64; 3] {
        [self.left, self.none, self.right]
    }
}

/// Per-question counts of the participants listed in `sample` (indices into `answers`; a
/// participant drawn twice counts twice). Used for the bootstrap; the point estimates come from the
/// same tally over every participant once.
pub fn tally(
    answers: &[Vec<Option<Answer>>],
    questions: usize,
    sample: &[usize],
) -> Vec<QuestionCounts> {
    let mut counts = vec![QuestionCounts::default(); questions];
    for &p in sample {
        for (q, answer) in answers[p].iter().enumerate() {
            if let Some(answer) = answer {
                counts[q].add(*answer);
            }
        }
    }
    counts
}

/// Factors of one comparison group.
#[derive(Clone, Debug, PartialEq)]
pub struct GroupFactors {
    /// All answers to the group's questions, ties included (the factors' denominator).
    pub responses: u64,
    /// Factor of each of the group's configurations, aligned with
    /// [`crate::design::ComparisonGroup::configurations`] (NaN when the group has no answer).
    pub factors: Vec<f64>,
}

/// Everything the dissertation's method derives from the counts.
#[derive(Clone, Debug, PartialEq)]
pub struct MethodResult {
    /// Per comparison group.
    pub groups: Vec<GroupFactors>,
    /// `rows[r][l]`: mean factor of level `l` of table row `r` over the groups averaged in it.
    pub rows: Vec<Vec<f64>>,
    /// Overall weight of each cell of [`Design::cells`]: the sum of the mean factors it receives.
    pub cells: Vec<f64>,
    /// Overall weight of each configuration before averaging: the sum of its factors over the
    /// groups it appears in (NaN when it is in none).
    pub configurations: Vec<f64>,
}

/// Applies the method to per-question counts.
pub fn preference_factors(
    design: &Design,
    questions: &[Question],
    counts: &[QuestionCounts],
    configuration_count: usize,
) -> MethodResult {
    let groups: Vec<GroupFactors> = design
        .groups
        .iter()
        .map(|group| {
            let responses: u64 = group.questions.iter().map(|&q| counts[q].total()).sum();
            let factors = group
                .configurations
                .iter()
                .map(|&c| {
                    let votes: u64 = group
                        .questions
                        .iter()
                        .map(|&q| {
                            let question = &questions[q];
                            let mut votes = 0;
                            if question.left == c {
                                votes += counts[q].left;
                            }
                            if question.right == c {
                                votes += counts[q].right;
                            }
                            votes
                        })
                        .sum();
                    if responses == 0 {
                        f64::NAN
                    } else {
                        votes as f64 / responses as f64
                    }
                })
                .collect();
            GroupFactors { responses, factors }
        })
        .collect();

    let rows: Vec<Vec<f64>> = design
        .rows
        .iter()
        .map(|row| {
            row.levels
                .iter()
                .map(|level| {
                    let values: Vec<f64> = row
                        .groups
                        .iter()
                        .filter_map(|&g| {
                            let group = &design.groups[g];
                            group
                                .configurations
                                .iter()
                                .position(|&c| level_of(design, group.varied, c) == Some(level))
                                .map(|k| groups[g].factors[k])
                        })
                        .filter(|f| f.is_finite())
                        .collect();
                    mean(&values)
                })
                .collect()
        })
        .collect();

    let mut cells = vec![f64::NAN; design.cells.len()];
    for (r, row) in design.rows.iter().enumerate() {
        for (l, level) in row.levels.iter().enumerate() {
            if let Some(cell) = design.cell_of_row_level(r, level) {
                if rows[r][l].is_finite() {
                    cells[cell] = if cells[cell].is_nan() {
                        0.0
                    } else {
                        cells[cell]
                    } + rows[r][l];
                }
            }
        }
    }

    let mut configurations = vec![f64::NAN; configuration_count];
    for (g, group) in design.groups.iter().enumerate() {
        for (k, &c) in group.configurations.iter().enumerate() {
            let factor = groups[g].factors[k];
            if factor.is_finite() {
                configurations[c] = if configurations[c].is_nan() {
                    0.0
                } else {
                    configurations[c]
                } + factor;
            }
        }
    }
    MethodResult {
        groups,
        rows,
        cells,
        configurations,
    }
}

/// The value of the varied variable for configuration `c`, looked up through the design's groups.
fn level_of(design: &Design, varied: usize, c: usize) -> Option<&str> {
    design
        .configuration_values
        .get(c)
        .and_then(|values| values.get(varied))
        .map(String::as_str)
}

/// Arithmetic mean; NaN for no values.
pub fn mean(values: &[f64]) -> f64 {
    if values.is_empty() {
        f64::NAN
    } else {
        values.iter().sum::<f64>() / values.len() as f64
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::data::Configurations;
    use std::path::{Path, PathBuf};

    /// One object... two objects, variables lattice (b, s) and clustering (u, i).
    fn setup() -> (Configurations, Vec<Question>, Design) {
        let mut names = Vec::new();
        let mut values = Vec::new();
        for object in ["ss", "bs"] {
            for lattice in ["b", "s"] {
                for clustering in ["u", "i"] {
                    names.push(format!("{object}_{lattice}{clustering}"));
                    values.push(vec![object.into(), lattice.into(), clustering.into()]);
                }
            }
        }
        let c = Configurations {
            path: PathBuf::from("c.csv"),
            variables: vec!["object".into(), "lattice".into(), "clustering".into()],
            names,
            values,
        };
        let q = |id: &str, l: &str, r: &str| Question {
            id: id.into(),
            left: c.index_of(l).unwrap(),
            right: c.index_of(r).unwrap(),
            row: 1,
        };
        let questions = vec![
            q("Q1", "ss_bu", "ss_bi"),
            q("Q2", "bs_bu", "bs_bi"),
            q("Q3", "ss_bu", "ss_su"),
            q("Q4", "bs_bu", "bs_su"),
        ];
        let design = Design::build(&c, &questions, Path::new("q"), Some("object"), false).unwrap();
        (c, questions, design)
    }

    #[test]
    fn factors_means_and_weights_match_hand_computation() {
        let (c, questions, design) = setup();
        let counts = [
            // Q1 ss_bu vs ss_bi: 2 left, 1 none, 7 right.
            QuestionCounts {
                left: 2,
                none: 1,
                right: 7,
            },
            // Q2 bs_bu vs bs_bi: 4 left, 2 none, 4 right.
            QuestionCounts {
                left: 4,
                none: 2,
                right: 4,
            },
            // Q3 ss_bu vs ss_su: 6 left, 0 none, 4 right.
            QuestionCounts {
                left: 6,
                none: 0,
                right: 4,
            },
            // Q4 bs_bu vs bs_su: 5 left, 5 none, 0 right.
            QuestionCounts {
                left: 5,
                none: 5,
                right: 0,
            },
        ];
        let result = preference_factors(&design, &questions, &counts, c.names.len());
        // Group 0 (clustering, sphere, b): bu 2/10, bi 7/10.
        assert_eq!(result.groups[0].responses, 10);
        assert_eq!(result.groups[0].factors, vec![0.2, 0.7]);
        // Group 1 (clustering, bunny, b): 0.4, 0.4. Row mean: u 0.3, i 0.55.
        let row = &result.rows[0];
        assert!((row[0] - 0.3).abs() < 1e-12 && (row[1] - 0.55).abs() < 1e-12);
        // Lattice row (clustering = u): sphere b 0.6 s 0.4, bunny b 0.5 s 0: means 0.55, 0.2.
        let row = &result.rows[1];
        assert!((row[0] - 0.55).abs() < 1e-12 && (row[1] - 0.2).abs() < 1e-12);
        // Factors of every group sum to at most 1 (ties count for nobody).
        for g in &result.groups {
            assert!(g.factors.iter().sum::<f64>() <= 1.0 + 1e-12);
        }
        // Cells (lattice, clustering): (b,u) = 0.3 + 0.55, (b,i) = 0.55, (s,u) = 0.2, (s,i) none.
        assert!((result.cells[0] - 0.85).abs() < 1e-12);
        assert!((result.cells[1] - 0.55).abs() < 1e-12);
        assert!((result.cells[2] - 0.2).abs() < 1e-12);
        assert!(result.cells[3].is_nan());
        // ss_bu before averaging: 0.2 (clustering group) + 0.6 (lattice group).
        assert!((result.configurations[0] - 0.8).abs() < 1e-12);
    }

    #[test]
    fn tally_counts_resampled_participants_with_multiplicity() {
        let answers = vec![
            vec![Some(Answer::Left), None],
            vec![Some(Answer::Right), Some(Answer::NoPreference)],
        ];
        let counts = tally(&answers, 2, &[0, 1, 1]);
        assert_eq!(
            counts[0],
            QuestionCounts {
                left: 1,
                none: 0,
                right: 2
            }
        );
        assert_eq!(
            counts[1],
            QuestionCounts {
                left: 0,
                none: 2,
                right: 0
            }
        );
    }
}
