//! `experiments questionnaire <run>`: side-by-side question GIFs, questions.csv,
//! questionnaire.html and questionnaire_key.csv from a rendered run folder (see
//! `rmt_render::questionnaire` and `rmt_render::run_folder`).

use anyhow::Context;
use rmt_render::questionnaire::QuestionnaireOptions;
use std::path::PathBuf;

/// Arguments of `questionnaire`.
#[derive(clap::Args, Debug)]
pub struct Args {
    /// The run folder, after `experiments render`.
    pub run: PathBuf,
    /// Seed of question order, left/right assignment and control choice.
    #[arg(long, default_value_t = 1)]
    pub seed: u64,
    /// Also ask every pair with the sides swapped.
    #[arg(long)]
    pub reverse_pairs: bool,
    /// Number of control questions (an animation against itself).
    #[arg(long, default_value_t = 0)]
    pub controls: usize,
    /// Gap between the two animations in pixels (before scaling).
    #[arg(long, default_value_t = 8)]
    pub gap: u16,
    /// Nearest-neighbour scale factor of the question animations.
    #[arg(long, default_value_t = 2, value_parser = clap::value_parser!(u16).range(1..=8))]
    pub scale: u16,
}

/// Runs `questionnaire`.
pub fn run(args: Args) -> anyhow::Result<()> {
    let options = QuestionnaireOptions {
        seed: args.seed,
        reverse_pairs: args.reverse_pairs,
        controls: args.controls,
        gap: args.gap,
        scale: args.scale,
    };
    let written = rmt_render::run_folder::build_questionnaire(&args.run, &options, |k, n, q| {
        eprintln!("[{k}/{n}] {} ({} kB)", q.path.display(), q.bytes / 1000);
    })
    .with_context(|| format!("building the questionnaire of {}", args.run.display()))?;
    let total: u64 = written.iter().map(|q| q.bytes).sum();
    let dir = args.run.join(rmt_render::run_folder::QUESTIONNAIRE_DIR);
    println!(
        "{} questions ({} kB of GIFs) in {}; open {}; key in {}",
        written.len(),
        total / 1000,
        dir.display(),
        dir.join(rmt_render::run_folder::HTML_FILE).display(),
        args.run
            .join(rmt_render::run_folder::QUESTIONNAIRE_KEY_FILE)
            .display()
    );
    Ok(())
}
