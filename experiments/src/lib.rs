//! The experiment runner as a library: the `experiments` binary only parses arguments and calls
//! into these modules.
//!
//! - [`objects`]: the sample objects (sphere, asteroid, gyroid, torus, bunny, terrain, caves) built
//!   from names and parameters, shared by `extract` and manifests;
//! - [`config`]: one extraction's full description and the names of its settings;
//! - [`cmd_extract`]: one extraction, printed as a summary or JSON;
//! - [`manifest`]: experiment manifests (TOML) expanded into configurations;
//! - [`runner`]: runs a manifest's configurations N times into raw and summary CSV files,
//!   crash-safe and resumable; [`provenance`] records where and how;
//! - [`cmd_run`]: the `run` subcommand;
//! - [`shard`], [`merge`], [`slurm`]: runs split over many machines (`run --shard I/N`), merged
//!   back into one run folder (`merge`), and submitted to Slurm as a job array plus a merge job
//!   (`slurm`); [`cmd_cluster`] holds the `merge` and `slurm` subcommands;
//! - [`seeds`]: seed studies, every noise configuration over many seeds, summarised in `seeds.csv`;
//! - [`edit`]: chunked terrain (`rmt-terrain`): `extract --chunks` and the `edit` workload;
//! - [`cmd_render`], [`cmd_questionnaire`]: turntable GIFs of a run's meshes and the questionnaire
//!   built from them (`rmt-render`);
//! - [`cmd_analyse`]: the questionnaire analysis (`rmt-analysis`);
//! - [`studio`], [`cmd_studio`]: the studio's backend (page parameters parsed and checked as
//!   `extract` options) and the `studio` subcommand (`rmt-server`);
//! - [`cmd_survey`]: the survey server and its export (`rmt-server`);
//! - [`cmd_report`]: figures, tables and README of `reports/` rebuilt from a run (`rmt-report`);
//! - [`bench`](mod@bench), [`cmd_bench`]: extraction speed against peer crates on pre-sampled values.

pub mod bench;
pub mod cmd_analyse;
pub mod cmd_bench;
pub mod cmd_cluster;
pub mod cmd_extract;
pub mod cmd_questionnaire;
pub mod cmd_render;
pub mod cmd_report;
pub mod cmd_run;
pub mod cmd_studio;
pub mod cmd_survey;
pub mod config;
pub mod edit;
pub mod manifest;
pub mod merge;
pub mod objects;
pub mod provenance;
pub mod runner;
pub mod seeds;
pub mod shard;
pub mod slurm;
pub mod studio;
pub mod topology;
