//! The validated inputs: configurations with their variables, questions as pairs of
//! configurations, and each participant's answers.

use std::fmt;
use std::path::PathBuf;
use std::str::FromStr;

use polars::prelude::DataFrame;

/// One answer to a question, as shown on screen.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord, Hash)]
pub enum Answer {
    /// Prefer the left animation.
    Left,
    /// No preference (a tie: counts for nobody).
    NoPreference,
    /// Prefer the right animation.
    Right,
}

impl Answer {
    /// All answers in table order (left, none, right).
    pub const ALL: [Answer; 3] = [Answer::Left, Answer::NoPreference, Answer::Right];

    /// Reads `L`/`N`/`R`, `left`/`none`/`right` or the survey tool's "Prefer left" /
    /// "No preference" / "Prefer right", ignoring case and surrounding spaces.
    /// `None` for anything else (the empty string included).
    pub fn parse(text: &str) -> Option<Answer> {
        match text.trim().to_ascii_lowercase().as_str() {
            "l" | "left" | "prefer left" => Some(Answer::Left),
            "n" | "none" | "no preference" | "tie" => Some(Answer::NoPreference),
            "r" | "right" | "prefer right" => Some(Answer::Right),
            _ => None,
        }
    }

    /// The one-letter code used in tables and long frames.
    pub fn code(self) -> &'static str {
        match self {
            Answer::Left => "L",
            Answer::NoPreference => "N",
            Answer::Right => "R",
        }
    }

    /// Position of this answer in [`Answer::ALL`].
    pub fn index(self) -> usize {
        match self {
            Answer::Left => 0,
            Answer::NoPreference => 1,
            Answer::Right => 2,
        }
    }
}

/// Layout of a responses file.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum InputFormat {
    /// One row per participant (`participant` column), one column per question id.
    Wide,
    /// One row per answer: `participant`, `question`, `response` (or `answer`).
    Long,
    /// A survey tool's export: a timestamp column, one column per question titled like
    /// "Question 7 - Which of these two animations do you prefer?", answers "Prefer left" /
    /// "No preference" / "Prefer right"; participants numbered P01, P02, ... in row order unless
    /// a `participant` (or `respondent`) column names them.
    Survey,
}

impl fmt::Display for InputFormat {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(match self {
            InputFormat::Wide => "wide",
            InputFormat::Long => "long",
            InputFormat::Survey => "survey",
        })
    }
}

impl FromStr for InputFormat {
    type Err = String;

    fn from_str(text: &str) -> Result<Self, Self::Err> {
        match text.trim().to_ascii_lowercase().as_str() {
            "wide" => Ok(InputFormat::Wide),
            "long" => Ok(InputFormat::Long),
            "survey" | "export" => Ok(InputFormat::Survey),
            other => Err(format!(
                "unknown responses format '{other}' (expected wide, long or survey)"
            )),
        }
    }
}

/// The configurations file: one row per configuration, a name column and one column per
/// variable. Nothing here is specific to the paper's object, lattice and clustering.
#[derive(Clone, Debug, PartialEq)]
pub struct Configurations {
    /// Where it was read from.
    pub path: PathBuf,
    /// The variables (every column except the name column), in file order.
    pub variables: Vec<String>,
    /// Configuration names, in file order.
    pub names: Vec<String>,
    /// `values[c][v]`: value of variable `v` for configuration `c`.
    pub values: Vec<Vec<String>>,
}

impl Configurations {
    /// Index of the configuration called `name`.
    pub fn index_of(&self, name: &str) -> Option<usize> {
        self.names.iter().position(|n| n == name)
    }

    /// Index of the variable called `name`.
    pub fn variable_index(&self, name: &str) -> Option<usize> {
        self.variables.iter().position(|v| v == name)
    }

    /// The distinct values of variable `v` in order of first appearance (the tables' order).
    pub fn levels(&self, v: usize) -> Vec<String> {
        let mut levels: Vec<String> = Vec::new();
        for row in &self.values {
            if !levels.contains(&row[v]) {
                levels.push(row[v].clone());
            }
        }
        levels
    }

    /// Position of `value` among [`Configurations::levels`] of variable `v`.
    pub fn level_index(&self, v: usize, value: &str) -> usize {
        self.levels(v)
            .iter()
            .position(|l| l == value)
            .unwrap_or(usize::MAX)
    }
}

/// One question: two configurations side by side.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Question {
    /// The id used in the responses (`Q7`).
    pub id: String,
    /// Configuration shown on the left (index into [`Configurations::names`]).
    pub left: usize,
    /// Configuration shown on the right.
    pub right: usize,
    /// 1-based data row in the questions file.
    pub row: usize,
}

/// What a survey server records with an answer besides the answer itself (the optional
/// `order`, `swapped` and `seconds` columns of the long layout).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct AnswerMeta {
    /// 1-based position at which the participant saw the question.
    pub order: u32,
    /// Whether the question's canonical left was shown on the right (the answer is canonical).
    pub swapped: bool,
    /// Seconds the participant took, when recorded.
    pub seconds: Option<f64>,
}

/// Answers after validation, exclusion and (optionally) dropping of missing answers.
#[derive(Clone, Debug)]
pub struct Responses {
    /// Where they were read from.
    pub path: PathBuf,
    /// The detected or requested layout.
    pub format: InputFormat,
    /// Participant ids in file order (excluded participants removed).
    pub participants: Vec<String>,
    /// `answers[p][q]`: participant `p`'s answer to question `q` (`None`: dropped as missing).
    pub answers: Vec<Vec<Option<Answer>>>,
    /// Participants removed on request, in the order given.
    pub excluded: Vec<String>,
    /// Missing answers dropped (only with missing answers allowed); excluded participants'
    /// missing answers are not counted.
    pub dropped_missing: usize,
    /// The same answers as a tidy frame: `participant` (str), `question` (u32 index),
    /// `answer` (str `L`/`N`/`R`), one row per answer, excluded participants removed.
    pub long: DataFrame,
    /// `meta[p][q]`, aligned with `answers`, when the file has the survey columns `order` and
    /// `swapped` (long layout only); `None` otherwise.
    pub meta: Option<Vec<Vec<Option<AnswerMeta>>>>,
}

/// The three inputs after validation.
#[derive(Clone, Debug)]
pub struct Dataset {
    /// Configurations and their variables.
    pub configurations: Configurations,
    /// Questions in file order.
    pub questions: Vec<Question>,
    /// Answers.
    pub responses: Responses,
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn answers_parse_in_all_spellings_and_reject_others() {
        assert_eq!(Answer::parse(" l "), Some(Answer::Left));
        assert_eq!(Answer::parse("Prefer left"), Some(Answer::Left));
        assert_eq!(Answer::parse("No preference"), Some(Answer::NoPreference));
        assert_eq!(Answer::parse("R"), Some(Answer::Right));
        assert_eq!(Answer::parse("PREFER RIGHT"), Some(Answer::Right));
        assert_eq!(Answer::parse(""), None);
        assert_eq!(Answer::parse("X"), None);
        assert_eq!(Answer::parse("Prefer middle"), None);
    }

    #[test]
    fn formats_parse_and_print_round_trip() {
        for format in [InputFormat::Wide, InputFormat::Long, InputFormat::Survey] {
            assert_eq!(format.to_string().parse::<InputFormat>(), Ok(format));
        }
        assert!("tall".parse::<InputFormat>().is_err());
    }
}
