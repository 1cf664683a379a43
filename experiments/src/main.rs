//! `experiments`: thin command-line front end over the workspace's libraries.

use anyhow::Result;
use clap::{Parser, Subcommand};

#[derive(Parser)]
#[command(name = "experiments", version, about = "Isosurface extraction experiments: extract, run manifests, render, analyse, report")]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Subcommand)]
enum Command {
    /// Extract one surface and print its statistics.
    Extract(experiments::cmd_extract::Args),
}

fn main() -> Result<()> {
    let cli = Cli::parse();
    match cli.command {
        Command::Extract(args) => experiments::cmd_extract::run(args),
    }
}
