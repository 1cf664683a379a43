//! The one error type of the crate: every variant names the file, row, column or key at fault.

use std::path::{Path, PathBuf};

/// Everything that can go wrong while reading a run folder or writing a report.
///
/// Rows are counted as lines of the file (the header is line 1), so "line 3" is the second data
/// row.
#[derive(Debug, thiserror::Error)]
pub enum ReportError {
    /// A file or folder could not be read or written.
    #[error("{path}: {source}")]
    Io {
        /// The file or folder.
        path: PathBuf,
        /// The operating system's error.
        source: std::io::Error,
    },
    /// A file that the report needs is absent.
    #[error("{path}: not found ({hint})")]
    MissingFile {
        /// The file.
        path: PathBuf,
        /// What it is and where it comes from.
        hint: String,
    },
    /// A file is not well-formed CSV.
    #[error("{path}: not a readable CSV file: {message}")]
    Csv {
        /// The file.
        path: PathBuf,
        /// What the CSV reader said.
        message: String,
    },
    /// A column that the report needs is absent.
    #[error("{path}: missing column `{column}`")]
    MissingColumn {
        /// The file.
        path: PathBuf,
        /// The column.
        column: String,
    },
    /// A cell that must hold a number does not.
    #[error("{path}: line {line}, column `{column}`: `{value}` is not a number")]
    BadNumber {
        /// The file.
        path: PathBuf,
        /// The line of the file (header = 1).
        line: usize,
        /// The column.
        column: String,
        /// The cell.
        value: String,
    },
    /// A cell that must not be empty is.
    #[error("{path}: line {line}, column `{column}` is empty")]
    EmptyCell {
        /// The file.
        path: PathBuf,
        /// The line of the file (header = 1).
        line: usize,
        /// The column.
        column: String,
    },
    /// `run.json` is not JSON or lacks a key.
    #[error("{path}: {message}")]
    Json {
        /// The file.
        path: PathBuf,
        /// What is wrong, naming the key.
        message: String,
    },
    /// The input is well-formed but cannot make a report (no configurations, duplicate ids...).
    #[error("{path}: {message}")]
    Input {
        /// The file.
        path: PathBuf,
        /// What is wrong.
        message: String,
    },
    /// plotters failed to draw or encode a figure.
    #[error("drawing {path}: {message}")]
    Chart {
        /// The figure file.
        path: PathBuf,
        /// What plotters said.
        message: String,
    },
    /// The questionnaire analysis failed.
    #[error("questionnaire analysis: {0}")]
    Analysis(#[from] rmt_analysis::AnalysisError),
}

/// The crate's result type.
pub type Result<T> = std::result::Result<T, ReportError>;

/// A failed atomic write is an I/O error on the file it was to write.
impl From<rmt_runfolder::WriteError> for ReportError {
    fn from(e: rmt_runfolder::WriteError) -> Self {
        ReportError::Io {
            path: e.path,
            source: e.source,
        }
    }
}

/// Maps an I/O error to [`ReportError::Io`] for `path`.
pub(crate) fn io_error(path: &Path) -> impl FnOnce(std::io::Error) -> ReportError + '_ {
    move |source| ReportError::Io {
        path: path.to_path_buf(),
        source,
    }
}
