//! `README.md` of the report: provenance at the top, then each figure with one sentence (numbers
//! taken from the data) and the tables it comes from.

use crate::data::{Configuration, Run, RunInfo};
use crate::figures::{stage_shares_of, stages, variant_label};
use crate::format::{self, fixed, percent, readable, sig};
use crate::output::{markdown_block, TextTable};
use crate::scaling::ScalingFit;

/// What the questionnaire part produced.
#[derive(Clone, Debug, PartialEq)]
pub struct QuestionnaireSummary {
    /// Participants analysed.
    pub participants: usize,
    /// Responses analysed.
    pub responses: u64,
    /// Questions.
    pub questions: usize,
    /// Questions significant after Holm's correction.
    pub significant: usize,
    /// Files written, relative to the questionnaire folder, sorted.
    pub files: Vec<String>,
}

/// Everything the README describes.
pub struct ReadmeInput<'a> {
    /// The benchmark run.
    pub run: &'a Run,
    /// The scaling run and its fits, when given.
    pub scaling: Option<(&'a Run, &'a [ScalingFit])>,
    /// Figure stems written to `figures/`.
    pub figures: &'a [String],
    /// Tables written to `tables/`.
    pub tables: &'a [TextTable],
    /// The questionnaire part, when made.
    pub questionnaire: Option<&'a QuestionnaireSummary>,
    /// Files copied to `data/`, relative to it.
    pub data_files: &'a [String],
    /// The check-cost run, when given.
    pub check_cost: Option<&'a Run>,
    /// The peers run and its rows, when given.
    pub peers: Option<(&'a RunInfo, &'a [crate::peers::PeerRow])>,
    /// The second study, when given.
    pub study: Option<&'a crate::study::Study>,
    /// The `lod` run, when given.
    pub lod: Option<&'a crate::lod::LodRun>,
}

fn provenance_rows(info: &RunInfo) -> Vec<(String, String)> {
    let mut settings = Vec::new();
    if let Some(r) = info.repetitions {
        settings.push(format!("{r} timed repetitions"));
    }
    if let Some(w) = info.warmup {
        settings.push(format!("{w} warm-up"));
    }
    if let Some(t) = info.threads {
        settings.push(format!("{t} thread{}", if t == 1 { "" } else { "s" }));
    }
    let mut rows = vec![
        (
            "run".to_string(),
            format!(
                "`{}` (manifest `{}`, status {})",
                info.run_id, info.name, info.status
            ),
        ),
        ("machine".to_string(), info.machine()),
        ("commit".to_string(), format!("`{}`", info.commit())),
        (
            "build".to_string(),
            format!(
                "{} profile, experiments {}",
                info.build_profile, info.version
            ),
        ),
        (
            "date".to_string(),
            match &info.ended {
                Some(end) => format!("{} to {} (UTC)", info.date, end),
                None => format!("{} (UTC, start)", info.date),
            },
        ),
    ];
    if !settings.is_empty() {
        rows.push(("settings".to_string(), settings.join(", ")));
    }
    if info.sessions > 1 {
        let mut text = format!("{} sessions (resumed)", info.sessions);
        if !info.other_cpus.is_empty() {
            text.push_str(&format!(
                "; later sessions also ran on {}",
                info.other_cpus.join(", ")
            ));
        }
        rows.push(("sessions".to_string(), text));
    }
    if info.build_profile != "release" {
        rows.push((
            "note".to_string(),
            "not a release build: times are not comparable".to_string(),
        ));
    }
    rows
}

fn provenance_table(info: &RunInfo) -> String {
    let mut out = String::from("| | |\n|---|---|\n");
    for (k, v) in provenance_rows(info) {
        out.push_str(&format!("| {k} | {} |\n", v.replace('|', "\\|")));
    }
    out
}

fn range<T: Copy>(items: &[(f64, T)]) -> Option<((f64, T), (f64, T))> {
    let min = items.iter().copied().min_by(|a, b| a.0.total_cmp(&b.0))?;
    let max = items.iter().copied().max_by(|a, b| a.0.total_cmp(&b.0))?;
    Some((min, max))
}

fn triangles_sentence(run: &Run) -> String {
    let mut parts = Vec::new();
    for variant in [
        "integrated",
        "integrated-unchecked",
        "postprocessed",
        "meshopt",
    ] {
        let reductions: Vec<(f64, ())> = run
            .configurations
            .iter()
            .filter(|c| c.variant() == variant)
            .filter_map(|c| c.triangle_reduction)
            .map(|r| (r, ()))
            .collect();
        if let Some(((lo, _), (hi, _))) = range(&reductions) {
            let span = if (hi - lo).abs() < 5e-4 {
                percent(lo)
            } else {
                format!("{}–{}", fixed(lo * 100.0, 1), percent(hi))
            };
            parts.push(format!(
                "{} removes {span} of the unclustered triangles",
                variant_label(variant).trim_start_matches("MT, ")
            ));
        }
    }
    let base = "Output triangles of each configuration (bars), grouped by object, with the \
                dissertation's count as a black tick where it has one";
    if parts.is_empty() {
        format!("{base}.")
    } else {
        format!("{base}: {}.", parts.join("; "))
    }
}

fn times_sentence(run: &Run) -> String {
    let max = run
        .configurations
        .iter()
        .flat_map(|c| [c.mean_time("vertex"), c.mean_time("geometry")])
        .fold(0.0, f64::max);
    let (scale, unit) = format::time_unit(max);
    let describe = |stage: &str| {
        let items: Vec<(f64, &str)> = run
            .configurations
            .iter()
            .filter_map(|c| c.time(stage).map(|t| (t.mean, c.id.as_str())))
            .collect();
        range(&items).map(|((lo, a), (hi, b))| {
            format!(
                "{} {unit} ({a}) to {} {unit} ({b})",
                readable(lo * scale),
                readable(hi * scale)
            )
        })
    };
    let mut text = String::from(
        "Mean time of the two passes per extraction, whiskers one standard deviation over the \
         repetitions",
    );
    if let (Some(v), Some(g)) = (describe("vertex"), describe("geometry")) {
        text.push_str(&format!(
            ": the vertex pass takes {v}, the geometry pass {g}"
        ));
    }
    text.push('.');
    text
}

fn shares_sentence(run: &Run) -> String {
    let stages = stages(run);
    let sampling: Vec<f64> = run
        .configurations
        .iter()
        .filter_map(|c| {
            stage_shares_of(c, &stages)
                .into_iter()
                .find(|(s, _)| s == "sampling")
                .map(|s| s.1)
        })
        .collect();
    let mut text =
        String::from("Where the time goes: each stage's mean time as a share of the mean total");
    if let Some(median) = crate::tables::median(&sampling) {
        let lo = sampling.iter().copied().fold(f64::INFINITY, f64::min);
        let hi = sampling.iter().copied().fold(f64::NEG_INFINITY, f64::max);
        text.push_str(&format!(
            "; sampling the field takes {}–{}% (median {}%) of every extraction",
            fixed(lo * 100.0, 0),
            fixed(hi * 100.0, 0),
            fixed(median * 100.0, 0)
        ));
    }
    text.push('.');
    text
}

fn aspect_sentence(run: &Run) -> String {
    let items: Vec<(f64, &str)> = run
        .configurations
        .iter()
        .map(|c| (c.ar_mean, c.id.as_str()))
        .collect();
    let mut text = String::from(
        "Mean radius ratio of the triangles (1 = equilateral) with one standard deviation each \
         way and the median",
    );
    if let Some(((lo, a), (hi, b))) = range(&items) {
        text.push_str(&format!(
            ": from {} ({a}) to {} ({b})",
            sig(lo, 3),
            sig(hi, 3)
        ));
    }
    text.push('.');
    text
}

fn fidelity_sentence(run: &Run) -> String {
    let items: Vec<(f64, &str)> = run
        .configurations
        .iter()
        .filter_map(|c| c.fidelity_mean_h.map(|f| (f, c.id.as_str())))
        .collect();
    let mut text = String::from(
        "The trade-off: triangles kept against the mean distance of the vertices to the true \
         surface (in grid spacings), for the objects whose distance is known",
    );
    if let Some(((lo, a), (hi, b))) = range(&items) {
        text.push_str(&format!(
            "; the distance runs from {} h ({a}) to {} h ({b})",
            sig(lo, 2),
            sig(hi, 2)
        ));
    }
    text.push('.');
    text
}

fn scaling_sentence(fits: &[ScalingFit]) -> String {
    let items: Vec<(f64, &str)> = fits
        .iter()
        .filter_map(|f| f.exponent.map(|b| (b, f.label.as_str())))
        .collect();
    let mut text = String::from(
        "Mean total time against cells per axis N on log-log axes, with the least-squares \
         power law t = a N^b of each method",
    );
    if let Some(((lo, a), (hi, b))) = range(&items) {
        text.push_str(&format!(
            ": b runs from {} ({a}) to {} ({b}); b = 3 means time grows with the number of cells",
            fixed(lo, 2),
            fixed(hi, 2)
        ));
    }
    text.push('.');
    text
}

fn validation_sentence(configurations: &[Configuration]) -> String {
    let defective: Vec<&str> = configurations
        .iter()
        .filter(|c| !c.closed_manifold)
        .map(|c| c.id.as_str())
        .collect();
    if defective.is_empty() {
        format!(
            "All {} meshes are closed and manifold with consistent orientation (surfaces that \
             leave the sampled box are open only on the box).",
            configurations.len()
        )
    } else {
        format!(
            "{} of {} meshes have defects (interior boundary, non-manifold edges or vertices, or \
             flipped triangles): {}.",
            defective.len(),
            configurations.len(),
            defective.join(", ")
        )
    }
}

fn table_link(tables: &[TextTable], name: &str) -> Option<String> {
    tables
        .iter()
        .find(|t| t.name == name)
        .map(|t| format!("[{}](tables/{name}.md) ([CSV](tables/{name}.csv))", t.title))
}

/// The heading of a figure in the README.
fn figure_heading(name: &str) -> &str {
    match name {
        "triangles" => "Triangle counts",
        "pass_times" => "Vertex and geometry pass times",
        "stage_shares" => "Share of time per stage",
        "aspect_ratio" => "Triangle aspect ratio",
        "fidelity" => "Triangle count against fidelity",
        "peers_occupancy" => "Quad occupancy against screen size (peers)",
        "peers_time_triangles" => "Time against triangles, quality as the marker (peers)",
        "scaling" => "Time against resolution",
        "seed_triangles" => "Triangles over the seeds",
        "seed_reduction" => "Triangle reduction over the seeds",
        "seed_radius_ratio" => "Radius ratio over the seeds",
        "lod_top_view" => "The level map from above (lod run)",
        "lod_triangles" => "Triangles per level (lod run)",
        other => other,
    }
}

fn figure(out: &mut String, figures: &[String], name: &str, sentence: &str) {
    let heading = figure_heading(name);
    if !figures.iter().any(|f| f == name) {
        return;
    }
    out.push_str(&format!("### {heading}\n\n{sentence}\n\n"));
    out.push_str(&format!(
        "![{heading}](figures/{name}.png)\n\n[SVG](figures/{name}.svg)\n\n"
    ));
}

/// The README text.
pub fn readme(input: &ReadmeInput) -> String {
    let run = input.run;
    let mut out = String::from("# Results\n\n");
    out.push_str(
        "Figures and tables rebuilt from data by `cargo run --release -p experiments -- report` \
         (see [Regenerate](#regenerate)); do not edit by hand. The benchmark comes from the run \
         whose files are in [`data/`](data/)",
    );
    if input.questionnaire.is_some() {
        out.push_str(
            ", the questionnaire from the answers in `data/questionnaire/` of the repository",
        );
    }
    out.push_str(".\n\n");
    out.push_str("## Provenance\n\n");
    out.push_str(&provenance_table(&run.info));
    out.push('\n');
    if let Some(protocol) = &run.info.timing_protocol {
        out.push_str(&format!("Timing: {protocol}\n\n"));
    }

    out.push_str("## Benchmark\n\n");
    out.push_str(&format!(
        "{} configurations of the `{}` manifest. {}\n\n",
        run.configurations.len(),
        run.info.name,
        validation_sentence(&run.configurations)
    ));
    if let Some(link) = table_link(input.tables, "benchmark_summary") {
        out.push_str(&format!(
            "Table: {link}, in the dissertation's columns.\n\n"
        ));
    }
    let figures = input.figures;
    figure(&mut out, figures, "triangles", &triangles_sentence(run));
    figure(&mut out, figures, "pass_times", &times_sentence(run));
    figure(&mut out, figures, "stage_shares", &shares_sentence(run));
    figure(&mut out, figures, "aspect_ratio", &aspect_sentence(run));
    figure(&mut out, figures, "fidelity", &fidelity_sentence(run));
    match input.scaling {
        Some((scaling_run, fits)) if figures.iter().any(|f| f == "scaling") => {
            figure(
                &mut out,
                figures,
                "scaling",
                &format!(
                    "{} From run `{}` (`{}` manifest, {}; commit `{}`, {}).",
                    scaling_sentence(fits),
                    scaling_run.info.run_id,
                    scaling_run.info.name,
                    scaling_run.info.machine(),
                    scaling_run.info.commit(),
                    scaling_run.info.date
                ),
            );
            if let Some(link) = table_link(input.tables, "scaling") {
                out.push_str(&format!("Table: {link}.\n\n"));
            }
        }
        _ => out.push_str(
            "### Time against resolution\n\nNot included: no scaling run was given (`report \
             --scaling <run folder of experiments/manifests/scaling.toml>`).\n\n",
        ),
    }

    if let Some(ratios) = input.tables.iter().find(|t| t.name == "paper_ratios") {
        out.push_str("## Comparison with the dissertation\n\n");
        out.push_str(
            "Our numbers divided by the dissertation's (`data/paper/benchmark.csv`), over the \
             configurations both have. Counts and memory depend only on the method; times also \
             on the machine and the implementation.\n\n",
        );
        for block in &ratios.blocks {
            out.push_str(&markdown_block(block));
        }
        out.push('\n');
        if let Some(link) = table_link(input.tables, "paper_comparison") {
            out.push_str(&format!("Per configuration: {link}.\n\n"));
        }
    }

    if let (Some(cost_run), Some(table)) = (
        input.check_cost,
        input.tables.iter().find(|t| t.name == "check_cost"),
    ) {
        out.push_str("## The cost of the exact check\n\n");
        out.push_str(&format!(
            "Plain MT, the dissertation's integrated clustering without our exact test \
             (`integrated-unchecked`) and RMT with it (`integrated`), from run `{}` on {} \
             (commit `{}`, {}). Passes are the vertex plus the geometry pass; ratios are over \
             plain MT.\n\n",
            cost_run.info.name,
            cost_run.info.machine(),
            cost_run.info.commit(),
            cost_run.info.date
        ));
        if let Some(sentence) = crate::check_cost::summary_sentence(cost_run) {
            out.push_str(&sentence);
            out.push_str("\n\n");
        }
        out.push_str(&table.blocks_markdown());
        if let Some(link) = table_link(input.tables, "check_cost") {
            out.push_str(&format!("Table: {link}.\n\n"));
        }
    }

    if let (Some((info, rows)), Some(table)) =
        (input.peers, input.tables.iter().find(|t| t.name == "peers"))
    {
        out.push_str(
            "## Against what game developers use

",
        );
        out.push_str(&format!(
            "RMT beside marching cubes and surface nets, as they come and simplified by \
             meshoptimizer to RMT's triangle count (plain and with locked borders), plain MT and \
             edge collapse, from run `{}` on {} (commit `{}`, {}). Every mesh is validated; the \
             peers' defects are counted, not failed.\n\n",
            info.name,
            info.machine(),
            info.commit(),
            info.date
        ));
        if let Some(text) = crate::peers::summary_text(rows) {
            out.push_str(&text);
            out.push_str("\n\n");
        }
        figure(
            &mut out,
            input.figures,
            "peers_occupancy",
            &crate::peers::occupancy_sentence(rows),
        );
        figure(
            &mut out,
            input.figures,
            "peers_time_triangles",
            &crate::peers::time_sentence(rows),
        );
        out.push_str("### Per object\n\n");
        out.push_str(&table.blocks_markdown());
        if let Some(link) = table_link(input.tables, "peers") {
            out.push_str(&format!("Table: {link}.\n\n"));
        }
        if let Some(seeds) = input.tables.iter().find(|t| t.name == "peers_seeds") {
            out.push_str(&format!("### {}\n\n", seeds.title));
            for note in &seeds.notes {
                out.push_str(note);
                out.push_str("\n\n");
            }
            out.push_str(&seeds.blocks_markdown());
            if let Some(link) = table_link(input.tables, "peers_seeds") {
                out.push_str(&format!("Table: {link}.\n\n"));
            }
        }
    }

    if let Some(rows) = &run.seeds {
        out.push_str(&crate::seeds::readme_section(
            rows,
            input.figures,
            table_link(input.tables, "seed_distributions"),
        ));
    }

    if let Some(q) = input.questionnaire {
        out.push_str("## Questionnaire\n\n");
        out.push_str(&format!(
            "{} participants, {} responses to {} side-by-side questions; {} question{} show a \
             significant preference after Holm's correction. All tables: \
             [analysis](questionnaire/analysis.md).\n\n",
            q.participants,
            q.responses,
            q.questions,
            q.significant,
            if q.significant == 1 { "" } else { "s" }
        ));
        let charts = [
            (
                "preference_factors",
                "Mean preference factors",
                "How often each level of a variable was preferred within its comparison group \
                 (the dissertation's factors), with 95% participant-bootstrap intervals.",
            ),
            (
                "preference_weights",
                "Overall preference weights",
                "The dissertation's overall weights per combination of lattice and clustering, \
                 with bootstrap intervals in each cell.",
            ),
            (
                "bradley_terry",
                "Bradley-Terry strengths",
                "Paired-comparison strengths per comparison group (Bradley-Terry with Davidson's \
                 ties), centred, with bootstrap intervals: further right is preferred.",
            ),
        ];
        for (name, heading, sentence) in charts {
            if q.files.iter().any(|f| f == &format!("{name}.png")) {
                out.push_str(&format!("### {heading}\n\n{sentence}\n\n"));
                out.push_str(&format!(
                    "![{heading}](questionnaire/{name}.png)\n\n[SVG](questionnaire/{name}.svg)\n\n"
                ));
            }
        }
        let tables: Vec<String> = q
            .files
            .iter()
            .filter(|f| f.ends_with(".md") && *f != "analysis.md")
            .map(|f| {
                let stem = f.trim_end_matches(".md");
                format!("[{stem}](questionnaire/{f}) ([CSV](questionnaire/{stem}.csv))")
            })
            .collect();
        if !tables.is_empty() {
            out.push_str(&format!("Tables: {}.\n\n", tables.join(", ")));
        }
    }

    if let Some(study) = input.study {
        out.push_str(&crate::study::readme_section(study, input.tables, |name| {
            table_link(input.tables, name)
        }));
    }

    if let Some(lod) = input.lod {
        out.push_str(&crate::lod::readme_section(lod, |name| {
            table_link(input.tables, name)
        }));
    }

    out.push_str("## Files\n\n");
    out.push_str("| file | what |\n|---|---|\n");
    for table in input.tables {
        out.push_str(&format!(
            "| `tables/{0}.md`, `tables/{0}.csv` | {1} |\n",
            table.name, table.title
        ));
    }
    for name in figures {
        out.push_str(&format!(
            "| `figures/{name}.png`, `figures/{name}.svg` | figure: {} |\n",
            figure_heading(name)
        ));
    }
    for file in input.data_files {
        let what = match file.rsplit('/').next().unwrap_or(file) {
            "run.json" => "provenance, settings and configurations of the run",
            "manifest.toml" => "the manifest as run",
            "configurations.csv" => "the configurations",
            "raw.csv" => "one row per timed repetition",
            "summary.csv" => "one row per configuration (the source of every benchmark figure)",
            "paper_comparison.csv" => "ours against the dissertation, per configuration and metric",
            "seeds.csv" => "each configuration's distribution over the noise seeds (seed study)",
            "study.csv" => "the study's design: questions, power assumptions, answers' source",
            "questions.csv" => "question to configurations (canonical sides)",
            "responses.csv" => "one row per answer to a pair (as the survey export writes it)",
            "controls.csv" => "one row per control answer",
            "coverage.csv" => "coverage of the planted strengths over simulated studies",
            "coverage_tests.csv" => "the simulated studies' test rates",
            "lod.csv" => "one row per viewer step of the lod flight",
            "lod_levels.csv" => "chunks and triangles per viewer step and level",
            "lod_map.csv" => "the level map at the flight's last step, one row per chunk",
            _ => "input",
        };
        let scope = if file.starts_with("scaling/") {
            " (scaling run)"
        } else if file.starts_with("check-cost/") {
            " (check-cost run)"
        } else if file.starts_with("peers/") {
            " (peers run)"
        } else if file.starts_with("peers-seeds/") {
            " (peers seed study)"
        } else if file.starts_with("study/") {
            " (second study)"
        } else if file.starts_with("lod/") {
            " (lod run)"
        } else {
            ""
        };
        out.push_str(&format!("| `data/{file}` | {what}{scope} |\n"));
    }
    if !input.data_files.iter().any(|f| f == "raw.csv") {
        out.push_str(
            "\n`data/raw.csv` (one row per repetition) is not kept here; `summary.csv` holds \
             every number the report uses.\n",
        );
    }
    out.push('\n');

    out.push_str("## Regenerate\n\n```sh\n");
    out.push_str(
        "# from the committed data (what CI checks: tables must come out identical)\n\
         cargo run --release -p experiments -- report --check\n\
         # from new runs\n\
         cargo run --release -p experiments -- run experiments/manifests/paper.toml\n\
         cargo run --release -p experiments -- run experiments/manifests/scaling.toml\n\
         cargo run --release -p experiments -- run experiments/manifests/check-cost.toml\n\
         cargo run --release -p experiments -- run experiments/manifests/peers.toml\n\
         cargo run --release -p experiments -- run experiments/manifests/peers-seeds.toml\n\
         cargo run --release -p experiments -- run experiments/manifests/lod-ci.toml\n\
         cargo run --release -p experiments -- report --run results/<paper run> --scaling \
         results/<scaling run> --check-cost results/<check-cost run> --peers results/<peers \
         run> --peers-seeds results/<peers-seeds run> --lod results/<lod-ci run>\n```\n",
    );
    out
}
