//! The survey's SQLite store: the study, participants with their plans, and answers.
//!
//! One database file per survey (`<run>/survey.sqlite` by default), in WAL mode with
//! `synchronous=FULL`: every answer is its own `IMMEDIATE` transaction, committed before the
//! server acknowledges it, so an acknowledged answer survives a crash of the server (and of the
//! machine). The study (configurations, questions, seed) is stored as JSON in `meta`, so an
//! export needs nothing but the database; restarting the server on a database of another study is
//! refused.
//!
//! **A second answer to the same question is rejected** ([`StoreError::AlreadyAnswered`], HTTP
//! 409) and the first answer stands: answers are final once stored, which also makes a retried
//! request harmless (the reply names the stored answer).
//!
//! Tables:
//! ```text
//! meta(key, value)                      schema version, study JSON, created
//! participants(seq, token, started_ms, finished_ms, question_order, swaps)
//! answers(participant, question, position, swapped, shown, response,
//!         client_ms, server_ms, answered_ms)          primary key (participant, question)
//! ```
//! `question_order` lists question ids in the order shown, `swaps` one `0`/`1` per shown
//! position; `shown` is the side clicked on screen, `response` the same answer mapped back to the
//! question's canonical left and right.

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};
use std::sync::Mutex;

use rusqlite::{params, Connection, OptionalExtension, TransactionBehavior};
use serde::Serialize;

use crate::clock::{iso_utc, now_ms};
use crate::study::Study;

/// Version of the schema below.
pub const SCHEMA_VERSION: &str = "1";

const SCHEMA: &str = "
CREATE TABLE IF NOT EXISTS meta (key TEXT PRIMARY KEY, value TEXT NOT NULL) STRICT;
CREATE TABLE IF NOT EXISTS participants (
  seq INTEGER PRIMARY KEY,
  token TEXT NOT NULL UNIQUE,
  started_ms INTEGER NOT NULL,
  finished_ms INTEGER,
  question_order TEXT NOT NULL,
  swaps TEXT NOT NULL
) STRICT;
CREATE TABLE IF NOT EXISTS answers (
  participant INTEGER NOT NULL REFERENCES participants(seq),
  question TEXT NOT NULL,
  position INTEGER NOT NULL,
  swapped INTEGER NOT NULL,
  shown TEXT NOT NULL CHECK (shown IN ('L', 'N', 'R')),
  response TEXT NOT NULL CHECK (response IN ('L', 'N', 'R')),
  client_ms INTEGER,
  server_ms INTEGER NOT NULL,
  answered_ms INTEGER NOT NULL,
  PRIMARY KEY (participant, question)
) STRICT;
";

/// Errors of the store. The survey routes map each to an HTTP status.
#[derive(Debug, thiserror::Error)]
pub enum StoreError {
    /// SQLite failed.
    #[error("database {path}: {source}")]
    Sqlite {
        /// The database file.
        path: PathBuf,
        /// What SQLite said.
        source: rusqlite::Error,
    },
    /// The database holds another study, or is not a survey database.
    #[error("database {path}: {message}")]
    BadDatabase {
        /// The database file.
        path: PathBuf,
        /// What is wrong.
        message: String,
    },
    /// No session has this token.
    #[error("unknown participant token")]
    UnknownToken,
    /// The item number is not one of the session's questions.
    #[error("unknown question {item}: this session has questions 1 to {total}")]
    UnknownItem {
        /// The number sent.
        item: u64,
        /// Questions in the session.
        total: usize,
    },
    /// The question was answered before; the first answer stands.
    #[error("question {item} was already answered ({stored}); answers are final")]
    AlreadyAnswered {
        /// The question number.
        item: usize,
        /// The stored answer, as shown on screen.
        stored: String,
    },
    /// The session is finished; no more answers are taken.
    #[error("this session is finished; no more answers are taken")]
    Finished,
    /// Finishing needs every question answered.
    #[error("{missing} of {total} questions are not answered yet")]
    Unfinished {
        /// Unanswered questions.
        missing: usize,
        /// Questions in the session.
        total: usize,
    },
    /// Writing an export failed.
    #[error("{path}: {source}")]
    Io {
        /// The file.
        path: PathBuf,
        /// The error.
        source: std::io::Error,
    },
}

/// Result of the store.
pub type Result<T, E = StoreError> = std::result::Result<T, E>;

/// A side of the screen, or no preference; also the canonical answer after unswapping.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
pub enum Side {
    /// Left.
    #[serde(rename = "L")]
    Left,
    /// No preference.
    #[serde(rename = "N")]
    None,
    /// Right.
    #[serde(rename = "R")]
    Right,
}

impl Side {
    /// Reads `L`, `N` or `R`.
    pub fn parse(text: &str) -> Option<Side> {
        match text {
            "L" => Some(Side::Left),
            "N" => Some(Side::None),
            "R" => Some(Side::Right),
            _ => None,
        }
    }

    /// `L`, `N` or `R`.
    pub fn code(self) -> &'static str {
        match self {
            Side::Left => "L",
            Side::None => "N",
            Side::Right => "R",
        }
    }

    /// Left and right exchanged.
    pub fn mirrored(self) -> Side {
        match self {
            Side::Left => Side::Right,
            Side::None => Side::None,
            Side::Right => Side::Left,
        }
    }
}

/// One question of a session as the participant's browser sees it: a number and two
/// anonymous animation names, nothing else.
#[derive(Clone, Debug, PartialEq, Eq, Serialize)]
pub struct ItemView {
    /// 1-based position in this participant's order.
    pub item: usize,
    /// Animation name shown on the left.
    pub left: String,
    /// Animation name shown on the right.
    pub right: String,
}

/// A stored answer as the participant gave it.
#[derive(Clone, Debug, PartialEq, Eq, Serialize)]
pub struct ItemAnswer {
    /// The question number.
    pub item: usize,
    /// The side clicked.
    pub answer: Side,
}

/// A participant's session as sent to their browser (blind: names only).
#[derive(Clone, Debug, PartialEq, Eq, Serialize)]
pub struct SessionView {
    /// The session token (the participant's only credential).
    pub token: String,
    /// Number of questions.
    pub total: usize,
    /// Questions in order.
    pub items: Vec<ItemView>,
    /// Answers given so far.
    pub answers: Vec<ItemAnswer>,
    /// Whether the participant finished.
    pub finished: bool,
}

/// Acknowledgement of a stored answer.
#[derive(Clone, Debug, PartialEq, Eq, Serialize)]
pub struct AnswerAck {
    /// The question number.
    pub item: usize,
    /// The stored answer as clicked.
    pub answer: Side,
    /// Answers stored in this session.
    pub answered: usize,
    /// Questions in the session.
    pub total: usize,
}

/// Live counts for the admin page.
#[derive(Clone, Debug, PartialEq, Eq, Serialize)]
pub struct Counts {
    /// Sessions started (consent given).
    pub participants: u64,
    /// Sessions finished.
    pub finished: u64,
    /// Answers to real questions.
    pub answers: u64,
    /// Answers to control questions.
    pub control_answers: u64,
    /// Questions per session.
    pub questions: usize,
    /// Answers per question id, in study order.
    pub per_question: Vec<(String, u64)>,
}

/// One participant's row.
struct ParticipantRow {
    seq: i64,
    token: String,
    started_ms: i64,
    finished_ms: Option<i64>,
    order: Vec<usize>,
    swaps: Vec<bool>,
}

/// One stored answer.
struct AnswerRow {
    participant: i64,
    question: String,
    position: i64,
    swapped: bool,
    shown: String,
    response: String,
    client_ms: Option<i64>,
    server_ms: i64,
    answered_ms: i64,
}

/// The survey database.
pub struct Store {
    conn: Mutex<Connection>,
    study: Study,
    path: PathBuf,
}

impl Store {
    fn sql<T>(&self, r: rusqlite::Result<T>) -> Result<T> {
        r.map_err(|source| StoreError::Sqlite {
            path: self.path.clone(),
            source,
        })
    }

    fn connect(path: &Path) -> Result<Connection> {
        let sql_error = |source| StoreError::Sqlite {
            path: path.to_path_buf(),
            source,
        };
        let conn = Connection::open(path).map_err(sql_error)?;
        conn.busy_timeout(std::time::Duration::from_secs(10))
            .map_err(sql_error)?;
        let mode: String = conn
            .query_row("PRAGMA journal_mode=WAL", [], |r| r.get(0))
            .map_err(sql_error)?;
        if !mode.eq_ignore_ascii_case("wal") {
            return Err(StoreError::BadDatabase {
                path: path.to_path_buf(),
                message: format!("could not switch to WAL mode (journal mode is {mode})"),
            });
        }
        conn.execute_batch("PRAGMA synchronous=FULL; PRAGMA foreign_keys=ON;")
            .map_err(sql_error)?;
        Ok(conn)
    }

    /// Opens (or creates) the database for `study`. A database that already holds a study must
    /// hold this one: its participants and answers are kept and the survey resumes.
    pub fn open(path: &Path, study: &Study) -> Result<Store> {
        let conn = Self::connect(path)?;
        let store = Store {
            conn: Mutex::new(conn),
            study: study.clone(),
            path: path.to_path_buf(),
        };
        let json = serde_json::to_string(study).map_err(|e| StoreError::BadDatabase {
            path: path.to_path_buf(),
            message: e.to_string(),
        })?;
        {
            let mut conn = store.lock();
            let tx = store.sql(conn.transaction_with_behavior(TransactionBehavior::Immediate))?;
            store.sql(tx.execute_batch(SCHEMA))?;
            let stored: Option<String> = store.sql(
                tx.query_row("SELECT value FROM meta WHERE key = 'study'", [], |r| {
                    r.get(0)
                })
                .optional(),
            )?;
            match stored {
                None => {
                    for (key, value) in [
                        ("schema", SCHEMA_VERSION.to_string()),
                        ("study", json),
                        ("created", iso_utc(now_ms())),
                    ] {
                        store.sql(tx.execute(
                            "INSERT INTO meta (key, value) VALUES (?1, ?2)",
                            params![key, value],
                        ))?;
                    }
                }
                Some(stored) => {
                    let same = serde_json::from_str::<Study>(&stored)
                        .map(|s| &s == study)
                        .unwrap_or(false);
                    if !same {
                        return Err(StoreError::BadDatabase {
                            path: path.to_path_buf(),
                            message: "it holds the answers of another study (other questions, \
                                      names, controls or seed); use another --db"
                                .into(),
                        });
                    }
                }
            }
            store.sql(tx.commit())?;
        }
        Ok(store)
    }

    /// Opens an existing survey database (for exports); the study is read from it.
    pub fn open_existing(path: &Path) -> Result<Store> {
        if !path.is_file() {
            return Err(StoreError::BadDatabase {
                path: path.to_path_buf(),
                message: "no such file".into(),
            });
        }
        let conn = Self::connect(path)?;
        let bad = |message: String| StoreError::BadDatabase {
            path: path.to_path_buf(),
            message,
        };
        let stored: Option<String> = conn
            .query_row("SELECT value FROM meta WHERE key = 'study'", [], |r| {
                r.get(0)
            })
            .optional()
            .map_err(|e| bad(format!("not a survey database ({e})")))?;
        let stored = stored.ok_or_else(|| bad("not a survey database (no study)".into()))?;
        let study: Study = serde_json::from_str(&stored)
            .map_err(|e| bad(format!("the stored study is unreadable: {e}")))?;
        Ok(Store {
            conn: Mutex::new(conn),
            study,
            path: path.to_path_buf(),
        })
    }

    fn lock(&self) -> std::sync::MutexGuard<'_, Connection> {
        // A panic while holding the lock cannot leave a transaction half-done (SQLite rolls an
        // unfinished transaction back), so a poisoned lock is still usable.
        self.conn.lock().unwrap_or_else(|e| e.into_inner())
    }

    /// The study.
    pub fn study(&self) -> &Study {
        &self.study
    }

    /// The database file.
    pub fn path(&self) -> &Path {
        &self.path
    }

    /// Starts a session (after consent) with a fresh random token; returns its view.
    pub fn create_session(&self, token: &str) -> Result<SessionView> {
        let mut conn = self.lock();
        let tx = self.sql(conn.transaction_with_behavior(TransactionBehavior::Immediate))?;
        let seq: i64 = self.sql(tx.query_row(
            "SELECT COALESCE(MAX(seq), 0) + 1 FROM participants",
            [],
            |r| r.get(0),
        ))?;
        let plan = self.study.plan_for(token, seq as u64);
        let order: Vec<&str> = plan
            .order
            .iter()
            .map(|&q| self.study.questions[q].id.as_str())
            .collect();
        let swaps: String = plan
            .order
            .iter()
            .map(|&q| if plan.swapped[q] { '1' } else { '0' })
            .collect();
        self.sql(tx.execute(
            "INSERT INTO participants (seq, token, started_ms, question_order, swaps) \
             VALUES (?1, ?2, ?3, ?4, ?5)",
            params![seq, token, now_ms(), order.join(" "), swaps],
        ))?;
        self.sql(tx.commit())?;
        let row = self.participant(&conn, token)?;
        Ok(self.view(&row, &[]))
    }

    fn participant(&self, conn: &Connection, token: &str) -> Result<ParticipantRow> {
        let row = self.sql(
            conn.query_row(
                "SELECT seq, token, started_ms, finished_ms, question_order, swaps \
                 FROM participants WHERE token = ?1",
                params![token],
                |r| {
                    Ok((
                        r.get::<_, i64>(0)?,
                        r.get::<_, String>(1)?,
                        r.get::<_, i64>(2)?,
                        r.get::<_, Option<i64>>(3)?,
                        r.get::<_, String>(4)?,
                        r.get::<_, String>(5)?,
                    ))
                },
            )
            .optional(),
        )?;
        let (seq, token, started_ms, finished_ms, order, swaps) =
            row.ok_or(StoreError::UnknownToken)?;
        self.parse_participant(seq, token, started_ms, finished_ms, &order, &swaps)
    }

    fn parse_participant(
        &self,
        seq: i64,
        token: String,
        started_ms: i64,
        finished_ms: Option<i64>,
        order: &str,
        swaps: &str,
    ) -> Result<ParticipantRow> {
        let order = order
            .split_whitespace()
            .map(|id| {
                self.study
                    .question_index(id)
                    .ok_or_else(|| StoreError::BadDatabase {
                        path: self.path.clone(),
                        message: format!("participant {seq}: unknown question `{id}` in order"),
                    })
            })
            .collect::<Result<Vec<usize>>>()?;
        let swaps: Vec<bool> = swaps.chars().map(|c| c == '1').collect();
        if swaps.len() != order.len() {
            return Err(StoreError::BadDatabase {
                path: self.path.clone(),
                message: format!("participant {seq}: order and swaps differ in length"),
            });
        }
        Ok(ParticipantRow {
            seq,
            token,
            started_ms,
            finished_ms,
            order,
            swaps,
        })
    }

    fn answers_of(&self, conn: &Connection, seq: i64) -> Result<Vec<(usize, Side)>> {
        let mut stmt = self.sql(
            conn.prepare_cached("SELECT position, shown FROM answers WHERE participant = ?1"),
        )?;
        let rows = self.sql(stmt.query_map(params![seq], |r| {
            Ok((r.get::<_, i64>(0)?, r.get::<_, String>(1)?))
        }))?;
        let mut out = Vec::new();
        for row in rows {
            let (position, shown) = self.sql(row)?;
            out.push((position as usize, Side::parse(&shown).unwrap_or(Side::None)));
        }
        out.sort_by_key(|a| a.0);
        Ok(out)
    }

    fn view(&self, row: &ParticipantRow, answers: &[(usize, Side)]) -> SessionView {
        let items = row
            .order
            .iter()
            .zip(&row.swaps)
            .enumerate()
            .map(|(k, (&q, &swapped))| {
                let question = &self.study.questions[q];
                let (mut left, mut right) = (question.left, question.right);
                if swapped {
                    std::mem::swap(&mut left, &mut right);
                }
                ItemView {
                    item: k + 1,
                    left: self.study.configurations[left].name.clone(),
                    right: self.study.configurations[right].name.clone(),
                }
            })
            .collect();
        SessionView {
            token: row.token.clone(),
            total: row.order.len(),
            items,
            answers: answers
                .iter()
                .map(|&(item, answer)| ItemAnswer { item, answer })
                .collect(),
            finished: row.finished_ms.is_some(),
        }
    }

    /// The session of this token (and nothing about anyone else).
    pub fn session(&self, token: &str) -> Result<SessionView> {
        let conn = self.lock();
        let row = self.participant(&conn, token)?;
        let answers = self.answers_of(&conn, row.seq)?;
        Ok(self.view(&row, &answers))
    }

    /// Stores the answer to question `item` (1-based, in the participant's order) as clicked on
    /// screen, with the time the participant took (`client_ms`, as measured by the page), in one
    /// transaction. A second answer to the same question is rejected.
    pub fn answer(
        &self,
        token: &str,
        item: u64,
        shown: Side,
        client_ms: Option<u64>,
    ) -> Result<AnswerAck> {
        let mut conn = self.lock();
        let tx = self.sql(conn.transaction_with_behavior(TransactionBehavior::Immediate))?;
        let row = self.participant(&tx, token)?;
        let total = row.order.len();
        if item == 0 || item > total as u64 {
            return Err(StoreError::UnknownItem { item, total });
        }
        let position = item as usize;
        if row.finished_ms.is_some() {
            return Err(StoreError::Finished);
        }
        let q = row.order[position - 1];
        let swapped = row.swaps[position - 1];
        let question = &self.study.questions[q];
        let stored: Option<String> = self.sql(
            tx.query_row(
                "SELECT shown FROM answers WHERE participant = ?1 AND question = ?2",
                params![row.seq, question.id],
                |r| r.get(0),
            )
            .optional(),
        )?;
        if let Some(stored) = stored {
            return Err(StoreError::AlreadyAnswered {
                item: position,
                stored,
            });
        }
        let now = now_ms();
        let last: Option<i64> = self.sql(tx.query_row(
            "SELECT MAX(answered_ms) FROM answers WHERE participant = ?1",
            params![row.seq],
            |r| r.get(0),
        ))?;
        let since = last.unwrap_or(row.started_ms).max(row.started_ms);
        let response = if swapped { shown.mirrored() } else { shown };
        self.sql(tx.execute(
            "INSERT INTO answers (participant, question, position, swapped, shown, response, \
             client_ms, server_ms, answered_ms) VALUES (?1, ?2, ?3, ?4, ?5, ?6, ?7, ?8, ?9)",
            params![
                row.seq,
                question.id,
                position as i64,
                i64::from(swapped),
                shown.code(),
                response.code(),
                client_ms.map(|m| m as i64),
                (now - since).max(0),
                now
            ],
        ))?;
        let answered: i64 = self.sql(tx.query_row(
            "SELECT COUNT(*) FROM answers WHERE participant = ?1",
            params![row.seq],
            |r| r.get(0),
        ))?;
        self.sql(tx.commit())?;
        Ok(AnswerAck {
            item: position,
            answer: shown,
            answered: answered as usize,
            total,
        })
    }

    /// Marks the session finished once every question is answered. Idempotent: finishing again
    /// changes nothing and returns the same session.
    pub fn finish(&self, token: &str) -> Result<SessionView> {
        let mut conn = self.lock();
        let tx = self.sql(conn.transaction_with_behavior(TransactionBehavior::Immediate))?;
        let row = self.participant(&tx, token)?;
        if row.finished_ms.is_none() {
            let answered: i64 = self.sql(tx.query_row(
                "SELECT COUNT(*) FROM answers WHERE participant = ?1",
                params![row.seq],
                |r| r.get(0),
            ))?;
            let total = row.order.len();
            if (answered as usize) < total {
                return Err(StoreError::Unfinished {
                    missing: total - answered as usize,
                    total,
                });
            }
            self.sql(tx.execute(
                "UPDATE participants SET finished_ms = ?1 WHERE seq = ?2 AND finished_ms IS NULL",
                params![now_ms(), row.seq],
            ))?;
        }
        self.sql(tx.commit())?;
        let row = self.participant(&conn, token)?;
        let answers = self.answers_of(&conn, row.seq)?;
        Ok(self.view(&row, &answers))
    }

    /// Live counts.
    pub fn counts(&self) -> Result<Counts> {
        let conn = self.lock();
        let one = |sql: &str| -> Result<u64> {
            self.sql(conn.query_row(sql, [], |r| r.get::<_, i64>(0)))
                .map(|v| v as u64)
        };
        let participants = one("SELECT COUNT(*) FROM participants")?;
        let finished = one("SELECT COUNT(*) FROM participants WHERE finished_ms IS NOT NULL")?;
        let mut per: BTreeMap<String, u64> = BTreeMap::new();
        {
            let mut stmt =
                self.sql(conn.prepare("SELECT question, COUNT(*) FROM answers GROUP BY question"))?;
            let rows = self
                .sql(stmt.query_map([], |r| Ok((r.get::<_, String>(0)?, r.get::<_, i64>(1)?))))?;
            for row in rows {
                let (q, n) = self.sql(row)?;
                per.insert(q, n as u64);
            }
        }
        let mut answers = 0;
        let mut control_answers = 0;
        let per_question = self
            .study
            .questions
            .iter()
            .map(|q| {
                let n = per.get(&q.id).copied().unwrap_or(0);
                if q.is_control() {
                    control_answers += n;
                } else {
                    answers += n;
                }
                (q.id.clone(), n)
            })
            .collect();
        Ok(Counts {
            participants,
            finished,
            answers,
            control_answers,
            questions: self.study.questions.len(),
            per_question,
        })
    }

    /// `PRAGMA integrity_check`: `ok` for a sound database.
    pub fn integrity_check(&self) -> Result<String> {
        let conn = self.lock();
        self.sql(conn.query_row("PRAGMA integrity_check", [], |r| r.get(0)))
    }

    fn all_participants(&self, conn: &Connection) -> Result<Vec<ParticipantRow>> {
        let mut stmt = self.sql(conn.prepare(
            "SELECT seq, token, started_ms, finished_ms, question_order, swaps \
             FROM participants ORDER BY seq",
        ))?;
        let rows = self.sql(stmt.query_map([], |r| {
            Ok((
                r.get::<_, i64>(0)?,
                r.get::<_, String>(1)?,
                r.get::<_, i64>(2)?,
                r.get::<_, Option<i64>>(3)?,
                r.get::<_, String>(4)?,
                r.get::<_, String>(5)?,
            ))
        }))?;
        let mut out = Vec::new();
        for row in rows {
            let (seq, token, started, finished, order, swaps) = self.sql(row)?;
            out.push(self.parse_participant(seq, token, started, finished, &order, &swaps)?);
        }
        Ok(out)
    }

    fn all_answers(&self, conn: &Connection) -> Result<Vec<AnswerRow>> {
        let mut stmt = self.sql(conn.prepare(
            "SELECT participant, question, position, swapped, shown, response, client_ms, \
             server_ms, answered_ms FROM answers ORDER BY participant, position",
        ))?;
        let rows = self.sql(stmt.query_map([], |r| {
            Ok(AnswerRow {
                participant: r.get(0)?,
                question: r.get(1)?,
                position: r.get(2)?,
                swapped: r.get::<_, i64>(3)? != 0,
                shown: r.get(4)?,
                response: r.get(5)?,
                client_ms: r.get(6)?,
                server_ms: r.get(7)?,
                answered_ms: r.get(8)?,
            })
        }))?;
        let mut out = Vec::new();
        for row in rows {
            out.push(self.sql(row)?);
        }
        Ok(out)
    }

    /// Everything stored, as the export files (read in one transaction, so consistent while
    /// the server keeps taking answers).
    pub fn export(&self) -> Result<crate::export::Export> {
        let mut conn = self.lock();
        let tx = self.sql(conn.transaction_with_behavior(TransactionBehavior::Deferred))?;
        let participants = self.all_participants(&tx)?;
        let answers = self.all_answers(&tx)?;
        self.sql(tx.commit())?;
        drop(conn);
        let participants = participants
            .into_iter()
            .map(|p| crate::export::ExportParticipant {
                seq: p.seq,
                token: p.token,
                started_ms: p.started_ms,
                finished_ms: p.finished_ms,
                order: p
                    .order
                    .iter()
                    .map(|&q| self.study.questions[q].id.clone())
                    .collect(),
                swaps: p.swaps,
            })
            .collect();
        let answers = answers
            .into_iter()
            .map(|a| crate::export::ExportAnswer {
                participant: a.participant,
                question: a.question,
                position: a.position,
                swapped: a.swapped,
                shown: a.shown,
                response: a.response,
                client_ms: a.client_ms,
                server_ms: a.server_ms,
                answered_ms: a.answered_ms,
            })
            .collect();
        crate::export::Export::build(&self.study, participants, answers).map_err(|e| {
            StoreError::BadDatabase {
                path: self.path.clone(),
                message: e,
            }
        })
    }
}
