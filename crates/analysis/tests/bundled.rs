//! The bundled questionnaire (data/questionnaire: 18 configurations, 27 questions, 19 answer
//! columns): both tables for all participants and with an exclusion, and the properties the
//! method guarantees.

use std::path::Path;

use rmt_analysis::analysis::question_counts;
use rmt_analysis::input::{load, LoadOptions};
use rmt_analysis::method::tally;
use rmt_analysis::tables::{factors_table, weights_table};
use rmt_analysis::{analyse, Inputs, Options};

fn bundled() -> Inputs {
    Inputs::in_dir(&Path::new(env!("CARGO_MANIFEST_DIR")).join("../../data/questionnaire"))
}

#[test]
fn tables_for_all_participants_follow_the_method() {
    let options = Options {
        resamples: 1_000,
        ..Options::default()
    };
    let a = analyse(&bundled(), &options).unwrap();
    assert_eq!(a.participants.len(), 19);
    assert_eq!(a.questions.len(), 27);
    assert_eq!(a.basis.participants, 19);
    assert_eq!(a.basis.responses, 19 * 27);
    // 3 objects x (2 clustering groups + 3 lattice groups), averaged into 5 rows.
    assert_eq!(a.design.groups.len(), 15);
    assert_eq!(a.factors.len(), 5);
    for group in &a.group_factors {
        let sum: f64 = group.configurations.iter().map(|c| c.factor).sum();
        assert!(sum <= 1.0 + 1e-12, "{}: {sum}", group.label);
        assert_eq!(group.responses, 19 * group.questions.len() as u64);
    }
    for row in &a.factors {
        assert_eq!(row.groups, 3);
        let sum: f64 = row.levels.iter().map(|l| l.factor).sum();
        assert!(sum <= 1.0 + 1e-12, "{}: {sum}", row.label);
        for level in &row.levels {
            let (lo, hi) = level.interval.unwrap();
            assert!(
                lo <= level.factor + 1e-12 && level.factor <= hi + 1e-12,
                "{}",
                row.label
            );
        }
    }
    // Each weight is its clustering-group mean factor plus its lattice-group mean factor.
    let w = &a.weights;
    assert_eq!(w.rows, ["none", "integrated", "postprocessed"]);
    assert_eq!(w.columns, ["bcdl", "simple"]);
    for (r, clustering) in w.rows.iter().enumerate() {
        for (c, lattice) in w.columns.iter().enumerate() {
            let factor = |varied: &str, fixed: &str, level: &str| {
                a.factors
                    .iter()
                    .find(|row| row.varied == varied && row.fixed == fixed)
                    .and_then(|row| row.levels.iter().find(|l| l.level == level))
                    .map(|l| l.factor)
                    .unwrap()
            };
            let expected = factor("clustering", &format!("lattice={lattice}"), clustering)
                + factor("lattice", &format!("clustering={clustering}"), lattice);
            assert!((w.values[r][c] - expected).abs() < 1e-12);
        }
    }
    let factors = factors_table(&a).to_markdown();
    assert!(
        factors.contains("Participants: 19; responses: 513"),
        "{factors}"
    );
    assert!(weights_table(&a).to_markdown().contains("Participants: 19"));
    // Holm never lowers a p-value, and every significant question has a winner.
    for q in &a.questions {
        assert!(q.p_holm >= q.p_value);
        assert_eq!(q.significant, q.preferred.is_some());
    }
}

#[test]
fn tables_with_an_exclusion_count_one_participant_fewer() {
    let options = Options {
        exclude: vec!["P18".into()],
        resamples: 0,
        ..Options::default()
    };
    let a = analyse(&bundled(), &options).unwrap();
    let all = analyse(
        &bundled(),
        &Options {
            resamples: 0,
            ..Options::default()
        },
    )
    .unwrap();
    assert_eq!(a.participants.len(), 18);
    assert!(!a.participants.contains(&"P18".to_string()));
    assert_eq!(a.basis.participants, 18);
    assert_eq!(a.basis.responses, 18 * 27);
    assert!(factors_table(&a).to_markdown().contains("Excluded: P18."));
    // The exclusion changes the counts of every question by exactly P18's answer.
    for (q, (x, y)) in a.questions.iter().zip(&all.questions).enumerate() {
        assert_eq!(x.counts.total() + 1, y.counts.total(), "question {q}");
    }
    for row in &a.factors {
        assert!(row.levels.iter().map(|l| l.factor).sum::<f64>() <= 1.0 + 1e-12);
    }
}

#[test]
fn polars_counts_agree_with_the_bootstrap_tally() {
    let dataset = load(&bundled(), &LoadOptions::default()).unwrap();
    let responses = &dataset.responses;
    let from_polars = question_counts(&responses.long, dataset.questions.len()).unwrap();
    let everyone: Vec<usize> = (0..responses.participants.len()).collect();
    let from_tally = tally(&responses.answers, dataset.questions.len(), &everyone);
    assert_eq!(from_polars, from_tally);
    assert_eq!(from_polars.iter().map(|c| c.total()).sum::<u64>(), 513);
}
