//! The second perception study (issue 42): RMT against the peers under smooth and flat shading,
//! analysed as `experiments study analyse` does (`rmt_analysis::study`): Bradley-Terry with
//! Davidson's ties and a left-side parameter per object and shading, the likelihood-ratio test of
//! a method x shading interaction, the position and order effects, the power table, and the
//! coverage check of the analysis on simulated studies.
//!
//! The input is a folder (kept in a report as `data/study/`) with the survey export's files in
//! the study's names, as `experiments study simulate --out` writes them, and two files of the
//! study's own:
//!
//! ```text
//!   configurations.csv  id,object,method,shading   ──► the study's configurations
//!   questions.csv       question,left,right        ──► one pair per question (canonical sides)
//!   responses.csv       participant,question,response,order,swapped   ──► answers
//!   controls.csv        participant,control,configuration,name,response,order ──► controls
//!   study.csv           key,value: questions per participant, power assumptions, and
//!                       `answers` (simulated or real), model and seed
//!   coverage.csv, coverage_tests.csv (optional): `experiments study coverage --out`
//!        │
//!        └──► tables study_strengths, study_power, study_coverage and the README's section,
//!             titled as built from simulated participants while `answers` says so
//! ```

use std::collections::BTreeMap;
use std::path::Path;

use rmt_analysis::study::power::{power_table, PowerTable};
use rmt_analysis::study::{
    analyse_study, PairKind, StudyAnalysis, StudyAnswer, StudyControl, StudyItems, StudyPair,
};
use rmt_analysis::Answer;

use crate::csv_file::CsvFile;
use crate::error::{ReportError, Result};
use crate::output::{Block, TextTable};

/// The files of a study folder the report reads (and copies into `data/study/`), in order; the
/// last two are optional.
pub const STUDY_FILES: [&str; 7] = [
    "study.csv",
    "configurations.csv",
    "questions.csv",
    "responses.csv",
    "controls.csv",
    "coverage.csv",
    "coverage_tests.csv",
];

/// How many of [`STUDY_FILES`] must exist.
const REQUIRED: usize = 5;

/// The coverage check of the analysis, as `experiments study coverage --out` writes it.
#[derive(Clone, Debug, PartialEq)]
pub struct Coverage {
    /// Per method and shading: method, shading, intervals, covered, mean error.
    pub rows: Vec<(String, String, u64, u64, f64)>,
    /// `coverage_tests.csv`: studies, participants, converged, planted_interaction, ...
    pub tests: BTreeMap<String, String>,
}

/// A study read and analysed.
#[derive(Clone, Debug)]
pub struct Study {
    /// `study.csv`.
    pub design: BTreeMap<String, String>,
    /// The configurations.
    pub items: StudyItems,
    /// The pairs, one per question of `questions.csv`.
    pub pairs: Vec<StudyPair>,
    /// The analysis.
    pub analysis: StudyAnalysis,
    /// The power table of the design.
    pub power: PowerTable,
    /// The coverage check, when given.
    pub coverage: Option<Coverage>,
}

/// Whether `folder` holds a study (its `study.csv` and `responses.csv`).
pub fn is_study(folder: &Path) -> bool {
    folder.join(STUDY_FILES[0]).is_file() && folder.join(STUDY_FILES[3]).is_file()
}

/// The files of [`STUDY_FILES`] that `folder` holds, read (the required ones must exist).
pub fn study_files(folder: &Path) -> Result<Vec<(&'static str, Vec<u8>)>> {
    let mut files = Vec::new();
    for (k, name) in STUDY_FILES.into_iter().enumerate() {
        let path = folder.join(name);
        if path.is_file() {
            files.push((
                name,
                std::fs::read(&path).map_err(crate::error::io_error(&path))?,
            ));
        } else if k < REQUIRED {
            return Err(ReportError::MissingFile {
                path,
                hint: "a study folder as `experiments study simulate --out` writes it".into(),
            });
        }
    }
    Ok(files)
}

fn bad(path: &Path, message: String) -> ReportError {
    ReportError::Input {
        path: path.to_path_buf(),
        message,
    }
}

fn key_values(file: &CsvFile) -> Result<BTreeMap<String, String>> {
    let (k, v) = (file.column("key")?, file.column("value")?);
    Ok(file
        .rows
        .iter()
        .map(|r| (r[k].clone(), r[v].clone()))
        .collect())
}

fn parse<T: std::str::FromStr>(path: &Path, line: usize, what: &str, text: &str) -> Result<T> {
    text.parse().map_err(|_| {
        bad(
            path,
            format!("line {line}: {what} `{text}` is not a number"),
        )
    })
}

fn design_value<T: std::str::FromStr>(
    design: &BTreeMap<String, String>,
    path: &Path,
    key: &str,
) -> Result<T> {
    let text = design
        .get(key)
        .ok_or_else(|| bad(path, format!("no `{key}` row")))?;
    text.parse()
        .map_err(|_| bad(path, format!("`{key}` = `{text}` is not a number")))
}

/// Reads the study in `folder` and analyses it.
pub fn read_study(folder: &Path) -> Result<Study> {
    let path = |name: &str| folder.join(name);
    let design_path = path("study.csv");
    let design = key_values(&CsvFile::read(&design_path)?)?;

    // Configurations: the study's objects, methods and shadings in order of first appearance.
    let configs = CsvFile::read(&path("configurations.csv"))?;
    let cols = ["id", "object", "method", "shading"]
        .map(|c| configs.column(c))
        .into_iter()
        .collect::<Result<Vec<usize>>>()?;
    let mut items = StudyItems {
        objects: Vec::new(),
        methods: Vec::new(),
        shadings: Vec::new(),
    };
    for row in &configs.rows {
        for (list, col) in [
            (&mut items.objects, cols[1]),
            (&mut items.methods, cols[2]),
            (&mut items.shadings, cols[3]),
        ] {
            if !list.contains(&row[col]) {
                list.push(row[col].clone());
            }
        }
    }
    let index = |list: &[String], v: &str| list.iter().position(|x| x == v);
    let mut item_of: BTreeMap<String, usize> = BTreeMap::new();
    for row in &configs.rows {
        let (o, m, s) = (
            index(&items.objects, &row[cols[1]]),
            index(&items.methods, &row[cols[2]]),
            index(&items.shadings, &row[cols[3]]),
        );
        if let (Some(o), Some(m), Some(s)) = (o, m, s) {
            item_of.insert(row[cols[0]].clone(), items.item(o, m, s));
        }
    }

    // One pair per question, its canonical sides the question's.
    let questions = CsvFile::read(&path("questions.csv"))?;
    let (q, l, r) = (
        questions.column("question")?,
        questions.column("left")?,
        questions.column("right")?,
    );
    let mut pairs = Vec::new();
    let mut pair_of: BTreeMap<String, usize> = BTreeMap::new();
    for (n, row) in questions.rows.iter().enumerate() {
        let item = |c: usize| {
            item_of.get(&row[c]).copied().ok_or_else(|| {
                bad(
                    &questions.path,
                    format!(
                        "line {}: configuration `{}` is not in configurations.csv",
                        n + 2,
                        row[c]
                    ),
                )
            })
        };
        let (a, b) = (item(l)?, item(r)?);
        let ((oa, ma, sa), (ob, mb, sb)) = (items.parts(a), items.parts(b));
        let kind = match (oa == ob, ma == mb, sa == sb) {
            (true, false, true) => PairKind::Method,
            (true, true, false) => PairKind::Shading,
            _ => {
                return Err(bad(
                    &questions.path,
                    format!(
                        "line {}: `{}` against `{}` differ in more than the method or the shading",
                        n + 2,
                        row[l],
                        row[r]
                    ),
                ))
            }
        };
        pair_of.insert(row[q].clone(), pairs.len());
        pairs.push(StudyPair {
            first: a,
            second: b,
            kind,
        });
    }

    let mut participants: BTreeMap<String, usize> = BTreeMap::new();
    let responses = CsvFile::read(&path("responses.csv"))?;
    let rp = &responses.path;
    let (cp, cq, cr, co, cs) = (
        responses.column("participant")?,
        responses.column("question")?,
        responses.column("response")?,
        responses.column("order")?,
        responses.column("swapped")?,
    );
    let mut answers = Vec::with_capacity(responses.rows.len());
    for (n, row) in responses.rows.iter().enumerate() {
        let line = n + 2;
        let next = participants.len();
        let participant = *participants.entry(row[cp].clone()).or_insert(next);
        let pair = *pair_of
            .get(&row[cq])
            .ok_or_else(|| bad(rp, format!("line {line}: unknown question `{}`", row[cq])))?;
        let response = Answer::parse(&row[cr])
            .ok_or_else(|| bad(rp, format!("line {line}: response `{}`", row[cr])))?;
        let swapped = match row[cs].as_str() {
            "0" | "false" => false,
            "1" | "true" => true,
            other => return Err(bad(rp, format!("line {line}: swapped `{other}`"))),
        };
        answers.push(StudyAnswer {
            participant,
            pair,
            order: parse(rp, line, "order", &row[co])?,
            swapped,
            response,
        });
    }
    let controls_file = CsvFile::read(&path("controls.csv"))?;
    let cpath = &controls_file.path;
    let (cp, cc, cr, co) = (
        controls_file.column("participant")?,
        controls_file.column("configuration")?,
        controls_file.column("response")?,
        controls_file.column("order")?,
    );
    let mut controls = Vec::with_capacity(controls_file.rows.len());
    for (n, row) in controls_file.rows.iter().enumerate() {
        let line = n + 2;
        let next = participants.len();
        let participant = *participants.entry(row[cp].clone()).or_insert(next);
        controls.push(StudyControl {
            participant,
            item: *item_of.get(&row[cc]).ok_or_else(|| {
                bad(
                    cpath,
                    format!("line {line}: unknown configuration `{}`", row[cc]),
                )
            })?,
            order: parse(cpath, line, "order", &row[co])?,
            response: Answer::parse(&row[cr])
                .ok_or_else(|| bad(cpath, format!("line {line}: response `{}`", row[cr])))?,
        });
    }

    let analysis = analyse_study(&items, &pairs, &answers, &controls);
    let reference_name = design
        .get("reference")
        .ok_or_else(|| bad(&design_path, "no `reference` row".into()))?;
    let reference = index(&items.methods, reference_name).ok_or_else(|| {
        bad(
            &design_path,
            format!("reference `{reference_name}` is not a method of the study"),
        )
    })?;
    let power = power_table(
        &items,
        &pairs,
        design_value(&design, &design_path, "questions")?,
        reference,
        design_value(&design, &design_path, "effect")?,
        design_value(&design, &design_path, "tie_rate")?,
        design_value(&design, &design_path, "alpha")?,
    );

    let coverage = if path("coverage.csv").is_file() {
        let file = CsvFile::read(&path("coverage.csv"))?;
        let fp = &file.path;
        let c = ["method", "shading", "intervals", "covered", "mean_error"]
            .map(|name| file.column(name))
            .into_iter()
            .collect::<Result<Vec<usize>>>()?;
        let mut rows = Vec::new();
        for (n, row) in file.rows.iter().enumerate() {
            rows.push((
                row[c[0]].clone(),
                row[c[1]].clone(),
                parse(fp, n + 2, "intervals", &row[c[2]])?,
                parse(fp, n + 2, "covered", &row[c[3]])?,
                parse(fp, n + 2, "mean_error", &row[c[4]])?,
            ));
        }
        let tests = key_values(&CsvFile::read(&path("coverage_tests.csv"))?)?;
        Some(Coverage { rows, tests })
    } else {
        None
    };
    Ok(Study {
        design,
        items,
        pairs,
        analysis,
        power,
        coverage,
    })
}

impl Study {
    /// Whether the answers are simulated (`answers` of `study.csv` is not `real`).
    pub fn simulated(&self) -> bool {
        self.design.get("answers").map(String::as_str) != Some("real")
    }

    /// The section's title: it says when the answers are simulated.
    pub fn title(&self) -> String {
        if self.simulated() {
            "A second study on screen, from simulated participants (no real answers yet)".into()
        } else {
            "A second study on screen".into()
        }
    }

    fn value(&self, key: &str) -> &str {
        self.design.get(key).map_or("?", String::as_str)
    }
}

fn signed(x: f64) -> String {
    format!("{x:+.3}")
}

/// Table `study_strengths`: log-strengths per method and shading (mean over objects, ± 1.96
/// standard errors) and per configuration with 95% intervals.
pub fn strengths_table(study: &Study) -> TextTable {
    let it = &study.items;
    let a = &study.analysis;
    let mut csv_rows = Vec::new();
    let mut mean_rows = Vec::new();
    for m in 0..it.methods.len() {
        let mut cells = vec![it.methods[m].clone()];
        for s in 0..it.shadings.len() {
            match a.methods.iter().find(|r| r.method == m && r.shading == s) {
                Some(r) => {
                    cells.push(format!("{} ± {:.3}", signed(r.log_strength), 1.96 * r.se));
                    csv_rows.push(vec![
                        "all".into(),
                        it.methods[m].clone(),
                        it.shadings[s].clone(),
                        format!("{:.6}", r.log_strength),
                        format!("{:.6}", r.se),
                        format!("{:.6}", r.log_strength - 1.96 * r.se),
                        format!("{:.6}", r.log_strength + 1.96 * r.se),
                    ]);
                }
                None => cells.push("-".into()),
            }
        }
        mean_rows.push(cells);
    }
    let mut config_rows = Vec::new();
    for r in &a.strengths {
        let (o, m, s) = it.parts(r.item);
        config_rows.push(vec![
            it.objects[o].clone(),
            it.methods[m].clone(),
            it.shadings[s].clone(),
            signed(r.log_strength),
            format!("[{}, {}]", signed(r.low), signed(r.high)),
        ]);
        csv_rows.push(vec![
            it.objects[o].clone(),
            it.methods[m].clone(),
            it.shadings[s].clone(),
            format!("{:.6}", r.log_strength),
            format!("{:.6}", r.se),
            format!("{:.6}", r.low),
            format!("{:.6}", r.high),
        ]);
    }
    let mut header = vec!["method".to_string()];
    header.extend(it.shadings.iter().cloned());
    TextTable {
        name: "study_strengths".into(),
        title: format!("Study strengths per shading{}", simulated_note(study)),
        notes: vec![format!(
            "Bradley-Terry with Davidson's ties and a left-side parameter, one block of strengths \
             per object and shading; log-strengths centred per block, Wald 95% intervals; {} \
             participants, {} answers to pairs.{}",
            a.participants,
            a.answers,
            if a.converged {
                ""
            } else {
                " The fit did not converge: these are not estimates."
            }
        )],
        csv_header: [
            "object",
            "method",
            "shading",
            "log_strength",
            "se",
            "low",
            "high",
        ]
        .map(String::from)
        .to_vec(),
        csv_rows,
        blocks: vec![
            Block {
                caption: Some("Per shading, mean over objects (± 95%)".into()),
                header,
                rows: mean_rows,
            },
            Block {
                caption: Some("Per configuration".into()),
                header: [
                    "object",
                    "method",
                    "shading",
                    "log-strength",
                    "95% interval",
                ]
                .map(String::from)
                .to_vec(),
                rows: config_rows,
            },
        ],
    }
}

fn simulated_note(study: &Study) -> &'static str {
    if study.simulated() {
        " (simulated participants)"
    } else {
        ""
    }
}

fn opt(n: Option<u64>) -> String {
    n.map_or("-".into(), |n| n.to_string())
}

/// Table `study_power`: participants for 80% power against each peer, per shading.
pub fn power_table_text(study: &Study) -> TextTable {
    let p = &study.power;
    let it = &study.items;
    let rows: Vec<Vec<String>> = p
        .rows
        .iter()
        .map(|r| {
            vec![
                it.shadings[r.shading].clone(),
                it.methods[r.peer].clone(),
                r.questions.to_string(),
                opt(r.answers_needed),
                opt(r.pooled),
                opt(r.per_object),
                format!("{:.3}", r.exact_power),
            ]
        })
        .collect();
    TextTable {
        name: "study_power".into(),
        title: "Study power: participants for 80% power".into(),
        notes: vec![format!(
            "To detect a {:.0}/{:.0} preference between {} and each peer at α = {}, with \
             {:.0}% \"no preference\" and {} of the {} pair questions per participant (exact sign \
             test). Pooled: the comparison's answers on every object together; per object: one \
             object alone.",
            100.0 * p.effect,
            100.0 * (1.0 - p.effect),
            it.methods[p.reference],
            p.alpha,
            100.0 * p.tie_rate,
            study.value("questions"),
            study.pairs.len()
        )],
        csv_header: [
            "shading",
            "peer",
            "questions",
            "answers_per_question",
            "participants_pooled",
            "participants_per_object",
            "exact_power_at_pooled",
        ]
        .map(String::from)
        .to_vec(),
        csv_rows: rows.clone(),
        blocks: vec![Block {
            caption: None,
            header: [
                "shading",
                "peer",
                "questions",
                "answers per question",
                "participants, pooled",
                "participants, per object",
                "exact power at pooled",
            ]
            .map(String::from)
            .to_vec(),
            rows,
        }],
    }
}

fn percent(part: u64, whole: u64) -> String {
    format!("{:.1}%", 100.0 * part as f64 / whole.max(1) as f64)
}

/// Table `study_coverage`: how often the 95% intervals held the planted strengths over the
/// simulated studies, when the coverage check is given.
pub fn coverage_table(study: &Study) -> Option<TextTable> {
    let c = study.coverage.as_ref()?;
    let mut rows: Vec<Vec<String>> = c
        .rows
        .iter()
        .map(|(m, s, n, k, e)| {
            vec![
                m.clone(),
                s.clone(),
                n.to_string(),
                k.to_string(),
                percent(*k, *n),
                format!("{e:+.4}"),
            ]
        })
        .collect();
    let (n, k) = c.rows.iter().fold((0, 0), |(n, k), r| (n + r.2, k + r.3));
    rows.push(vec![
        "all".into(),
        "all".into(),
        n.to_string(),
        k.to_string(),
        percent(k, n),
        String::new(),
    ]);
    let get = |key: &str| c.tests.get(key).map_or("?", String::as_str);
    Some(TextTable {
        name: "study_coverage".into(),
        title: "Study method check: coverage on simulated studies".into(),
        notes: vec![format!(
            "{} simulated studies of {} participants from the planted model ({} converged): \
             the share of 95% intervals that hold the planted log-strength, per method and \
             shading over every object.",
            get("studies"),
            get("participants"),
            get("converged")
        )],
        csv_header: [
            "method",
            "shading",
            "intervals",
            "covered",
            "coverage",
            "mean_error",
        ]
        .map(String::from)
        .to_vec(),
        csv_rows: rows.clone(),
        blocks: vec![Block {
            caption: None,
            header: [
                "method",
                "shading",
                "intervals",
                "covered",
                "coverage",
                "mean error",
            ]
            .map(String::from)
            .to_vec(),
            rows,
        }],
    })
}

/// Every table of the study section.
pub fn study_tables(study: &Study) -> Vec<TextTable> {
    let mut tables = vec![strengths_table(study), power_table_text(study)];
    tables.extend(coverage_table(study));
    tables
}

/// The README's section (tables from `tables`, linked with `link`).
pub fn readme_section(
    study: &Study,
    tables: &[TextTable],
    link: impl Fn(&str) -> Option<String>,
) -> String {
    let a = &study.analysis;
    let it = &study.items;
    let mut out = format!("## {}\n\n", study.title());
    out.push_str(&format!(
        "At the same triangle budget, does RMT look better than what game developers use, and \
         does the answer change with shading? {} against {}, on the {} ({} shading), from the \
         design `experiments/studies/peers.toml`.",
        it.methods.first().map_or("", String::as_str),
        it.methods.get(1..).map_or(String::new(), |m| m.join(", ")),
        it.objects.join(", "),
        it.shadings.join(" and ")
    ));
    if study.simulated() {
        out.push_str(&format!(
            " **No participant has answered yet.** This section is built from {} simulated \
             participants (planted model `{}`, seed {}), each answering {} pair questions and {} \
             controls as the survey serves them, written as the survey export writes them \
             (`data/study/`). It shows what the analysis will report and checks that it \
             recovers what was planted; its numbers are not findings about players.",
            study.value("participants"),
            study.value("model"),
            study.value("seed"),
            study.value("questions"),
            study.value("controls")
        ));
    }
    out.push_str("\n\n");
    let find = |name: &str| tables.iter().find(|t| t.name == name);
    if let Some(t) = find("study_strengths") {
        out.push_str("### Bradley-Terry with ties, per shading\n\n");
        for note in &t.notes {
            out.push_str(note);
            out.push_str("\n\n");
        }
        out.push_str(&t.blocks_markdown());
        if let Some(l) = link("study_strengths") {
            out.push_str(&format!("Table: {l}.\n\n"));
        }
    }
    out.push_str("### Does the ranking change with shading?\n\n");
    match &a.interaction {
        Some(t) => out.push_str(&format!(
            "Likelihood-ratio test of strengths per shading against one strength per method in \
             every shading (method x shading interaction): statistic {:.2} on {} degrees of \
             freedom, p = {:.4}{}.\n\n",
            t.statistic,
            t.df,
            t.p_value,
            if t.converged {
                ""
            } else {
                " (a fit did not converge)"
            }
        )),
        None => out.push_str("Not tested: the study has one shading.\n\n"),
    }
    if !a.shading_pairs.is_empty() {
        out.push_str("Shading pairs, pooled over objects (flat against smooth, same method):\n\n");
        out.push_str(
            "| method | first | second | for first | ties | for second | share first | sign \
             test p |\n| --- | --- | --- | --- | --- | --- | --- | --- |\n",
        );
        for sp in &a.shading_pairs {
            out.push_str(&format!(
                "| {} | {} | {} | {} | {} | {} | {:.3} | {:.4} |\n",
                it.methods[sp.method],
                it.shadings[sp.shadings.0],
                it.shadings[sp.shadings.1],
                sp.counts[0],
                sp.counts[1],
                sp.counts[2],
                sp.share_first,
                sp.p_value
            ));
        }
        out.push('\n');
    }
    let p = &a.position;
    out.push_str("### Position and order\n\n");
    out.push_str(&format!(
        "- left-side odds ratio α = {:.3} (95% interval {:.3}-{:.3}), Wald p = {:.4};\n\
         - decided answers on the left of the screen: {} of {} (binomial p = {:.4});\n\
         - controls (one animation on both sides): left {}, no preference {}, right {} \
         (binomial p on the decided = {:.4});\n\
         - tie parameter v = {:.3};\n",
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
    ));
    for t in &a.order.thirds {
        out.push_str(&format!(
            "- positions {}-{}: {} answers, {:.1}% no preference;\n",
            t.first,
            t.last,
            t.answers,
            100.0 * t.ties as f64 / t.answers.max(1) as f64
        ));
    }
    out.push_str(&format!(
        "- trend of ties over positions (Cochran-Armitage): z = {:.2}, p = {:.4}.\n\n",
        a.order.trend_z, a.order.trend_p
    ));
    if let Some(t) = find("study_power") {
        out.push_str("### Power\n\n");
        for note in &t.notes {
            out.push_str(note);
            out.push_str("\n\n");
        }
        out.push_str(&t.blocks_markdown());
        if let Some(n) = study.power.participants() {
            out.push_str(&format!(
                "The design asks for **{n} participants**: every comparison then reaches 80% \
                 power.\n\n"
            ));
        }
        if let Some(l) = link("study_power") {
            out.push_str(&format!("Table: {l}.\n\n"));
        }
    }
    if let (Some(t), Some(c)) = (find("study_coverage"), &study.coverage) {
        out.push_str("### Method: does the analysis recover what was planted?\n\n");
        for note in &t.notes {
            out.push_str(note);
            out.push_str("\n\n");
        }
        out.push_str(&t.blocks_markdown());
        let num = |key: &str| c.tests.get(key).and_then(|v| v.parse::<f64>().ok());
        if let (Some(tests), Some(rejected)) =
            (num("interaction_tests"), num("interaction_rejections"))
        {
            let planted = c.tests.get("planted_interaction").map(String::as_str) == Some("true");
            out.push_str(&format!(
                "- the interaction test at 5% rejected {} of {} ({:.1}%): {};\n",
                rejected,
                tests,
                100.0 * rejected / tests.max(1.0),
                if planted {
                    "its power against the planted interaction"
                } else {
                    "its false-positive rate, with no interaction planted"
                }
            ));
        }
        if let (Some(found), Some(converged), Some(stated)) = (
            num("bias_detected"),
            num("converged"),
            num("stated_bias_power"),
        ) {
            out.push_str(&format!(
                "- the planted left bias was detected at 5% in {:.1}% of the studies; the \
                 design's stated power is {:.1}%.\n",
                100.0 * found / converged.max(1.0),
                100.0 * stated
            ));
        }
        out.push('\n');
        if let Some(l) = link("study_coverage") {
            out.push_str(&format!("Table: {l}.\n\n"));
        }
    }
    out.push_str(
        "Regenerate the inputs: `experiments study simulate experiments/studies/peers.toml \
         --model experiments/studies/peers-model.toml --seed 1 --out DIR` and `experiments \
         study coverage experiments/studies/peers.toml --model \
         experiments/studies/peers-model.toml --studies 200 --seed 1 --out DIR`, then \
         `experiments report --study DIR`.\n\n",
    );
    out
}
