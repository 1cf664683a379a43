//! The experimental design read off the questions: comparison groups, the table rows that
//! average a group over one variable (the object), and the cells of the overall-weights table.
//!
//! A question whose two configurations differ in exactly one variable belongs to the comparison
//! group of that variable with every other variable fixed, e.g. varying clustering with
//! object = sphere and lattice = bcdl: {ss_bu-ss_bi, ss_bu-ss_bp, ss_bp-ss_bi}. Groups that differ
//! only in the averaged variable (the object) share a table row. Nothing depends on the names of
//! the paper's variables.

use std::collections::BTreeMap;

use crate::data::{Configurations, Question};
use crate::error::{AnalysisError, Result};

/// Questions that vary one variable with all others fixed.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct ComparisonGroup {
    /// The varied variable (index into [`Configurations::variables`]).
    pub varied: usize,
    /// Every other variable with its fixed value, in variable order.
    pub fixed: Vec<(usize, String)>,
    /// Its questions (indices into the question list), in file order.
    pub questions: Vec<usize>,
    /// The configurations compared, ordered by the varied variable's level order.
    pub configurations: Vec<usize>,
    /// The table row this group is averaged into.
    pub row: usize,
}

/// A row of the mean-factor table: one varied variable with the non-averaged variables fixed,
/// averaged over the groups that differ only in the averaged variable.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct TableRow {
    /// The varied variable.
    pub varied: usize,
    /// The other non-averaged variables with their fixed values.
    pub fixed: Vec<(usize, String)>,
    /// Groups averaged in this row (one per value of the averaged variable).
    pub groups: Vec<usize>,
    /// Values of the varied variable that occur, in level order (the row's columns).
    pub levels: Vec<String>,
}

/// A question outside all groups: its sides differ in zero or several variables.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Ungrouped {
    /// The question index.
    pub question: usize,
    /// The variables in which its sides differ.
    pub differing: Vec<usize>,
}

/// Groups, rows and weight cells of a questionnaire.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Design {
    /// Variable names (the configurations' columns).
    pub variables: Vec<String>,
    /// The variable averaged over (the paper's object), if any.
    pub mean_over: Option<usize>,
    /// Comparison groups, ordered by row and then by the averaged variable's level.
    pub groups: Vec<ComparisonGroup>,
    /// Table rows, ordered by the varied variable's first appearance among the questions and then
    /// by the fixed values' level order.
    pub rows: Vec<TableRow>,
    /// For each question, its group.
    pub question_group: Vec<Option<usize>>,
    /// Questions outside all groups.
    pub ungrouped: Vec<Ungrouped>,
    /// The variables that span the weights table: all except the averaged one.
    pub cell_variables: Vec<usize>,
    /// Every combination of `cell_variables` values that some configuration has, in level order.
    pub cells: Vec<Vec<String>>,
    /// Configuration names (copied from the configurations).
    pub configuration_names: Vec<String>,
    /// `configuration_values[c][v]`: value of variable `v` for configuration `c`.
    pub configuration_values: Vec<Vec<String>>,
}

impl Design {
    /// Derives the design; `mean_over` names the variable to average over (`None`: none).
    /// With `allow_ungrouped` false, a question that differs in zero or several variables is an
    /// error naming it.
    pub fn build(
        configurations: &Configurations,
        questions: &[Question],
        questions_path: &std::path::Path,
        mean_over: Option<&str>,
        allow_ungrouped: bool,
    ) -> Result<Design> {
        let variables = configurations.variables.clone();
        let mean_over = match mean_over {
            None => None,
            Some(name) => Some(configurations.variable_index(name).ok_or_else(|| {
                AnalysisError::UnknownVariable {
                    path: configurations.path.clone(),
                    variable: name.to_string(),
                    columns: variables.clone(),
                }
            })?),
        };
        let level = |v: usize, value: &str| configurations.level_index(v, value);
        let value = |c: usize, v: usize| configurations.values[c][v].clone();

        // Rank of each variable by its first appearance as the varied one.
        let mut varied_rank: Vec<usize> = vec![usize::MAX; variables.len()];
        let mut next_rank = 0;
        // row key -> (varied, fixed) ; group key -> questions
        type RowKey = (usize, usize, Vec<usize>);
        let mut row_groups: BTreeMap<RowKey, BTreeMap<usize, Vec<usize>>> = BTreeMap::new();
        let mut ungrouped = Vec::new();
        for (q, question) in questions.iter().enumerate() {
            let differing: Vec<usize> = (0..variables.len())
                .filter(|&v| value(question.left, v) != value(question.right, v))
                .collect();
            if differing.len() != 1 {
                if !allow_ungrouped {
                    return Err(AnalysisError::Ungroupable {
                        path: questions_path.to_path_buf(),
                        row: question.row,
                        question: question.id.clone(),
                        sides: format!(
                            "{} vs {}",
                            configurations.names[question.left],
                            configurations.names[question.right]
                        ),
                        differing: differing.len(),
                        variables: differing.iter().map(|&v| variables[v].clone()).collect(),
                    });
                }
                ungrouped.push(Ungrouped {
                    question: q,
                    differing,
                });
                continue;
            }
            let varied = differing[0];
            if varied_rank[varied] == usize::MAX {
                varied_rank[varied] = next_rank;
                next_rank += 1;
            }
            let row_levels: Vec<usize> = (0..variables.len())
                .filter(|&v| v != varied && Some(v) != mean_over)
                .map(|v| level(v, &value(question.left, v)))
                .collect();
            let averaged_level = match mean_over {
                Some(m) if m != varied => level(m, &value(question.left, m)),
                _ => 0,
            };
            row_groups
                .entry((varied_rank[varied], varied, row_levels))
                .or_default()
                .entry(averaged_level)
                .or_default()
                .push(q);
        }

        let mut groups = Vec::new();
        let mut rows = Vec::new();
        let mut question_group = vec![None; questions.len()];
        for ((_, varied, _), by_level) in row_groups {
            let row_index = rows.len();
            let mut row_group_indices = Vec::new();
            let mut row_levels: Vec<String> = Vec::new();
            let first_question = &questions[by_level.values().next().map_or(0, |qs| qs[0])];
            for group_questions in by_level.into_values() {
                let mut members: Vec<usize> = group_questions
                    .iter()
                    .flat_map(|&q| [questions[q].left, questions[q].right])
                    .collect();
                members.sort_by_key(|&c| (level(varied, &value(c, varied)), c));
                members.dedup();
                for &c in &members {
                    let v = value(c, varied);
                    if !row_levels.contains(&v) {
                        row_levels.push(v);
                    }
                }
                let any = questions[group_questions[0]].left;
                let fixed = (0..variables.len())
                    .filter(|&v| v != varied)
                    .map(|v| (v, value(any, v)))
                    .collect();
                for &q in &group_questions {
                    question_group[q] = Some(groups.len());
                }
                row_group_indices.push(groups.len());
                groups.push(ComparisonGroup {
                    varied,
                    fixed,
                    questions: group_questions,
                    configurations: members,
                    row: row_index,
                });
            }
            row_levels.sort_by_key(|l| level(varied, l));
            let fixed = (0..variables.len())
                .filter(|&v| v != varied && Some(v) != mean_over)
                .map(|v| (v, value(first_question.left, v)))
                .collect();
            rows.push(TableRow {
                varied,
                fixed,
                groups: row_group_indices,
                levels: row_levels,
            });
        }

        let cell_variables: Vec<usize> = (0..variables.len())
            .filter(|&v| Some(v) != mean_over)
            .collect();
        let mut cells: Vec<Vec<String>> = Vec::new();
        for c in 0..configurations.names.len() {
            let cell: Vec<String> = cell_variables.iter().map(|&v| value(c, v)).collect();
            if !cells.contains(&cell) {
                cells.push(cell);
            }
        }
        cells.sort_by_key(|cell| {
            cell_variables
                .iter()
                .zip(cell)
                .map(|(&v, x)| level(v, x))
                .collect::<Vec<_>>()
        });

        Ok(Design {
            variables,
            mean_over,
            groups,
            rows,
            question_group,
            ungrouped,
            cell_variables,
            cells,
            configuration_names: configurations.names.clone(),
            configuration_values: configurations.values.clone(),
        })
    }

    fn assignment(&self, fixed: &[(usize, String)]) -> String {
        fixed
            .iter()
            .map(|(v, x)| format!("{}={x}", self.variables[*v]))
            .collect::<Vec<_>>()
            .join(", ")
    }

    /// "lattice=bcdl": the fixed values of a row.
    pub fn row_fixed_label(&self, row: usize) -> String {
        self.assignment(&self.rows[row].fixed)
    }

    /// "clustering | lattice=bcdl": the varied variable and the row's fixed values.
    pub fn row_label(&self, row: usize) -> String {
        let r = &self.rows[row];
        let fixed = self.assignment(&r.fixed);
        if fixed.is_empty() {
            self.variables[r.varied].clone()
        } else {
            format!("{} | {fixed}", self.variables[r.varied])
        }
    }

    /// "object=sphere, lattice=bcdl": the fixed values of a group.
    pub fn group_fixed_label(&self, group: usize) -> String {
        self.assignment(&self.groups[group].fixed)
    }

    /// "clustering | object=sphere, lattice=bcdl".
    pub fn group_label(&self, group: usize) -> String {
        let g = &self.groups[group];
        let fixed = self.assignment(&g.fixed);
        if fixed.is_empty() {
            self.variables[g.varied].clone()
        } else {
            format!("{} | {fixed}", self.variables[g.varied])
        }
    }

    /// Index into [`Design::cells`] of the cell that row `row`'s level `level` contributes to.
    pub fn cell_of_row_level(&self, row: usize, level: &str) -> Option<usize> {
        let r = &self.rows[row];
        let wanted: Vec<&str> = self
            .cell_variables
            .iter()
            .map(|&v| {
                if v == r.varied {
                    Some(level)
                } else {
                    r.fixed
                        .iter()
                        .find(|(fv, _)| *fv == v)
                        .map(|(_, x)| x.as_str())
                }
            })
            .collect::<Option<Vec<&str>>>()?;
        self.cells
            .iter()
            .position(|cell| cell.iter().map(String::as_str).eq(wanted.iter().copied()))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::path::{Path, PathBuf};

    /// Two objects x two lattices x two clusterings, the paper's layout in miniature.
    pub(crate) fn small_configurations() -> Configurations {
        let mut names = Vec::new();
        let mut values = Vec::new();
        for object in ["sphere", "bunny"] {
            for lattice in ["bcdl", "simple"] {
                for clustering in ["none", "integrated"] {
                    names.push(format!(
                        "{}{}{}",
                        &object[..1],
                        &lattice[..1],
                        &clustering[..1]
                    ));
                    values.push(vec![object.into(), lattice.into(), clustering.into()]);
                }
            }
        }
        Configurations {
            path: PathBuf::from("c.csv"),
            variables: vec!["object".into(), "lattice".into(), "clustering".into()],
            names,
            values,
        }
    }

    fn question(c: &Configurations, id: &str, left: &str, right: &str) -> Question {
        Question {
            id: id.into(),
            left: c.index_of(left).unwrap(),
            right: c.index_of(right).unwrap(),
            row: 1,
        }
    }

    #[test]
    fn questions_fall_into_groups_and_rows_averaged_over_objects() {
        let c = small_configurations();
        let qs = vec![
            question(&c, "Q1", "sbn", "sbi"),
            question(&c, "Q2", "bbn", "bbi"),
            question(&c, "Q3", "sbn", "ssn"),
            question(&c, "Q4", "ssi", "ssn"),
        ];
        let d = Design::build(&c, &qs, Path::new("q.csv"), Some("object"), false).unwrap();
        assert_eq!(d.groups.len(), 4);
        // Clustering varies first among the questions, so its row comes first.
        assert_eq!(d.row_label(0), "clustering | lattice=bcdl");
        assert_eq!(d.rows[0].groups.len(), 2);
        assert_eq!(
            d.rows[0].levels,
            vec!["none".to_string(), "integrated".to_string()]
        );
        assert_eq!(d.row_label(1), "clustering | lattice=simple");
        assert_eq!(d.row_label(2), "lattice | clustering=none");
        assert_eq!(d.group_label(0), "clustering | object=sphere, lattice=bcdl");
        assert_eq!(d.question_group, vec![Some(0), Some(1), Some(3), Some(2)]);
        assert_eq!(d.cells.len(), 4);
        assert_eq!(d.cell_of_row_level(2, "simple"), Some(2));
    }

    #[test]
    fn a_question_varying_two_variables_is_an_error_or_ungrouped() {
        let c = small_configurations();
        let qs = vec![
            question(&c, "Q1", "sbn", "ssi"),
            question(&c, "Q2", "sbn", "sbn"),
        ];
        let err = Design::build(&c, &qs, Path::new("q.csv"), Some("object"), false).unwrap_err();
        assert!(
            matches!(err, AnalysisError::Ungroupable { differing: 2, .. }),
            "{err}"
        );
        let d = Design::build(&c, &qs, Path::new("q.csv"), Some("object"), true).unwrap();
        assert!(d.groups.is_empty());
        assert_eq!(d.ungrouped.len(), 2);
        assert_eq!(d.ungrouped[1].differing, Vec::<usize>::new());
    }

    #[test]
    fn an_unknown_averaging_variable_is_reported() {
        let c = small_configurations();
        let err = Design::build(&c, &[], Path::new("q.csv"), Some("shape"), false).unwrap_err();
        assert!(matches!(err, AnalysisError::UnknownVariable { .. }));
    }
}
