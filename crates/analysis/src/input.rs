//! Loading and validating the three input files with polars.
//!
//! Every file is read by polars' CSV reader with all columns as strings. Responses in any of the
//! three layouts are reshaped into one tidy frame (`participant`, `row`, `column`, `question`,
//! `value`): wide and survey files by unpivoting their question columns, survey titles by a join
//! with the question ids they name. Question ids and configuration names are resolved by joins, and
//! the resulting frames are walked in row order to report the first fault with its file, row and
//! column.

use std::collections::{BTreeMap, HashSet};
use std::path::{Path, PathBuf};

use polars::prelude::*;

use crate::data::{Answer, AnswerMeta, Configurations, Dataset, InputFormat, Question, Responses};
use crate::error::{io_error, AnalysisError, Result};

/// Paths of the three input files and the responses' layout (`None`: detect it).
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Inputs {
    /// Responses in the wide, long or survey-export layout.
    pub responses: PathBuf,
    /// `question,left,right`: the configurations shown on each side.
    pub questions: PathBuf,
    /// `name,<variable>,<variable>,...`: each configuration's variables.
    pub configurations: PathBuf,
    /// The responses' layout; detected from the header when `None`.
    pub format: Option<InputFormat>,
}

impl Inputs {
    /// The bundled questionnaire under `dir` (`responses.csv`, `questions.csv`,
    /// `configurations.csv`), format detected.
    pub fn in_dir(dir: &Path) -> Self {
        Self {
            responses: dir.join("responses.csv"),
            questions: dir.join("questions.csv"),
            configurations: dir.join("configurations.csv"),
            format: None,
        }
    }
}

/// What to do with the answers while loading.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct LoadOptions {
    /// Participants to leave out (they must exist).
    pub exclude: Vec<String>,
    /// Drop missing answers (and count them) instead of failing.
    pub allow_missing: bool,
}

/// Reads and validates all three files.
pub fn load(inputs: &Inputs, options: &LoadOptions) -> Result<Dataset> {
    let configurations = load_configurations(&inputs.configurations)?;
    let questions = load_questions(&inputs.questions, &configurations)?;
    let responses = load_responses(&inputs.responses, inputs.format, &questions, options)?;
    Ok(Dataset {
        configurations,
        questions,
        responses,
    })
}

/// Reads a CSV file into a frame, every column as a (nullable) string; empty cells are null.
/// Parsed with the `csv` crate (polars' own CSV reader would bring its streaming engine and its
/// cloud I/O stack into the build); a duplicate title, a row with another number of cells than
/// the header, or bytes that are not UTF-8 are errors naming the file and the line.
pub fn read_csv(path: &Path) -> Result<DataFrame> {
    let mut bytes = std::fs::read(path).map_err(io_error(path))?;
    if bytes.starts_with(&[0xEF, 0xBB, 0xBF]) {
        bytes.drain(..3);
    }
    let csv_error = |message: String| AnalysisError::Csv {
        path: path.to_path_buf(),
        message,
    };
    let mut reader = csv::ReaderBuilder::new()
        .has_headers(true)
        .flexible(false)
        .from_reader(bytes.as_slice());
    let header: Vec<String> = match reader.headers() {
        Ok(h) if h.iter().any(|title| !title.is_empty()) => h.iter().map(str::to_string).collect(),
        Ok(_) => return Err(csv_error("the file is empty (no header)".into())),
        Err(e) => return Err(csv_error(e.to_string())),
    };
    let mut seen = HashSet::new();
    for title in &header {
        if !seen.insert(title.trim()) {
            return Err(AnalysisError::DuplicateColumn {
                path: path.to_path_buf(),
                column: title.clone(),
            });
        }
    }
    let mut cells: Vec<Vec<Option<String>>> = vec![Vec::new(); header.len()];
    for record in reader.records() {
        let record = record.map_err(|e| csv_error(e.to_string()))?;
        for (column, cell) in cells.iter_mut().zip(record.iter()) {
            column.push((!cell.is_empty()).then(|| cell.to_string()));
        }
    }
    let height = cells.first().map_or(0, Vec::len);
    let columns = header
        .iter()
        .zip(cells)
        .map(|(title, values)| Column::new(title.as_str().into(), values))
        .collect();
    DataFrame::new(height, columns).map_err(|e| csv_error(e.to_string()))
}

/// Titles of the frame's columns, as written.
fn header(df: &DataFrame) -> Vec<String> {
    df.get_column_names()
        .iter()
        .map(|n| n.to_string())
        .collect()
}

/// The column whose trimmed, lower-cased title is one of `names`.
fn find_column(header: &[String], names: &[&str]) -> Option<String> {
    header
        .iter()
        .find(|h| names.contains(&h.trim().to_ascii_lowercase().as_str()))
        .cloned()
}

fn require_column(path: &Path, header: &[String], names: &[&str]) -> Result<String> {
    find_column(header, names).ok_or_else(|| AnalysisError::MissingColumn {
        path: path.to_path_buf(),
        column: names[0].to_string(),
        hint: format!("expected one of {names:?}; the header is {header:?}"),
    })
}

/// A string column's values, trimmed; null and blank cells become `None`.
fn strings(df: &DataFrame, column: &str) -> Result<Vec<Option<String>>> {
    let column = df.column(column)?.cast(&DataType::String)?;
    Ok(column
        .str()?
        .iter()
        .map(|v| {
            v.map(str::trim)
                .filter(|v| !v.is_empty())
                .map(str::to_string)
        })
        .collect())
}

fn u64s(df: &DataFrame, column: &str) -> Result<Vec<Option<u64>>> {
    let column = df.column(column)?.cast(&DataType::UInt64)?;
    Ok(column.u64()?.iter().collect())
}

/// Values of a column that must never be empty.
fn required_strings(df: &DataFrame, path: &Path, column: &str) -> Result<Vec<String>> {
    strings(df, column)?
        .into_iter()
        .enumerate()
        .map(|(i, v)| {
            v.ok_or_else(|| AnalysisError::EmptyValue {
                path: path.to_path_buf(),
                row: i + 1,
                column: column.to_string(),
            })
        })
        .collect()
}

const PARTICIPANT_COLUMNS: [&str; 5] = [
    "participant",
    "participant id",
    "respondent",
    "respondent id",
    "id",
];
const RESPONSE_COLUMNS: [&str; 3] = ["response", "answer", "value"];
/// Optional columns of the long layout written by `experiments survey export`: the position at
/// which the question was shown, whether its sides were swapped, and the answer time.
pub const SURVEY_COLUMNS: [&str; 3] = ["order", "swapped", "seconds"];

/// Reads the configurations file: a `name` column (or the first column) and one column per
/// variable.
pub fn load_configurations(path: &Path) -> Result<Configurations> {
    let df = read_csv(path)?;
    let header = header(&df);
    let name_column = find_column(&header, &["name", "configuration"])
        .or_else(|| header.first().cloned())
        .ok_or_else(|| AnalysisError::MissingColumn {
            path: path.to_path_buf(),
            column: "name".into(),
            hint: "the configurations file needs a name column and variable columns".into(),
        })?;
    let variables: Vec<String> = header
        .iter()
        .filter(|h| **h != name_column)
        .map(|h| h.trim().to_string())
        .collect();
    if variables.is_empty() {
        return Err(AnalysisError::MissingColumn {
            path: path.to_path_buf(),
            column: "<variable>".into(),
            hint: "the configurations file has no variable columns besides the name".into(),
        });
    }
    let names = required_strings(&df, path, &name_column)?;
    for (i, name) in names.iter().enumerate() {
        if names[..i].contains(name) {
            return Err(AnalysisError::DuplicateConfiguration {
                path: path.to_path_buf(),
                row: i + 1,
                column: name_column.clone(),
                name: name.clone(),
            });
        }
    }
    let mut columns = Vec::new();
    for title in header.iter().filter(|h| **h != name_column) {
        columns.push(required_strings(&df, path, title)?);
    }
    let values = (0..names.len())
        .map(|c| columns.iter().map(|col| col[c].clone()).collect())
        .collect();
    Ok(Configurations {
        path: path.to_path_buf(),
        variables,
        names,
        values,
    })
}

/// Reads the questions file (`question,left,right`) and resolves both sides against the
/// configurations with a join.
pub fn load_questions(path: &Path, configurations: &Configurations) -> Result<Vec<Question>> {
    let df = read_csv(path)?;
    let header = header(&df);
    let question_column = require_column(path, &header, &["question", "id"])?;
    let left_column = require_column(path, &header, &["left"])?;
    let right_column = require_column(path, &header, &["right"])?;
    let ids = required_strings(&df, path, &question_column)?;
    for (i, id) in ids.iter().enumerate() {
        if ids[..i].contains(id) {
            return Err(AnalysisError::DuplicateQuestion {
                path: path.to_path_buf(),
                row: i + 1,
                column: question_column.clone(),
                question: id.clone(),
            });
        }
    }
    let lefts = required_strings(&df, path, &left_column)?;
    let rights = required_strings(&df, path, &right_column)?;
    let index: Vec<u32> = (0..configurations.names.len() as u32).collect();
    let known = df!("name" => configurations.names.clone(), "configuration" => index)?;
    let rows: Vec<u32> = (1..=ids.len() as u32).collect();
    let sides = df!("row" => rows, "left" => lefts.clone(), "right" => rights.clone())?;
    // Both sides resolved to configuration indices; a null marks an unknown name.
    let resolved = sides
        .lazy()
        .left_join(known.clone().lazy(), col("left"), col("name"))
        .rename(["configuration"], ["left_index"], true)
        .left_join(known.lazy(), col("right"), col("name"))
        .rename(["configuration"], ["right_index"], true)
        .sort(["row"], SortMultipleOptions::default())
        .collect()?;
    let left_index = u64s(&resolved, "left_index")?;
    let right_index = u64s(&resolved, "right_index")?;
    let mut questions = Vec::with_capacity(ids.len());
    for (i, id) in ids.into_iter().enumerate() {
        let side = |index: Option<u64>, column: &str, name: &str| {
            index
                .map(|c| c as usize)
                .ok_or_else(|| AnalysisError::UnknownConfiguration {
                    path: path.to_path_buf(),
                    row: i + 1,
                    column: column.to_string(),
                    name: name.to_string(),
                })
        };
        let left = side(left_index[i], &left_column, &lefts[i])?;
        let right = side(right_index[i], &right_column, &rights[i])?;
        questions.push(Question {
            id,
            left,
            right,
            row: i + 1,
        });
    }
    Ok(questions)
}

/// Detects the layout of a responses file from its header.
pub fn detect_format(header: &[String]) -> Option<InputFormat> {
    if header.iter().any(|h| survey_question_number(h).is_some()) {
        return Some(InputFormat::Survey);
    }
    let participant = find_column(header, &PARTICIPANT_COLUMNS).is_some();
    let question = find_column(header, &["question"]).is_some();
    let response = find_column(header, &RESPONSE_COLUMNS).is_some();
    match (participant, question, response) {
        (true, true, true) => Some(InputFormat::Long),
        (true, _, _) => Some(InputFormat::Wide),
        _ => None,
    }
}

/// The number in a survey title such as "Question 7 - Which of these ...".
fn survey_question_number(title: &str) -> Option<u64> {
    let lower = title.trim().to_ascii_lowercase();
    let rest = lower.strip_prefix("question")?.trim_start();
    let digits: String = rest.chars().take_while(|c| c.is_ascii_digit()).collect();
    if digits.is_empty() {
        return None;
    }
    digits.parse().ok()
}

/// Columns of a survey export that carry no answers (timestamps and the like).
fn is_metadata_column(title: &str) -> bool {
    let lower = title.trim().to_ascii_lowercase();
    ["timestamp", "time", "date", "submitted", "start", "end"]
        .iter()
        .any(|m| lower.contains(m))
}

/// Tidy answers before validation: one row per (participant, question) cell.
struct TidyAnswers {
    frame: DataFrame,
    /// Column title to cite for faults in the `question` field (long format) or `None` (the
    /// answer's own column is cited).
    question_column: Option<String>,
}

/// Wide or survey frame -> tidy frame by unpivoting `question_columns`; `question_ids` gives the
/// question id for each of those columns (joined back in).
fn unpivot_questions(
    df: DataFrame,
    participant: Vec<Option<String>>,
    question_columns: &[String],
    question_ids: &[String],
) -> Result<DataFrame> {
    let rows: Vec<u32> = (1..=df.height() as u32).collect();
    let mut frame = df.select(
        question_columns
            .iter()
            .map(|c| PlSmallStr::from(c.as_str())),
    )?;
    frame.with_column(Column::new("participant".into(), participant))?;
    frame.with_column(Column::new("row".into(), rows))?;
    let long = frame.unpivot(
        Some(
            question_columns
                .iter()
                .map(|c| PlSmallStr::from(c.as_str()))
                .collect::<Vec<_>>(),
        ),
        ["participant", "row"],
    )?;
    let titles = df!("column" => question_columns, "question" => question_ids)?;
    Ok(long
        .lazy()
        .rename(["variable"], ["column"], true)
        .with_column(col("value").cast(DataType::String))
        .left_join(titles.lazy(), col("column"), col("column"))
        .collect()?)
}

fn tidy_wide(path: &Path, df: DataFrame) -> Result<TidyAnswers> {
    let header = header(&df);
    let participant_column = require_column(path, &header, &PARTICIPANT_COLUMNS)?;
    let participant = strings(&df, &participant_column)?;
    let question_columns: Vec<String> = header
        .iter()
        .filter(|h| **h != participant_column)
        .cloned()
        .collect();
    let ids: Vec<String> = question_columns
        .iter()
        .map(|c| c.trim().to_string())
        .collect();
    let frame = unpivot_questions(df, participant, &question_columns, &ids)?;
    Ok(TidyAnswers {
        frame,
        question_column: None,
    })
}

fn tidy_survey(path: &Path, df: DataFrame, questions: &[Question]) -> Result<TidyAnswers> {
    let header = header(&df);
    let participant_column = find_column(&header, &PARTICIPANT_COLUMNS);
    let mut question_columns = Vec::new();
    let mut ids = Vec::new();
    for title in &header {
        if Some(title) == participant_column.as_ref() {
            continue;
        }
        if let Some(number) = survey_question_number(title) {
            let wanted = [format!("q{number}"), number.to_string()];
            let id = questions
                .iter()
                .find(|q| wanted.contains(&q.id.to_ascii_lowercase()))
                .ok_or_else(|| AnalysisError::UnknownQuestion {
                    path: path.to_path_buf(),
                    location: "header".into(),
                    column: title.clone(),
                    question: format!("Q{number}"),
                })?;
            question_columns.push(title.clone());
            ids.push(id.id.clone());
        } else if !is_metadata_column(title) {
            return Err(AnalysisError::UnexpectedColumn {
                path: path.to_path_buf(),
                column: title.clone(),
            });
        }
    }
    // Unnamed respondents are numbered in row order, P01, P02, ... (at least two digits).
    let participant = match &participant_column {
        Some(column) => strings(&df, column)?,
        None => {
            let width = df.height().to_string().len().max(2);
            (1..=df.height())
                .map(|i| Some(format!("P{i:0width$}")))
                .collect()
        }
    };
    let frame = unpivot_questions(df, participant, &question_columns, &ids)?;
    Ok(TidyAnswers {
        frame,
        question_column: None,
    })
}

fn tidy_long(path: &Path, df: DataFrame) -> Result<TidyAnswers> {
    let header = header(&df);
    let participant_column = require_column(path, &header, &PARTICIPANT_COLUMNS)?;
    let question_column = require_column(path, &header, &["question"])?;
    let response_column = require_column(path, &header, &RESPONSE_COLUMNS)?;
    for title in &header {
        if ![&participant_column, &question_column, &response_column].contains(&title)
            && !SURVEY_COLUMNS.contains(&title.trim().to_ascii_lowercase().as_str())
        {
            return Err(AnalysisError::UnexpectedColumn {
                path: path.to_path_buf(),
                column: title.clone(),
            });
        }
    }
    // Ids are trimmed before the join with the questions (a survey tool may pad them).
    let rows: Vec<u32> = (1..=df.height() as u32).collect();
    let mut frame = df!(
        "participant" => strings(&df, &participant_column)?,
        "question" => strings(&df, &question_column)?,
        "value" => strings(&df, &response_column)?,
        "column" => vec![response_column.clone(); df.height()],
        "row" => rows,
    )?;
    // The survey server's columns ride along under fixed names.
    for name in SURVEY_COLUMNS {
        if let Some(title) = find_column(&header, &[name]) {
            frame.with_column(Column::new(name.into(), strings(&df, &title)?))?;
        }
    }
    Ok(TidyAnswers {
        frame,
        question_column: Some(question_column),
    })
}

/// Reads, reshapes and validates the responses.
pub fn load_responses(
    path: &Path,
    format: Option<InputFormat>,
    questions: &[Question],
    options: &LoadOptions,
) -> Result<Responses> {
    let df = read_csv(path)?;
    let header = header(&df);
    let format = match format {
        Some(format) => format,
        None => detect_format(&header).ok_or_else(|| AnalysisError::UnknownFormat {
            path: path.to_path_buf(),
            header: header.clone(),
        })?,
    };
    if format == InputFormat::Wide {
        // Header faults first: every non-participant column must be a question id.
        let participant_column = require_column(path, &header, &PARTICIPANT_COLUMNS)?;
        for title in header.iter().filter(|h| **h != participant_column) {
            if !questions.iter().any(|q| q.id == title.trim()) {
                return Err(AnalysisError::UnknownQuestion {
                    path: path.to_path_buf(),
                    location: "header".into(),
                    column: title.clone(),
                    question: title.trim().to_string(),
                });
            }
        }
    }
    let tidy = match format {
        InputFormat::Wide => tidy_wide(path, df)?,
        InputFormat::Survey => tidy_survey(path, df, questions)?,
        InputFormat::Long => tidy_long(path, df)?,
    };
    let ids: Vec<String> = questions.iter().map(|q| q.id.clone()).collect();
    let index: Vec<u32> = (0..questions.len() as u32).collect();
    let known = df!("question" => ids, "question_index" => index)?;
    let cells = tidy
        .frame
        .clone()
        .lazy()
        .left_join(known.lazy(), col("question"), col("question"))
        .sort(["row", "question_index"], SortMultipleOptions::default())
        .collect()?;
    validate_cells(path, format, &cells, &tidy, questions, options)
}

/// Walks the tidy cells in file order and builds the participant x question matrix.
fn validate_cells(
    path: &Path,
    format: InputFormat,
    cells: &DataFrame,
    tidy: &TidyAnswers,
    questions: &[Question],
    options: &LoadOptions,
) -> Result<Responses> {
    let participant = strings(cells, "participant")?;
    let rows = u64s(cells, "row")?;
    let columns = strings(cells, "column")?;
    let question_text = strings(cells, "question")?;
    let question_index = u64s(cells, "question_index")?;
    let values = strings(cells, "value")?;
    let has = |name: &str| cells.get_column_names().iter().any(|c| c.as_str() == name);
    let with_meta = has("order") && has("swapped");
    let optional = |name: &str| -> Result<Vec<Option<String>>> {
        if has(name) {
            strings(cells, name)
        } else {
            Ok(vec![None; cells.height()])
        }
    };
    let (orders, swaps, seconds) = (
        optional("order")?,
        optional("swapped")?,
        optional("seconds")?,
    );
    let mut meta_of: BTreeMap<(usize, usize), AnswerMeta> = BTreeMap::new();

    let mut participants: Vec<String> = Vec::new();
    let mut participant_index: BTreeMap<String, usize> = BTreeMap::new();
    // (participant, question) -> (row, answer or None for an empty cell, column title)
    let mut cell_of: BTreeMap<(usize, usize), (usize, Option<Answer>, String)> = BTreeMap::new();
    for k in 0..cells.height() {
        let row = rows[k].unwrap_or(0) as usize;
        let column = columns[k].clone().unwrap_or_default();
        let Some(name) = participant[k].clone() else {
            return Err(AnalysisError::EmptyValue {
                path: path.to_path_buf(),
                row,
                column: "participant".into(),
            });
        };
        let Some(q) = question_index[k].map(|q| q as usize) else {
            return Err(match &question_text[k] {
                Some(text) => AnalysisError::UnknownQuestion {
                    path: path.to_path_buf(),
                    location: format!("row {row}"),
                    column: tidy.question_column.clone().unwrap_or(column),
                    question: text.clone(),
                },
                None => AnalysisError::EmptyValue {
                    path: path.to_path_buf(),
                    row,
                    column: tidy.question_column.clone().unwrap_or(column),
                },
            });
        };
        let answer = match &values[k] {
            None => None,
            Some(text) => {
                Some(
                    Answer::parse(text).ok_or_else(|| AnalysisError::InvalidAnswer {
                        path: path.to_path_buf(),
                        row,
                        column: column.clone(),
                        value: text.clone(),
                    })?,
                )
            }
        };
        let p = *participant_index.entry(name.clone()).or_insert_with(|| {
            participants.push(name.clone());
            participants.len() - 1
        });
        if let Some((first_row, _, _)) = cell_of.get(&(p, q)) {
            return Err(AnalysisError::DuplicateParticipant {
                path: path.to_path_buf(),
                row,
                first_row: *first_row,
                column,
                participant: name,
                question: questions[q].id.clone(),
            });
        }
        if with_meta {
            let invalid = |column: &str, value: &str, expected: &str| AnalysisError::InvalidValue {
                path: path.to_path_buf(),
                row,
                column: column.to_string(),
                value: value.to_string(),
                expected: expected.to_string(),
            };
            let order_text = orders[k].clone().unwrap_or_default();
            let order = order_text
                .parse::<u32>()
                .ok()
                .filter(|&o| o > 0)
                .ok_or_else(|| invalid("order", &order_text, "a position 1, 2, ..."))?;
            let swapped = match swaps[k].as_deref().unwrap_or("") {
                "0" | "false" => false,
                "1" | "true" => true,
                other => return Err(invalid("swapped", other, "0 or 1")),
            };
            let seconds = match &seconds[k] {
                None => None,
                Some(text) => Some(
                    text.parse::<f64>()
                        .ok()
                        .filter(|s| s.is_finite() && *s >= 0.0)
                        .ok_or_else(|| invalid("seconds", text, "a non-negative number"))?,
                ),
            };
            meta_of.insert(
                (p, q),
                AnswerMeta {
                    order,
                    swapped,
                    seconds,
                },
            );
        }
        cell_of.insert((p, q), (row, answer, column));
    }

    for name in &options.exclude {
        if !participant_index.contains_key(name.trim()) {
            return Err(AnalysisError::UnknownParticipant {
                path: path.to_path_buf(),
                participant: name.clone(),
            });
        }
    }
    let excluded: Vec<String> = options
        .exclude
        .iter()
        .map(|e| e.trim().to_string())
        .collect();

    let mut answers = vec![vec![None; questions.len()]; participants.len()];
    let mut dropped_missing = 0;
    for (p, name) in participants.iter().enumerate() {
        if excluded.contains(name) {
            continue;
        }
        for (q, question) in questions.iter().enumerate() {
            match cell_of.get(&(p, q)) {
                Some((_, Some(answer), _)) => answers[p][q] = Some(*answer),
                missing => {
                    if !options.allow_missing {
                        let location = match missing {
                            Some((row, _, column)) => {
                                format!("row {row}, column '{column}' is empty")
                            }
                            None => "no row or column holds it".into(),
                        };
                        return Err(AnalysisError::MissingAnswer {
                            path: path.to_path_buf(),
                            participant: name.clone(),
                            question: question.id.clone(),
                            location,
                        });
                    }
                    dropped_missing += 1;
                }
            }
        }
    }
    let keep: Vec<bool> = participants.iter().map(|p| !excluded.contains(p)).collect();
    let mut kept_participants = Vec::new();
    let mut kept_answers = Vec::new();
    let mut kept_meta = Vec::new();
    for (p, ((name, row), keep)) in participants.into_iter().zip(answers).zip(keep).enumerate() {
        if keep {
            kept_meta.push(
                (0..questions.len())
                    .map(|q| row[q].and_then(|_| meta_of.get(&(p, q)).copied()))
                    .collect::<Vec<_>>(),
            );
            kept_participants.push(name);
            kept_answers.push(row);
        }
    }
    if kept_participants.is_empty() {
        return Err(AnalysisError::Empty(format!(
            "{}: no participant left after exclusion",
            path.display()
        )));
    }
    let long = long_frame(&kept_participants, &kept_answers)?;
    Ok(Responses {
        path: path.to_path_buf(),
        format,
        participants: kept_participants,
        answers: kept_answers,
        excluded,
        dropped_missing,
        long,
        meta: with_meta.then_some(kept_meta),
    })
}

/// The validated answers as a tidy frame (participant, question index, answer code).
fn long_frame(participants: &[String], answers: &[Vec<Option<Answer>>]) -> Result<DataFrame> {
    let mut who = Vec::new();
    let mut question = Vec::new();
    let mut code = Vec::new();
    for (name, row) in participants.iter().zip(answers) {
        for (q, answer) in row.iter().enumerate() {
            if let Some(answer) = answer {
                who.push(name.as_str());
                question.push(q as u32);
                code.push(answer.code());
            }
        }
    }
    Ok(df!("participant" => who, "question" => question, "answer" => code)?)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn h(titles: &[&str]) -> Vec<String> {
        titles.iter().map(|t| t.to_string()).collect()
    }

    #[test]
    fn formats_are_detected_from_the_header() {
        assert_eq!(
            detect_format(&h(&["participant", "Q1", "Q2"])),
            Some(InputFormat::Wide)
        );
        assert_eq!(
            detect_format(&h(&["participant", "question", "response"])),
            Some(InputFormat::Long)
        );
        assert_eq!(
            detect_format(&h(&["Timestamp", "Question 1 - Which do you prefer?"])),
            Some(InputFormat::Survey)
        );
        assert_eq!(detect_format(&h(&["when", "Q1"])), None);
    }

    #[test]
    fn survey_titles_give_their_question_number() {
        assert_eq!(
            survey_question_number("Question 7 - Which of these two?"),
            Some(7)
        );
        assert_eq!(survey_question_number("question12"), Some(12));
        assert_eq!(survey_question_number("Questionnaire"), None);
        assert_eq!(survey_question_number("Q7"), None);
    }
}
