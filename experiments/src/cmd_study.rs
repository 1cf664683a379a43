//! `experiments study ...`: a perception study of methods under shadings from its design file
//! (see `study::design_file`): `plan` (questions, minutes, power table), `simulate` (answers
//! of simulated participants as survey-export files), `analyse` (the analysis of an export),
//! `coverage` (the analysis checked on many simulated studies), `run` (manifest, render and
//! the survey's question key, then the `survey serve` command).

use std::path::PathBuf;

use anyhow::{Context, Result};
use rmt_analysis::study::analyse_study;
use rmt_analysis::study::simulate::{coverage, simulate};
use rmt_runfolder::write_atomic;

use crate::study::{self, design_file, export, http_participants, model_file};

/// Arguments of `study`.
#[derive(clap::Args, Debug)]
pub struct Args {
    /// What to do.
    #[command(subcommand)]
    pub command: Command,
}

/// The `study` subcommands.
#[derive(clap::Subcommand, Debug)]
pub enum Command {
    /// Print the questions per participant, expected minutes and the power table of a design.
    Plan(PlanArgs),
    /// Write the answers of simulated participants as survey-export files.
    Simulate(SimulateArgs),
    /// Analyse a study's answers (a survey export, or `simulate`'s output).
    Analyse(AnalyseArgs),
    /// Check the analysis on many simulated studies: interval coverage and test rates.
    Coverage(CoverageArgs),
    /// From the design to a survey: run its manifest, render, write the survey's question key,
    /// and print the `survey serve` command.
    Run(RunArgs),
}

/// Arguments of `study run`.
#[derive(clap::Args, Debug)]
pub struct RunArgs {
    /// The design file.
    pub study: PathBuf,
    /// The run folder (new or empty).
    #[arg(long)]
    pub out: PathBuf,
    /// Seed of the anonymous animation names (keep it as secret as key.csv).
    #[arg(long, default_value_t = 1)]
    pub seed: u64,
}

/// Arguments of `study plan`.
#[derive(clap::Args, Debug)]
pub struct PlanArgs {
    /// The design file (`experiments/studies/*.toml`).
    pub study: PathBuf,
}

/// Arguments of `study simulate`.
#[derive(clap::Args, Debug)]
pub struct SimulateArgs {
    /// The design file.
    pub study: PathBuf,
    /// Participants (default: what the power table asks for).
    #[arg(long)]
    pub participants: Option<usize>,
    /// The planted preference model (TOML).
    #[arg(long)]
    pub model: PathBuf,
    /// Seed of the answers.
    #[arg(long, default_value_t = 1)]
    pub seed: u64,
    /// Output folder of the export-shaped files (without --serve), with `study.csv`: the
    /// design's numbers, which the report's study section reads beside them.
    #[arg(long, required_unless_present = "serve")]
    pub out: Option<PathBuf>,
    /// Answer through the survey served at this address instead (`survey serve` of a folder
    /// made by `study run`), as participants' browsers do.
    #[arg(long, requires = "run", conflicts_with = "out")]
    pub serve: Option<std::net::SocketAddr>,
    /// The run folder the survey serves (its key.csv and study_key.csv name the animations).
    #[arg(long)]
    pub run: Option<PathBuf>,
}

/// Arguments of `study analyse`.
#[derive(clap::Args, Debug)]
pub struct AnalyseArgs {
    /// The design file.
    pub study: PathBuf,
    /// The folder with `responses.csv`, `questions.csv` (and `controls.csv`).
    #[arg(long)]
    pub answers: PathBuf,
    /// Configuration key `id,object,method,shading` (default: the folder's configurations.csv).
    #[arg(long)]
    pub key: Option<PathBuf>,
    /// Title of the text (say "simulated" when the answers are).
    #[arg(long, default_value = "Study analysis")]
    pub title: String,
    /// Also write the text to this file.
    #[arg(long)]
    pub out: Option<PathBuf>,
}

/// Arguments of `study coverage`.
#[derive(clap::Args, Debug)]
pub struct CoverageArgs {
    /// The design file.
    pub study: PathBuf,
    /// The planted preference model (TOML).
    #[arg(long)]
    pub model: PathBuf,
    /// Simulated studies.
    #[arg(long, default_value_t = 200)]
    pub studies: usize,
    /// Participants per study (default: what the power table asks for).
    #[arg(long)]
    pub participants: Option<usize>,
    /// Seed of the first study (study k uses seed + k).
    #[arg(long, default_value_t = 1)]
    pub seed: u64,
    /// Also write the table as `coverage.csv` and `coverage_tests.csv` into this folder (the
    /// report's study section reads them).
    #[arg(long)]
    pub out: Option<PathBuf>,
}

/// Runs `study`.
pub fn run(args: Args) -> Result<()> {
    match args.command {
        Command::Plan(a) => {
            let design = design_file::read(&a.study)?;
            print!("{}", study::plan_text(&design));
            Ok(())
        }
        Command::Simulate(a) => {
            let design = design_file::read(&a.study)?;
            let model = model_file::read(&a.model, &design.items)?;
            let n = a
                .participants
                .unwrap_or_else(|| study::planned_participants(&design, 100));
            if let (Some(addr), Some(run)) = (a.serve, &a.run) {
                let names = http_participants::names_to_items(run, &design.items)?;
                let sent = http_participants::answer_over_http(addr, &names, &model, n, a.seed)?;
                println!("{n} simulated participants sent {sent} answers to http://{addr}/");
                return Ok(());
            }
            let out = a.out.context("--out is needed without --serve")?;
            let plans = study::participant_plans(&design, n);
            let sim = simulate(&design.pairs, &plans, &model, a.seed);
            export::write_export(&out, &design.items, &design.pairs, &plans, &sim)?;
            study::report_data::write_study_csv(&out, &design, n, &a.model, a.seed)?;
            println!(
                "{n} simulated participants, {} answers and {} control answers in {}",
                sim.answers.len(),
                sim.controls.len(),
                out.display()
            );
            Ok(())
        }
        Command::Analyse(a) => {
            let design = design_file::read(&a.study)?;
            let read =
                export::read_export(&a.answers, a.key.as_deref(), &design.items, &design.pairs)
                    .with_context(|| format!("reading the answers in {}", a.answers.display()))?;
            let analysis =
                analyse_study(&design.items, &design.pairs, &read.answers, &read.controls);
            let text = study::analysis_text(&design, &analysis, &a.title);
            if let Some(out) = &a.out {
                write_atomic(out, text.as_bytes())
                    .with_context(|| format!("writing {}", out.display()))?;
            }
            print!("{text}");
            Ok(())
        }
        Command::Run(a) => {
            let design = design_file::read(&a.study)?;
            let settings = rmt_render::TurntableSettings::default();
            let done = study::run_study(&design, &a.out, &settings, a.seed, |m| eprintln!("{m}"))?;
            let largest = done.gifs.iter().map(|g| g.1).max().unwrap_or(0);
            let total: u64 = done.gifs.iter().map(|g| g.1).sum();
            println!(
                "{} turntables, {:.2} MB in all, the largest {:.2} MB ({})",
                done.gifs.len(),
                total as f64 / 1e6,
                largest as f64 / 1e6,
                if largest <= study::MAX_GIF_BYTES {
                    "within the 2 MB a browser should load"
                } else {
                    "OVER the 2 MB a browser should load: render smaller"
                }
            );
            println!(
                "serve it:   experiments survey serve {} --controls {} --per-participant {}",
                done.folder.display(),
                design.controls,
                design.questions
            );
            println!(
                "analyse it: experiments survey export {0}/survey.sqlite --out {0}/survey && \\\n  \
                 experiments study analyse {1} --answers {0}/survey --key {0}/study_key.csv",
                done.folder.display(),
                a.study.display()
            );
            Ok(())
        }
        Command::Coverage(a) => {
            let design = design_file::read(&a.study)?;
            let model = model_file::read(&a.model, &design.items)?;
            let n = a
                .participants
                .unwrap_or_else(|| study::planned_participants(&design, 100));
            let plans = study::participant_plans(&design, n);
            let report = coverage(
                &design.items,
                &design.pairs,
                &plans,
                &model,
                a.studies,
                a.seed,
            );
            if let Some(out) = &a.out {
                study::report_data::write_coverage(out, &design, &report, n)?;
            }
            print!("{}", study::coverage_text(&design, &report, n));
            Ok(())
        }
    }
}
