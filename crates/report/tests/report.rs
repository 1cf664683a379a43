//! The report end to end on real run folders (`tests/fixtures/ci`: `experiments run` of
//! `experiments/manifests/ci.toml`; `tests/fixtures/scaling`: a small scaling sweep at 8..24
//! cells) and the bundled questionnaire data.

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

use rmt_report::{build, check, compare, Questionnaire, ReportInputs};

fn fixtures() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/fixtures")
}

fn questionnaire(resamples: usize) -> Questionnaire {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../data/questionnaire");
    Questionnaire {
        inputs: rmt_analysis::Inputs::in_dir(&dir),
        options: rmt_analysis::Options {
            resamples,
            ..rmt_analysis::Options::default()
        },
    }
}

fn inputs(run: &Path, scaling: Option<&Path>, resamples: Option<usize>) -> ReportInputs {
    ReportInputs {
        run: run.to_path_buf(),
        scaling: scaling.map(Path::to_path_buf),
        check_cost: None,
        peers: None,
        peers_seeds: None,
        study: None,
        lod: None,
        questionnaire: resamples.map(questionnaire),
        keep_raw: true,
    }
}

/// Every file under `dir` with its bytes, keyed by relative path.
fn tree(dir: &Path) -> BTreeMap<PathBuf, Vec<u8>> {
    fn walk(root: &Path, dir: &Path, out: &mut BTreeMap<PathBuf, Vec<u8>>) {
        for entry in std::fs::read_dir(dir).unwrap() {
            let path = entry.unwrap().path();
            if path.is_dir() {
                walk(root, &path, out);
            } else {
                let relative = path.strip_prefix(root).unwrap().to_path_buf();
                out.insert(relative, std::fs::read(&path).unwrap());
            }
        }
    }
    let mut out = BTreeMap::new();
    walk(dir, dir, &mut out);
    out
}

fn copy_dir(from: &Path, to: &Path) {
    std::fs::create_dir_all(to).unwrap();
    for entry in std::fs::read_dir(from).unwrap() {
        let path = entry.unwrap().path();
        std::fs::copy(&path, to.join(path.file_name().unwrap())).unwrap();
    }
}

#[test]
fn the_same_inputs_give_the_same_bytes_wherever_they_are() {
    // The second build reads copies of the inputs from other paths.
    let elsewhere = tempfile::tempdir().unwrap();
    let ci = elsewhere.path().join("some/other/ci");
    let scaling = elsewhere.path().join("scaling-copy");
    copy_dir(&fixtures().join("ci"), &ci);
    copy_dir(&fixtures().join("scaling"), &scaling);

    let a = tempfile::tempdir().unwrap();
    let b = tempfile::tempdir().unwrap();
    let files_a = build(
        &inputs(
            &fixtures().join("ci"),
            Some(&fixtures().join("scaling")),
            Some(1000),
        ),
        a.path(),
    )
    .unwrap();
    let files_b = build(&inputs(&ci, Some(&scaling), Some(1000)), b.path()).unwrap();
    assert_eq!(files_a, files_b);
    let (tree_a, tree_b) = (tree(a.path()), tree(b.path()));
    assert_eq!(
        tree_a.keys().collect::<Vec<_>>(),
        tree_b.keys().collect::<Vec<_>>()
    );
    for (path, bytes) in &tree_a {
        assert!(bytes == &tree_b[path], "{} differs", path.display());
    }
    // Every written file is listed, and only those.
    let listed: Vec<&PathBuf> = files_a.iter().collect();
    assert_eq!(listed, tree_a.keys().collect::<Vec<_>>());
    // The figures and tables the issue asks for.
    for name in [
        "triangles",
        "pass_times",
        "stage_shares",
        "aspect_ratio",
        "fidelity",
        "scaling",
    ] {
        for ext in ["png", "svg"] {
            let path = PathBuf::from(format!("figures/{name}.{ext}"));
            assert!(tree_a.contains_key(&path), "missing {}", path.display());
        }
    }
    for name in [
        "benchmark_summary",
        "paper_comparison",
        "paper_ratios",
        "scaling",
    ] {
        for ext in ["md", "csv"] {
            let path = PathBuf::from(format!("tables/{name}.{ext}"));
            assert!(tree_a.contains_key(&path), "missing {}", path.display());
        }
    }
    for name in ["preference_factors", "preference_weights", "bradley_terry"] {
        assert!(tree_a.contains_key(&PathBuf::from(format!("questionnaire/{name}.png"))));
    }
}

#[test]
fn a_report_rebuilds_identically_from_its_own_data_copy() {
    let out = tempfile::tempdir().unwrap();
    build(
        &inputs(
            &fixtures().join("ci"),
            Some(&fixtures().join("scaling")),
            Some(0),
        ),
        out.path(),
    )
    .unwrap();
    // data/ is a run folder, and data/scaling is found without being named.
    let data = out.path().join("data");
    let scaling = rmt_report::default_scaling(&data);
    assert_eq!(scaling.as_deref(), Some(data.join("scaling").as_path()));
    let outcome = check(&inputs(&data, scaling.as_deref(), Some(0)), out.path()).unwrap();
    assert!(outcome.passed(), "{outcome:?}");
    assert!(outcome.figures_changed.is_empty(), "{outcome:?}");
    assert!(outcome.compared > 40, "{}", outcome.compared);

    // Rebuilding over its own data folder changes nothing either.
    let before = tree(out.path());
    build(&inputs(&data, scaling.as_deref(), Some(0)), out.path()).unwrap();
    assert!(before == tree(out.path()));
}

#[test]
fn check_names_edited_missing_and_unexpected_files() {
    let out = tempfile::tempdir().unwrap();
    let ci = fixtures().join("ci");
    build(&inputs(&ci, None, None), out.path()).unwrap();
    let summary_md = out.path().join("tables/benchmark_summary.md");
    let mut text = std::fs::read_to_string(&summary_md).unwrap();
    text.push_str("edited\n");
    std::fs::write(&summary_md, text).unwrap();
    std::fs::remove_file(out.path().join("figures/triangles.svg")).unwrap();
    std::fs::write(out.path().join("tables/extra.csv"), "a\n1\n").unwrap();
    // A valid figure with other bytes is allowed (reported, not a failure).
    std::fs::copy(
        out.path().join("figures/triangles.png"),
        out.path().join("figures/pass_times.png"),
    )
    .unwrap();
    let ratios = out.path().join("tables/paper_ratios.csv");
    let mut ragged = std::fs::read_to_string(&ratios).unwrap();
    ragged.push_str("only,two\n");
    std::fs::write(&ratios, ragged).unwrap();
    let readme = out.path().join("README.md");
    let mut text = std::fs::read_to_string(&readme).unwrap();
    text.push_str("[gone](figures/gone.png)\n");
    std::fs::write(&readme, text).unwrap();
    // Files outside the folders the report owns are not its business.
    std::fs::write(out.path().join("notes.txt"), "mine").unwrap();

    let outcome = check(&inputs(&ci, None, None), out.path()).unwrap();
    assert!(!outcome.passed());
    assert_eq!(
        outcome.differing,
        [
            PathBuf::from("README.md"),
            PathBuf::from("tables/benchmark_summary.md"),
            PathBuf::from("tables/paper_ratios.csv"),
        ]
    );
    let invalid: Vec<(&str, &str)> = outcome
        .invalid
        .iter()
        .map(|(f, why)| (f.to_str().unwrap(), why.as_str()))
        .collect();
    assert_eq!(invalid.len(), 3, "{invalid:?}");
    assert_eq!(
        invalid[0],
        ("README.md", "links to missing figures/triangles.svg")
    );
    assert_eq!(
        invalid[1],
        ("README.md", "links to missing figures/gone.png")
    );
    assert_eq!(invalid[2].0, "tables/paper_ratios.csv");
    assert!(invalid[2].1.contains("found record with 2 fields"));
    assert_eq!(outcome.missing, [PathBuf::from("figures/triangles.svg")]);
    assert_eq!(outcome.unexpected, [PathBuf::from("tables/extra.csv")]);
    assert_eq!(
        outcome.figures_changed,
        [PathBuf::from("figures/pass_times.png")]
    );
}

#[test]
fn scaling_is_optional_and_a_rebuild_without_it_removes_its_files() {
    let out = tempfile::tempdir().unwrap();
    let ci = fixtures().join("ci");
    build(
        &inputs(&ci, Some(&fixtures().join("scaling")), None),
        out.path(),
    )
    .unwrap();
    assert!(out.path().join("figures/scaling.png").is_file());
    assert!(out.path().join("data/scaling/summary.csv").is_file());
    let readme = std::fs::read_to_string(out.path().join("README.md")).unwrap();
    assert!(readme.contains("![Time against resolution](figures/scaling.png)"));

    let files = build(&inputs(&ci, None, None), out.path()).unwrap();
    for gone in [
        "figures/scaling.png",
        "figures/scaling.svg",
        "tables/scaling.md",
        "tables/scaling.csv",
        "data/scaling/summary.csv",
        "data/scaling/run.json",
    ] {
        assert!(!out.path().join(gone).exists(), "{gone} left behind");
        assert!(!files.contains(&PathBuf::from(gone)));
    }
    let readme = std::fs::read_to_string(out.path().join("README.md")).unwrap();
    assert!(readme.contains("Not included: no scaling run was given"));
    assert!(!readme.contains("figures/scaling.png"));
    // And the smaller report checks clean against itself.
    let outcome = compare(out.path(), out.path()).unwrap();
    assert!(outcome.passed());
}

#[test]
fn every_file_parses_and_every_readme_link_resolves() {
    let out = tempfile::tempdir().unwrap();
    let files = build(
        &inputs(
            &fixtures().join("ci"),
            Some(&fixtures().join("scaling")),
            Some(0),
        ),
        out.path(),
    )
    .unwrap();
    for file in &files {
        let path = out.path().join(file);
        let bytes = std::fs::read(&path).unwrap();
        match path.extension().and_then(|e| e.to_str()) {
            Some("png") => {
                assert_eq!(&bytes[..8], b"\x89PNG\r\n\x1a\n", "{}", file.display());
                let width = u32::from_be_bytes(bytes[16..20].try_into().unwrap());
                let height = u32::from_be_bytes(bytes[20..24].try_into().unwrap());
                assert!(
                    width >= 400 && height >= 200,
                    "{}: {width}x{height}",
                    file.display()
                );
            }
            Some("svg") => {
                let text = String::from_utf8(bytes).unwrap();
                assert!(text.starts_with("<svg"), "{}", file.display());
                assert!(text.trim_end().ends_with("</svg>"), "{}", file.display());
                assert!(text.contains("<text"), "{}: no text", file.display());
            }
            Some("csv") => {
                let mut reader = csv::Reader::from_reader(bytes.as_slice());
                let columns = reader.headers().unwrap().len();
                assert!(columns >= 2, "{}", file.display());
                for record in reader.records() {
                    assert_eq!(record.unwrap().len(), columns, "{}", file.display());
                }
            }
            Some("json") => {
                serde_json::from_slice::<serde_json::Value>(&bytes).unwrap();
            }
            Some("md") => {
                let text = String::from_utf8(bytes).unwrap();
                assert!(text.starts_with('#'), "{}", file.display());
            }
            _ => {}
        }
    }
    let readme = std::fs::read_to_string(out.path().join("README.md")).unwrap();
    let mut links = 0;
    for part in readme.split("](").skip(1) {
        let target = &part[..part.find(')').unwrap()];
        if target.starts_with('#') || target.starts_with("http") {
            continue;
        }
        links += 1;
        assert!(
            out.path().join(target).exists(),
            "README links to missing {target}"
        );
    }
    assert!(links > 20, "{links}");
    // Provenance comes from run.json, not from the clock.
    let run: serde_json::Value =
        serde_json::from_slice(&std::fs::read(fixtures().join("ci/run.json")).unwrap()).unwrap();
    let date = run["provenance"]["date"].as_str().unwrap();
    let commit = &run["provenance"]["git_commit"].as_str().unwrap()[..12];
    assert!(readme.contains(date) && readme.contains(commit));
}

#[test]
fn the_summary_table_has_the_dissertations_columns_and_the_runs_numbers() {
    let out = tempfile::tempdir().unwrap();
    let ci = fixtures().join("ci");
    build(&inputs(&ci, None, None), out.path()).unwrap();
    let paper = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../data/paper/benchmark.csv");
    let paper_header: Vec<String> = csv::Reader::from_path(&paper)
        .unwrap()
        .headers()
        .unwrap()
        .iter()
        .map(String::from)
        .collect();
    let mut ours = csv::Reader::from_path(out.path().join("tables/benchmark_summary.csv")).unwrap();
    let header: Vec<String> = ours.headers().unwrap().iter().map(String::from).collect();
    assert_eq!(header[..paper_header.len()], paper_header[..]);

    let mut summary = csv::Reader::from_path(ci.join("summary.csv")).unwrap();
    let summary_header = summary.headers().unwrap().clone();
    let column = |name: &str| summary_header.iter().position(|h| h == name).unwrap();
    let expected: Vec<(String, String, String)> = summary
        .records()
        .map(|r| {
            let r = r.unwrap();
            (
                r[column("id")].to_string(),
                r[column("triangles")].to_string(),
                r[column("vertices")].to_string(),
            )
        })
        .collect();
    let got: Vec<(String, String, String)> = ours
        .records()
        .map(|r| {
            let r = r.unwrap();
            (r[0].to_string(), r[8].to_string(), r[7].to_string())
        })
        .collect();
    assert_eq!(got, expected);
}

#[test]
fn a_run_without_summary_says_how_to_finish_it() {
    let dir = tempfile::tempdir().unwrap();
    std::fs::copy(fixtures().join("ci/run.json"), dir.path().join("run.json")).unwrap();
    let out = tempfile::tempdir().unwrap();
    let error = build(&inputs(dir.path(), None, None), out.path())
        .unwrap_err()
        .to_string();
    assert!(error.contains("summary.csv: not found"), "{error}");
    assert!(error.contains("--resume"), "{error}");
    // Nothing was written.
    assert_eq!(std::fs::read_dir(out.path()).unwrap().count(), 0);
}

#[test]
fn a_bad_cell_names_file_line_and_column() {
    let dir = tempfile::tempdir().unwrap();
    copy_dir(&fixtures().join("ci"), dir.path());
    let path = dir.path().join("summary.csv");
    let text = std::fs::read_to_string(&path).unwrap();
    let mut lines: Vec<String> = text.lines().map(String::from).collect();
    let header: Vec<&str> = lines[0].split(',').collect();
    let triangles = header.iter().position(|h| *h == "triangles").unwrap();
    let mut cells: Vec<String> = lines[2].split(',').map(String::from).collect();
    cells[triangles] = "many".into();
    lines[2] = cells.join(",");
    std::fs::write(&path, lines.join("\n") + "\n").unwrap();
    let out = tempfile::tempdir().unwrap();
    let error = build(&inputs(dir.path(), None, None), out.path())
        .unwrap_err()
        .to_string();
    assert!(
        error.ends_with("summary.csv: line 3, column `triangles`: `many` is not a number"),
        "{error}"
    );
}

/// Reads `id`'s row of a CSV file as (column, cell) pairs.
fn csv_row(path: &Path, key_col: &str, key: &str) -> BTreeMap<String, String> {
    let mut reader = csv::Reader::from_path(path).unwrap();
    let header: Vec<String> = reader.headers().unwrap().iter().map(String::from).collect();
    let k = header.iter().position(|h| h == key_col).unwrap();
    for record in reader.records() {
        let record = record.unwrap();
        if &record[k] == key {
            return header
                .iter()
                .cloned()
                .zip(record.iter().map(String::from))
                .collect();
        }
    }
    panic!("{key} not in {}", path.display());
}

#[test]
fn the_check_cost_section_compares_unchecked_and_checked_with_the_dissertation() {
    let out = tempfile::tempdir().unwrap();
    let ci = fixtures().join("ci");
    let cost_run = fixtures().join("check-cost");
    let with_cost = ReportInputs {
        check_cost: Some(cost_run.clone()),
        ..inputs(&ci, None, None)
    };
    build(&with_cost, out.path()).unwrap();
    assert!(out.path().join("data/check-cost/summary.csv").is_file());
    let table = out.path().join("tables/check_cost.csv");
    let text = std::fs::read_to_string(&table).unwrap();
    // One row per configuration of the run: 3 objects x 2 lattices x 3 modes.
    assert_eq!(text.lines().count(), 1 + 18, "{text}");

    // Every row's counts are the run's own.
    let summary = cost_run.join("summary.csv");
    let mut reader = csv::Reader::from_path(&table).unwrap();
    let header: Vec<String> = reader.headers().unwrap().iter().map(String::from).collect();
    let col = |name: &str| header.iter().position(|h| h == name).unwrap();
    for record in reader.records() {
        let record = record.unwrap();
        let ours = csv_row(&summary, "id", &record[col("id")]);
        for c in [
            "triangles",
            "non_manifold_edges",
            "duplicate_triangles",
            "euler",
        ] {
            let a: f64 = record[col(c)].parse().unwrap();
            let b: f64 = ours[c].parse().unwrap();
            assert_eq!(a, b, "{} {c}", &record[col("id")]);
        }
        let passes = |row: &BTreeMap<String, String>| {
            row["t_vertex_s_mean"].parse::<f64>().unwrap()
                + row["t_geometry_s_mean"].parse::<f64>().unwrap()
        };
        let base_id = format!("{}u", &record[col("id")][..4]);
        let base = csv_row(&summary, "id", &base_id);
        let ratio: f64 = record[col("passes_over_none")].parse().unwrap();
        assert!((ratio - passes(&ours) / passes(&base)).abs() < 1e-5 * ratio);
    }

    // The dissertation's ratio on the unchecked row: its integrated passes over its unclustered
    // passes, straight from data/paper/benchmark.csv.
    let bench = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../data/paper/benchmark.csv");
    let theirs = |id: &str| {
        let row = csv_row(&bench, "id", id);
        row["t_vertex_s"].parse::<f64>().unwrap() + row["t_geometry_s"].parse::<f64>().unwrap()
    };
    let row = csv_row(&table, "id", "as_bc");
    let expected = theirs("as_bi") / theirs("as_bu");
    let got: f64 = row["dissertation_passes_over_none"].parse().unwrap();
    assert!((got - expected).abs() < 1e-5, "{got} against {expected}");
    assert_eq!(
        csv_row(&table, "id", "as_bi")["dissertation_passes_over_none"],
        ""
    );

    // The README's sentence counts defects from the data: unchecked meshes that have any, and
    // checked ones (RMT's guarantee: none).
    let broken = ["ss", "as", "bs"]
        .iter()
        .flat_map(|o| ["b", "s"].map(|l| format!("{o}_{l}c")))
        .filter(|id| {
            let r = csv_row(&summary, "id", id);
            [
                "non_manifold_edges",
                "duplicate_triangles",
                "boundary_edges_interior",
            ]
            .iter()
            .any(|c| r[*c] != "0")
        })
        .count();
    let readme = std::fs::read_to_string(out.path().join("README.md")).unwrap();
    assert!(readme.contains("## The cost of the exact check"));
    assert!(
        readme.contains(&format!(
            "Without the check, {broken} of 6 meshes have defects"
        )),
        "{readme}"
    );
    assert!(readme.contains("with it, 0 of 6 have defects and 0 change the topology"));
    assert!(readme.contains("(tables/check_cost.md)"));

    // The report's own data copy finds the run again, and a rebuild without it removes it all.
    let again = ReportInputs {
        check_cost: rmt_report::default_check_cost(&out.path().join("data")),
        ..inputs(&out.path().join("data"), None, None)
    };
    assert!(check(&again, out.path()).unwrap().passed());
    build(&inputs(&ci, None, None), out.path()).unwrap();
    for gone in ["tables/check_cost.csv", "data/check-cost/summary.csv"] {
        assert!(!out.path().join(gone).exists(), "{gone} left behind");
    }
    let readme = std::fs::read_to_string(out.path().join("README.md")).unwrap();
    assert!(!readme.contains("The cost of the exact check"));
}

#[test]
fn the_peers_section_shows_every_method_per_object_and_the_seed_intervals() {
    let out = tempfile::tempdir().unwrap();
    let ci = fixtures().join("ci");
    let with_peers = ReportInputs {
        peers: Some(fixtures().join("peers")),
        peers_seeds: Some(fixtures().join("peers-seeds")),
        ..inputs(&ci, None, None)
    };
    build(&with_peers, out.path()).unwrap();
    for file in [
        "data/peers/summary.csv",
        "data/peers-seeds/seeds.csv",
        "tables/peers.csv",
        "tables/peers_seeds.csv",
        "figures/peers_occupancy.png",
        "figures/peers_time_triangles.svg",
    ] {
        assert!(out.path().join(file).is_file(), "{file} missing");
    }
    assert!(!out.path().join("data/peers/raw.csv").exists());
    // One table row per configuration without the vertex-cache order: 5 objects x 15 methods.
    let table = std::fs::read_to_string(out.path().join("tables/peers.csv")).unwrap();
    assert_eq!(table.lines().count(), 1 + 5 * 15, "{table}");
    for method in [
        "RMT, body-centred",
        "marching cubes + meshopt, borders locked",
        "surface nets",
        "plain MT + meshopt, body-centred",
    ] {
        assert!(table.contains(method), "{method} missing");
    }
    let seeds = std::fs::read_to_string(out.path().join("tables/peers_seeds.csv")).unwrap();
    assert_eq!(seeds.lines().count(), 1 + 15, "{seeds}");
    let readme = std::fs::read_to_string(out.path().join("README.md")).unwrap();
    assert!(readme.contains("## Against what game developers use"));
    assert!(readme.contains("Where RMT loses") || readme.contains("RMT loses on none"));
    assert!(readme.contains("(figures/peers_occupancy.png)"));
    assert!(readme.contains("across asteroids"));

    // The report's own data copy finds both runs again; without them the section goes.
    let again = ReportInputs {
        peers: rmt_report::default_peers(&out.path().join("data")),
        peers_seeds: rmt_report::default_peers_seeds(&out.path().join("data")),
        ..inputs(&out.path().join("data"), None, None)
    };
    assert!(again.peers.is_some() && again.peers_seeds.is_some());
    assert!(check(&again, out.path()).unwrap().passed());
    build(&inputs(&ci, None, None), out.path()).unwrap();
    for gone in [
        "tables/peers.csv",
        "figures/peers_occupancy.png",
        "data/peers/summary.csv",
        "data/peers-seeds/seeds.csv",
    ] {
        assert!(!out.path().join(gone).exists(), "{gone} left behind");
    }
}

#[test]
fn the_study_section_is_built_from_simulated_answers_and_says_so() {
    let out = tempfile::tempdir().unwrap();
    let ci = fixtures().join("ci");
    let with_study = ReportInputs {
        study: Some(fixtures().join("study")),
        ..inputs(&ci, None, None)
    };
    build(&with_study, out.path()).unwrap();
    for file in [
        "data/study/study.csv",
        "data/study/responses.csv",
        "data/study/coverage.csv",
        "tables/study_strengths.csv",
        "tables/study_power.csv",
        "tables/study_coverage.csv",
    ] {
        assert!(out.path().join(file).is_file(), "{file} missing");
    }
    let readme = std::fs::read_to_string(out.path().join("README.md")).unwrap();
    assert!(readme.contains(
        "## A second study on screen, from simulated participants (no real answers yet)"
    ));
    assert!(readme.contains("**No participant has answered yet.**"));
    for heading in [
        "### Bradley-Terry with ties, per shading",
        "### Does the ranking change with shading?",
        "### Position and order",
        "### Power",
        "### Method: does the analysis recover what was planted?",
    ] {
        assert!(readme.contains(heading), "{heading} missing");
    }
    assert!(readme.contains("statistic ") && readme.contains("degrees of freedom"));
    // One strength per configuration (3 objects x 4 methods x 2 shadings) after the 8 means.
    let strengths = std::fs::read_to_string(out.path().join("tables/study_strengths.csv")).unwrap();
    assert_eq!(strengths.lines().count(), 1 + 8 + 24, "{strengths}");
    // The planted order (rmt-bcdl strongest, mc-meshopt weakest) comes back in both shadings.
    let mean = |method: &str, shading: &str| -> f64 {
        let line = strengths
            .lines()
            .find(|l| l.starts_with(&format!("all,{method},{shading},")))
            .unwrap();
        line.split(',').nth(3).unwrap().parse().unwrap()
    };
    for shading in ["smooth", "flat"] {
        assert!(
            mean("rmt-bcdl", shading) > mean("mc-meshopt", shading),
            "{shading}"
        );
    }
    // Power: the reference against each of the 3 peers in each shading.
    let power = std::fs::read_to_string(out.path().join("tables/study_power.csv")).unwrap();
    assert_eq!(power.lines().count(), 1 + 6, "{power}");

    // The report's own copy finds the study again; real answers drop "simulated" from the title.
    let again = ReportInputs {
        study: rmt_report::default_study(&out.path().join("data")),
        ..inputs(&out.path().join("data"), None, None)
    };
    assert!(again.study.is_some());
    assert!(check(&again, out.path()).unwrap().passed());
    let real = tempfile::tempdir().unwrap();
    for entry in std::fs::read_dir(fixtures().join("study")).unwrap() {
        let path = entry.unwrap().path();
        let text = std::fs::read_to_string(&path).unwrap();
        let text = text.replace("answers,simulated", "answers,real");
        std::fs::write(real.path().join(path.file_name().unwrap()), text).unwrap();
    }
    let with_real = ReportInputs {
        study: Some(real.path().to_path_buf()),
        ..inputs(&ci, None, None)
    };
    build(&with_real, out.path()).unwrap();
    let readme = std::fs::read_to_string(out.path().join("README.md")).unwrap();
    assert!(readme.contains("## A second study on screen\n"));
    assert!(!readme.contains("simulated participants (planted model"));
    // Without it the section and its files go.
    build(&inputs(&ci, None, None), out.path()).unwrap();
    for gone in ["tables/study_power.csv", "data/study/study.csv"] {
        assert!(!out.path().join(gone).exists(), "{gone} left behind");
    }
    let readme = std::fs::read_to_string(out.path().join("README.md")).unwrap();
    assert!(!readme.contains("A second study on screen"));
}

#[test]
fn the_lod_section_shows_the_level_map_from_above_and_triangles_per_level() {
    let out = tempfile::tempdir().unwrap();
    let ci = fixtures().join("ci");
    let with_lod = ReportInputs {
        lod: Some(fixtures().join("lod")),
        ..inputs(&ci, None, None)
    };
    let files = build(&with_lod, out.path()).unwrap();
    for file in [
        "data/lod/lod_map.csv",
        "data/lod/lod_levels.csv",
        "data/lod/lod.csv",
        "data/lod/summary.csv",
        "figures/lod_top_view.png",
        "figures/lod_top_view.svg",
        "figures/lod_triangles.png",
        "tables/lod_levels.csv",
        "tables/lod_summary.md",
    ] {
        assert!(out.path().join(file).is_file(), "{file} missing");
        assert!(
            files.iter().any(|f| f == Path::new(file)),
            "{file} not listed"
        );
    }
    let readme = std::fs::read_to_string(out.path().join("README.md")).unwrap();
    assert!(readme.contains("## Level of detail: the level map from above"));
    // The section names its world: the lod-ci manifest's caves.
    assert!(
        readme.contains("the `lod-ci` manifest's run"),
        "world not named"
    );
    assert!(readme.contains("caves of 64 x 32 x 64 finest cells"));
    assert!(readme.contains("![The level map from above](figures/lod_top_view.png)"));
    // Triangles per level at the last step add up to lod.csv's last step.
    let levels = std::fs::read_to_string(out.path().join("tables/lod_levels.csv")).unwrap();
    let total: u64 = levels
        .lines()
        .skip(1)
        .map(|l| l.split(',').nth(3).unwrap().parse::<u64>().unwrap())
        .sum();
    let steps = std::fs::read_to_string(fixtures().join("lod/lod.csv")).unwrap();
    let last = steps.lines().last().unwrap();
    let header: Vec<&str> = steps.lines().next().unwrap().split(',').collect();
    let col = header.iter().position(|h| *h == "triangles").unwrap();
    assert_eq!(
        total,
        last.split(',').nth(col).unwrap().parse::<u64>().unwrap()
    );
    assert_eq!(levels.lines().count(), 1 + 3, "levels 0-2");
    // Every chunk the section cuts is drawn: the SVG holds the level colours' rectangles.
    let svg = std::fs::read_to_string(out.path().join("figures/lod_top_view.svg")).unwrap();
    assert!(svg.matches("<rect").count() > 10);

    // The report's own copy finds the lod run again and rebuilds identically.
    let again = ReportInputs {
        lod: rmt_report::default_lod(&out.path().join("data")),
        ..inputs(&out.path().join("data"), None, None)
    };
    assert!(again.lod.is_some());
    assert!(check(&again, out.path()).unwrap().passed());
    // Without it the section and its files go.
    build(&inputs(&ci, None, None), out.path()).unwrap();
    for gone in [
        "tables/lod_levels.csv",
        "figures/lod_top_view.png",
        "data/lod/lod_map.csv",
    ] {
        assert!(!out.path().join(gone).exists(), "{gone} left behind");
    }
    let readme = std::fs::read_to_string(out.path().join("README.md")).unwrap();
    assert!(!readme.contains("Level of detail"));
}

#[test]
fn a_lod_folder_without_its_map_is_refused_by_name() {
    let dir = tempfile::tempdir().unwrap();
    copy_dir(&fixtures().join("lod"), dir.path());
    std::fs::remove_file(dir.path().join("lod_map.csv")).unwrap();
    assert!(!rmt_report::lod::is_lod(dir.path()));
    let with_lod = ReportInputs {
        lod: Some(dir.path().to_path_buf()),
        ..inputs(&fixtures().join("ci"), None, None)
    };
    let out = tempfile::tempdir().unwrap();
    let err = build(&with_lod, out.path()).unwrap_err().to_string();
    assert!(err.contains("lod_map.csv"), "{err}");
}
