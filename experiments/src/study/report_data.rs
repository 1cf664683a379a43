//! What the report's study section reads besides the answers (`report --study DIR`, kept in a
//! report as `data/study/`): the design's numbers beside a simulated study's export files, and
//! the coverage check's table.
//!
//! | file | columns |
//! |---|---|
//! | `study.csv` | `key,value`: `name`, `participants`, `questions` (pair questions per participant), `controls`, `seconds_per_question`, `reference` (the power table's method), `effect`, `tie_rate`, `alpha`, `answers` (`simulated` or `real`), `model` (the planted model's file name), `seed` |
//! | `coverage.csv` | `method,shading,intervals,covered,mean_error`: the 95% intervals' coverage of the planted log-strengths over the simulated studies |
//! | `coverage_tests.csv` | `key,value`: `studies`, `participants`, `converged`, `planted_interaction`, `interaction_tests`, `interaction_rejections`, `bias_detected`, `stated_bias_power`, `mean_tie_parameter` |

use std::path::Path;

use anyhow::{Context, Result};
use rmt_analysis::study::simulate::CoverageReport;
use rmt_runfolder::{csv_bytes, write_atomic};

use super::design_file::Design;

/// The file of the design's numbers.
pub const STUDY_CSV: &str = "study.csv";
/// The coverage table.
pub const COVERAGE_CSV: &str = "coverage.csv";
/// The coverage check's test rates.
pub const COVERAGE_TESTS_CSV: &str = "coverage_tests.csv";

fn write(dir: &Path, name: &str, rows: &[Vec<String>]) -> Result<()> {
    std::fs::create_dir_all(dir).with_context(|| format!("creating {}", dir.display()))?;
    let path = dir.join(name);
    let bytes = csv_bytes(rows).with_context(|| format!("writing {}", path.display()))?;
    write_atomic(&path, &bytes).with_context(|| format!("writing {}", path.display()))
}

fn pairs(rows: Vec<(&str, String)>) -> Vec<Vec<String>> {
    std::iter::once(vec!["key".to_string(), "value".to_string()])
        .chain(rows.into_iter().map(|(k, v)| vec![k.to_string(), v]))
        .collect()
}

/// Writes `study.csv` into `dir`: the design's numbers for `participants` simulated
/// participants answering from the model file `model` with `seed`.
pub fn write_study_csv(
    dir: &Path,
    design: &Design,
    participants: usize,
    model: &Path,
    seed: u64,
) -> Result<()> {
    let model = model
        .file_name()
        .map(|n| n.to_string_lossy().into_owned())
        .unwrap_or_default();
    let rows = pairs(vec![
        ("name", design.name.clone()),
        ("participants", participants.to_string()),
        ("questions", design.questions.to_string()),
        ("controls", design.controls.to_string()),
        (
            "seconds_per_question",
            design.seconds_per_question.to_string(),
        ),
        ("reference", design.items.methods[design.reference].clone()),
        ("effect", design.effect.to_string()),
        ("tie_rate", design.tie_rate.to_string()),
        ("alpha", design.alpha.to_string()),
        ("answers", "simulated".to_string()),
        ("model", model),
        ("seed", seed.to_string()),
    ]);
    write(dir, STUDY_CSV, &rows)
}

/// Writes `coverage.csv` and `coverage_tests.csv` of `report` (studies of `participants`
/// participants) into `dir`.
pub fn write_coverage(
    dir: &Path,
    design: &Design,
    report: &CoverageReport,
    participants: usize,
) -> Result<()> {
    let it = &design.items;
    let mut rows = vec![["method", "shading", "intervals", "covered", "mean_error"]
        .map(String::from)
        .to_vec()];
    for r in &report.rows {
        rows.push(vec![
            it.methods[r.method].clone(),
            it.shadings[r.shading].clone(),
            r.intervals.to_string(),
            r.covered.to_string(),
            format!("{:.6}", r.mean_error),
        ]);
    }
    write(dir, COVERAGE_CSV, &rows)?;
    let tests = pairs(vec![
        ("studies", report.studies.to_string()),
        ("participants", participants.to_string()),
        ("converged", (report.studies - report.failed).to_string()),
        (
            "planted_interaction",
            report.planted_interaction.to_string(),
        ),
        ("interaction_tests", report.interaction_tests.to_string()),
        (
            "interaction_rejections",
            report.interaction_rejections.to_string(),
        ),
        ("bias_detected", report.bias_detected.to_string()),
        (
            "stated_bias_power",
            format!("{:.6}", report.stated_bias_power),
        ),
        (
            "mean_tie_parameter",
            format!("{:.6}", report.mean_tie_parameter),
        ),
    ]);
    write(dir, COVERAGE_TESTS_CSV, &tests)
}
