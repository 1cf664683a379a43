//! The run folder's one owner: where each file of a run folder lives ([`layout`]), which columns
//! its CSV files have ([`schema`]), the CSV table they are read into and written from
//! ([`Table`]), and the atomic write ([`write_atomic`]) that every crate of the workspace uses
//! for its output files.
//!
//! The runner (`experiments run`, `merge`) writes run folders; `rmt-render` and `rmt-report` read
//! them; `rmt-analysis` and `rmt-report` write their own outputs with the same atomic write.
//! Adding a column to the run CSVs starts in [`schema`].
//!
//! ```
//! use rmt_runfolder::{layout, schema, write_atomic, Table};
//!
//! let dir = tempfile::tempdir()?;
//! let table = Table {
//!     header: schema::PAPER_COMPARISON.map(String::from).to_vec(),
//!     rows: vec![["ss_bu", "triangles", "90", "100", "0.9"].map(String::from).to_vec()],
//! };
//! let path = dir.path().join(layout::PAPER_CSV);
//! write_atomic(&path, &table.to_csv()?)?;
//! assert_eq!(Table::read(&path)?, table);
//! # Ok::<(), Box<dyn std::error::Error>>(())
//! ```

mod atomic;
pub mod layout;
pub mod schema;
mod table;

pub use atomic::{write_atomic, WriteError};
pub use table::{csv_bytes, Table, TableError};
