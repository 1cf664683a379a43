//! Reading the run folder's CSV files by column name, with errors that name the file, line and
//! column of any bad cell.

use std::path::{Path, PathBuf};

use crate::error::{ReportError, Result};

/// A CSV file read into memory: its header and rows of text cells.
#[derive(Clone, Debug, PartialEq)]
pub struct CsvFile {
    /// Where it was read from (for error messages).
    pub path: PathBuf,
    /// Column names.
    pub header: Vec<String>,
    /// Rows of cells, each as long as the header.
    pub rows: Vec<Vec<String>>,
}

impl CsvFile {
    /// Reads `path`; ragged rows and bad quoting are errors.
    pub fn read(path: &Path) -> Result<CsvFile> {
        let bytes = std::fs::read(path).map_err(crate::error::io_error(path))?;
        Self::parse(path, &bytes)
    }

    /// Parses CSV `bytes`, naming `path` in errors.
    pub fn parse(path: &Path, bytes: &[u8]) -> Result<CsvFile> {
        let csv_error = |e: csv::Error| ReportError::Csv {
            path: path.to_path_buf(),
            message: e.to_string(),
        };
        let mut reader = csv::Reader::from_reader(bytes);
        let header: Vec<String> = reader
            .headers()
            .map_err(csv_error)?
            .iter()
            .map(str::to_string)
            .collect();
        if header.is_empty() {
            return Err(ReportError::Csv {
                path: path.to_path_buf(),
                message: "no header".into(),
            });
        }
        let mut rows = Vec::new();
        for record in reader.records() {
            rows.push(
                record
                    .map_err(csv_error)?
                    .iter()
                    .map(str::to_string)
                    .collect(),
            );
        }
        Ok(CsvFile {
            path: path.to_path_buf(),
            header,
            rows,
        })
    }

    /// Index of column `name`, or an error naming the file and column.
    pub fn column(&self, name: &str) -> Result<usize> {
        self.header
            .iter()
            .position(|h| h == name)
            .ok_or_else(|| ReportError::MissingColumn {
                path: self.path.clone(),
                column: name.to_string(),
            })
    }

    /// Whether the file has column `name`.
    pub fn has(&self, name: &str) -> bool {
        self.header.iter().any(|h| h == name)
    }

    /// The cell of `row` in column `name`.
    pub fn text(&self, row: usize, name: &str) -> Result<&str> {
        let col = self.column(name)?;
        Ok(self.rows[row][col].as_str())
    }

    /// The number in `row`, column `name`: `None` for an empty cell, an error for text that is
    /// not a number.
    pub fn number(&self, row: usize, name: &str) -> Result<Option<f64>> {
        let cell = self.text(row, name)?.trim();
        if cell.is_empty() {
            return Ok(None);
        }
        cell.parse::<f64>()
            .map(Some)
            .map_err(|_| ReportError::BadNumber {
                path: self.path.clone(),
                line: row + 2,
                column: name.to_string(),
                value: cell.to_string(),
            })
    }

    /// The number in `row`, column `name`; an empty cell is an error.
    pub fn required(&self, row: usize, name: &str) -> Result<f64> {
        self.number(row, name)?
            .ok_or_else(|| ReportError::EmptyCell {
                path: self.path.clone(),
                line: row + 2,
                column: name.to_string(),
            })
    }

    /// The number in `row`, column `name`, or `None` when the column is absent or the cell empty.
    pub fn optional(&self, row: usize, name: &str) -> Result<Option<f64>> {
        if self.has(name) {
            self.number(row, name)
        } else {
            Ok(None)
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn file(text: &str) -> CsvFile {
        CsvFile::parse(Path::new("t.csv"), text.as_bytes()).unwrap()
    }

    #[test]
    fn cells_are_found_by_column_name() {
        let f = file("a,b\n1,x\n,2.5\n");
        assert_eq!(f.text(0, "b").unwrap(), "x");
        assert_eq!(f.number(1, "b").unwrap(), Some(2.5));
        assert_eq!(f.number(1, "a").unwrap(), None);
        assert_eq!(f.optional(0, "zzz").unwrap(), None);
    }

    #[test]
    fn bad_cells_name_file_line_and_column() {
        let f = file("a,b\n1,x\n,2\n");
        let message = f.number(0, "b").unwrap_err().to_string();
        assert_eq!(message, "t.csv: line 2, column `b`: `x` is not a number");
        let message = f.required(1, "a").unwrap_err().to_string();
        assert_eq!(message, "t.csv: line 3, column `a` is empty");
        let message = f.column("c").unwrap_err().to_string();
        assert_eq!(message, "t.csv: missing column `c`");
    }

    #[test]
    fn ragged_rows_are_errors() {
        let error = CsvFile::parse(Path::new("t.csv"), b"a,b\n1,2,3\n").unwrap_err();
        assert!(error
            .to_string()
            .starts_with("t.csv: not a readable CSV file"));
    }
}
