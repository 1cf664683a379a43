//! One session of a run (a start or a resume): its options ([`RunOptions`]), opened in
//! `run.json`, shown as a progress bar, closed in `run.json` with how it ended, and reported
//! ([`RunReport`]).

use std::path::{Path, PathBuf};

use anyhow::Result;
use indicatif::{ProgressBar, ProgressStyle};
use rmt_runfolder::layout::RUN_JSON;

use crate::provenance::{self, Provenance};
use crate::run_files::write_json;
use crate::run_record::{RunRecord, Session, Status};

/// Options of a run that are not part of the plan.
#[derive(Clone, Debug, Default)]
pub struct RunOptions {
    /// No progress bar or summary.
    pub quiet: bool,
    /// Stop (as if killed) after this many configurations of this session; for testing resume.
    pub stop_after: Option<usize>,
}

/// What a session did.
#[derive(Clone, Debug)]
pub struct RunReport {
    /// The run folder.
    pub folder: PathBuf,
    /// How it ended.
    pub status: Status,
    /// Configurations run in this session.
    pub configurations_run: usize,
    /// Configurations finished overall.
    pub configurations_done: usize,
    /// Configurations in the plan.
    pub configurations_total: usize,
}

/// Adds a running session to `record` and writes `run.json`.
pub(super) fn open(folder: &Path, record: &mut RunRecord, provenance: Provenance) -> Result<()> {
    record.sessions.push(Session {
        provenance,
        ended: None,
        configurations_run: 0,
        status: Status::Running,
    });
    write_json(&folder.join(RUN_JSON), record)
}

/// Records the end of the current session (status, configurations run) in `run.json`.
pub(super) fn close(
    folder: &Path,
    record: &mut RunRecord,
    status: Status,
    ran: usize,
) -> Result<()> {
    record.status = status;
    if let Some(s) = record.sessions.last_mut() {
        s.ended = Some(provenance::utc_now_iso());
        s.configurations_run = ran;
        s.status = status;
    }
    write_json(&folder.join(RUN_JSON), record)
}

/// A progress bar of `len` steps drawn with `template` (hidden when `quiet`).
pub(super) fn progress_bar(quiet: bool, len: u64, template: &str) -> ProgressBar {
    if quiet {
        return ProgressBar::hidden();
    }
    let bar = ProgressBar::new(len);
    let style = ProgressStyle::with_template(template)
        .unwrap_or_else(|_| ProgressStyle::default_bar())
        .progress_chars("=> ");
    bar.set_style(style);
    bar
}
