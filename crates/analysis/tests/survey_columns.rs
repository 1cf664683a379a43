//! Survey-server data (`experiments survey export`): the long layout with `order`, `swapped` and
//! `seconds`, and `controls.csv`. Checks the position effect (swaps undone, controls), the order
//! effect, the power table, bad values, and that data without these columns gives exactly the
//! tables it gave before.

use std::fmt::Write as _;
use std::path::{Path, PathBuf};

use rmt_analysis::tables::all_tables;
use rmt_analysis::{analyse, AnalysisError, Inputs, Options};

fn fixture(name: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("tests/fixtures")
        .join(name)
}

fn inputs(responses: &Path) -> Inputs {
    Inputs {
        responses: responses.to_path_buf(),
        questions: fixture("questions.csv"),
        configurations: fixture("configurations.csv"),
        format: None,
    }
}

/// 40 participants x the 8 fixture questions. Everyone clicks the left screen whenever a
/// question is not a tie; ties become more frequent later in the session; answers get faster.
/// Question `q` of participant `p` is shown at position `(q + p) % 8 + 1`, swapped when
/// `(q + p)` is odd (so swaps are balanced).
fn survey_file(dir: &Path) -> PathBuf {
    let mut text = String::from("participant,question,response,order,swapped,seconds\n");
    for p in 0..40 {
        for q in 0..8 {
            let order = (q + p) % 8 + 1;
            let swapped = (q + p) % 2 == 1;
            // Ties: positions 7 and 8 for every other participant.
            let tie = order >= 7 && p % 2 == 0;
            let response = match (tie, swapped) {
                (true, _) => "N",
                (false, false) => "L",
                (false, true) => "R", // the left screen showed the canonical right
            };
            let seconds = 10.0 - order as f64; // faster later
            let _ = writeln!(
                text,
                "P{p:02},Q{},{response},{order},{},{seconds:.1}",
                q + 1,
                u8::from(swapped)
            );
        }
    }
    let path = dir.join("responses.csv");
    std::fs::write(&path, text).unwrap();
    path
}

#[test]
fn position_order_and_power_from_survey_columns() {
    let dir = tempfile::tempdir().unwrap();
    let responses = survey_file(dir.path());
    let controls = dir.path().join("controls.csv");
    std::fs::write(
        &controls,
        "participant,control,configuration,name,response,order,seconds\n\
         P00,C1,ss_bu,bcdf,N,9,3.0\nP01,C1,ss_bu,bcdf,L,9,3.0\nP02,C1,ss_bu,bcdf,L,9,3.0\n",
    )
    .unwrap();
    let options = Options {
        resamples: 0,
        controls: Some(controls),
        ..Options::default()
    };
    let a = analyse(&inputs(&responses), &options).unwrap();
    let survey = a.survey.as_ref().expect("survey effects");

    // Everyone clicked the left screen: 40 x 8 answers minus 40 ties (20 participants x 2).
    let questions = &survey.position[0];
    assert_eq!(
        (questions.left, questions.none, questions.right),
        (280, 40, 0)
    );
    assert_eq!(questions.share_left, 1.0);
    assert!(questions.p_value < 1e-60);
    // Canonically the answers are half L, half R, so the old pooled test sees no bias.
    assert_eq!(a.position.left, a.position.right);
    let controls = &survey.position[1];
    assert_eq!((controls.left, controls.none, controls.right), (2, 1, 0));

    // Order: positions 1-3, 4-6, 7-8 in thirds; ties only at 7 and 8.
    let order = survey.order.as_ref().expect("order effect");
    let bins: Vec<(u32, u32, u64, u64)> = order
        .bins
        .iter()
        .map(|b| (b.first, b.last, b.answers, b.ties))
        .collect();
    assert_eq!(bins, [(1, 3, 120, 0), (4, 6, 120, 0), (7, 8, 80, 40)]);
    assert!(order.tie_trend_z > 5.0 && order.tie_trend_p < 1e-6);
    // Median time: first third 8 s (positions 1-3: 9, 8, 7), last third 2.5 s.
    assert_eq!(order.bins[0].median_seconds, 8.0);
    assert_eq!(order.bins[2].median_seconds, 2.5);
    assert_eq!((order.faster, order.slower), (40, 0));
    assert!((order.time_ratio - 2.5 / 8.0).abs() < 1e-12);

    // Power is on for survey data; every group has numbers.
    let power = survey.power.as_ref().expect("power");
    assert_eq!(power.m, 8);
    assert!(!power.groups.is_empty());
    for q in &power.questions {
        // Per question 5 of 40 answers are ties, all on one canonical side: 20 against 15.
        assert_eq!((q.pilot, q.tie_rate), (40, 5.0 / 40.0), "{}", q.question);
        assert_eq!(q.majority_share, 20.0 / 35.0, "{}", q.question);
        let needed = rmt_analysis::effects::participants_needed(20.0 / 35.0, 0.125, 0.05);
        assert_eq!(q.needed, needed);
        assert!(
            needed.unwrap() > 300,
            "a small effect needs many participants"
        );
        assert!(q.needed_holm.unwrap() > needed.unwrap());
        assert!((q.exact_power - 0.8).abs() < 0.05, "{}", q.exact_power);
    }
    let names: Vec<String> = all_tables(&a).into_iter().map(|t| t.name).collect();
    for name in [
        "position_effect",
        "order_effect",
        "power",
        "power_questions",
    ] {
        assert!(names.iter().any(|n| n == name), "{name} in {names:?}");
    }
}

#[test]
fn data_without_survey_columns_gives_the_same_tables_as_before() {
    let wide = fixture("responses_wide.csv");
    let a = analyse(
        &inputs(&wide),
        &Options {
            resamples: 0,
            ..Options::default()
        },
    )
    .unwrap();
    assert!(a.survey.is_none());
    let names: Vec<String> = all_tables(&a).into_iter().map(|t| t.name).collect();
    assert_eq!(
        names,
        [
            "preference_factors",
            "preference_weights",
            "preference_weight_intervals",
            "group_factors",
            "configuration_weights",
            "questions",
            "strengths",
            "summary"
        ]
    );
    // On request, the power table with this data as the pilot.
    let p = analyse(
        &inputs(&wide),
        &Options {
            resamples: 0,
            power: true,
            ..Options::default()
        },
    )
    .unwrap();
    let power = p.survey.as_ref().unwrap().power.as_ref().unwrap();
    // Q1: 0 left / 1 tie / 4 right: majority share 1, tie rate 0.2.
    let q1 = &power.questions[0];
    assert_eq!((q1.pilot, q1.majority_share, q1.tie_rate), (5, 1.0, 0.2));
    assert_eq!(
        q1.needed,
        rmt_analysis::effects::participants_needed(1.0, 0.2, 0.05)
    );
    assert!(q1.needed.is_some());
    assert!(p.survey.as_ref().unwrap().order.is_none());
}

#[test]
fn bad_survey_values_name_row_and_column() {
    let dir = tempfile::tempdir().unwrap();
    let responses = survey_file(dir.path());
    let text = std::fs::read_to_string(&responses).unwrap();
    let cases = [
        (
            "P00,Q1,L,1,0,9.0",
            "P00,Q1,L,1,maybe,9.0",
            "'swapped'",
            "0 or 1",
        ),
        (
            "P00,Q1,L,1,0,9.0",
            "P00,Q1,L,0,0,9.0",
            "'order'",
            "a position",
        ),
        (
            "P00,Q1,L,1,0,9.0",
            "P00,Q1,L,1,0,-2",
            "'seconds'",
            "non-negative",
        ),
    ];
    for (from, to, column, expected) in cases {
        assert!(text.contains(from));
        let bad = dir.path().join("bad.csv");
        std::fs::write(&bad, text.replacen(from, to, 1)).unwrap();
        let err = analyse(
            &inputs(&bad),
            &Options {
                resamples: 0,
                ..Options::default()
            },
        )
        .unwrap_err();
        assert!(matches!(err, AnalysisError::InvalidValue { .. }), "{err}");
        let message = err.to_string();
        assert!(
            message.contains("row 1") && message.contains(column) && message.contains(expected),
            "{message}"
        );
    }
}
