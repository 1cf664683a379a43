//! `experiments survey serve|export`: the questionnaire of a rendered run folder served to
//! participants, answers stored in SQLite, and exported for `experiments analyse`
//! (see `rmt_server`).

use std::net::SocketAddr;
use std::path::PathBuf;

use anyhow::Context;
use rmt_server::store::Store;
use rmt_server::study::{Study, StudyOptions};

/// Arguments of `survey`.
#[derive(clap::Args, Debug)]
pub struct Args {
    /// What to do.
    #[command(subcommand)]
    pub command: Command,
}

/// The `survey` subcommands.
#[derive(clap::Subcommand, Debug)]
pub enum Command {
    /// Serve the questionnaire of a rendered run folder and store the answers (until Ctrl-C).
    Serve(ServeArgs),
    /// Export a survey database: responses.csv (the long layout `analyse` reads), controls.csv,
    /// questions.csv, configurations.csv, participants.csv and a summary.
    Export(ExportArgs),
}

/// Arguments of `survey serve`.
#[derive(clap::Args, Debug)]
pub struct ServeArgs {
    /// The run folder, after `experiments render` (and optionally `experiments questionnaire`,
    /// whose questions are then asked).
    pub run: PathBuf,
    /// Address to listen on (use 0.0.0.0:PORT to let other machines in; port 0 picks one).
    #[arg(long, default_value = "127.0.0.1:8080")]
    pub addr: SocketAddr,
    /// The SQLite database [default: RUN/survey.sqlite]. An existing one resumes the survey.
    #[arg(long)]
    pub db: Option<PathBuf>,
    /// Control questions (one animation on both sides) added to every session.
    #[arg(long, default_value_t = 0)]
    pub controls: usize,
    /// Seed of question planning (when the run has no questionnaire), controls and swaps.
    #[arg(long, default_value_t = 1)]
    pub seed: u64,
    /// Real questions per participant: each answers a balanced subset of this many (every
    /// question answered by the same number of participants, up to one) [default: all].
    #[arg(long)]
    pub per_participant: Option<usize>,
}

/// Arguments of `survey export`.
#[derive(clap::Args, Debug)]
pub struct ExportArgs {
    /// The survey database.
    pub db: PathBuf,
    /// Output folder [default: `survey_export` beside the database].
    #[arg(long)]
    pub out: Option<PathBuf>,
}

/// Runs `survey`.
pub fn run(args: Args) -> anyhow::Result<()> {
    match args.command {
        Command::Serve(args) => serve(args),
        Command::Export(args) => export(args),
    }
}

fn serve(args: ServeArgs) -> anyhow::Result<()> {
    let options = StudyOptions {
        seed: args.seed,
        controls: args.controls,
    };
    let mut study = Study::from_run(&args.run, &options)
        .with_context(|| format!("reading the study of {}", args.run.display()))?;
    if let Some(q) = args.per_participant {
        study = study.with_subsets(q)?;
    }
    let db = args
        .db
        .clone()
        .unwrap_or_else(|| args.run.join("survey.sqlite"));
    let store = Store::open(&db, &study)?;
    let counts = store.counts()?;
    let admin = rmt_server::http::random_token().context("drawing the admin token")?;
    println!(
        "Survey of {}: {} questions + {} controls per session (questions: {}{}), {} animations",
        args.run.display(),
        study.real_questions_per_participant(),
        study.questions.len() - study.real_questions(),
        study.source,
        if study.per_participant.is_some() {
            format!(", a balanced subset of {}", study.real_questions())
        } else {
            String::new()
        },
        study.shown_names().len()
    );
    println!(
        "Database {} ({} participants, {} answers so far)",
        db.display(),
        counts.participants,
        counts.answers + counts.control_answers
    );
    let survey = rmt_server::survey::Survey::new(
        store,
        args.run.join(rmt_render::run_folder::RENDER_DIR),
        admin.clone(),
    );
    let router = rmt_server::survey::router(survey);
    rmt_server::http::serve_until_ctrl_c(router, args.addr, |addr| {
        println!("Listening on http://{addr}/ (Ctrl-C stops; answers are stored as they arrive)");
        println!("Participants: http://{addr}/");
        println!("Admin:        http://{addr}/admin?token={admin}");
    })
    .with_context(|| format!("serving on {}", args.addr))?;
    println!("Stopped.");
    Ok(())
}

fn export(args: ExportArgs) -> anyhow::Result<()> {
    let store = Store::open_existing(&args.db)?;
    let export = store.export()?;
    let out = args.out.unwrap_or_else(|| {
        args.db
            .parent()
            .unwrap_or(std::path::Path::new("."))
            .join("survey_export")
    });
    let files = export
        .write_to(&out)
        .with_context(|| format!("writing the export to {}", out.display()))?;
    println!(
        "{} participants with answers ({} completed), {} answers, {} control answers: {} files in {}",
        export.participants,
        export.completed,
        export.answers,
        export.control_answers,
        files.len(),
        out.display()
    );
    println!(
        "Analyse with: experiments analyse --responses {0}/responses.csv --questions {0}/questions.csv \
         --configurations {0}/configurations.csv --controls {0}/controls.csv --out {0}/analysis \
         (add --allow-missing while sessions are unfinished)",
        out.display()
    );
    Ok(())
}
