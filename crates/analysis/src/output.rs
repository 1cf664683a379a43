//! Writing results: every table as CSV and Markdown, every chart as PNG and SVG, each file written
//! with the workspace's atomic write ([`rmt_runfolder::write_atomic`]: a temporary name in the
//! target directory renamed over the target), so a reader never sees a half-written file and an
//! interrupted run leaves the previous file intact.

use std::path::{Path, PathBuf};

use rmt_runfolder::write_atomic;

use crate::analysis::Analysis;
use crate::charts::write_charts;
use crate::error::{io_error, Result};
use crate::tables::all_tables;

/// Writes every table (`NAME.csv`, `NAME.md`), a combined `analysis.md` and the charts
/// (`NAME.png`, `NAME.svg`) into `out_dir` (created if needed). Returns the files written, in
/// writing order. The same analysis always gives the same bytes.
pub fn write_outputs(analysis: &Analysis, out_dir: &Path) -> Result<Vec<PathBuf>> {
    std::fs::create_dir_all(out_dir).map_err(io_error(out_dir))?;
    let mut written = Vec::new();
    let mut combined = String::from("# Questionnaire analysis\n\n");
    for table in all_tables(analysis) {
        let csv = out_dir.join(format!("{}.csv", table.name));
        write_atomic(&csv, &table.to_csv())?;
        written.push(csv);
        let markdown = table.to_markdown();
        let md = out_dir.join(format!("{}.md", table.name));
        write_atomic(&md, markdown.as_bytes())?;
        written.push(md);
        combined.push_str(&markdown);
    }
    let all = out_dir.join("analysis.md");
    write_atomic(&all, combined.as_bytes())?;
    written.push(all);
    written.extend(write_charts(analysis, out_dir)?);
    Ok(written)
}
