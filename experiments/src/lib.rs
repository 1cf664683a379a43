//! The experiment runner as a library: the `experiments` binary only parses arguments and calls
//! into these modules. Library modules come first, in the order data flows; the `cmd_*` modules
//! are the subcommands, each importing only library modules.
//!
//! - [`objects`]: the sample objects (sphere, asteroid, gyroid, torus, bunny, terrain, caves,
//!   random) built from names and parameters, shared by `extract` and manifests;
//! - [`config`]: one extraction's full description, the names of its settings (each list of
//!   choices once), and its record as JSON;
//! - [`simplify`]: the names of meshoptimizer's simplification to a budget, a finish step;
//! - [`finish`]: the steps any method's mesh may take after extraction (meshoptimizer's
//!   simplifier to a budget, vertex-cache order), run and timed;
//! - [`extract_args`]: the options of one extraction parsed and checked (the `extract` command
//!   line and the studio);
//! - [`measured`]: one mesh's full record (measurement, finish steps, rendering cost), the
//!   columns of `raw.csv` and the keys of `extract --json`;
//! - [`manifest`]: experiment manifests (TOML) expanded into configurations;
//! - [`runner`]: runs a manifest's configurations N times into raw and summary CSV files,
//!   crash-safe and resumable; the run folder's files and columns are `rmt_runfolder`'s;
//!   [`run_record`] (`run.json`, `progress.json`), [`run_csv`] (the rows of `raw.csv` and
//!   `configurations.csv`), [`run_files`] (folders, JSON, appends) and [`provenance`] (where
//!   and how) serve it;
//! - [`summary`]: the statistics of `summary.csv`; [`paper`]: the comparison with the
//!   dissertation (`paper_comparison.csv`);
//! - [`shard`], [`merge`], [`slurm`]: runs split over many machines (`run --shard I/N`), merged
//!   back into one run folder (`merge`), and submitted to Slurm as a job array plus a merge job
//!   (`slurm`);
//! - [`seeds`]: seed studies, every noise configuration over many seeds, summarised in `seeds.csv`;
//!   [`topology`]: their topology tallies;
//! - [`edit`]: chunked terrain (`rmt-terrain`): `extract --chunks` and the `edit` workload;
//! - [`lod`]: level of detail (`rmt_terrain::lod`): the `lod` workload, a viewer flown over a
//!   multiresolution world;
//! - [`studio`]: the studio's backend (page parameters parsed and checked as `extract` options);
//! - [`bench`](mod@bench): extraction speed against peer crates on pre-sampled values;
//!   [`bench_python`]: the Python peers (VTK's Flying Edges, scikit-image) on the same values;
//! - [`study`]: perception studies of methods under shadings (design file, simulated
//!   participants, the texts of `study plan`, `analyse` and `coverage`; the statistics are
//!   `rmt_analysis::study`'s), run by [`cmd_study`].
//!
//! Subcommands: [`cmd_extract`] (one extraction, printed as a summary or JSON), [`cmd_run`],
//! [`cmd_cluster`] (`merge`, `slurm`), [`cmd_render`] and [`cmd_questionnaire`] (turntable GIFs
//! of a run's meshes and the questionnaire built from them, `rmt-render`), [`cmd_analyse`] (the
//! questionnaire analysis, `rmt-analysis`), [`cmd_studio`] and [`cmd_survey`] (`rmt-server`),
//! [`cmd_report`] (`reports/` rebuilt from a run, `rmt-report`), [`cmd_bench`].

pub mod bench;
pub mod bench_python;
pub mod cmd_analyse;
pub mod cmd_bench;
pub mod cmd_cluster;
pub mod cmd_extract;
pub mod cmd_questionnaire;
pub mod cmd_render;
pub mod cmd_report;
pub mod cmd_run;
pub mod cmd_studio;
pub mod cmd_study;
pub mod cmd_survey;
pub mod config;
pub mod edit;
pub mod extract_args;
pub mod finish;
pub mod lod;
pub mod manifest;
pub mod measured;
pub mod merge;
pub mod objects;
pub mod paper;
pub mod provenance;
pub mod run_csv;
pub mod run_files;
pub mod run_record;
pub mod runner;
pub mod seeds;
pub mod shard;
pub mod simplify;
pub mod slurm;
pub mod studio;
pub mod study;
pub mod summary;
pub mod topology;
