//! Hand-computed checks on the small fixture questionnaire in `tests/fixtures/`:
//! 8 configurations (object sphere/bunny x lattice bcdl/simple x clustering none/integrated),
//! 8 questions, 5 participants, the same answers in the wide, long and survey-export layouts, and
//! one file per kind of bad input.
//!
//! Counts (left / none / right) of the fixture answers:
//! Q1 ss_bu-ss_bi 0/1/4, Q2 ss_su-ss_si 1/0/4, Q3 ss_bu-ss_su 4/0/1, Q4 ss_bi-ss_si 3/1/1,
//! Q5 bs_bu-bs_bi 1/0/4, Q6 bs_su-bs_si 0/1/4, Q7 bs_bu-bs_su 4/1/0, Q8 bs_bi-bs_si 3/1/1.

use std::path::{Path, PathBuf};

use rmt_analysis::tables::all_tables;
use rmt_analysis::{analyse, write_outputs, AnalysisError, InputFormat, Inputs, Options};

fn fixture(name: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("tests/fixtures")
        .join(name)
}

fn inputs(responses: &str) -> Inputs {
    Inputs {
        responses: fixture(responses),
        questions: fixture("questions.csv"),
        configurations: fixture("configurations.csv"),
        format: None,
    }
}

fn quick() -> Options {
    Options {
        resamples: 0,
        ..Options::default()
    }
}

fn close(a: f64, b: f64) -> bool {
    (a - b).abs() < 1e-12
}

#[test]
fn factors_and_weights_match_hand_computation() {
    let a = analyse(&inputs("responses_wide.csv"), &quick()).unwrap();
    assert_eq!(a.format, InputFormat::Wide);
    assert_eq!(a.participants.len(), 5);
    assert_eq!(a.basis.participants, 5);
    assert_eq!(a.basis.responses, 40);
    // Rows in the dissertation's order: clustering groups first (Q1 varies clustering).
    let labels: Vec<&str> = a.factors.iter().map(|r| r.label.as_str()).collect();
    assert_eq!(
        labels,
        [
            "clustering | lattice=bcdl",
            "clustering | lattice=simple",
            "lattice | clustering=none",
            "lattice | clustering=integrated"
        ]
    );
    // clustering | bcdl: sphere (Q1) none 0/5, integrated 4/5; bunny (Q5) 1/5, 4/5.
    // Means: none 0.1, integrated 0.8. Likewise for the other rows.
    let expected = [[0.1, 0.8], [0.1, 0.8], [0.8, 0.1], [0.6, 0.2]];
    for (row, want) in a.factors.iter().zip(expected) {
        assert_eq!(row.groups, 2);
        assert_eq!(row.responses, 10);
        for (level, w) in row.levels.iter().zip(want) {
            assert!(
                close(level.factor, w),
                "{}: {} vs {w}",
                row.label,
                level.factor
            );
        }
        // Ties count for nobody: a row's factors sum to at most 1.
        assert!(row.levels.iter().map(|l| l.factor).sum::<f64>() <= 1.0 + 1e-12);
    }
    // Weights: clustering down (none, integrated), lattice across (bcdl, simple).
    let w = &a.weights;
    assert_eq!(w.column_variable, "lattice");
    assert_eq!(w.columns, ["bcdl", "simple"]);
    assert_eq!(w.rows, ["none", "integrated"]);
    let want = [[0.9, 0.2], [1.4, 1.0]];
    for (got, want) in w.values.iter().flatten().zip(want.iter().flatten()) {
        assert!(close(*got, *want), "{:?}", w.values);
    }
    assert!(close(w.row_means[0], 0.55) && close(w.row_means[1], 1.2));
    assert!(close(w.column_means[0], 1.15) && close(w.column_means[1], 0.6));
    assert!(close(w.grand_mean, 0.875));
}

#[test]
fn question_statistics_match_hand_computation() {
    let a = analyse(&inputs("responses_wide.csv"), &quick()).unwrap();
    let q1 = &a.questions[0];
    assert_eq!((q1.counts.left, q1.counts.none, q1.counts.right), (0, 1, 4));
    // Sign test 0 vs 4: 2 * (1/2)^4.
    assert!(close(q1.p_value, 0.125));
    assert!(close(q1.tie_rate, 0.2));
    assert!(close(q1.net_preference, -0.8));
    // Q3: 4 vs 1: 2 * (1 + 5) / 32.
    assert!(close(a.questions[2].p_value, 0.375));
    // Holm over 8 questions: the smallest p (0.125, four ties at the top) times 8 exceeds 1.
    assert!(a
        .questions
        .iter()
        .all(|q| q.p_holm >= q.p_value && !q.significant));
    // Position: left 16 answers, right 19 (5 ties).
    assert_eq!((a.position.left, a.position.right), (16, 19));
}

#[test]
fn exclusion_removes_the_participant_from_every_table() {
    let options = Options {
        exclude: vec!["P05".into()],
        ..quick()
    };
    let a = analyse(&inputs("responses_wide.csv"), &options).unwrap();
    assert_eq!(a.participants, ["P01", "P02", "P03", "P04"]);
    assert_eq!(a.excluded, ["P05"]);
    assert_eq!(a.basis.participants, 4);
    assert_eq!(a.basis.responses, 32);
    // Q1 without P05: 0 / 1 / 3, so in the sphere group none 0/4, integrated 3/4; bunny Q5
    // without P05: 1 / 0 / 3: 1/4, 3/4. Means: none 0.125, integrated 0.75.
    let row = &a.factors[0];
    assert!(close(row.levels[0].factor, 0.125) && close(row.levels[1].factor, 0.75));
    let err = analyse(
        &inputs("responses_wide.csv"),
        &Options {
            exclude: vec!["P99".into()],
            ..quick()
        },
    )
    .unwrap_err();
    assert!(
        matches!(err, AnalysisError::UnknownParticipant { ref participant, .. } if participant == "P99")
    );
}

#[test]
fn all_three_formats_give_identical_tables() {
    let options = Options {
        resamples: 1_000,
        seed: 7,
        ..Options::default()
    };
    let render = |name: &str, format: InputFormat| {
        let a = analyse(&inputs(name), &options).unwrap();
        assert_eq!(a.format, format);
        all_tables(&a)
            .into_iter()
            // The summary names the responses file and its format; everything else must agree.
            .filter(|t| t.name != "summary")
            .map(|t| (t.name.clone(), t.to_csv(), t.to_markdown()))
            .collect::<Vec<_>>()
    };
    let wide = render("responses_wide.csv", InputFormat::Wide);
    let long = render("responses_long.csv", InputFormat::Long);
    let survey = render("responses_survey.csv", InputFormat::Survey);
    assert_eq!(wide.len(), 7);
    assert_eq!(wide, long);
    assert_eq!(wide, survey);
}

#[test]
fn an_explicit_format_overrides_detection() {
    let mut i = inputs("responses_long.csv");
    i.format = Some(InputFormat::Long);
    assert_eq!(analyse(&i, &quick()).unwrap().participants.len(), 5);
    // Read as wide, the long file's "question" column is not a question id.
    i.format = Some(InputFormat::Wide);
    let err = analyse(&i, &quick()).unwrap_err();
    assert!(
        matches!(err, AnalysisError::UnknownQuestion { ref column, .. } if column == "question"),
        "{err}"
    );
}

#[test]
fn outputs_are_byte_identical_for_the_same_inputs_and_seed() {
    let options = Options {
        resamples: 1_000,
        seed: 3,
        ..Options::default()
    };
    let a = analyse(&inputs("responses_wide.csv"), &options).unwrap();
    let b = analyse(&inputs("responses_wide.csv"), &options).unwrap();
    let (da, db) = (tempfile::tempdir().unwrap(), tempfile::tempdir().unwrap());
    let fa = write_outputs(&a, da.path()).unwrap();
    let fb = write_outputs(&b, db.path()).unwrap();
    assert_eq!(fa.len(), fb.len());
    for (x, y) in fa.iter().zip(&fb) {
        assert_eq!(x.file_name(), y.file_name());
        assert_eq!(
            std::fs::read(x).unwrap(),
            std::fs::read(y).unwrap(),
            "{}",
            x.display()
        );
    }
    for ext in ["csv", "md", "png", "svg"] {
        assert!(
            fa.iter().any(|f| f.extension().is_some_and(|e| e == ext)),
            "no .{ext}"
        );
    }
    // No temporary files are left behind.
    let leftovers: Vec<_> = std::fs::read_dir(da.path())
        .unwrap()
        .filter_map(|e| e.ok())
        .filter(|e| e.file_name().to_string_lossy().starts_with('.'))
        .collect();
    assert!(leftovers.is_empty());
    // A different seed changes the intervals (the continuous ones: factor intervals of five
    // participants move in steps of 0.1 and may coincide).
    let c = analyse(
        &inputs("responses_wide.csv"),
        &Options {
            seed: 4,
            ..options.clone()
        },
    )
    .unwrap();
    assert_ne!(a.strengths, c.strengths);
    assert_eq!(a.factors.len(), c.factors.len());
}

fn error_for(responses: &str, questions: &str, options: &Options) -> AnalysisError {
    let mut i = inputs(responses);
    i.questions = fixture(questions);
    analyse(&i, options).unwrap_err()
}

#[test]
fn each_bad_input_gives_its_specific_error() {
    let o = quick();
    let message = |e: &AnalysisError| e.to_string();

    let e = error_for("bad_unknown_question.csv", "questions.csv", &o);
    assert!(
        matches!(&e, AnalysisError::UnknownQuestion { location, question, .. }
        if location == "header" && question == "Q9"),
        "{e}"
    );
    assert!(message(&e).contains("bad_unknown_question.csv"));

    let e = error_for("bad_unknown_question_long.csv", "questions.csv", &o);
    assert!(
        matches!(&e, AnalysisError::UnknownQuestion { location, column, question, .. }
        if location == "row 41" && column == "question" && question == "Q42"),
        "{e}"
    );

    let e = error_for("bad_survey_unknown_question.csv", "questions.csv", &o);
    assert!(
        matches!(&e, AnalysisError::UnknownQuestion { question, .. } if question == "Q12"),
        "{e}"
    );

    let e = error_for("bad_invalid_answer.csv", "questions.csv", &o);
    assert!(
        matches!(&e, AnalysisError::InvalidAnswer { row: 3, column, value, .. }
        if column == "Q6" && value == "X"),
        "{e}"
    );
    assert!(message(&e).contains("row 3, column 'Q6'"));

    let e = error_for("bad_duplicate_participant.csv", "questions.csv", &o);
    assert!(
        matches!(&e, AnalysisError::DuplicateParticipant { row: 6, first_row: 2, participant, .. }
        if participant == "P02"),
        "{e}"
    );

    let e = error_for("bad_duplicate_answer_long.csv", "questions.csv", &o);
    assert!(
        matches!(&e, AnalysisError::DuplicateParticipant { row: 41, participant, question, .. }
        if participant == "P03" && question == "Q4"),
        "{e}"
    );

    let e = error_for("bad_missing_answer.csv", "questions.csv", &o);
    assert!(
        matches!(&e, AnalysisError::MissingAnswer { participant, question, location, .. }
        if participant == "P03" && question == "Q4" && location.contains("row 3")),
        "{e}"
    );

    let e = error_for("bad_missing_answer_long.csv", "questions.csv", &o);
    assert!(
        matches!(&e, AnalysisError::MissingAnswer { participant, question, .. }
        if participant == "P04" && question == "Q8"),
        "{e}"
    );

    let e = error_for(
        "responses_wide.csv",
        "bad_questions_unknown_configuration.csv",
        &o,
    );
    assert!(
        matches!(&e, AnalysisError::UnknownConfiguration { row: 6, column, name, .. }
        if column == "right" && name == "bs_sx"),
        "{e}"
    );

    let e = error_for("responses_wide.csv", "bad_questions_two_variables.csv", &o);
    assert!(
        matches!(&e, AnalysisError::Ungroupable { row: 4, differing: 2, question, .. }
        if question == "Q4"),
        "{e}"
    );

    let e = error_for("bad_duplicate_column.csv", "questions.csv", &o);
    assert!(
        matches!(&e, AnalysisError::DuplicateColumn { column, .. } if column == "Q1"),
        "{e}"
    );

    let e = error_for("bad_unknown_format.csv", "questions.csv", &o);
    assert!(matches!(&e, AnalysisError::UnknownFormat { .. }), "{e}");

    let e = error_for("missing_file.csv", "questions.csv", &o);
    assert!(matches!(&e, AnalysisError::Io { .. }), "{e}");
    assert!(message(&e).contains("missing_file.csv"));
}

#[test]
fn missing_answers_can_be_dropped_and_counted() {
    let options = Options {
        allow_missing: true,
        ..quick()
    };
    let a = analyse(&inputs("bad_missing_answer.csv"), &options).unwrap();
    assert_eq!(a.dropped_missing, 1);
    assert_eq!(a.responses, 39);
    // Q4 (ss_bi vs ss_si) without P03's answer: 3 / 1 / 0.
    let q4 = &a.questions[3];
    assert_eq!((q4.counts.left, q4.counts.none, q4.counts.right), (3, 1, 0));
    assert_eq!(a.basis.responses, 39);
    assert_eq!(a.basis.participants, 5);
}

#[test]
fn ungroupable_questions_can_be_reported_outside_all_groups() {
    let mut i = inputs("responses_wide.csv");
    i.questions = fixture("bad_questions_two_variables.csv");
    let options = Options {
        allow_ungrouped: true,
        ..quick()
    };
    let a = analyse(&i, &options).unwrap();
    assert_eq!(a.ungrouped.len(), 1);
    assert!(
        a.ungrouped[0].starts_with("Q4 (ss_bi vs ss_su)"),
        "{}",
        a.ungrouped[0]
    );
    assert_eq!(a.basis.responses, 35);
    assert!(a.questions[3].group.is_none());
}
