//! The one error type of the crate: every variant names the file, row, column or key at fault.

use std::path::PathBuf;

/// Everything that can go wrong while loading, validating, analysing or writing.
///
/// Rows are 1-based data rows (the header is not counted), so "row 3" is the third line
/// after the header of a plain CSV file.
#[derive(Debug, thiserror::Error)]
pub enum AnalysisError {
    /// A file could not be read or written.
    #[error("{path}: {source}")]
    Io {
        /// The file.
        path: PathBuf,
        /// The operating system's error.
        source: std::io::Error,
    },
    /// A file is not well-formed CSV (ragged rows, bad quoting, no header).
    #[error("{path}: not a readable CSV file: {message}")]
    Csv {
        /// The file.
        path: PathBuf,
        /// What the CSV reader said.
        message: String,
    },
    /// A column that the format requires is absent.
    #[error("{path}: missing column '{column}' ({hint})")]
    MissingColumn {
        /// The file.
        path: PathBuf,
        /// The column that is needed.
        column: String,
        /// Which columns were expected.
        hint: String,
    },
    /// Two columns of the header have the same title.
    #[error("{path}: duplicate column '{column}'")]
    DuplicateColumn {
        /// The file.
        path: PathBuf,
        /// The repeated title.
        column: String,
    },
    /// A column that no format expects (and that is not a question).
    #[error("{path}: column '{column}' is neither a question nor a known metadata column")]
    UnexpectedColumn {
        /// The file.
        path: PathBuf,
        /// The column title.
        column: String,
    },
    /// The layout of the responses file matches none of the three formats.
    #[error(
        "{path}: cannot tell the format (wide, long or survey export) from the header {header:?}; \
         pass the format explicitly"
    )]
    UnknownFormat {
        /// The file.
        path: PathBuf,
        /// The header that was seen.
        header: Vec<String>,
    },
    /// A cell that must hold a value is empty.
    #[error("{path}, row {row}, column '{column}': empty value")]
    EmptyValue {
        /// The file.
        path: PathBuf,
        /// 1-based data row.
        row: usize,
        /// The column title.
        column: String,
    },
    /// A configuration name appears twice in the configurations file.
    #[error("{path}, row {row}, column '{column}': duplicate configuration '{name}'")]
    DuplicateConfiguration {
        /// The file.
        path: PathBuf,
        /// 1-based data row of the second occurrence.
        row: usize,
        /// The name column.
        column: String,
        /// The repeated name.
        name: String,
    },
    /// A question id appears twice in the questions file.
    #[error("{path}, row {row}, column '{column}': duplicate question '{question}'")]
    DuplicateQuestion {
        /// The file.
        path: PathBuf,
        /// 1-based data row of the second occurrence.
        row: usize,
        /// The question column.
        column: String,
        /// The repeated id.
        question: String,
    },
    /// A question names a configuration that the configurations file does not define.
    #[error("{path}, row {row}, column '{column}': unknown configuration '{name}'")]
    UnknownConfiguration {
        /// The file.
        path: PathBuf,
        /// 1-based data row.
        row: usize,
        /// `left` or `right`.
        column: String,
        /// The unknown name.
        name: String,
    },
    /// A question whose two sides do not differ in exactly one variable.
    #[error(
        "{path}, row {row}: question '{question}' ({sides}) differs in {differing} \
         variable(s) {variables:?}, not exactly one; it belongs to no comparison group \
         (allow ungrouped questions to report it outside all groups)"
    )]
    Ungroupable {
        /// The questions file.
        path: PathBuf,
        /// 1-based data row.
        row: usize,
        /// The question id.
        question: String,
        /// "left vs right" configurations.
        sides: String,
        /// How many variables differ.
        differing: usize,
        /// The names of the differing variables.
        variables: Vec<String>,
    },
    /// A responses row or column refers to a question id that the questions file lacks.
    #[error("{path}, {location}, column '{column}': unknown question '{question}'")]
    UnknownQuestion {
        /// The responses file.
        path: PathBuf,
        /// `header` or `row N` (1-based data row).
        location: String,
        /// The column title.
        column: String,
        /// The question id as written.
        question: String,
    },
    /// An answer that is not left, no preference or right.
    #[error(
        "{path}, row {row}, column '{column}': invalid answer '{value}' (expected L, N or R, \
         or Prefer left / No preference / Prefer right)"
    )]
    InvalidAnswer {
        /// The responses file.
        path: PathBuf,
        /// 1-based data row.
        row: usize,
        /// The column title.
        column: String,
        /// The answer as written.
        value: String,
    },
    /// A survey column (`order`, `swapped`, `seconds`, a control's `response`) holds a value of
    /// the wrong kind.
    #[error("{path}, row {row}, column '{column}': invalid value '{value}' (expected {expected})")]
    InvalidValue {
        /// The file.
        path: PathBuf,
        /// 1-based data row.
        row: usize,
        /// The column title.
        column: String,
        /// The value as written.
        value: String,
        /// What the column holds.
        expected: String,
    },
    /// The same participant appears twice (wide, survey) or answers a question twice (long).
    #[error(
        "{path}, row {row}, column '{column}': duplicate participant '{participant}' for \
         question '{question}' (first seen in row {first_row})"
    )]
    DuplicateParticipant {
        /// The responses file.
        path: PathBuf,
        /// 1-based data row of the second occurrence.
        row: usize,
        /// 1-based data row of the first occurrence.
        first_row: usize,
        /// The column title.
        column: String,
        /// The participant id.
        participant: String,
        /// The question id.
        question: String,
    },
    /// An answer is missing and missing answers are not allowed.
    #[error(
        "{path}: participant '{participant}' has no answer for question '{question}' \
         ({location}); allow missing answers to drop them"
    )]
    MissingAnswer {
        /// The responses file.
        path: PathBuf,
        /// The participant.
        participant: String,
        /// The question id.
        question: String,
        /// Where: "row 4, column 'Q7'" or "no row".
        location: String,
    },
    /// An excluded participant is not in the responses.
    #[error("cannot exclude participant '{participant}': not in {path}")]
    UnknownParticipant {
        /// The responses file.
        path: PathBuf,
        /// The participant id given.
        participant: String,
    },
    /// An option names a variable that the configurations file lacks.
    #[error("{path}: no variable (column) '{variable}' to average over; columns are {columns:?}")]
    UnknownVariable {
        /// The configurations file.
        path: PathBuf,
        /// The variable.
        variable: String,
        /// The variables that exist.
        columns: Vec<String>,
    },
    /// An option value is out of range.
    #[error("invalid option: {0}")]
    InvalidOption(String),
    /// Nothing left to analyse (every participant excluded or no question).
    #[error("nothing to analyse: {0}")]
    Empty(String),
    /// polars failed on a well-formed frame (a bug or resource problem, not user input).
    #[error("data frame operation failed: {0}")]
    Frame(#[from] polars::prelude::PolarsError),
    /// Drawing a chart failed.
    #[error("chart {path}: {message}")]
    Chart {
        /// The chart file.
        path: PathBuf,
        /// What the drawing backend said.
        message: String,
    },
}

/// The crate's result type.
pub type Result<T> = std::result::Result<T, AnalysisError>;

/// A failed atomic write is an I/O error on the file it was to write.
impl From<rmt_runfolder::WriteError> for AnalysisError {
    fn from(e: rmt_runfolder::WriteError) -> Self {
        AnalysisError::Io {
            path: e.path,
            source: e.source,
        }
    }
}

/// Wraps an I/O error with its path.
pub(crate) fn io_error(path: &std::path::Path) -> impl FnOnce(std::io::Error) -> AnalysisError {
    let path = path.to_path_buf();
    move |source| AnalysisError::Io { path, source }
}
