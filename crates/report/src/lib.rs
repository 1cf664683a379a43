//! Reports rebuilt from data: the benchmark figures and tables of a run folder, the comparison
//! with the dissertation's published numbers, the growth of time with resolution, and the
//! questionnaire analysis, gathered under one `README.md`.
//!
//! The input is a run folder of `experiments run` (`run.json`, `summary.csv`, optionally
//! `paper_comparison.csv`, `raw.csv`), optionally run folders of the scaling and check-cost
//! manifests, and the questionnaire CSV files. The output folder gets figures (PNG and SVG, plotters with a
//! bundled font), tables (Markdown and CSV), the questionnaire analysis, a copy of the input
//! files under `data/` and the README with the run's provenance at the top.
//!
//! Everything is byte-deterministic: the same input files give the same output bytes (no clock,
//! no input paths, no hash-map order), so a committed report can be checked by rebuilding it from
//! its own `data/` copy ([`check`]: same files, identical tables and README, every file parses
//! ([`validate`]) and every README link resolves).
//!
//! - [`data`]: the run folder read by column name ([`csv_file`]), with errors naming file, line
//!   and column;
//! - [`tables`], [`figures`], [`scaling`]: what the report shows; [`plot`] draws it;
//! - [`seeds`]: the section "Across N asteroids" of a seed study (`seeds.csv`);
//! - [`check_cost`]: the cost of the exact check (plain MT, unchecked and checked integrated
//!   clustering, with the dissertation's own ratio) and the defects of each mesh;
//! - [`peers`]: against what game developers use (marching cubes, surface nets, meshoptimizer
//!   at RMT's count): time, quality, rendering cost and defects per object, over seeds too;
//! - [`lod`]: level of detail, from a `lod` run: the level map from above with the viewer's
//!   path, and the triangles per level;
//! - [`study`]: the second perception study (RMT against the peers, smooth and flat): the
//!   analysis of its answers, the power table and the coverage check on simulated studies;
//! - [`readme`]: the one-page README; [`report`]: building and checking the folder.
//!
//! ```no_run
//! use std::path::{Path, PathBuf};
//! use rmt_report::{build, check, ReportInputs};
//!
//! let inputs = ReportInputs {
//!     run: PathBuf::from("results/paper-20260301-120000"),
//!     scaling: None,
//!     check_cost: None,
//!     peers: None,
//!     peers_seeds: None,
//!     study: None,
//!     lod: None,
//!     questionnaire: None,
//!     keep_raw: true,
//! };
//! let files = build(&inputs, Path::new("reports"))?;
//! assert!(files.iter().any(|f| f.ends_with("README.md")));
//! let from_copy = ReportInputs { run: PathBuf::from("reports/data"), ..inputs };
//! assert!(check(&from_copy, Path::new("reports"))?.passed());
//! # Ok::<(), rmt_report::ReportError>(())
//! ```
//!
//! Cost: a few hundred milliseconds for the benchmark part; the questionnaire's bootstrap
//! (10,000 resamples by default) takes a few seconds in a release build.

pub mod check_cost;
pub mod csv_file;
pub mod data;
pub mod error;
pub mod figures;
pub mod format;
pub mod lod;
pub mod output;
pub mod peers;
pub mod plot;
pub mod readme;
pub mod report;
pub mod scaling;
pub mod seeds;
pub mod study;
pub mod tables;

pub use error::{ReportError, Result};
pub use report::{
    build, check, compare, default_check_cost, default_lod, default_peers, default_peers_seeds,
    default_scaling, default_study, validate, CheckOutcome, Questionnaire, ReportInputs,
};
