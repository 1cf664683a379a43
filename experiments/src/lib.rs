//! The experiment runner as a library: the `experiments` binary only parses arguments and calls
//! into these modules.
//!
//! - [`objects`]: the sample objects (sphere, asteroid, gyroid, torus, bunny, terrain) built from
//!   names and parameters, shared by `extract` and manifests;
//! - [`cmd_extract`]: one extraction, printed as JSON;
//! - further subcommands (run, render, questionnaire, analyse, report) live in their own modules.

pub mod cmd_extract;
pub mod objects;
