//! Questionnaire analysis: preference factors and weights, statistics and charts from survey
//! responses.
//!
//! Participants watch two turntable animations side by side and answer "prefer left", "no
//! preference" or "prefer right". This crate turns the answers into the dissertation's two tables
//! (mean preference factors per comparison group; overall preference weights) and adds what the
//! dissertation lacked: per-question Wilson intervals and exact sign tests with Holm's correction,
//! Bradley-Terry strengths with Davidson's ties extension, a position-bias test, Fleiss' kappa,
//! and participant-bootstrap intervals for everything estimated.
//!
//! - [`input`]: loads the three CSV files with polars (wide, long or survey-export responses)
//!   and validates them with errors naming file, row and column;
//! - [`design`]: comparison groups read off the questions, generic over the variables;
//! - [`method`]: the dissertation's factors, means and weights, exactly;
//! - [`stats`], [`bradley_terry`]: the statistics, in plain Rust;
//! - [`analysis`]: all of it together with the seeded bootstrap;
//! - [`effects`]: what survey-server data adds (position effect from swaps and controls, order
//!   effect on ties and times, participants needed for 80% power);
//! - [`tables`], [`charts`], [`output`]: CSV, Markdown, PNG and SVG, byte-deterministic;
//! - [`study`] (over [`bradley_terry_position`]: Davidson's model with a left-side parameter,
//!   Newton-fitted with Wald intervals): a study of methods under shadings, its balanced
//!   subsets of pairs, its analysis (strengths per shading, the method x shading interaction
//!   test, position and order effects), its power table, and simulated participants.
//!
//! ```no_run
//! use std::path::Path;
//! use rmt_analysis::{analyse, write_outputs, Inputs, Options};
//!
//! let inputs = Inputs::in_dir(Path::new("data/questionnaire"));
//! let analysis = analyse(&inputs, &Options { exclude: vec!["P18".into()], ..Options::default() })?;
//! assert_eq!(analysis.participants.len(), 18);
//! let files = write_outputs(&analysis, Path::new("reports/questionnaire"))?;
//! assert!(!files.is_empty());
//! # Ok::<(), rmt_analysis::AnalysisError>(())
//! ```
//!
//! Cost: the bundled 19 x 27 answers with the default 10,000 resamples take about 20 s in a debug
//! build on a 2-core machine (each resample refits all 20 Bradley-Terry models); release builds
//! are several times faster. Reproduce with `experiments analyse` from the workspace root.

pub mod analysis;
pub mod bradley_terry;
pub mod bradley_terry_position;
pub mod charts;
pub mod data;
pub mod design;
pub mod effects;
pub mod error;
pub mod input;
pub mod method;
pub mod output;
pub mod stats;
pub mod study;
pub mod tables;

pub use analysis::{analyse, analyse_dataset, Analysis, Options};
pub use data::{Answer, InputFormat};
pub use error::{AnalysisError, Result};
pub use input::Inputs;
pub use output::write_outputs;
