//! `experiments`: thin command-line front end over the workspace's libraries.

use anyhow::Result;
use clap::{Parser, Subcommand};

#[derive(Parser)]
#[command(
    name = "experiments",
    version,
    about = "Isosurface extraction experiments: extract, run manifests, render, analyse, report"
)]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Subcommand)]
enum Command {
    /// Extract one surface and print its statistics.
    Extract(experiments::extract_args::Args),
    /// Run a manifest: every configuration N times, into raw and summary CSV files.
    Run(experiments::cmd_run::Args),
    /// Render a turntable GIF of every configuration of a run folder, under anonymous names.
    Render(experiments::cmd_render::Args),
    /// Build the side-by-side questionnaire from a rendered run folder.
    Questionnaire(experiments::cmd_questionnaire::Args),
    /// Analyse questionnaire responses: preference tables, tests, Bradley-Terry strengths.
    Analyse(experiments::cmd_analyse::Args),
    /// Benchmark extraction against peer crates (medians of interleaved repetitions).
    Bench(experiments::cmd_bench::Args),
    /// Run the questionnaire for real: serve it to participants, store answers, export them.
    Survey(experiments::cmd_survey::Args),
    /// The interactive studio in the browser: live parameters, compare, sculpt terrain.
    Studio(experiments::cmd_studio::Args),
    /// Merge the shard folders of `run --shard I/N` into one run folder.
    Merge(experiments::cmd_cluster::MergeArgs),
    /// Write (and with --submit, submit) a Slurm job array running a manifest in N shards, and a
    /// merge job that depends on it.
    Slurm(experiments::cmd_cluster::SlurmArgs),
    /// A perception study of methods under shadings: plan, simulate, analyse, coverage.
    Study(experiments::cmd_study::Args),
    /// Rebuild reports/ (figures, tables, README) from a run folder and the questionnaire data.
    Report(experiments::cmd_report::Args),
}

fn main() -> Result<()> {
    let cli = Cli::parse();
    match cli.command {
        Command::Extract(args) => experiments::cmd_extract::run(args),
        Command::Run(args) => experiments::cmd_run::run(args),
        Command::Render(args) => experiments::cmd_render::run(args),
        Command::Questionnaire(args) => experiments::cmd_questionnaire::run(args),
        Command::Analyse(args) => experiments::cmd_analyse::run(args),
        Command::Bench(args) => experiments::cmd_bench::run(args),
        Command::Report(args) => experiments::cmd_report::run(args),
        Command::Survey(args) => experiments::cmd_survey::run(args),
        Command::Studio(args) => experiments::cmd_studio::run(args),
        Command::Study(args) => experiments::cmd_study::run(args),
        Command::Merge(args) => experiments::cmd_cluster::merge(args),
        Command::Slurm(args) => experiments::cmd_cluster::slurm(args),
    }
}
