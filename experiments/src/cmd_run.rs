//! `experiments run`: runs a manifest (see [`crate::manifest`]) into a run folder (see
//! [`crate::runner`]), or continues an interrupted run.
//!
//! ```text
//! experiments run experiments/manifests/paper.toml [--out DIR] [--reps N] [--warmup N]
//!     [--threads N] [--no-meshes] [--quiet] [--dry-run]
//! experiments run --resume results/paper-20260301-120000
//! ```

use std::path::PathBuf;

use anyhow::{Context, Result};

use crate::manifest::{self, Overrides};
use crate::runner::{self, RunOptions, Status, Table};

/// Arguments of `run`.
#[derive(clap::Args, Debug)]
pub struct Args {
    /// The manifest (TOML).
    #[arg(required_unless_present = "resume")]
    pub manifest: Option<PathBuf>,
    /// Continue the run in this folder (same options as when it started).
    #[arg(long, conflicts_with_all = ["manifest", "out", "reps", "warmup", "threads", "no_meshes", "dry_run"])]
    pub resume: Option<PathBuf>,
    /// The run folder (new or empty); default `<output>/<name>-<UTC timestamp>`.
    #[arg(long)]
    pub out: Option<PathBuf>,
    /// Timed repetitions per configuration (overrides the manifest).
    #[arg(long)]
    pub reps: Option<usize>,
    /// Warm-up extractions per configuration (overrides the manifest).
    #[arg(long)]
    pub warmup: Option<usize>,
    /// Worker threads (overrides the manifest).
    #[arg(long)]
    pub threads: Option<usize>,
    /// Do not save the last repetition's meshes.
    #[arg(long)]
    pub no_meshes: bool,
    /// No progress bar and no summary table.
    #[arg(long)]
    pub quiet: bool,
    /// Check the manifest and list its configurations without running them.
    #[arg(long)]
    pub dry_run: bool,
    /// Stop after K configurations, as if killed (for testing resume).
    #[arg(long, hide = true)]
    pub stop_after: Option<usize>,
}

/// Runs `run`.
pub fn run(args: Args) -> Result<()> {
    let opts = RunOptions {
        quiet: args.quiet,
        stop_after: args.stop_after,
    };
    let report = match (&args.resume, &args.manifest) {
        (Some(folder), _) => runner::resume(folder, &opts)?,
        (None, Some(path)) => {
            let overrides = Overrides {
                repetitions: args.reps,
                warmup: args.warmup,
                threads: args.threads,
                save_meshes: args.no_meshes.then_some(false),
            };
            if args.dry_run {
                let plan = manifest::load(path, &overrides)?.plan;
                println!(
                    "{}: {} configurations x ({} warm-up + {} repetitions), {} thread(s)",
                    plan.name,
                    plan.configurations.len(),
                    plan.warmup,
                    plan.repetitions,
                    plan.threads
                );
                print!(
                    "{}",
                    String::from_utf8_lossy(&runner::configurations_csv(&plan)?)
                );
                return Ok(());
            }
            runner::start(path, &overrides, args.out.as_deref(), &opts)?
        }
        (None, None) => anyhow::bail!("give a manifest or --resume FOLDER"),
    };
    let folder = report.folder.display();
    match report.status {
        Status::Finished => {
            if !args.quiet && report.configurations_run > 0 {
                print_summary(&report.folder.join("summary.csv"))?;
            }
            println!(
                "finished: {} configurations in {folder} ({} run in this session)",
                report.configurations_total, report.configurations_run
            );
        }
        Status::Stopped | Status::Running => println!(
            "stopped after {} of {} configurations; continue with `experiments run --resume {folder}`",
            report.configurations_done, report.configurations_total
        ),
    }
    Ok(())
}

/// Prints id, triangles, mean total time and mean radius ratio per configuration.
fn print_summary(path: &std::path::Path) -> Result<()> {
    let t = Table::read(path).with_context(|| format!("reading {}", path.display()))?;
    println!(
        "{:<24} {:>10} {:>10} {:>12} {:>10}",
        "id", "vertices", "triangles", "t_total ms", "ar_mean"
    );
    for r in 0..t.rows.len() {
        let ms = t
            .get(r, "t_total_s_mean")
            .and_then(|v| v.parse::<f64>().ok())
            .map(|v| format!("{:.3}", v * 1e3))
            .unwrap_or_default();
        let ar = t
            .get(r, "ar_mean")
            .and_then(|v| v.parse::<f64>().ok())
            .map(|v| format!("{v:.3}"))
            .unwrap_or_default();
        println!(
            "{:<24} {:>10} {:>10} {:>12} {:>10}",
            t.get(r, "id").unwrap_or(""),
            t.get(r, "vertices").unwrap_or(""),
            t.get(r, "triangles").unwrap_or(""),
            ms,
            ar
        );
    }
    Ok(())
}
