//! `experiments run`: runs a manifest (see [`crate::manifest`]) into a run folder (see
//! [`crate::runner`]), or continues an interrupted run.
//!
//! ```text
//! experiments run experiments/manifests/paper.toml [--out DIR] [--reps N] [--warmup N]
//!     [--threads N] [--no-meshes] [--quiet] [--dry-run]
//! experiments run --resume results/paper-20260301-120000
//! experiments run experiments/manifests/paper.toml --shard 2/8 --out shards/shard-2
//! ```
//!
//! `--shard I/N` runs only shard I of N of the manifest's work units (see [`crate::shard`]);
//! `experiments merge` combines the shards into one run.

use std::path::PathBuf;

use anyhow::{Context, Result};

use crate::manifest::{self, Overrides};
use rmt_runfolder::layout::SUMMARY_CSV;
use rmt_runfolder::Table;

use crate::run_csv::configurations_csv;
use crate::run_record::Status;
use crate::runner::{self, RunOptions};

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
    /// Run only shard I of N of the work units (`2/8`); merge the shards with `experiments merge`.
    #[arg(long, value_name = "I/N")]
    pub shard: Option<crate::shard::ShardSpec>,
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
        (Some(folder), _) => {
            if args.shard.is_some() {
                anyhow::bail!("--shard applies to a new run; a resumed shard keeps its own");
            }
            runner::resume(folder, &opts)?
        }
        (None, Some(path)) => {
            let overrides = Overrides {
                repetitions: args.reps,
                warmup: args.warmup,
                threads: args.threads,
                save_meshes: args.no_meshes.then_some(false),
            };
            if args.dry_run {
                let plan = manifest::load(path, &overrides)?.plan;
                if let Some(spec) = args.shard {
                    let ids: Vec<String> =
                        plan.configurations.iter().map(|c| c.id.clone()).collect();
                    let (split, units) = crate::shard::units_of(&ids, plan.repetitions, spec)?;
                    println!("shard {spec} ({split:?}): {} work units", units.len());
                    for u in &units {
                        println!("{} repetitions {}-{}", u.id, u.first, u.last);
                    }
                    return Ok(());
                }
                println!(
                    "{}: {} configurations x ({} warm-up + {} repetitions), {} thread(s)",
                    plan.name,
                    plan.configurations.len(),
                    plan.warmup,
                    plan.repetitions,
                    plan.threads
                );
                print!("{}", String::from_utf8_lossy(&configurations_csv(&plan)?));
                return Ok(());
            }
            runner::start_shard(path, &overrides, args.out.as_deref(), &opts, args.shard)?
        }
        (None, None) => anyhow::bail!("give a manifest or --resume FOLDER"),
    };
    let folder = report.folder.display();
    match report.status {
        Status::Finished => {
            if !args.quiet && report.configurations_run > 0 {
                print_summary(&report.folder.join(SUMMARY_CSV))?;
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
