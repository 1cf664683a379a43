//! `experiments analyse`: the questionnaire analysis (the dissertation's preference tables plus
//! per-question tests, Bradley-Terry strengths, position bias and agreement) from survey CSVs.
//! Parses arguments, calls `rmt_analysis`, prints the two tables and writes every output file.

use std::path::PathBuf;

use anyhow::Context;
use rmt_analysis::tables::{factors_table, weights_table};
use rmt_analysis::{analyse, write_outputs, InputFormat, Inputs, Options};

/// Arguments of `analyse`.
#[derive(clap::Args, Debug)]
pub struct Args {
    /// Responses: wide (participant + one column per question), long (participant, question,
    /// response, optionally order, swapped, seconds), a survey-tool export ("Question 7 - ..."
    /// columns), or a survey database (`experiments survey serve`; its questions,
    /// configurations and controls are used, and its export is written to OUT/survey_export).
    #[arg(long, default_value = "data/questionnaire/responses.csv")]
    pub responses: PathBuf,
    /// Questions: question,left,right (configuration names).
    #[arg(long, default_value = "data/questionnaire/questions.csv")]
    pub questions: PathBuf,
    /// Configurations: name plus one column per variable.
    #[arg(long, default_value = "data/questionnaire/configurations.csv")]
    pub configurations: PathBuf,
    /// Layout of the responses file: wide, long or survey [default: detected from the header].
    #[arg(long)]
    pub format: Option<InputFormat>,
    /// Participants to leave out, comma-separated (e.g. P18,P03).
    #[arg(long, value_delimiter = ',')]
    pub exclude: Vec<String>,
    /// Directory for the tables (CSV, Markdown) and charts (PNG, SVG).
    #[arg(long, default_value = "reports/questionnaire")]
    pub out: PathBuf,
    /// Drop missing answers (and report how many) instead of failing.
    #[arg(long)]
    pub allow_missing: bool,
    /// Report questions whose sides differ in zero or several variables outside all groups
    /// instead of failing.
    #[arg(long)]
    pub allow_ungrouped: bool,
    /// Variable whose groups are combined by the arithmetic mean; "none" keeps every group.
    #[arg(long, default_value = "object")]
    pub mean_over: String,
    /// Participant-bootstrap resamples (0 for none, otherwise at least 1000).
    #[arg(long, default_value_t = 10_000)]
    pub resamples: usize,
    /// Bootstrap seed.
    #[arg(long, default_value_t = 1)]
    pub seed: u64,
    /// Family-wise error rate of the Holm-corrected sign tests.
    #[arg(long, default_value_t = 0.05)]
    pub alpha: f64,
    /// Control answers of a survey export (controls.csv) for the position effect.
    #[arg(long)]
    pub controls: Option<PathBuf>,
    /// Add the power table (participants needed for 80% power with these answers as the
    /// pilot); always on for survey data.
    #[arg(long)]
    pub power: bool,
}

/// Whether the file starts like an SQLite database.
fn is_sqlite(path: &std::path::Path) -> bool {
    let mut magic = [0u8; 16];
    std::fs::File::open(path)
        .and_then(|mut f| std::io::Read::read_exact(&mut f, &mut magic))
        .is_ok()
        && magic == *b"SQLite format 3\0"
}

/// Runs `analyse`.
pub fn run(args: Args) -> anyhow::Result<()> {
    let mut inputs = Inputs {
        responses: args.responses,
        questions: args.questions,
        configurations: args.configurations,
        format: args.format,
    };
    let mut controls = args.controls;
    if is_sqlite(&inputs.responses) {
        // A survey database: analyse its export (written beside the results).
        let store = rmt_server::store::Store::open_existing(&inputs.responses)?;
        let dir = args.out.join("survey_export");
        store
            .export()?
            .write_to(&dir)
            .with_context(|| format!("writing the survey export to {}", dir.display()))?;
        println!(
            "Survey database {}: exported to {}",
            inputs.responses.display(),
            dir.display()
        );
        inputs = Inputs {
            responses: dir.join(rmt_server::export::RESPONSES_FILE),
            questions: dir.join(rmt_server::export::QUESTIONS_FILE),
            configurations: dir.join(rmt_server::export::CONFIGURATIONS_FILE),
            format: None,
        };
        controls = controls.or_else(|| Some(dir.join(rmt_server::export::CONTROLS_FILE)));
    }
    let options = Options {
        exclude: args.exclude,
        allow_missing: args.allow_missing,
        allow_ungrouped: args.allow_ungrouped,
        mean_over: match args.mean_over.trim() {
            "" | "none" => None,
            name => Some(name.to_string()),
        },
        resamples: args.resamples,
        seed: args.seed,
        alpha: args.alpha,
        controls,
        power: args.power,
        ..Options::default()
    };
    let analysis = analyse(&inputs, &options).context("questionnaire analysis failed")?;
    println!("{}", factors_table(&analysis).to_markdown());
    println!("{}", weights_table(&analysis).to_markdown());
    let significant: Vec<String> = analysis
        .questions
        .iter()
        .filter(|q| q.significant)
        .map(|q| {
            format!(
                "{} {} vs {}: {} preferred (L/N/R {}/{}/{}, Holm p = {:.2e})",
                q.id,
                q.left,
                q.right,
                q.preferred.as_deref().unwrap_or("?"),
                q.counts.left,
                q.counts.none,
                q.counts.right,
                q.p_holm
            )
        })
        .collect();
    println!(
        "Significant after Holm correction (alpha {}): {} of {} questions",
        options.alpha,
        significant.len(),
        analysis.questions.len()
    );
    for line in &significant {
        println!("  {line}");
    }
    for line in rmt_analysis::analysis::summary_lines(&analysis) {
        println!("{line}");
    }
    for line in &analysis.ungrouped {
        println!("Outside all groups: {line}");
    }
    let files = write_outputs(&analysis, &args.out)
        .with_context(|| format!("writing outputs to {}", args.out.display()))?;
    println!("Wrote {} files to {}", files.len(), args.out.display());
    Ok(())
}
