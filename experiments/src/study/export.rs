//! A study's answers as the survey export's files, written (simulated participants) and read
//! back (any export of the study).
//!
//! | file | columns |
//! |---|---|
//! | `responses.csv` | `participant,question,response,order,swapped,seconds` (the survey export's): the response canonical (`L` prefers the question's `left`) |
//! | `controls.csv` | `participant,control,configuration,name,response,order,seconds`: the response is the screen side |
//! | `questions.csv` | `question,left,right`: configuration ids, canonical sides |
//! | `configurations.csv` | `id,object,method,shading`: the study's names (a study key) |
//! | `participants.csv` | `participant,answered,total,order,swaps` |
//!
//! Reading maps each configuration id to the study's (object, method, shading) through a key
//! with the columns of `configurations.csv` (that file itself by default), and each question to
//! the study's pair with the same two configurations (answers flipped when the question's
//! sides are the pair's the other way round).

use std::collections::BTreeMap;
use std::path::Path;

use anyhow::{bail, Context, Result};
use rmt_analysis::study::simulate::Simulated;
use rmt_analysis::study::{ParticipantPlan, StudyAnswer, StudyControl, StudyItems, StudyPair};
use rmt_analysis::Answer;
use rmt_runfolder::{csv_bytes, write_atomic};

/// Participant name: `P001`, like the survey export.
pub fn participant_name(p: usize) -> String {
    format!("P{:03}", p + 1)
}

/// The question id of pair `k`: `Q{k+1}`.
pub fn question_id(k: usize) -> String {
    format!("Q{}", k + 1)
}

fn write(dir: &Path, name: &str, rows: &[Vec<String>]) -> Result<()> {
    let path = dir.join(name);
    let bytes = csv_bytes(rows).with_context(|| format!("writing {}", path.display()))?;
    write_atomic(&path, &bytes).with_context(|| format!("writing {}", path.display()))
}

fn row<const N: usize>(cells: [&str; N]) -> Vec<String> {
    cells.iter().map(|s| s.to_string()).collect()
}

/// Writes the export files of simulated answers into `dir` (created).
pub fn write_export(
    dir: &Path,
    items: &StudyItems,
    pairs: &[StudyPair],
    plans: &[ParticipantPlan],
    sim: &Simulated,
) -> Result<()> {
    std::fs::create_dir_all(dir).with_context(|| format!("creating {}", dir.display()))?;
    let mut configurations = vec![row(["id", "object", "method", "shading"])];
    for i in 0..items.len() {
        let (o, m, s) = items.parts(i);
        configurations.push(vec![
            items.id(i),
            items.objects[o].clone(),
            items.methods[m].clone(),
            items.shadings[s].clone(),
        ]);
    }
    write(dir, "configurations.csv", &configurations)?;
    let mut questions = vec![row(["question", "left", "right"])];
    for (k, p) in pairs.iter().enumerate() {
        questions.push(vec![question_id(k), items.id(p.first), items.id(p.second)]);
    }
    write(dir, "questions.csv", &questions)?;
    let mut responses = vec![row(rmt_server::export::RESPONSES_COLUMNS)];
    for (a, s) in sim.answers.iter().zip(&sim.answer_seconds) {
        responses.push(vec![
            participant_name(a.participant),
            question_id(a.pair),
            a.response.code().to_string(),
            a.order.to_string(),
            u8::from(a.swapped).to_string(),
            format!("{s:.3}"),
        ]);
    }
    write(dir, "responses.csv", &responses)?;
    let mut controls = vec![row(rmt_server::export::CONTROLS_COLUMNS)];
    for (c, s) in sim.controls.iter().zip(&sim.control_seconds) {
        controls.push(vec![
            participant_name(c.participant),
            format!("C{}", c.item + 1),
            items.id(c.item),
            String::new(),
            c.response.code().to_string(),
            c.order.to_string(),
            format!("{s:.3}"),
        ]);
    }
    write(dir, "controls.csv", &controls)?;
    let mut participants = vec![row(["participant", "answered", "total", "order", "swaps"])];
    for (p, plan) in plans.iter().enumerate() {
        let order: Vec<String> = plan
            .questions
            .iter()
            .map(|s| match s.pair {
                Some(k) => question_id(k),
                None => format!("C{}", s.left + 1),
            })
            .collect();
        let swaps: String = plan
            .questions
            .iter()
            .map(|s| if s.swapped { '1' } else { '0' })
            .collect();
        participants.push(vec![
            participant_name(p),
            plan.questions.len().to_string(),
            plan.questions.len().to_string(),
            order.join(" "),
            swaps,
        ]);
    }
    write(dir, "participants.csv", &participants)
}

/// A CSV file as header -> column index and rows.
struct Csv {
    path: std::path::PathBuf,
    header: Vec<String>,
    rows: Vec<Vec<String>>,
}

impl Csv {
    fn read(path: &Path) -> Result<Self> {
        let mut reader = csv::ReaderBuilder::new()
            .trim(csv::Trim::All)
            .from_path(path)
            .with_context(|| format!("reading {}", path.display()))?;
        let header: Vec<String> = reader
            .headers()
            .with_context(|| format!("reading {}", path.display()))?
            .iter()
            .map(String::from)
            .collect();
        let mut rows = Vec::new();
        for r in reader.records() {
            let r = r.with_context(|| format!("reading {}", path.display()))?;
            rows.push(r.iter().map(String::from).collect());
        }
        Ok(Self {
            path: path.to_path_buf(),
            header,
            rows,
        })
    }

    fn column(&self, name: &str) -> Result<usize> {
        self.header
            .iter()
            .position(|h| h == name)
            .with_context(|| format!("{}: no `{name}` column", self.path.display()))
    }
}

/// A study's answers read from an export folder.
#[derive(Clone, Debug, PartialEq)]
pub struct ReadAnswers {
    /// Answers to pairs.
    pub answers: Vec<StudyAnswer>,
    /// Control answers.
    pub controls: Vec<StudyControl>,
}

/// Reads `responses.csv`, `questions.csv` and (when present) `controls.csv` from `dir`, the
/// configurations mapped through `key` (`id,object,method,shading`; default
/// `dir/configurations.csv`).
pub fn read_export(
    dir: &Path,
    key: Option<&Path>,
    items: &StudyItems,
    pairs: &[StudyPair],
) -> Result<ReadAnswers> {
    let key_path = key.map_or_else(|| dir.join("configurations.csv"), Path::to_path_buf);
    let key = Csv::read(&key_path)?;
    let (id, object, method, shading) = (
        key.column("id")?,
        key.column("object")?,
        key.column("method")?,
        key.column("shading")?,
    );
    let mut item_of: BTreeMap<String, usize> = BTreeMap::new();
    for (r, row) in key.rows.iter().enumerate() {
        let find = |list: &[String], v: &str, what: &str| {
            list.iter().position(|x| x == v).with_context(|| {
                format!(
                    "{} line {}: the study has no {what} `{v}`",
                    key_path.display(),
                    r + 2
                )
            })
        };
        let o = find(&items.objects, &row[object], "object")?;
        let m = find(&items.methods, &row[method], "method")?;
        let s = find(&items.shadings, &row[shading], "shading")?;
        item_of.insert(row[id].clone(), items.item(o, m, s));
    }
    let questions = Csv::read(&dir.join("questions.csv"))?;
    let (q, l, r) = (
        questions.column("question")?,
        questions.column("left")?,
        questions.column("right")?,
    );
    // Question id -> (pair, flipped).
    let mut pair_of: BTreeMap<String, (usize, bool)> = BTreeMap::new();
    for (n, row) in questions.rows.iter().enumerate() {
        let item = |c: usize| {
            item_of.get(&row[c]).copied().with_context(|| {
                format!(
                    "questions.csv line {}: configuration `{}` is not in {}",
                    n + 2,
                    row[c],
                    key_path.display()
                )
            })
        };
        let (a, b) = (item(l)?, item(r)?);
        let found = pairs.iter().position(|p| (p.first, p.second) == (a, b));
        let flipped = pairs.iter().position(|p| (p.first, p.second) == (b, a));
        let entry = match (found, flipped) {
            (Some(k), _) => (k, false),
            (None, Some(k)) => (k, true),
            (None, None) => bail!(
                "questions.csv line {}: `{}` against `{}` is not a pair of the study",
                n + 2,
                row[l],
                row[r]
            ),
        };
        pair_of.insert(row[q].clone(), entry);
    }
    let responses = Csv::read(&dir.join("responses.csv"))?;
    let (cp, cq, cr, co, cs) = (
        responses.column("participant")?,
        responses.column("question")?,
        responses.column("response")?,
        responses.column("order")?,
        responses.column("swapped")?,
    );
    let mut participants: BTreeMap<String, usize> = BTreeMap::new();
    let mut answers = Vec::new();
    for (n, row) in responses.rows.iter().enumerate() {
        let line = n + 2;
        let next = participants.len();
        let participant = *participants.entry(row[cp].clone()).or_insert(next);
        let &(pair, flipped) = pair_of.get(&row[cq]).with_context(|| {
            format!("responses.csv line {line}: unknown question `{}`", row[cq])
        })?;
        let response = Answer::parse(&row[cr])
            .with_context(|| format!("responses.csv line {line}: response `{}`", row[cr]))?;
        let order: u32 = row[co]
            .parse()
            .with_context(|| format!("responses.csv line {line}: order `{}`", row[co]))?;
        let swapped = match row[cs].as_str() {
            "0" | "false" => false,
            "1" | "true" => true,
            other => bail!("responses.csv line {line}: swapped `{other}` (expected 0 or 1)"),
        };
        let flip = |a: Answer| match a {
            Answer::Left => Answer::Right,
            Answer::Right => Answer::Left,
            Answer::NoPreference => Answer::NoPreference,
        };
        answers.push(StudyAnswer {
            participant,
            pair,
            order,
            swapped: swapped != flipped,
            response: if flipped { flip(response) } else { response },
        });
    }
    let mut controls = Vec::new();
    let path = dir.join("controls.csv");
    if path.exists() {
        let c = Csv::read(&path)?;
        let (cp, cc, cr, co) = (
            c.column("participant")?,
            c.column("configuration")?,
            c.column("response")?,
            c.column("order")?,
        );
        for (n, row) in c.rows.iter().enumerate() {
            let line = n + 2;
            let next = participants.len();
            let participant = *participants.entry(row[cp].clone()).or_insert(next);
            let item = *item_of.get(&row[cc]).with_context(|| {
                format!(
                    "controls.csv line {line}: unknown configuration `{}`",
                    row[cc]
                )
            })?;
            controls.push(StudyControl {
                participant,
                item,
                order: row[co]
                    .parse()
                    .with_context(|| format!("controls.csv line {line}: order"))?,
                response: Answer::parse(&row[cr])
                    .with_context(|| format!("controls.csv line {line}: response"))?,
            });
        }
    }
    Ok(ReadAnswers { answers, controls })
}
