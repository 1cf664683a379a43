//! `experiments merge` and `experiments slurm`: the command-line side of [`crate::merge`] and
//! [`crate::slurm`].
//!
//! ```text
//! experiments merge results/paper-merged shards/shard-1 shards/shard-2 ...
//! experiments slurm experiments/manifests/paper.toml --shards 18 [--partition P] [--time T]
//!     [--cpus C] [--out DIR] [--submit]
//! experiments slurm --resume results/paper-20260301-120000      # resubmit missing/failed shards
//! ```

use std::path::PathBuf;

use anyhow::{Context, Result};

use crate::{merge, slurm};

/// Arguments of `merge`.
#[derive(clap::Args, Debug)]
pub struct MergeArgs {
    /// The merged run folder to write (new or empty).
    pub out: PathBuf,
    /// The shard folders (`run --shard I/N`), in any order.
    #[arg(required = true)]
    pub shards: Vec<PathBuf>,
}

/// Runs `merge`.
pub fn merge(args: MergeArgs) -> Result<()> {
    let report = merge::merge(&args.out, &args.shards)
        .with_context(|| format!("merging into {}", args.out.display()))?;
    println!(
        "merged {} shards: {} configurations, {} rows in {}",
        report.shards,
        report.configurations,
        report.rows,
        report.folder.display()
    );
    Ok(())
}

/// Arguments of `slurm`.
#[derive(clap::Args, Debug)]
pub struct SlurmArgs {
    /// The manifest (TOML).
    #[arg(required_unless_present = "resume")]
    pub manifest: Option<PathBuf>,
    /// Number of shards: array tasks, each `run --shard I/N`.
    #[arg(long, required_unless_present = "resume")]
    pub shards: Option<usize>,
    /// Slurm partition of the jobs.
    #[arg(long)]
    pub partition: Option<String>,
    /// Time limit per job, in Slurm's syntax (`30:00`, `2:00:00`).
    #[arg(long)]
    pub time: Option<String>,
    /// CPUs per array task, also the extraction threads [default: the manifest's threads, else 1].
    #[arg(long)]
    pub cpus: Option<usize>,
    /// The merged run folder [default: `<output>/<name>-<UTC timestamp>`]; the scripts, shards
    /// and logs go beside it in `<OUT>.slurm/`.
    #[arg(long)]
    pub out: Option<PathBuf>,
    /// Submit the array and the merge job with sbatch (otherwise only write the scripts).
    #[arg(long)]
    pub submit: bool,
    /// Resubmit the missing or failed shards of this run (its folder or its `.slurm` folder),
    /// and a new merge job.
    #[arg(long, conflicts_with_all = ["manifest", "shards", "partition", "time", "cpus", "out", "submit"])]
    pub resume: Option<PathBuf>,
}

/// Runs `slurm`.
pub fn slurm(args: SlurmArgs) -> Result<()> {
    if let Some(dir) = &args.resume {
        let r = slurm::resume(dir)?;
        match &r.submission {
            None => println!("already merged: {}", r.out.display()),
            Some(s) => {
                if r.resubmitted.is_empty() {
                    println!("every shard is finished; resubmitted the merge only");
                } else if let Some(id) = &s.array_job {
                    println!(
                        "resubmitted shards {} as array job {id}",
                        slurm::task_list(&r.resubmitted)
                    );
                }
                println!("merge job {}", s.merge_job);
                println!("merged run will be in {}", r.out.display());
            }
        }
        return Ok(());
    }
    let (Some(manifest), Some(shards)) = (args.manifest, args.shards) else {
        anyhow::bail!("give a manifest and --shards N, or --resume DIR");
    };
    let opts = slurm::SlurmOptions {
        manifest,
        shards,
        partition: args.partition,
        time: args.time,
        cpus: args.cpus,
        out: args.out,
        binary: std::env::current_exe().context("finding the experiments binary")?,
    };
    let p = slurm::prepare(&opts)?;
    println!("array script: {}", p.shards_script.display());
    println!("merge script: {}", p.merge_script.display());
    if args.submit {
        let s = slurm::submit(&p.job_dir, Some(format!("1-{shards}")).as_deref())?;
        if let Some(id) = &s.array_job {
            println!("array job {id} ({shards} shards)");
        }
        println!("merge job {}", s.merge_job);
    } else {
        println!(
            "not submitted: `experiments slurm --resume {}` submits it",
            p.job_dir.display()
        );
    }
    println!("merged run will be in {}", p.out.display());
    Ok(())
}
