//! Perception studies of methods under shadings (`experiments study ...`): the design file
//! ([`design_file`]), the planted model of simulated participants ([`model_file`]), their
//! answers as survey-export files ([`export`]), and the texts the subcommands print: the plan
//! with its power table ([`plan_text`]), the analysis ([`analysis_text`]) and the coverage
//! check ([`coverage_text`]); and [`run_study`], from the design to a served survey's run
//! folder ([`survey_key`]). The statistics are `rmt_analysis::study`'s.

pub mod design_file;
pub mod export;
pub mod http_participants;
pub mod model_file;
pub mod report_data;
pub mod survey_key;

use std::fmt::Write as _;

use rmt_analysis::study::power::{power_table, PowerTable};
use rmt_analysis::study::simulate::CoverageReport;
use rmt_analysis::study::{assign, ParticipantPlan, StudyAnalysis};

use design_file::Design;

/// What [`run_study`] made.
#[derive(Clone, Debug)]
pub struct StudyRun {
    /// The run folder.
    pub folder: std::path::PathBuf,
    /// Each turntable: configuration id and bytes.
    pub gifs: Vec<(String, u64)>,
}

/// The largest turntable a browser should load, in bytes.
pub const MAX_GIF_BYTES: u64 = 2_000_000;

/// `study run`: checks that every configuration of the study has exactly one configuration in
/// the design's manifest (before anything runs), runs the manifest into `out`, renders every
/// configuration (`settings`, names from `seed`), and writes `questionnaire_key.csv` and
/// `study_key.csv` there, so that `survey serve out` asks the study's pairs.
pub fn run_study(
    design: &Design,
    out: &std::path::Path,
    settings: &rmt_render::TurntableSettings,
    seed: u64,
    mut progress: impl FnMut(&str),
) -> anyhow::Result<StudyRun> {
    use anyhow::Context;
    let overrides = crate::manifest::Overrides::default();
    let loaded = crate::manifest::load(&design.manifest, &overrides)?;
    let ids = survey_key::match_items(
        design,
        &survey_key::candidates(&loaded.plan),
        &design.manifest.display().to_string(),
    )?;
    drop(loaded);
    progress(&format!(
        "running {} into {}",
        design.manifest.display(),
        out.display()
    ));
    let report = crate::runner::start(
        &design.manifest,
        &overrides,
        Some(out),
        &crate::runner::RunOptions {
            quiet: true,
            stop_after: None,
        },
    )?;
    let rendered = rmt_render::run_folder::render_run(&report.folder, settings, seed, |k, n, a| {
        progress(&format!("[{k}/{n}] {} ({} kB)", a.id, a.bytes / 1000))
    })
    .with_context(|| format!("rendering {}", report.folder.display()))?;
    survey_key::write_survey_key(&report.folder, design, &ids)?;
    Ok(StudyRun {
        folder: report.folder,
        gifs: rendered.into_iter().map(|a| (a.id, a.bytes)).collect(),
    })
}

/// The design's power table.
pub fn design_power(design: &Design) -> PowerTable {
    power_table(
        &design.items,
        &design.pairs,
        design.questions,
        design.reference,
        design.effect,
        design.tie_rate,
        design.alpha,
    )
}

/// Participants the power table asks for, or `fallback` when some comparison is never asked.
pub fn planned_participants(design: &Design, fallback: usize) -> usize {
    design_power(design)
        .participants()
        .map_or(fallback, |n| n as usize)
}

/// Every participant's questions for `participants` participants.
pub fn participant_plans(design: &Design, participants: usize) -> Vec<ParticipantPlan> {
    assign(
        &design.items,
        &design.pairs,
        design.questions,
        design.controls,
        participants,
        design.seed,
    )
}

fn opt(n: Option<u64>) -> String {
    n.map_or("out of reach".to_string(), |n| n.to_string())
}

/// `study plan`: questions per participant, expected minutes, the balance of the subsets and
/// the power table.
pub fn plan_text(design: &Design) -> String {
    let mut s = String::new();
    let d = design;
    let method_pairs = d
        .pairs
        .iter()
        .filter(|p| p.kind == rmt_analysis::study::PairKind::Method)
        .count();
    let _ = writeln!(s, "# Study `{}`\n", d.name);
    let _ = writeln!(
        s,
        "- configurations: {} ({} objects x {} methods x {} shadings)",
        d.items.len(),
        d.items.objects.len(),
        d.items.methods.len(),
        d.items.shadings.len()
    );
    let _ = writeln!(
        s,
        "- pairs: {} ({} method pairs within an object and shading, {} shading pairs within an \
         object and method)",
        d.pairs.len(),
        method_pairs,
        d.pairs.len() - method_pairs
    );
    let _ = writeln!(
        s,
        "- questions per participant: {} ({} pairs + {} controls)",
        d.questions_per_participant(),
        d.questions,
        d.controls
    );
    let _ = writeln!(
        s,
        "- expected minutes per participant: {:.1} (at {} s an answer)",
        d.expected_minutes(),
        d.seconds_per_question
    );
    let power = design_power(d);
    let _ = writeln!(
        s,
        "- each pair is answered by {:.1}% of participants (balanced subsets: every pair seen by \
         the same number of participants up to one, sides counterbalanced per pair)",
        100.0 * power.share_per_pair
    );
    match power.participants() {
        Some(n) => {
            let plans = participant_plans(d, n as usize);
            let mut seen = vec![0usize; d.pairs.len()];
            for p in &plans {
                for q in &p.questions {
                    if let Some(k) = q.pair {
                        seen[k] += 1;
                    }
                }
            }
            let _ = writeln!(
                s,
                "- participants the power table asks for: **{n}** (each pair then seen {}-{} \
                 times; {:.0} participant-minutes)",
                seen.iter().min().unwrap_or(&0),
                seen.iter().max().unwrap_or(&0),
                n as f64 * d.expected_minutes()
            );
        }
        None => {
            let _ = writeln!(
                s,
                "- participants the power table asks for: out of reach (some comparison with \
                 the reference is never asked)"
            );
        }
    }
    let _ = writeln!(
        s,
        "\n## Power table\n\nParticipants for 80% power to detect a {:.0}/{:.0} preference \
         (decided answers) between `{}` and each peer, two-sided sign test at alpha {}, \
         assuming {:.0}% \"no preference\". Pooled: the comparison's answers on every object \
         together; per object: one object alone.\n",
        100.0 * d.effect,
        100.0 * (1.0 - d.effect),
        d.items.methods[d.reference],
        d.alpha,
        100.0 * d.tie_rate
    );
    let _ = writeln!(
        s,
        "| shading | peer | questions | answers per question | participants, pooled | \
         participants, per object | exact power at pooled |"
    );
    let _ = writeln!(s, "| --- | --- | --- | --- | --- | --- | --- |");
    for r in &power.rows {
        let _ = writeln!(
            s,
            "| {} | {} | {} | {} | {} | {} | {:.3} |",
            d.items.shadings[r.shading],
            d.items.methods[r.peer],
            r.questions,
            opt(r.answers_needed),
            opt(r.pooled),
            opt(r.per_object),
            r.exact_power
        );
    }
    s
}

/// `study analyse`: the analysis as Markdown.
pub fn analysis_text(design: &Design, a: &StudyAnalysis, title: &str) -> String {
    let it = &design.items;
    let mut s = String::new();
    let _ = writeln!(s, "# {title}\n");
    let _ = writeln!(
        s,
        "{} participants, {} answers to pairs. Bradley-Terry with Davidson's ties and a \
         left-side parameter, one block of strengths per object and shading; log-strengths \
         centred per block, Wald 95% intervals.{}\n",
        a.participants,
        a.answers,
        if a.converged {
            ""
        } else {
            " **The fit did not converge** (some configuration won or lost every answer): the \
             strengths are not estimates."
        }
    );
    let _ = writeln!(s, "## Strengths per shading (mean over objects)\n");
    let _ = writeln!(s, "| method | {} |", it.shadings.join(" | "));
    let _ = writeln!(s, "| --- |{}", " --- |".repeat(it.shadings.len()));
    for m in 0..it.methods.len() {
        let cells: Vec<String> = (0..it.shadings.len())
            .map(|sh| {
                a.methods
                    .iter()
                    .find(|r| r.method == m && r.shading == sh)
                    .map_or("-".into(), |r| {
                        format!("{:+.3} ± {:.3}", r.log_strength, 1.96 * r.se)
                    })
            })
            .collect();
        let _ = writeln!(s, "| {} | {} |", it.methods[m], cells.join(" | "));
    }
    let _ = writeln!(s, "\n## Strengths per configuration\n");
    let _ = writeln!(
        s,
        "| object | method | shading | log-strength | 95% interval |"
    );
    let _ = writeln!(s, "| --- | --- | --- | --- | --- |");
    for r in &a.strengths {
        let (o, m, sh) = it.parts(r.item);
        let _ = writeln!(
            s,
            "| {} | {} | {} | {:+.3} | [{:+.3}, {:+.3}] |",
            it.objects[o], it.methods[m], it.shadings[sh], r.log_strength, r.low, r.high
        );
    }
    if let Some(t) = &a.interaction {
        let _ = writeln!(
            s,
            "\n## Does the ranking change with shading?\n\nLikelihood-ratio test of strengths \
             per shading against one strength per method in every shading: statistic {:.2} on \
             {} degrees of freedom, p = {:.4}{}.",
            t.statistic,
            t.df,
            t.p_value,
            if t.converged {
                ""
            } else {
                " (a fit did not converge)"
            }
        );
    }
    let p = &a.position;
    let _ = writeln!(
        s,
        "\n## Position and order\n\n- left-side odds ratio α = {:.3} (95% interval {:.3}-{:.3}), \
         Wald p = {:.4}\n- decided answers on the left screen: {} of {} (binomial p = {:.4})\n\
         - controls: left {}, no preference {}, right {} (binomial p on the decided = {:.4})\n\
         - tie parameter v = {:.3}",
        p.log_odds.exp(),
        (p.log_odds - 1.96 * p.se).exp(),
        (p.log_odds + 1.96 * p.se).exp(),
        p.p_value,
        p.screen[0],
        p.screen[0] + p.screen[1],
        p.screen_p,
        p.controls[0],
        p.controls[1],
        p.controls[2],
        p.controls_p,
        a.tie_parameter
    );
    for t in &a.order.thirds {
        let _ = writeln!(
            s,
            "- positions {}-{}: {} answers, {:.1}% no preference",
            t.first,
            t.last,
            t.answers,
            100.0 * t.ties as f64 / t.answers.max(1) as f64
        );
    }
    let _ = writeln!(
        s,
        "- trend of ties over positions (Cochran-Armitage): z = {:.2}, p = {:.4}",
        a.order.trend_z, a.order.trend_p
    );
    if !a.shading_pairs.is_empty() {
        let _ = writeln!(s, "\n## Shading pairs (pooled over objects)\n");
        let _ = writeln!(
            s,
            "| method | first | second | for first | ties | for second | share first | sign test p |"
        );
        let _ = writeln!(s, "| --- | --- | --- | --- | --- | --- | --- | --- |");
        for sp in &a.shading_pairs {
            let _ = writeln!(
                s,
                "| {} | {} | {} | {} | {} | {} | {:.3} | {:.4} |",
                it.methods[sp.method],
                it.shadings[sp.shadings.0],
                it.shadings[sp.shadings.1],
                sp.counts[0],
                sp.counts[1],
                sp.counts[2],
                sp.share_first,
                sp.p_value
            );
        }
    }
    s
}

/// `study coverage`: the coverage table and the test rates.
pub fn coverage_text(design: &Design, r: &CoverageReport, participants: usize) -> String {
    let it = &design.items;
    let mut s = String::new();
    let _ = writeln!(
        s,
        "# Coverage: {} simulated studies of {} participants\n",
        r.studies, participants
    );
    let _ = writeln!(
        s,
        "Converged fits: {} of {}. Coverage of the planted log-strengths by the 95% intervals \
         (every object's configuration, centred per object and shading):\n",
        r.studies - r.failed,
        r.studies
    );
    let _ = writeln!(
        s,
        "| method | shading | intervals | covered | coverage | mean error |"
    );
    let _ = writeln!(s, "| --- | --- | --- | --- | --- | --- |");
    for row in &r.rows {
        let _ = writeln!(
            s,
            "| {} | {} | {} | {} | {:.1}% | {:+.4} |",
            it.methods[row.method],
            it.shadings[row.shading],
            row.intervals,
            row.covered,
            100.0 * row.covered as f64 / row.intervals.max(1) as f64,
            row.mean_error
        );
    }
    let _ = writeln!(
        s,
        "| all | all | {} | {} | **{:.1}%** | |",
        r.intervals,
        r.covered,
        100.0 * r.coverage()
    );
    let _ = writeln!(
        s,
        "\n- interaction test at 5%: {} of {} rejected ({:.1}%), {}",
        r.interaction_rejections,
        r.interaction_tests,
        100.0 * r.interaction_rate(),
        if r.planted_interaction {
            "the power against the planted interaction"
        } else {
            "the false-positive rate (no interaction planted)"
        }
    );
    let _ = writeln!(
        s,
        "- left bias detected at 5%: {:.1}% of studies; the design's stated power {:.1}%",
        100.0 * r.bias_rate(),
        100.0 * r.stated_bias_power
    );
    let _ = writeln!(
        s,
        "- mean fitted tie parameter v: {:.3}",
        r.mean_tie_parameter
    );
    s
}
