//! The CSV table of a run folder: a header and rows of strings, read and written with RFC 4180
//! quoting and `\n` line ends.

use std::path::{Path, PathBuf};

/// A CSV file that could not be read, or rows that could not be written.
#[derive(Debug, thiserror::Error)]
pub enum TableError {
    /// The file could not be opened or its header read.
    #[error("reading {}", path.display())]
    Read {
        /// The file.
        path: PathBuf,
        /// The reader's error.
        #[source]
        source: csv::Error,
    },
    /// A row is malformed (`row` counts lines from 1, the header being row 1).
    #[error("{}: row {row}", path.display())]
    Row {
        /// The file.
        path: PathBuf,
        /// The row's line.
        row: usize,
        /// The reader's error.
        #[source]
        source: csv::Error,
    },
    /// A row could not be written.
    #[error(transparent)]
    Write(#[from] csv::Error),
    /// The written rows could not be collected.
    #[error("writing CSV: {0}")]
    Collect(String),
}

/// A header and rows of strings.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Table {
    /// Column names.
    pub header: Vec<String>,
    /// Rows, each as long as the header.
    pub rows: Vec<Vec<String>>,
}

impl Table {
    /// Reads a CSV file.
    pub fn read(path: &Path) -> Result<Table, TableError> {
        let read = |source| TableError::Read {
            path: path.to_path_buf(),
            source,
        };
        let mut r = csv::Reader::from_path(path).map_err(read)?;
        let header = r
            .headers()
            .map_err(read)?
            .iter()
            .map(String::from)
            .collect();
        let mut rows = Vec::new();
        for (i, rec) in r.records().enumerate() {
            let rec = rec.map_err(|source| TableError::Row {
                path: path.to_path_buf(),
                row: i + 2,
                source,
            })?;
            rows.push(rec.iter().map(String::from).collect());
        }
        Ok(Table { header, rows })
    }

    /// Index of column `name`.
    pub fn column(&self, name: &str) -> Option<usize> {
        self.header.iter().position(|h| h == name)
    }

    /// The value of column `name` in row `row`.
    pub fn get(&self, row: usize, name: &str) -> Option<&str> {
        Some(self.rows.get(row)?.get(self.column(name)?)?.as_str())
    }

    /// CSV bytes: the header, then the rows.
    pub fn to_csv(&self) -> Result<Vec<u8>, TableError> {
        let mut all = vec![self.header.clone()];
        all.extend(self.rows.iter().cloned());
        csv_bytes(&all)
    }
}

/// CSV bytes of `rows` (the first is usually a header).
pub fn csv_bytes(rows: &[Vec<String>]) -> Result<Vec<u8>, TableError> {
    let mut w = csv::Writer::from_writer(Vec::new());
    for r in rows {
        w.write_record(r)?;
    }
    w.into_inner()
        .map_err(|e| TableError::Collect(e.to_string()))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn tables_round_trip_with_quoting() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("t.csv");
        let table = Table {
            header: vec!["id".into(), "note".into()],
            rows: vec![
                vec!["a".into(), "x,\"y\"".into()],
                vec!["b".into(), String::new()],
            ],
        };
        let bytes = table.to_csv().unwrap();
        assert_eq!(bytes, b"id,note\na,\"x,\"\"y\"\"\"\nb,\n");
        std::fs::write(&path, &bytes).unwrap();
        let back = Table::read(&path).unwrap();
        assert_eq!(back, table);
        assert_eq!(back.get(0, "note"), Some("x,\"y\""));
        assert_eq!(back.get(2, "note"), None);
        assert_eq!(back.column("missing"), None);
    }

    #[test]
    fn read_errors_name_the_file_and_row() {
        let dir = tempfile::tempdir().unwrap();
        let missing = dir.path().join("missing.csv");
        let err = Table::read(&missing).unwrap_err();
        assert_eq!(err.to_string(), format!("reading {}", missing.display()));
        let ragged = dir.path().join("ragged.csv");
        std::fs::write(&ragged, "a,b\n1,2\n3\n").unwrap();
        let err = Table::read(&ragged).unwrap_err();
        assert_eq!(err.to_string(), format!("{}: row 3", ragged.display()));
    }
}
