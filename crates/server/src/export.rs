//! The survey export: the stored answers as the files `experiments analyse` reads, plus the
//! participants and a summary.
//!
//! | file | columns |
//! |---|---|
//! | `responses.csv` | `participant,question,response,order,swapped,seconds`: real questions, the response mapped back to the canonical left/right of `questions.csv`; `order` is the 1-based position the participant saw it at, `swapped` 1 when the canonical left was shown on the right, `seconds` the answer time measured by the page (the server's time since the previous answer when the page sent none) |
//! | `controls.csv` | `participant,control,configuration,name,response,order,seconds`: control questions (one animation on both sides), the response as the screen side |
//! | `questions.csv` | `question,left,right`: configuration ids (canonical sides) |
//! | `configurations.csv` | `id` and one column per variable |
//! | `participants.csv` | `participant,token,started,finished,answered,total,completed,order,swaps` |
//! | `summary.csv` | per question: `question,kind,answers,L,N,R,median_seconds` |
//! | `summary.md` | completion and the median time per question, readable |
//!
//! Participants are named `P001`, `P002`, ... in order of arrival.

use std::collections::BTreeMap;
use std::fmt::Write as _;
use std::path::{Path, PathBuf};

use crate::clock::iso_utc;
use crate::study::Study;

/// A participant as exported.
#[derive(Clone, Debug)]
pub struct ExportParticipant {
    /// Arrival number (1-based).
    pub seq: i64,
    /// Session token.
    pub token: String,
    /// Start (consent), ms since the epoch.
    pub started_ms: i64,
    /// Finish, ms since the epoch.
    pub finished_ms: Option<i64>,
    /// Question ids in the order shown.
    pub order: Vec<String>,
    /// Per shown position: sides swapped.
    pub swaps: Vec<bool>,
}

/// An answer as exported.
#[derive(Clone, Debug)]
pub struct ExportAnswer {
    /// Participant arrival number.
    pub participant: i64,
    /// Question id.
    pub question: String,
    /// 1-based position shown.
    pub position: i64,
    /// Whether the canonical sides were swapped on screen.
    pub swapped: bool,
    /// Side clicked.
    pub shown: String,
    /// Canonical answer.
    pub response: String,
    /// Answer time measured by the page.
    pub client_ms: Option<i64>,
    /// Time since the previous answer (or the start), measured by the server.
    pub server_ms: i64,
    /// When it was stored.
    pub answered_ms: i64,
}

impl ExportAnswer {
    /// Seconds the participant took (page measure, else server measure).
    pub fn seconds(&self) -> f64 {
        self.client_ms.unwrap_or(self.server_ms) as f64 / 1000.0
    }
}

/// Export files in memory, in a fixed order.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Export {
    /// `(file name, contents)`.
    pub files: Vec<(String, Vec<u8>)>,
    /// Participants with at least one answer.
    pub participants: usize,
    /// Participants who finished.
    pub completed: usize,
    /// Answers to real questions.
    pub answers: usize,
    /// Answers to controls.
    pub control_answers: usize,
}

/// The export file that `experiments analyse --responses` reads.
pub const RESPONSES_FILE: &str = "responses.csv";
/// `question,left,right` with configuration ids.
pub const QUESTIONS_FILE: &str = "questions.csv";
/// Configurations and their variables.
pub const CONFIGURATIONS_FILE: &str = "configurations.csv";
/// Control answers.
pub const CONTROLS_FILE: &str = "controls.csv";

/// The columns of [`RESPONSES_FILE`], in order (what `analyse` reads; simulated studies write
/// the same).
pub const RESPONSES_COLUMNS: [&str; 6] = [
    "participant",
    "question",
    "response",
    "order",
    "swapped",
    "seconds",
];

/// The columns of [`CONTROLS_FILE`], in order.
pub const CONTROLS_COLUMNS: [&str; 7] = [
    "participant",
    "control",
    "configuration",
    "name",
    "response",
    "order",
    "seconds",
];
/// Participants.
pub const PARTICIPANTS_FILE: &str = "participants.csv";

/// Every export file, in the order written.
pub const EXPORT_FILES: [&str; 7] = [
    RESPONSES_FILE,
    CONTROLS_FILE,
    QUESTIONS_FILE,
    CONFIGURATIONS_FILE,
    PARTICIPANTS_FILE,
    "summary.csv",
    "summary.md",
];

/// Participant name in exports.
pub fn participant_name(seq: i64) -> String {
    format!("P{seq:03}")
}

fn csv_bytes(header: &[&str], rows: &[Vec<String>]) -> Result<Vec<u8>, String> {
    let mut writer = csv::Writer::from_writer(Vec::new());
    writer.write_record(header).map_err(|e| e.to_string())?;
    for row in rows {
        writer.write_record(row).map_err(|e| e.to_string())?;
    }
    writer.into_inner().map_err(|e| e.to_string())
}

fn median(values: &mut [f64]) -> Option<f64> {
    if values.is_empty() {
        return None;
    }
    values.sort_by(f64::total_cmp);
    let n = values.len();
    Some(if n % 2 == 1 {
        values[n / 2]
    } else {
        (values[n / 2 - 1] + values[n / 2]) / 2.0
    })
}

impl Export {
    /// Builds the files from the stored rows.
    pub fn build(
        study: &Study,
        participants: Vec<ExportParticipant>,
        answers: Vec<ExportAnswer>,
    ) -> Result<Export, String> {
        let kind_of: BTreeMap<&str, usize> = study
            .questions
            .iter()
            .enumerate()
            .map(|(k, q)| (q.id.as_str(), k))
            .collect();
        let mut responses = Vec::new();
        let mut controls = Vec::new();
        let mut answered: BTreeMap<i64, usize> = BTreeMap::new();
        let mut per_question: Vec<(Vec<f64>, [u64; 3])> =
            vec![(Vec::new(), [0; 3]); study.questions.len()];
        for a in &answers {
            let q = *kind_of
                .get(a.question.as_str())
                .ok_or_else(|| format!("answer to unknown question `{}`", a.question))?;
            let question = &study.questions[q];
            *answered.entry(a.participant).or_default() += 1;
            let seconds = format!("{:.3}", a.seconds());
            per_question[q].0.push(a.seconds());
            let slot = match a.response.as_str() {
                "L" => 0,
                "N" => 1,
                _ => 2,
            };
            per_question[q].1[slot] += 1;
            if question.is_control() {
                let c = &study.configurations[question.left];
                controls.push(vec![
                    participant_name(a.participant),
                    question.id.clone(),
                    c.id.clone(),
                    c.name.clone(),
                    a.shown.clone(),
                    a.position.to_string(),
                    seconds,
                ]);
            } else {
                responses.push(vec![
                    participant_name(a.participant),
                    question.id.clone(),
                    a.response.clone(),
                    a.position.to_string(),
                    u8::from(a.swapped).to_string(),
                    seconds,
                ]);
            }
        }
        let mut files = Vec::new();
        files.push((
            RESPONSES_FILE.to_string(),
            csv_bytes(&RESPONSES_COLUMNS, &responses)?,
        ));
        files.push((
            CONTROLS_FILE.to_string(),
            csv_bytes(&CONTROLS_COLUMNS, &controls)?,
        ));
        let question_rows: Vec<Vec<String>> = study
            .questions
            .iter()
            .filter(|q| !q.is_control())
            .map(|q| {
                vec![
                    q.id.clone(),
                    study.configurations[q.left].id.clone(),
                    study.configurations[q.right].id.clone(),
                ]
            })
            .collect();
        files.push((
            QUESTIONS_FILE.to_string(),
            csv_bytes(&["question", "left", "right"], &question_rows)?,
        ));
        let mut header = vec!["id"];
        header.extend(study.variables.iter().map(String::as_str));
        let configuration_rows: Vec<Vec<String>> = study
            .configurations
            .iter()
            .map(|c| {
                let mut row = vec![c.id.clone()];
                row.extend(c.values.iter().cloned());
                row
            })
            .collect();
        files.push((
            CONFIGURATIONS_FILE.to_string(),
            csv_bytes(&header, &configuration_rows)?,
        ));
        let total =
            study.real_questions_per_participant() + study.questions.len() - study.real_questions();
        let mut completed = 0;
        let mut durations = Vec::new();
        let participant_rows: Vec<Vec<String>> = participants
            .iter()
            .map(|p| {
                let n = answered.get(&p.seq).copied().unwrap_or(0);
                if let Some(end) = p.finished_ms {
                    completed += 1;
                    durations.push((end - p.started_ms) as f64 / 1000.0);
                }
                vec![
                    participant_name(p.seq),
                    p.token.clone(),
                    iso_utc(p.started_ms),
                    p.finished_ms.map(iso_utc).unwrap_or_default(),
                    n.to_string(),
                    p.order.len().to_string(),
                    u8::from(p.finished_ms.is_some()).to_string(),
                    p.order.join(" "),
                    p.swaps.iter().map(|&s| if s { '1' } else { '0' }).collect(),
                ]
            })
            .collect();
        files.push((
            PARTICIPANTS_FILE.to_string(),
            csv_bytes(
                &[
                    "participant",
                    "token",
                    "started",
                    "finished",
                    "answered",
                    "total",
                    "completed",
                    "order",
                    "swaps",
                ],
                &participant_rows,
            )?,
        ));
        let mut summary_rows = Vec::new();
        let mut md = String::new();
        let started = participants.len();
        let with_answers = answered.len();
        let _ = writeln!(md, "# Survey summary\n");
        let _ = writeln!(
            md,
            "- Participants: {started} started, {with_answers} answered at least one question, \
             {completed} completed ({:.0}% of those who started)",
            if started > 0 {
                100.0 * completed as f64 / started as f64
            } else {
                0.0
            }
        );
        let _ = writeln!(
            md,
            "- Answers: {} to real questions, {} to controls ({} questions per session)",
            responses.len(),
            controls.len(),
            total
        );
        if let Some(m) = median(&mut durations) {
            let _ = writeln!(
                md,
                "- Median session time of completed participants: {m:.1} s"
            );
        }
        let _ = writeln!(
            md,
            "\nCounts are canonical (the left and right of questions.csv); controls count the \
             screen side.\n\n| question | kind | answers | L | N | R | median s |\n|---|---|---:|---:|---:|---:|---:|"
        );
        for (q, (mut times, counts)) in study.questions.iter().zip(per_question) {
            let med = median(&mut times);
            let med_text = med.map(|m| format!("{m:.3}")).unwrap_or_default();
            let _ = writeln!(
                md,
                "| {} | {} | {} | {} | {} | {} | {} |",
                q.id,
                q.kind,
                times.len(),
                counts[0],
                counts[1],
                counts[2],
                med.map(|m| format!("{m:.1}")).unwrap_or_else(|| "-".into())
            );
            summary_rows.push(vec![
                q.id.clone(),
                q.kind.clone(),
                times.len().to_string(),
                counts[0].to_string(),
                counts[1].to_string(),
                counts[2].to_string(),
                med_text,
            ]);
        }
        files.push((
            "summary.csv".to_string(),
            csv_bytes(
                &[
                    "question",
                    "kind",
                    "answers",
                    "L",
                    "N",
                    "R",
                    "median_seconds",
                ],
                &summary_rows,
            )?,
        ));
        files.push(("summary.md".to_string(), md.into_bytes()));
        Ok(Export {
            files,
            participants: with_answers,
            completed,
            answers: responses.len(),
            control_answers: controls.len(),
        })
    }

    /// The contents of one file.
    pub fn file(&self, name: &str) -> Option<&[u8]> {
        self.files
            .iter()
            .find(|(n, _)| n == name)
            .map(|(_, b)| b.as_slice())
    }

    /// Writes every file into `dir` (created if needed); each file is written to a temporary
    /// name and renamed, so no half-written file is left under its real name.
    pub fn write_to(&self, dir: &Path) -> std::io::Result<Vec<PathBuf>> {
        std::fs::create_dir_all(dir)?;
        let mut written = Vec::new();
        for (name, bytes) in &self.files {
            let path = dir.join(name);
            let tmp = dir.join(format!(".{name}.tmp"));
            std::fs::write(&tmp, bytes)?;
            std::fs::rename(&tmp, &path)?;
            written.push(path);
        }
        Ok(written)
    }
}
