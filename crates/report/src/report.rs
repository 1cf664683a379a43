//! Building the report folder from a run folder (and optionally a scaling run and the
//! questionnaire data), and checking a committed report against a fresh rebuild.
//!
//! ```text
//! <out>/README.md            one page: provenance, every figure with a sentence, links
//! <out>/data/                the run's run.json, manifest.toml, configurations.csv, summary.csv,
//!                            raw.csv, paper_comparison.csv (copied; the report's own input)
//! <out>/data/scaling/        the same files of the scaling run, when given
//! <out>/data/check-cost/     the same files of the check-cost run, when given
//! <out>/data/peers/          the peers run (run.json, manifest.toml, configurations.csv,
//!                            summary.csv), when given
//! <out>/data/peers-seeds/    the peers seed study (run.json, manifest.toml, seeds.csv)
//! <out>/data/study/          the second study's answers and design (crate::study), when given
//! <out>/data/lod/            a `lod` run's files (crate::lod), when given
//! <out>/figures/NAME.{png,svg}
//! <out>/tables/NAME.{md,csv}
//! <out>/questionnaire/       the questionnaire analysis (rmt-analysis: tables and charts)
//! ```
//!
//! `data/` is itself a valid run folder (with `data/scaling/`, `data/check-cost/`,
//! `data/peers/`, `data/peers-seeds/`, `data/study/` and `data/lod/` found by default), so a report
//! rebuilds from its own copy: that is what [`check`] does.

use std::collections::BTreeSet;
use std::path::{Path, PathBuf};

use crate::csv_file::CsvFile;
use crate::data::{
    Run, RunInfo, CONFIGURATIONS_CSV, MANIFEST_TOML, PAPER_CSV, RAW_CSV, RUN_JSON, SUMMARY_CSV,
};
use crate::error::{io_error, ReportError, Result};
use crate::figures::{self, AnyFigure};
use crate::output::TextTable;
use crate::readme::{readme, QuestionnaireSummary, ReadmeInput};
use crate::scaling::{fit_scaling, ScalingFit};
use crate::tables;
use rmt_runfolder::write_atomic;

/// The run files copied into `data/` (when present), in this order.
pub const DATA_FILES: [&str; 7] = [
    RUN_JSON,
    MANIFEST_TOML,
    CONFIGURATIONS_CSV,
    SUMMARY_CSV,
    RAW_CSV,
    PAPER_CSV,
    crate::seeds::SEEDS_CSV,
];

/// The questionnaire part of a report.
#[derive(Clone, Debug)]
pub struct Questionnaire {
    /// The three CSV files.
    pub inputs: rmt_analysis::Inputs,
    /// Analysis options (exclusions, resamples, seed).
    pub options: rmt_analysis::Options,
}

/// What a report is built from.
#[derive(Clone, Debug)]
pub struct ReportInputs {
    /// The benchmark run folder (or a report's `data/` folder).
    pub run: PathBuf,
    /// The scaling run folder, if any (see [`default_scaling`]).
    pub scaling: Option<PathBuf>,
    /// The run folder of `experiments/manifests/check-cost.toml`, if any (see
    /// [`default_check_cost`]): plain MT, unchecked and checked integrated clustering.
    pub check_cost: Option<PathBuf>,
    /// The run folder of `experiments/manifests/peers.toml`, if any (see [`default_peers`]):
    /// RMT against marching cubes, surface nets and meshoptimizer, with rendering cost.
    pub peers: Option<PathBuf>,
    /// The run folder of `experiments/manifests/peers-seeds.toml` (its `seeds.csv`), if any (see
    /// [`default_peers_seeds`]).
    pub peers_seeds: Option<PathBuf>,
    /// The folder of the second study's answers and design (see [`crate::study`] and
    /// [`default_study`]), if any.
    pub study: Option<PathBuf>,
    /// A run folder of the `lod` workload (see [`crate::lod`] and [`default_lod`]), if any.
    pub lod: Option<PathBuf>,
    /// The questionnaire, if it is part of the report.
    pub questionnaire: Option<Questionnaire>,
    /// Copy `raw.csv` into `data/` (it can be large; `summary.csv` holds what the report uses).
    pub keep_raw: bool,
}

/// `run/scaling` when it holds a scaling run (as a report's `data/` folder does).
pub fn default_scaling(run: &Path) -> Option<PathBuf> {
    sub_run(run, SCALING_DIR)
}

/// `run/check-cost` when it holds a run (as a report's `data/` folder does).
pub fn default_check_cost(run: &Path) -> Option<PathBuf> {
    sub_run(run, CHECK_COST_DIR)
}

/// `run/peers` when it holds a run (as a report's `data/` folder does).
pub fn default_peers(run: &Path) -> Option<PathBuf> {
    sub_run(run, PEERS_DIR)
}

/// `run/peers-seeds` when it holds a seed study's `seeds.csv`.
pub fn default_peers_seeds(run: &Path) -> Option<PathBuf> {
    let candidate = run.join(PEERS_SEEDS_DIR);
    candidate
        .join(crate::seeds::SEEDS_CSV)
        .is_file()
        .then_some(candidate)
}

/// `run/study` when it holds a study (as a report's `data/` folder does).
pub fn default_study(run: &Path) -> Option<PathBuf> {
    let candidate = run.join(STUDY_DIR);
    crate::study::is_study(&candidate).then_some(candidate)
}

/// The folder of `data/` that holds the second study.
pub const STUDY_DIR: &str = "study";

/// `run/lod` when it holds a `lod` run with the section's files (as a report's `data/`
/// folder does).
pub fn default_lod(run: &Path) -> Option<PathBuf> {
    let candidate = run.join(LOD_DIR);
    crate::lod::is_lod(&candidate).then_some(candidate)
}

/// The folder of `data/` that holds the `lod` run.
pub const LOD_DIR: &str = "lod";

/// The folder of `data/` that holds the peers run.
pub const PEERS_DIR: &str = "peers";
/// The folder of `data/` that holds the peers seed study.
pub const PEERS_SEEDS_DIR: &str = "peers-seeds";

/// The folder of `data/` that holds the scaling run.
pub const SCALING_DIR: &str = "scaling";
/// The folder of `data/` that holds the check-cost run.
pub const CHECK_COST_DIR: &str = "check-cost";

fn sub_run(run: &Path, name: &str) -> Option<PathBuf> {
    let candidate = run.join(name);
    candidate.join(SUMMARY_CSV).is_file().then_some(candidate)
}

/// The files of a run folder that go into `data/`, read into memory (so a report can be rebuilt
/// over its own `data/`).
fn read_data_files(folder: &Path, keep_raw: bool) -> Result<Vec<(&'static str, Vec<u8>)>> {
    let mut files = Vec::new();
    for name in DATA_FILES {
        if name == RAW_CSV && !keep_raw {
            continue;
        }
        let path = folder.join(name);
        if path.is_file() {
            files.push((name, std::fs::read(&path).map_err(io_error(&path))?));
        }
    }
    Ok(files)
}

/// Writes the data files to `dir` and removes the run files that are not part of this report;
/// returns the names written.
fn write_data_files(dir: &Path, files: &[(&'static str, Vec<u8>)]) -> Result<Vec<String>> {
    std::fs::create_dir_all(dir).map_err(io_error(dir))?;
    for (name, bytes) in files {
        write_atomic(&dir.join(name), bytes)?;
    }
    for name in DATA_FILES {
        let path = dir.join(name);
        if path.is_file() && !files.iter().any(|(n, _)| *n == name) {
            std::fs::remove_file(&path).map_err(io_error(&path))?;
        }
    }
    Ok(files.iter().map(|(n, _)| n.to_string()).collect())
}

/// Removes files with one of `extensions` in `dir` that are not in `keep` (stale outputs of an
/// earlier report); other files are left alone.
fn remove_stale(dir: &Path, keep: &BTreeSet<PathBuf>, extensions: &[&str]) -> Result<()> {
    for entry in std::fs::read_dir(dir).map_err(io_error(dir))? {
        let path = entry.map_err(io_error(dir))?.path();
        let ours = path
            .extension()
            .and_then(|e| e.to_str())
            .is_some_and(|e| extensions.contains(&e));
        if path.is_file() && ours && !keep.contains(&path) {
            std::fs::remove_file(&path).map_err(io_error(&path))?;
        }
    }
    Ok(())
}

/// Writes `table` as `dir/NAME.csv` and `dir/NAME.md`.
fn write_table(dir: &Path, table: &TextTable) -> Result<Vec<PathBuf>> {
    let csv = dir.join(format!("{}.csv", table.name));
    write_atomic(&csv, &table.to_csv())?;
    let md = dir.join(format!("{}.md", table.name));
    write_atomic(&md, table.to_markdown().as_bytes())?;
    Ok(vec![csv, md])
}

/// Builds the report into `out` (created if needed); returns every file written, relative to
/// `out`, sorted. The same inputs always give the same bytes: nothing depends on the clock, the
/// paths of the inputs or the order of a hash map.
pub fn build(inputs: &ReportInputs, out: &Path) -> Result<Vec<PathBuf>> {
    let run = Run::read(&inputs.run)?;
    let scaling: Option<(Run, Vec<ScalingFit>)> = match &inputs.scaling {
        Some(folder) => {
            let scaling_run = Run::read(folder)?;
            let fits = fit_scaling(&scaling_run);
            Some((scaling_run, fits))
        }
        None => None,
    };
    let check_cost = match &inputs.check_cost {
        Some(folder) => Some(Run::read(folder)?),
        None => None,
    };
    let peers = match &inputs.peers {
        Some(folder) => Some((
            RunInfo::read(&folder.join(RUN_JSON))?,
            crate::peers::read_peers(folder)?,
        )),
        None => None,
    };
    let peers_seeds = match &inputs.peers_seeds {
        Some(folder) => Some((
            RunInfo::read(&folder.join(RUN_JSON))?,
            CsvFile::read(&folder.join(crate::seeds::SEEDS_CSV))?,
        )),
        None => None,
    };
    let study = match &inputs.study {
        Some(folder) => Some((
            crate::study::read_study(folder)?,
            crate::study::study_files(folder)?,
        )),
        None => None,
    };
    let lod = match &inputs.lod {
        Some(folder) => Some((
            crate::lod::read_lod(folder)?,
            crate::lod::lod_files(folder)?,
        )),
        None => None,
    };
    // Read every input before writing anything: `out/data` may be the input.
    let data = read_data_files(&inputs.run, inputs.keep_raw)?;
    let sub_data = |folder: &Option<PathBuf>| match folder {
        Some(folder) => read_data_files(folder, inputs.keep_raw).map(Some),
        None => Ok(None),
    };
    // The peers runs: no raw.csv (summary.csv, or seeds.csv, holds what the report uses).
    let peers_data = match &inputs.peers {
        Some(folder) => Some(read_data_files(folder, false)?),
        None => None,
    };
    let peers_seeds_data = match &inputs.peers_seeds {
        Some(folder) => Some(
            read_data_files(folder, false)?
                .into_iter()
                .filter(|(name, _)| {
                    [RUN_JSON, MANIFEST_TOML, crate::seeds::SEEDS_CSV].contains(name)
                })
                .collect(),
        ),
        None => None,
    };
    let subs = [
        (SCALING_DIR, sub_data(&inputs.scaling)?),
        (CHECK_COST_DIR, sub_data(&inputs.check_cost)?),
        (PEERS_DIR, peers_data),
        (PEERS_SEEDS_DIR, peers_seeds_data),
    ];
    let mut written: Vec<PathBuf> = Vec::new();
    std::fs::create_dir_all(out).map_err(io_error(out))?;
    let data_dir = out.join("data");
    let mut data_files = write_data_files(&data_dir, &data)?;
    // The study's folder holds its own files (not a run's): written whole, or removed.
    let study_dir = data_dir.join(STUDY_DIR);
    match &study {
        Some((_, files)) => {
            std::fs::create_dir_all(&study_dir).map_err(io_error(&study_dir))?;
            for (name, bytes) in files {
                write_atomic(&study_dir.join(name), bytes)?;
            }
            for name in crate::study::STUDY_FILES {
                let path = study_dir.join(name);
                if path.is_file() && !files.iter().any(|(n, _)| *n == name) {
                    std::fs::remove_file(&path).map_err(io_error(&path))?;
                }
            }
            data_files.extend(files.iter().map(|(n, _)| format!("{STUDY_DIR}/{n}")));
        }
        None if study_dir.is_dir() => {
            for name in crate::study::STUDY_FILES {
                let path = study_dir.join(name);
                if path.is_file() {
                    std::fs::remove_file(&path).map_err(io_error(&path))?;
                }
            }
        }
        None => {}
    }
    // The lod run's folder: its own files (lod.csv, lod_levels.csv, lod_map.csv and the run's).
    let lod_dir = data_dir.join(LOD_DIR);
    match &lod {
        Some((_, files)) => {
            std::fs::create_dir_all(&lod_dir).map_err(io_error(&lod_dir))?;
            for (name, bytes) in files {
                write_atomic(&lod_dir.join(name), bytes)?;
            }
            data_files.extend(files.iter().map(|(n, _)| format!("{LOD_DIR}/{n}")));
        }
        None if lod_dir.is_dir() => {
            for name in crate::lod::LOD_FILES {
                let path = lod_dir.join(name);
                if path.is_file() {
                    std::fs::remove_file(&path).map_err(io_error(&path))?;
                }
            }
        }
        None => {}
    }

    for (name, files) in &subs {
        let dir = data_dir.join(name);
        match files {
            Some(files) => {
                let names = write_data_files(&dir, files)?;
                data_files.extend(names.into_iter().map(|n| format!("{name}/{n}")));
            }
            None if dir.is_dir() => {
                write_data_files(&dir, &[])?;
            }
            None => {}
        }
    }
    written.extend(data_files.iter().map(|f| data_dir.join(f)));

    // Tables.
    let tables_dir = out.join("tables");
    std::fs::create_dir_all(&tables_dir).map_err(io_error(&tables_dir))?;
    let mut all_tables = vec![tables::benchmark_summary(&run)];
    if let Some(paper) = &run.paper {
        all_tables.push(tables::paper_comparison(&run, paper));
        all_tables.push(tables::paper_ratios(paper));
    }
    if let Some((scaling_run, fits)) = &scaling {
        all_tables.push(tables::scaling_table(scaling_run, fits));
    }
    if let Some(rows) = &run.seeds {
        all_tables.push(crate::seeds::seed_table(rows));
    }
    if let Some(table) = check_cost
        .as_ref()
        .and_then(crate::check_cost::check_cost_table)
    {
        all_tables.push(table);
    }
    if let Some((info, rows)) = &peers {
        all_tables.push(crate::peers::peers_table(info, rows));
    }
    if let Some((info, seeds)) = &peers_seeds {
        if let Some(table) = crate::peers::seeds_table(&info.run_id, seeds)? {
            all_tables.push(table);
        }
    }
    if let Some((s, _)) = &study {
        all_tables.extend(crate::study::study_tables(s));
    }
    if let Some((l, _)) = &lod {
        all_tables.extend(crate::lod::lod_tables(l));
    }
    let mut kept = BTreeSet::new();
    for table in &all_tables {
        for path in write_table(&tables_dir, table)? {
            kept.insert(path.clone());
            written.push(path);
        }
    }
    remove_stale(&tables_dir, &kept, &["csv", "md"])?;

    // Figures.
    let figures_dir = out.join("figures");
    std::fs::create_dir_all(&figures_dir).map_err(io_error(&figures_dir))?;
    let mut all_figures: Vec<(String, AnyFigure)> = vec![
        (
            "triangles".into(),
            AnyFigure::Rows(figures::triangles(&run)),
        ),
        (
            "pass_times".into(),
            AnyFigure::Rows(figures::pass_times(&run)),
        ),
        (
            "stage_shares".into(),
            AnyFigure::Rows(figures::stage_shares(&run)),
        ),
        (
            "aspect_ratio".into(),
            AnyFigure::Rows(figures::aspect_ratio(&run)),
        ),
    ];
    if let Some(chart) = figures::fidelity(&run) {
        all_figures.push(("fidelity".into(), AnyFigure::Xy(chart)));
    }
    if let Some((scaling_run, fits)) = &scaling {
        if let Some(chart) = figures::scaling(scaling_run, fits) {
            all_figures.push(("scaling".into(), AnyFigure::Xy(chart)));
        }
    }
    if let Some(rows) = &run.seeds {
        for (name, chart) in crate::seeds::seed_figures(&run, rows) {
            all_figures.push((name, AnyFigure::Rows(chart)));
        }
    }
    if let Some((info, rows)) = &peers {
        if let Some(chart) = crate::peers::occupancy_figure(info, rows) {
            all_figures.push(("peers_occupancy".into(), AnyFigure::Xy(chart)));
        }
        if let Some(chart) = crate::peers::time_figure(info, rows) {
            all_figures.push(("peers_time_triangles".into(), AnyFigure::Xy(chart)));
        }
    }
    if let Some((l, _)) = &lod {
        all_figures.push((
            "lod_top_view".into(),
            AnyFigure::TopView(crate::lod::top_view(l)),
        ));
        all_figures.push((
            "lod_triangles".into(),
            AnyFigure::Rows(crate::lod::triangles_figure(l)),
        ));
    }
    let mut kept = BTreeSet::new();
    for (name, figure) in &all_figures {
        for path in figure.write(&figures_dir, name)? {
            kept.insert(path.clone());
            written.push(path);
        }
    }
    remove_stale(&figures_dir, &kept, &["png", "svg"])?;
    let figure_names: Vec<String> = all_figures.iter().map(|(n, _)| n.clone()).collect();

    // Questionnaire.
    let questionnaire = match &inputs.questionnaire {
        Some(q) => {
            let analysis = rmt_analysis::analyse(&q.inputs, &q.options)?;
            let dir = out.join("questionnaire");
            let files = rmt_analysis::write_outputs(&analysis, &dir)?;
            let mut names: Vec<String> = files
                .iter()
                .filter_map(|f| f.file_name().map(|n| n.to_string_lossy().into_owned()))
                .collect();
            names.sort();
            written.extend(files);
            Some(QuestionnaireSummary {
                participants: analysis.basis.participants,
                responses: analysis.basis.responses,
                questions: analysis.questions.len(),
                significant: analysis.questions.iter().filter(|q| q.significant).count(),
                files: names,
            })
        }
        None => None,
    };

    let text = readme(&ReadmeInput {
        run: &run,
        scaling: scaling.as_ref().map(|(r, f)| (r, f.as_slice())),
        check_cost: check_cost.as_ref(),
        peers: peers.as_ref().map(|(info, rows)| (info, rows.as_slice())),
        study: study.as_ref().map(|(s, _)| s),
        lod: lod.as_ref().map(|(l, _)| l),
        figures: &figure_names,
        tables: &all_tables,
        questionnaire: questionnaire.as_ref(),
        data_files: &data_files,
    });
    let readme_path = out.join("README.md");
    write_atomic(&readme_path, text.as_bytes())?;
    written.push(readme_path);

    let mut relative: Vec<PathBuf> = written
        .iter()
        .map(|p| p.strip_prefix(out).unwrap_or(p).to_path_buf())
        .collect();
    relative.sort();
    relative.dedup();
    Ok(relative)
}

/// The folders and files of a report that [`build`] owns and [`check`] compares.
pub const OWNED: [&str; 5] = ["README.md", "data", "figures", "tables", "questionnaire"];

/// How a committed report differs from a fresh rebuild.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct CheckOutcome {
    /// Files compared.
    pub compared: usize,
    /// Text files (tables, README, data) whose bytes differ.
    pub differing: Vec<PathBuf>,
    /// Files the rebuild makes that the committed report lacks.
    pub missing: Vec<PathBuf>,
    /// Files in the committed report's owned folders that the rebuild does not make.
    pub unexpected: Vec<PathBuf>,
    /// Figures whose bytes differ (reported, not a failure: only the set of figures must match).
    pub figures_changed: Vec<PathBuf>,
    /// Committed files that do not parse (CSV, JSON, PNG, SVG, Markdown, README links), with why.
    pub invalid: Vec<(PathBuf, String)>,
}

impl CheckOutcome {
    /// Whether the committed report matches: same files, identical text, everything parses.
    pub fn passed(&self) -> bool {
        self.differing.is_empty()
            && self.missing.is_empty()
            && self.unexpected.is_empty()
            && self.invalid.is_empty()
    }
}

/// Why `bytes` (the file `name`) is not a well-formed file of its kind, if it is not.
pub fn validate(name: &Path, bytes: &[u8]) -> Option<String> {
    let extension = name.extension().and_then(|e| e.to_str()).unwrap_or("");
    match extension {
        "csv" => {
            let mut reader = csv::Reader::from_reader(bytes);
            let columns = match reader.headers() {
                Ok(h) if !h.is_empty() => h.len(),
                Ok(_) => return Some("no header".into()),
                Err(e) => return Some(e.to_string()),
            };
            for (i, record) in reader.records().enumerate() {
                match record {
                    Ok(r) if r.len() == columns => {}
                    Ok(r) => {
                        return Some(format!(
                            "line {}: {} cells, header has {columns}",
                            i + 2,
                            r.len()
                        ))
                    }
                    Err(e) => return Some(e.to_string()),
                }
            }
            None
        }
        "json" => serde_json::from_slice::<serde_json::Value>(bytes)
            .err()
            .map(|e| e.to_string()),
        "png" => {
            let signature_ok = bytes.len() > 24 && bytes[..8] == *b"\x89PNG\r\n\x1a\n";
            let ihdr_ok = signature_ok && &bytes[12..16] == b"IHDR";
            (!ihdr_ok).then(|| "not a PNG image".to_string())
        }
        "svg" => match std::str::from_utf8(bytes) {
            Ok(text) if text.starts_with("<svg") && text.trim_end().ends_with("</svg>") => None,
            _ => Some("not an SVG document".into()),
        },
        "md" => match std::str::from_utf8(bytes) {
            Ok(text) if text.starts_with('#') => None,
            _ => Some("not a Markdown page with a heading".into()),
        },
        _ => None,
    }
}

/// Relative link targets of a Markdown page (`[text](target)`), anchors and URLs left out.
pub fn local_links(markdown: &str) -> Vec<String> {
    markdown
        .split("](")
        .skip(1)
        .filter_map(|part| part.find(')').map(|end| part[..end].to_string()))
        .filter(|t| !t.starts_with('#') && !t.contains("://"))
        .collect()
}

/// Every file under the owned entries of `root`, relative to it, hidden files skipped.
fn owned_files(root: &Path) -> Result<BTreeSet<PathBuf>> {
    fn walk(root: &Path, dir: &Path, out: &mut BTreeSet<PathBuf>) -> Result<()> {
        let mut entries: Vec<PathBuf> = std::fs::read_dir(dir)
            .map_err(io_error(dir))?
            .map(|e| e.map(|e| e.path()).map_err(io_error(dir)))
            .collect::<Result<_>>()?;
        entries.sort();
        for path in entries {
            let hidden = path
                .file_name()
                .is_some_and(|n| n.to_string_lossy().starts_with('.'));
            if hidden {
                continue;
            }
            if path.is_dir() {
                walk(root, &path, out)?;
            } else if path.is_file() {
                out.insert(path.strip_prefix(root).unwrap_or(&path).to_path_buf());
            }
        }
        Ok(())
    }
    let mut files = BTreeSet::new();
    for name in OWNED {
        let path = root.join(name);
        if path.is_dir() {
            walk(root, &path, &mut files)?;
        } else if path.is_file() {
            files.insert(PathBuf::from(name));
        }
    }
    Ok(files)
}

fn is_figure(path: &Path) -> bool {
    path.extension()
        .and_then(|e| e.to_str())
        .is_some_and(|e| e == "png" || e == "svg")
}

/// Compares the report in `committed` with the one in `fresh` (file sets of the owned folders;
/// bytes of every non-figure file) and validates every committed file that the rebuild also
/// makes ([`validate`], and the README's links).
pub fn compare(committed: &Path, fresh: &Path) -> Result<CheckOutcome> {
    let theirs = owned_files(committed)?;
    let ours = owned_files(fresh)?;
    let mut outcome = CheckOutcome::default();
    for file in &ours {
        if !theirs.contains(file) {
            outcome.missing.push(file.clone());
            continue;
        }
        outcome.compared += 1;
        let a = committed.join(file);
        let b = fresh.join(file);
        let committed_bytes = std::fs::read(&a).map_err(io_error(&a))?;
        if let Some(why) = validate(file, &committed_bytes) {
            outcome.invalid.push((file.clone(), why));
        }
        if file == Path::new("README.md") {
            for target in local_links(&String::from_utf8_lossy(&committed_bytes)) {
                if !committed.join(&target).exists() {
                    outcome
                        .invalid
                        .push((file.clone(), format!("links to missing {target}")));
                }
            }
        }
        let same = committed_bytes == std::fs::read(&b).map_err(io_error(&b))?;
        if !same {
            if is_figure(file) {
                outcome.figures_changed.push(file.clone());
            } else {
                outcome.differing.push(file.clone());
            }
        }
    }
    outcome.unexpected = theirs.difference(&ours).cloned().collect();
    Ok(outcome)
}

/// Rebuilds the report from `inputs` into a temporary folder and compares it with the one in
/// `committed`.
pub fn check(inputs: &ReportInputs, committed: &Path) -> Result<CheckOutcome> {
    if !committed.is_dir() {
        return Err(ReportError::MissingFile {
            path: committed.to_path_buf(),
            hint: "the committed report folder to check".into(),
        });
    }
    let temporary = tempfile::tempdir().map_err(io_error(Path::new("temporary folder")))?;
    build(inputs, temporary.path())?;
    compare(committed, temporary.path())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn validation_finds_ragged_csv_bad_json_and_fake_images() {
        let p = |s: &str| PathBuf::from(s);
        assert_eq!(validate(&p("a.csv"), b"a,b\n1,2\n"), None);
        assert_eq!(
            validate(&p("a.csv"), b"a,b\n1,2\n3\n").as_deref(),
            Some("CSV error: record 2 (line: 3, byte: 8): found record with 1 fields, but the previous record has 2 fields")
        );
        assert!(validate(&p("run.json"), b"{\"a\": 1}").is_none());
        assert!(validate(&p("run.json"), b"{\"a\": ").is_some());
        assert!(validate(&p("f.png"), b"GIF89a not a png at all....").is_some());
        let mut png = b"\x89PNG\r\n\x1a\n\0\0\0\x0dIHDR".to_vec();
        png.extend([0u8; 13]);
        assert!(validate(&p("f.png"), &png).is_none());
        assert!(validate(&p("f.svg"), b"<svg></svg>\n").is_none());
        assert!(validate(&p("f.svg"), b"<svg>").is_some());
        assert!(validate(&p("t.md"), b"no heading").is_some());
        assert!(validate(&p("manifest.toml"), b"anything").is_none());
    }

    #[test]
    fn local_links_skip_anchors_and_urls() {
        let text = "[a](figures/a.png) [b](#regenerate) [c](https://x.org) ![d](tables/d.md)";
        assert_eq!(local_links(text), ["figures/a.png", "tables/d.md"]);
    }
}
