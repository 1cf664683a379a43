//! `experiments report`: figures, tables and a README rebuilt from a run folder (plus optional
//! scaling and check-cost runs and the questionnaire data) with `rmt-report`; `--check` rebuilds into a
//! temporary folder and compares with the committed report instead of writing.
//!
//! ```text
//! experiments report --run results/paper-20260301-120000 --scaling results/scaling-... \
//!     --check-cost results/check-cost-... --peers results/peers-... \
//!     --peers-seeds results/peers-seeds-... --study sim-study --lod results/lod-ci-... --out reports
//! experiments report --check        # reports/ against a rebuild from reports/data
//! ```

use std::path::PathBuf;

use anyhow::{bail, Context};
use rmt_report::{
    build, check, default_check_cost, default_lod, default_peers, default_peers_seeds,
    default_scaling, default_study, Questionnaire, ReportInputs,
};

/// Arguments of `report`.
#[derive(clap::Args, Debug)]
pub struct Args {
    /// Run folder of the benchmark (`experiments run`), or a report's `data/` folder.
    #[arg(long, default_value = "reports/data")]
    pub run: PathBuf,
    /// Run folder of the scaling manifest [default: RUN/scaling when it holds a run].
    #[arg(long, conflicts_with = "no_scaling")]
    pub scaling: Option<PathBuf>,
    /// Leave out the time-against-resolution figure and table.
    #[arg(long)]
    pub no_scaling: bool,
    /// Run folder of the check-cost manifest [default: RUN/check-cost when it holds a run].
    #[arg(long, conflicts_with = "no_check_cost")]
    pub check_cost: Option<PathBuf>,
    /// Leave out the section on the cost of the exact check.
    #[arg(long)]
    pub no_check_cost: bool,
    /// Run folder of the peers manifest [default: RUN/peers when it holds a run].
    #[arg(long, conflicts_with = "no_peers")]
    pub peers: Option<PathBuf>,
    /// Run folder of the peers seed study [default: RUN/peers-seeds when it holds one].
    #[arg(long, conflicts_with = "no_peers")]
    pub peers_seeds: Option<PathBuf>,
    /// Leave out the section "Against what game developers use".
    #[arg(long)]
    pub no_peers: bool,
    /// The second study's folder: `study simulate --out` (and `study coverage --out`) files
    /// [default: RUN/study when it holds one].
    #[arg(long, conflicts_with = "no_study")]
    pub study: Option<PathBuf>,
    /// Leave out the second study's section.
    #[arg(long)]
    pub no_study: bool,
    /// Run folder of a `lod` manifest (`experiments run experiments/manifests/lod-ci.toml`) for
    /// the level-of-detail section [default: RUN/lod when it holds one].
    #[arg(long, conflicts_with = "no_lod")]
    pub lod: Option<PathBuf>,
    /// Leave out the level-of-detail section.
    #[arg(long)]
    pub no_lod: bool,
    /// Report folder to write (or, with --check, to compare with).
    #[arg(long, default_value = "reports")]
    pub out: PathBuf,
    /// Folder with the questionnaire's responses.csv, questions.csv and configurations.csv.
    #[arg(long, default_value = "data/questionnaire")]
    pub questionnaire: PathBuf,
    /// Leave out the questionnaire analysis.
    #[arg(long)]
    pub no_questionnaire: bool,
    /// Participants to leave out of the questionnaire analysis, comma-separated.
    #[arg(long, value_delimiter = ',')]
    pub exclude: Vec<String>,
    /// Participant-bootstrap resamples of the questionnaire analysis (0, or at least 1000).
    #[arg(long, default_value_t = 10_000)]
    pub resamples: usize,
    /// Bootstrap seed.
    #[arg(long, default_value_t = 1)]
    pub seed: u64,
    /// Do not copy raw.csv into OUT/data (summary.csv holds every number the report uses).
    #[arg(long)]
    pub no_raw: bool,
    /// Rebuild into a temporary folder and compare with OUT: tables, README and data must be
    /// identical and the same figures must exist. Exits non-zero on any difference.
    #[arg(long)]
    pub check: bool,
}

/// Runs `report`.
pub fn run(args: Args) -> anyhow::Result<()> {
    let scaling = if args.no_scaling {
        None
    } else {
        args.scaling.clone().or_else(|| default_scaling(&args.run))
    };
    let check_cost = if args.no_check_cost {
        None
    } else {
        args.check_cost
            .clone()
            .or_else(|| default_check_cost(&args.run))
    };
    let (peers, peers_seeds) = if args.no_peers {
        (None, None)
    } else {
        (
            args.peers.clone().or_else(|| default_peers(&args.run)),
            args.peers_seeds
                .clone()
                .or_else(|| default_peers_seeds(&args.run)),
        )
    };
    let study = if args.no_study {
        None
    } else {
        args.study.clone().or_else(|| default_study(&args.run))
    };
    let lod = if args.no_lod {
        None
    } else {
        args.lod.clone().or_else(|| default_lod(&args.run))
    };
    let questionnaire = (!args.no_questionnaire).then(|| Questionnaire {
        inputs: rmt_analysis::Inputs::in_dir(&args.questionnaire),
        options: rmt_analysis::Options {
            exclude: args.exclude.clone(),
            resamples: args.resamples,
            seed: args.seed,
            ..rmt_analysis::Options::default()
        },
    });
    let inputs = ReportInputs {
        run: args.run.clone(),
        scaling,
        check_cost,
        peers,
        peers_seeds,
        study,
        lod,
        questionnaire,
        keep_raw: !args.no_raw,
    };
    if args.check {
        let outcome = check(&inputs, &args.out)
            .with_context(|| format!("checking the report in {}", args.out.display()))?;
        let list = |title: &str, files: &[PathBuf]| {
            for f in files {
                println!("{title}: {}", args.out.join(f).display());
            }
        };
        list("differs", &outcome.differing);
        list("missing", &outcome.missing);
        list("not produced by the rebuild", &outcome.unexpected);
        for (file, why) in &outcome.invalid {
            println!("invalid: {}: {why}", args.out.join(file).display());
        }
        if !outcome.figures_changed.is_empty() {
            println!(
                "note: {} figure(s) have other bytes than the rebuild (allowed)",
                outcome.figures_changed.len()
            );
        }
        if !outcome.passed() {
            bail!(
                "{} does not match a rebuild from {} (with the same questionnaire options \
                 --resamples, --seed, --exclude): regenerate it with `experiments report --run \
                 {} --out {}`",
                args.out.display(),
                args.run.display(),
                args.run.display(),
                args.out.display()
            );
        }
        println!(
            "{}: {} files match a rebuild from {}",
            args.out.display(),
            outcome.compared,
            args.run.display()
        );
        return Ok(());
    }
    let files = build(&inputs, &args.out).with_context(|| {
        format!(
            "building the report from {} into {}",
            args.run.display(),
            args.out.display()
        )
    })?;
    println!(
        "Wrote {} files to {} (open {})",
        files.len(),
        args.out.display(),
        args.out.join("README.md").display()
    );
    Ok(())
}
