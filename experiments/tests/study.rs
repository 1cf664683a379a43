//! `experiments study`: plan, simulate, analyse and coverage through the command line, on the
//! bundled peers study and model; and a manifest crossed with shading rendered end to end.

use std::process::{Command, Output};

fn experiments(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_experiments"))
        .args(args)
        .current_dir(env!("CARGO_MANIFEST_DIR"))
        .output()
        .unwrap()
}

fn stdout(o: &Output) -> String {
    String::from_utf8_lossy(&o.stdout).into_owned()
}

fn stderr(o: &Output) -> String {
    String::from_utf8_lossy(&o.stderr).into_owned()
}

const STUDY: &str = "studies/peers.toml";
const MODEL: &str = "studies/peers-model.toml";

#[test]
fn plan_prints_questions_minutes_and_the_power_table() {
    let o = experiments(&["study", "plan", STUDY]);
    assert!(o.status.success(), "{}", stderr(&o));
    let text = stdout(&o);
    assert!(
        text.contains("questions per participant: 26 (24 pairs + 2 controls)"),
        "{text}"
    );
    assert!(
        text.contains("expected minutes per participant: 5.2"),
        "{text}"
    );
    assert!(
        text.contains("participants the power table asks for: **170**"),
        "{text}"
    );
    // One row per peer and shading.
    assert_eq!(text.matches("| 3 | 243 | 170 | 486 |").count(), 6, "{text}");
}

#[test]
fn simulate_then_analyse_recovers_the_planted_order() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("sim");
    let o = experiments(&[
        "study",
        "simulate",
        STUDY,
        "--participants",
        "200",
        "--model",
        MODEL,
        "--seed",
        "3",
        "--out",
        out.to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    for f in [
        "responses.csv",
        "controls.csv",
        "questions.csv",
        "configurations.csv",
        "participants.csv",
    ] {
        assert!(out.join(f).exists(), "{f}");
    }
    let responses = std::fs::read_to_string(out.join("responses.csv")).unwrap();
    assert!(responses.starts_with("participant,question,response,order,swapped,seconds\n"));
    assert_eq!(responses.lines().count(), 1 + 200 * 24);
    // The same seed writes the same bytes.
    let again = dir.path().join("again");
    let o = experiments(&[
        "study",
        "simulate",
        STUDY,
        "--participants",
        "200",
        "--model",
        MODEL,
        "--seed",
        "3",
        "--out",
        again.to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    assert_eq!(
        std::fs::read(again.join("responses.csv")).unwrap(),
        responses.as_bytes()
    );
    let report = dir.path().join("analysis.md");
    let o = experiments(&[
        "study",
        "analyse",
        STUDY,
        "--answers",
        out.to_str().unwrap(),
        "--title",
        "Simulated participants",
        "--out",
        report.to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    let text = std::fs::read_to_string(&report).unwrap();
    assert_eq!(text, stdout(&o));
    assert!(text.starts_with("# Simulated participants"), "{text}");
    assert!(text.contains("200 participants, 4800 answers"), "{text}");
    assert!(
        text.contains("Does the ranking change with shading?"),
        "{text}"
    );
    // The planted best method (rmt-bcdl, +0.35 smooth, +0.05 flat, centred: the highest in
    // both shadings) comes out positive in both.
    let line = text
        .lines()
        .find(|l| l.starts_with("| rmt-bcdl |"))
        .unwrap();
    assert_eq!(line.matches("| +").count(), 2, "{line}");
}

#[test]
fn coverage_runs_a_few_studies_and_bad_inputs_are_named() {
    let o = experiments(&[
        "study",
        "coverage",
        STUDY,
        "--model",
        MODEL,
        "--studies",
        "4",
        "--participants",
        "120",
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    let text = stdout(&o);
    assert!(
        text.contains("4 simulated studies of 120 participants"),
        "{text}"
    );
    assert!(text.contains("false-positive rate"), "{text}");
    let dir = tempfile::tempdir().unwrap();
    let bad = dir.path().join("bad.toml");
    std::fs::write(&bad, "tie_rate = 0.1\n[strengths.smooth]\nrmt-bcdl = 1.0\n").unwrap();
    let o = experiments(&[
        "study",
        "coverage",
        STUDY,
        "--model",
        bad.to_str().unwrap(),
        "--studies",
        "1",
    ]);
    assert!(!o.status.success());
    assert!(
        stderr(&o).contains("strengths.flat.rmt-bcdl is missing"),
        "{}",
        stderr(&o)
    );
    let o = experiments(&["study", "plan", "studies/none.toml"]);
    assert!(!o.status.success());
    assert!(stderr(&o).contains("none.toml"), "{}", stderr(&o));
}

/// A manifest crossed with shading: `run` writes the shading column, `render` draws the flat
/// configurations flat (their GIFs differ from the smooth ones of the same mesh), and the
/// questionnaire pairs configurations within a shading and shadings within a method.
#[test]
fn a_manifest_crossed_with_shading_renders_each_configuration_with_its_own() {
    let dir = tempfile::tempdir().unwrap();
    let manifest = dir.path().join("m.toml");
    std::fs::write(
        &manifest,
        "name = \"shade\"\nrepetitions = 1\nwarmup = 0\nthreads = 1\n\
         [[objects]]\nname = \"sphere\"\nresolution = 8\nradius = 0.8\n\
         [matrix]\nmethods = [\"mt\", \"mc\"]\nlattices = [\"bcdl\"]\n\
         clustering = [\"integrated\"]\nshading = [\"smooth\", \"flat\"]\n",
    )
    .unwrap();
    let run = dir.path().join("run");
    let o = experiments(&[
        "run",
        manifest.to_str().unwrap(),
        "--out",
        run.to_str().unwrap(),
        "--quiet",
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    let configurations = std::fs::read_to_string(run.join("configurations.csv")).unwrap();
    let header = configurations.lines().next().unwrap();
    assert!(header.ends_with(",shading"), "{header}");
    for id in ["ss_bi", "ss_bi_flat", "ss_mu", "ss_mu_flat"] {
        assert!(
            configurations.contains(&format!("\n{id},")),
            "{configurations}"
        );
    }
    let o = experiments(&[
        "render",
        run.to_str().unwrap(),
        "--width",
        "32",
        "--height",
        "32",
        "--frames",
        "3",
        "--supersampling",
        "1",
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    let key = std::fs::read_to_string(run.join("key.csv")).unwrap();
    let name_of = |id: &str| -> String {
        key.lines()
            .find(|l| l.split(',').nth(1) == Some(id))
            .unwrap()
            .split(',')
            .next()
            .unwrap()
            .to_string()
    };
    let gif = |id: &str| std::fs::read(run.join("render").join(format!("{}.gif", name_of(id))));
    assert_ne!(gif("ss_bi").unwrap(), gif("ss_bi_flat").unwrap());
    // --flat on a run that sets its own shading is refused.
    let o = experiments(&["render", run.to_str().unwrap(), "--flat"]);
    assert!(!o.status.success());
    assert!(stderr(&o).contains("shading"), "{}", stderr(&o));
    let o = experiments(&["questionnaire", run.to_str().unwrap()]);
    assert!(o.status.success(), "{}", stderr(&o));
    let qkey = std::fs::read_to_string(run.join("questionnaire_key.csv")).unwrap();
    // mt against mc differs in method, lattice and clustering: no single-variable pair. The
    // shading pairs are ss_bi/ss_bi_flat and ss_mu/ss_mu_flat.
    let rows: Vec<&str> = qkey.lines().skip(1).collect();
    assert_eq!(rows.len(), 2, "{qkey}");
    assert!(rows.iter().all(|r| r.contains(",shading,")), "{qkey}");
}

/// From a design to a served survey and back: `study run` on a small design, `survey serve
/// --per-participant`, simulated participants answering through the HTTP API, `survey
/// export`, `study analyse --key`.
#[test]
fn study_run_serves_balanced_subsets_that_simulated_participants_answer_over_http() {
    use std::io::{BufRead, BufReader};
    use std::process::Stdio;

    let dir = tempfile::tempdir().unwrap();
    std::fs::write(
        dir.path().join("m.toml"),
        "name = \"tiny\"\nrepetitions = 1\nwarmup = 0\nthreads = 1\n\
         [[objects]]\nname = \"sphere\"\nresolution = 8\nradius = 0.8\n\
         [matrix]\nlattices = [\"bcdl\", \"simple\"]\nclustering = [\"integrated\"]\n\
         shading = [\"smooth\", \"flat\"]\n",
    )
    .unwrap();
    let study = dir.path().join("s.toml");
    std::fs::write(
        &study,
        "name = \"tiny\"\nmanifest = \"m.toml\"\nobjects = [\"sphere\"]\nquestions = 3\n\
         controls = 1\n[[methods]]\nname = \"rmt-b\"\nmethod = \"mt\"\n\
         [[methods]]\nname = \"rmt-s\"\nmethod = \"mt\"\nlattice = \"simple\"\n",
    )
    .unwrap();
    let model = dir.path().join("model.toml");
    std::fs::write(
        &model,
        "tie_rate = 0.2\nleft_bias = 1.2\n[strengths.smooth]\nrmt-b = 0.5\nrmt-s = 0.0\n\
         [strengths.flat]\nrmt-b = 0.2\nrmt-s = -0.3\n",
    )
    .unwrap();
    let run = dir.path().join("run");
    let o = experiments(&[
        "study",
        "run",
        study.to_str().unwrap(),
        "--out",
        run.to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    let text = stdout(&o);
    assert!(text.contains("4 turntables"), "{text}");
    assert!(text.contains("within the 2 MB"), "{text}");
    assert!(text.contains("--per-participant 3"), "{text}");
    let qkey = std::fs::read_to_string(run.join("questionnaire_key.csv")).unwrap();
    assert_eq!(
        qkey,
        "question,left,right,kind,variable\n\
         Q1,ss_bi,ss_si,pair,method\n\
         Q2,ss_bi_flat,ss_si_flat,pair,method\n\
         Q3,ss_bi,ss_bi_flat,pair,shading\n\
         Q4,ss_si,ss_si_flat,pair,shading\n"
    );

    let mut server = std::process::Command::new(env!("CARGO_BIN_EXE_experiments"))
        .args(["survey", "serve"])
        .arg(&run)
        .args([
            "--addr",
            "127.0.0.1:0",
            "--controls",
            "1",
            "--per-participant",
            "3",
        ])
        .stdout(Stdio::piped())
        .stderr(Stdio::inherit())
        .spawn()
        .unwrap();
    let mut lines = BufReader::new(server.stdout.take().unwrap()).lines();
    let addr = loop {
        let line = lines.next().expect("server exited").unwrap();
        if let Some(rest) = line.strip_prefix("Listening on http://") {
            break rest.split('/').next().unwrap().to_string();
        }
    };
    std::thread::spawn(move || for _ in lines {});
    let o = experiments(&[
        "study",
        "simulate",
        study.to_str().unwrap(),
        "--model",
        model.to_str().unwrap(),
        "--participants",
        "20",
        "--serve",
        &addr,
        "--run",
        run.to_str().unwrap(),
    ]);
    server.kill().unwrap();
    server.wait().unwrap();
    assert!(o.status.success(), "{}", stderr(&o));
    // 3 pairs and 1 control each.
    assert!(stdout(&o).contains("sent 80 answers"), "{}", stdout(&o));
    let export = dir.path().join("export");
    let o = experiments(&[
        "survey",
        "export",
        run.join("survey.sqlite").to_str().unwrap(),
        "--out",
        export.to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    let o = experiments(&[
        "study",
        "analyse",
        study.to_str().unwrap(),
        "--answers",
        export.to_str().unwrap(),
        "--key",
        run.join("study_key.csv").to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    let text = stdout(&o);
    assert!(text.contains("20 participants, 60 answers"), "{text}");
    // Balanced subsets: each of the 4 questions answered 15 times (60 / 4).
    let responses = std::fs::read_to_string(export.join("responses.csv")).unwrap();
    for q in ["Q1", "Q2", "Q3", "Q4"] {
        let n = responses
            .lines()
            .filter(|l| l.split(',').nth(1) == Some(q))
            .count();
        assert_eq!(n, 15, "{q}");
    }
}

/// The report's study section from the command line: `study simulate --out` writes the design's
/// numbers beside the export files, `study coverage --out` its table, `report --study` the
/// section (titled as simulated), and `report --check` rebuilds it from the report's copy.
#[test]
fn simulate_and_coverage_write_what_report_study_reads() {
    let dir = tempfile::tempdir().unwrap();
    let sim = dir.path().join("sim");
    let s = sim.to_str().unwrap();
    let o = experiments(&[
        "study",
        "simulate",
        STUDY,
        "--participants",
        "30",
        "--model",
        MODEL,
        "--seed",
        "5",
        "--out",
        s,
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    let design = std::fs::read_to_string(sim.join("study.csv")).unwrap();
    for row in [
        "participants,30\n",
        "questions,24\n",
        "reference,rmt-bcdl\n",
        "answers,simulated\n",
        "model,peers-model.toml\n",
        "seed,5\n",
    ] {
        assert!(design.contains(row), "{row} missing: {design}");
    }
    let o = experiments(&[
        "study",
        "coverage",
        STUDY,
        "--model",
        MODEL,
        "--studies",
        "3",
        "--participants",
        "30",
        "--out",
        s,
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    let coverage = std::fs::read_to_string(sim.join("coverage.csv")).unwrap();
    assert!(coverage.starts_with("method,shading,intervals,covered,mean_error\n"));
    assert_eq!(coverage.lines().count(), 1 + 8, "{coverage}");
    let tests = std::fs::read_to_string(sim.join("coverage_tests.csv")).unwrap();
    assert!(
        tests.contains("studies,3\n") && tests.contains("participants,30\n"),
        "{tests}"
    );

    let report = dir.path().join("report");
    let run = concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/../crates/report/tests/fixtures/ci"
    );
    let args = |check: bool| {
        let mut a = vec![
            "report",
            "--run",
            run,
            "--out",
            report.to_str().unwrap(),
            "--study",
            s,
            "--no-questionnaire",
        ];
        if check {
            a.push("--check");
        }
        a
    };
    let o = experiments(&args(false));
    assert!(o.status.success(), "{}", stderr(&o));
    let readme = std::fs::read_to_string(report.join("README.md")).unwrap();
    assert!(
        readme.contains(
            "## A second study on screen, from simulated participants (no real answers yet)"
        ),
        "{readme}"
    );
    assert!(readme.contains("30 simulated participants"), "{readme}");
    assert!(report.join("tables/study_coverage.md").is_file());
    assert!(report.join("data/study/responses.csv").is_file());
    let o = experiments(&args(true));
    assert!(o.status.success(), "{}{}", stdout(&o), stderr(&o));
}
