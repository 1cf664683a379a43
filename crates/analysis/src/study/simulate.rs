//! Simulated participants, and the check that the analysis recovers what was planted.
//!
//! **The planted model** ([`PlantedModel`]): a log-strength per configuration, a tie rate `t`
//! (the share of "no preference" between two equal configurations without a side bias, so the
//! tie parameter is `v = 2t / (1 - t)`), a left-side bias `α` (the left configuration's
//! strength is multiplied by α) and a fatigue drift `d`: at the share `x` of the way through a
//! participant's session (0 at the first question, 1 at the last) the tie parameter is
//! `v·exp(d·x)`. Each answer is drawn from the model of
//! [`crate::bradley_terry_position`] with these values; control questions too (one
//! configuration on both sides: only α and the ties matter). Answer times are drawn uniformly
//! from 4 to 12 s (no model reads them).
//!
//! **Coverage** ([`coverage`]): the same design (the same participants' plans), many studies
//! of answers drawn with different seeds, each analysed by [`super::analyse_study`]. Per
//! study: whether each configuration's 95% interval holds its planted log-strength (centred as
//! the analysis centres it), whether the interaction test rejects at 5%, whether the left bias
//! is detected (Wald test at 5%). The stated power of that detection is the one the design's
//! expected information gives at the planted values. A drift on ties leaves the odds among
//! decided answers untouched, so the strengths stay unbiased under it.

use super::design::{PairKind, ParticipantPlan, StudyItems, StudyPair};
use super::fit::{analyse_study, per_shading_parametrisation, StudyAnswer, StudyControl};
use crate::bradley_terry_position::{expected_information, probabilities, spd_inverse};
use crate::data::Answer;
use crate::effects::normal_cdf;
use crate::stats::{SplitMix64, Z_95};

/// What simulated participants answer from.
#[derive(Clone, Debug, PartialEq)]
pub struct PlantedModel {
    /// Log-strength of every configuration.
    pub log_strengths: Vec<f64>,
    /// Share of ties between equal configurations, no side bias, at the session's start.
    pub tie_rate: f64,
    /// Left-side odds multiplier α (1: none).
    pub left_bias: f64,
    /// Fatigue drift d of the tie log-propensity over a session.
    pub fatigue: f64,
}

impl PlantedModel {
    /// The tie log-propensity `ln v` at the share `x` of the session.
    pub fn tie_log(&self, x: f64) -> f64 {
        let t = self.tie_rate.clamp(1e-9, 1.0 - 1e-9);
        (2.0 * t / (1.0 - t)).ln() + self.fatigue * x
    }
}

/// Simulated answers, in the export's shape.
#[derive(Clone, Debug, PartialEq)]
pub struct Simulated {
    /// Answers to pairs.
    pub answers: Vec<StudyAnswer>,
    /// Seconds per answer.
    pub answer_seconds: Vec<f64>,
    /// Control answers.
    pub controls: Vec<StudyControl>,
    /// Seconds per control answer.
    pub control_seconds: Vec<f64>,
}

/// A uniform draw in [0, 1).
pub fn uniform(rng: &mut SplitMix64) -> f64 {
    (rng.next_u64() >> 11) as f64 / (1u64 << 53) as f64
}

/// One answer drawn from the probabilities of left, no preference, right.
pub fn draw(p: [f64; 3], rng: &mut SplitMix64) -> Answer {
    let u = uniform(rng);
    if u < p[0] {
        Answer::Left
    } else if u < p[0] + p[1] {
        Answer::NoPreference
    } else {
        Answer::Right
    }
}

/// Every participant of `plans` answers from `model` (seeded).
pub fn simulate(
    pairs: &[StudyPair],
    plans: &[ParticipantPlan],
    model: &PlantedModel,
    seed: u64,
) -> Simulated {
    let mut rng = SplitMix64::new(seed ^ 0xA45_3E25);
    let a = model.left_bias.ln();
    let mut out = Simulated {
        answers: Vec::new(),
        answer_seconds: Vec::new(),
        controls: Vec::new(),
        control_seconds: Vec::new(),
    };
    for (participant, plan) in plans.iter().enumerate() {
        let last = plan.questions.len().saturating_sub(1).max(1) as f64;
        for (k, shown) in plan.questions.iter().enumerate() {
            let u = model.tie_log(k as f64 / last);
            let p = probabilities(
                model.log_strengths[shown.left],
                model.log_strengths[shown.right],
                a,
                u,
            );
            let screen = draw(p, &mut rng);
            let seconds = 4.0 + 8.0 * uniform(&mut rng);
            let order = k as u32 + 1;
            match shown.pair {
                Some(pair) => {
                    let response = match (screen, shown.swapped) {
                        (Answer::Left, true) => Answer::Right,
                        (Answer::Right, true) => Answer::Left,
                        (r, _) => r,
                    };
                    debug_assert!(pairs.get(pair).is_some());
                    out.answers.push(StudyAnswer {
                        participant,
                        pair,
                        order,
                        swapped: shown.swapped,
                        response,
                    });
                    out.answer_seconds.push(seconds);
                }
                None => {
                    out.controls.push(StudyControl {
                        participant,
                        item: shown.left,
                        order,
                        response: screen,
                    });
                    out.control_seconds.push(seconds);
                }
            }
        }
    }
    out
}

/// Coverage of one group of configurations (a method in a shading, over objects).
#[derive(Clone, Debug, PartialEq)]
pub struct CoverageRow {
    /// Method index.
    pub method: usize,
    /// Shading index.
    pub shading: usize,
    /// Intervals checked (configurations x converged studies).
    pub intervals: u64,
    /// Intervals that held the planted value.
    pub covered: u64,
    /// Mean of estimate minus planted value.
    pub mean_error: f64,
}

/// What [`coverage`] finds.
#[derive(Clone, Debug, PartialEq)]
pub struct CoverageReport {
    /// Studies simulated.
    pub studies: usize,
    /// Studies whose fit did not converge (left out of the rates).
    pub failed: usize,
    /// Per method and shading.
    pub rows: Vec<CoverageRow>,
    /// Over every configuration.
    pub intervals: u64,
    /// Over every configuration.
    pub covered: u64,
    /// Whether the planted model has a method x shading interaction.
    pub planted_interaction: bool,
    /// Interaction tests run (converged).
    pub interaction_tests: u64,
    /// Of which rejected at 5%.
    pub interaction_rejections: u64,
    /// Left bias detected at 5% (Wald), out of the converged studies.
    pub bias_detected: u64,
    /// The power the design's expected information states for the planted left bias.
    pub stated_bias_power: f64,
    /// Mean fitted tie parameter v over studies.
    pub mean_tie_parameter: f64,
}

impl CoverageReport {
    /// Share of intervals that held the planted value.
    pub fn coverage(&self) -> f64 {
        self.covered as f64 / self.intervals.max(1) as f64
    }

    /// Share of interaction tests that rejected.
    pub fn interaction_rate(&self) -> f64 {
        self.interaction_rejections as f64 / self.interaction_tests.max(1) as f64
    }

    /// Share of converged studies that detected the left bias.
    pub fn bias_rate(&self) -> f64 {
        self.bias_detected as f64 / (self.studies - self.failed).max(1) as f64
    }
}

/// The planted log-strengths centred as the analysis centres them: within each object and
/// shading, over the configurations that method pairs compare.
pub fn planted_centred(items: &StudyItems, pairs: &[StudyPair], model: &PlantedModel) -> Vec<f64> {
    let in_pair: Vec<bool> = (0..items.len())
        .map(|i| {
            pairs
                .iter()
                .any(|p| p.kind == PairKind::Method && (p.first == i || p.second == i))
        })
        .collect();
    (0..items.len())
        .map(|i| {
            let (o, _, s) = items.parts(i);
            let block: Vec<usize> = (0..items.methods.len())
                .map(|m| items.item(o, m, s))
                .filter(|&j| in_pair[j])
                .collect();
            let mean = block.iter().map(|&j| model.log_strengths[j]).sum::<f64>()
                / block.len().max(1) as f64;
            model.log_strengths[i] - mean
        })
        .collect()
}

/// Whether method contrasts differ between shadings in the planted model.
pub fn has_interaction(items: &StudyItems, pairs: &[StudyPair], model: &PlantedModel) -> bool {
    let c = planted_centred(items, pairs, model);
    (0..items.objects.len()).any(|o| {
        (0..items.methods.len()).any(|m| {
            (1..items.shadings.len())
                .any(|s| (c[items.item(o, m, s)] - c[items.item(o, m, 0)]).abs() > 1e-12)
        })
    })
}

/// The power of the Wald test of the left bias that the design's expected information gives
/// at the planted values (ties at the middle of the session).
pub fn stated_bias_power(
    items: &StudyItems,
    pairs: &[StudyPair],
    plans: &[ParticipantPlan],
    model: &PlantedModel,
) -> f64 {
    let p = per_shading_parametrisation(items);
    let mut beta = vec![0.0; p.len()];
    // Each block's reference is its first item: strengths relative to it.
    let mut reference = vec![0.0; items.len()];
    for i in 0..items.len() {
        if p.strength_of[i].is_none() {
            reference[p.block_of[i]] = model.log_strengths[i];
        }
    }
    for i in 0..items.len() {
        if let Some(c) = p.strength_of[i] {
            beta[c] = model.log_strengths[i] - reference[p.block_of[i]];
        }
    }
    beta[p.position()] = model.left_bias.ln();
    beta[p.tie()] = model.tie_log(0.5);
    let mut shown: std::collections::BTreeMap<(usize, usize), f64> = Default::default();
    for plan in plans {
        for s in &plan.questions {
            if let Some(k) = s.pair {
                if pairs[k].kind == PairKind::Method {
                    *shown.entry((s.left, s.right)).or_insert(0.0) += 1.0;
                }
            }
        }
    }
    let list: Vec<(usize, usize, f64)> = shown.into_iter().map(|((l, r), n)| (l, r, n)).collect();
    let info = expected_information(&p, &list, &beta);
    // Items never compared have no information: drop their columns before inverting.
    let keep: Vec<usize> = (0..p.len()).filter(|&c| info[c][c] > 0.0).collect();
    let reduced: Vec<Vec<f64>> = keep
        .iter()
        .map(|&r| keep.iter().map(|&c| info[r][c]).collect())
        .collect();
    let Some(cov) = spd_inverse(&reduced) else {
        return f64::NAN;
    };
    let Some(at) = keep.iter().position(|&c| c == p.position()) else {
        return f64::NAN;
    };
    let se = cov[at][at].sqrt();
    let shift = model.left_bias.ln().abs() / se;
    normal_cdf(shift - Z_95) + normal_cdf(-shift - Z_95)
}

/// Simulates `studies` studies of the participants' `plans` answering from `model` (study `k`
/// drawn with seed `seed + k`) and checks the analysis against the planted values.
pub fn coverage(
    items: &StudyItems,
    pairs: &[StudyPair],
    plans: &[ParticipantPlan],
    model: &PlantedModel,
    studies: usize,
    seed: u64,
) -> CoverageReport {
    let planted = planted_centred(items, pairs, model);
    let mut rows: Vec<CoverageRow> = (0..items.shadings.len())
        .flat_map(|s| {
            (0..items.methods.len()).map(move |m| CoverageRow {
                method: m,
                shading: s,
                intervals: 0,
                covered: 0,
                mean_error: 0.0,
            })
        })
        .collect();
    let mut report = CoverageReport {
        studies,
        failed: 0,
        rows: Vec::new(),
        intervals: 0,
        covered: 0,
        planted_interaction: has_interaction(items, pairs, model),
        interaction_tests: 0,
        interaction_rejections: 0,
        bias_detected: 0,
        stated_bias_power: stated_bias_power(items, pairs, plans, model),
        mean_tie_parameter: 0.0,
    };
    let mut ties = 0.0;
    for k in 0..studies {
        let sim = simulate(pairs, plans, model, seed.wrapping_add(k as u64));
        let a = analyse_study(items, pairs, &sim.answers, &sim.controls);
        if !a.converged {
            report.failed += 1;
            continue;
        }
        ties += a.tie_parameter;
        for r in &a.strengths {
            let (_, m, s) = items.parts(r.item);
            let row = &mut rows[s * items.methods.len() + m];
            let truth = planted[r.item];
            row.intervals += 1;
            row.covered += u64::from(r.low <= truth && truth <= r.high);
            row.mean_error += r.log_strength - truth;
        }
        if let Some(t) = &a.interaction {
            if t.converged {
                report.interaction_tests += 1;
                report.interaction_rejections += u64::from(t.p_value < 0.05);
            }
        }
        report.bias_detected += u64::from(a.position.p_value < 0.05);
    }
    for row in &mut rows {
        row.mean_error /= row.intervals.max(1) as f64;
    }
    rows.retain(|r| r.intervals > 0);
    report.intervals = rows.iter().map(|r| r.intervals).sum();
    report.covered = rows.iter().map(|r| r.covered).sum();
    report.mean_tie_parameter = ties / (studies - report.failed).max(1) as f64;
    report.rows = rows;
    report
}

#[cfg(test)]
mod tests {
    use super::super::design::tests::items;
    use super::super::design::{assign, study_pairs};
    use super::*;

    /// Method strengths the same in both shadings (no interaction), flat a little worse.
    fn model(items: &StudyItems, interaction: f64) -> PlantedModel {
        let base = [0.4, 0.1, -0.2, -0.3];
        PlantedModel {
            log_strengths: (0..items.len())
                .map(|i| {
                    let (o, m, s) = items.parts(i);
                    base[m] + 0.05 * o as f64 - 0.3 * s as f64
                        + if s == 1 && m == 0 { interaction } else { 0.0 }
                })
                .collect(),
            tie_rate: 0.2,
            left_bias: 1.25,
            fatigue: 0.5,
        }
    }

    #[test]
    fn simulated_answers_follow_the_plans_and_the_model() {
        let it = items();
        let pairs = study_pairs(&it, None, true);
        let plans = assign(&it, &pairs, 24, 2, 300, 5);
        let m = model(&it, 0.0);
        let sim = simulate(&pairs, &plans, &m, 9);
        assert_eq!(sim.answers.len(), 300 * 24);
        assert_eq!(sim.controls.len(), 300 * 2);
        assert_eq!(sim, simulate(&pairs, &plans, &m, 9), "seeded");
        // Controls: left chosen over right about α = 1.25 times as often.
        let l = sim
            .controls
            .iter()
            .filter(|c| c.response == Answer::Left)
            .count() as f64;
        let r = sim
            .controls
            .iter()
            .filter(|c| c.response == Answer::Right)
            .count() as f64;
        assert!(l > r, "{l} {r}");
        // Fatigue: more ties in the last third than in the first.
        let a = analyse_study(&it, &pairs, &sim.answers, &sim.controls);
        let t = &a.order.thirds;
        let rate = |k: usize| t[k].ties as f64 / t[k].answers as f64;
        assert!(rate(2) > rate(0), "{:?}", t);
        // The strongest method is recovered in both shadings.
        for s in 0..2 {
            let best = a
                .methods
                .iter()
                .filter(|r| r.shading == s)
                .max_by(|x, y| x.log_strength.total_cmp(&y.log_strength))
                .unwrap();
            assert_eq!(best.method, 0);
        }
        // Shading pairs: smooth (first) preferred, as planted (flat 0.3 lower).
        for sp in &a.shading_pairs {
            assert!(sp.share_first > 0.5, "{sp:?}");
        }
    }

    /// The scaled-down coverage check: a few studies at the power table's size. Each bound
    /// fails when the intervals or the interaction test break (a standard error off by a
    /// factor of 1.5 gives 80% or 99.6% coverage; a test on the wrong degrees of freedom
    /// rejects far more or far less than 5%).
    #[test]
    fn coverage_in_small() {
        let it = items();
        let pairs = study_pairs(&it, None, true);
        let plans = assign(&it, &pairs, 24, 2, 162, 1);
        let m = model(&it, 0.0);
        let r = coverage(&it, &pairs, &plans, &m, 12, 100);
        assert_eq!(r.failed, 0);
        assert!(!r.planted_interaction);
        // 12 studies x 24 configurations = 288 intervals.
        assert_eq!(r.intervals, 288);
        let c = r.coverage();
        assert!((0.89..=0.99).contains(&c), "coverage {c}");
        assert!(
            r.interaction_rejections <= 3,
            "{}",
            r.interaction_rejections
        );
        assert!(r.stated_bias_power > 0.5 && r.stated_bias_power <= 1.0);
        assert!(r.bias_detected >= 6, "{}", r.bias_detected);
        // A planted interaction of 0.6 on one method is found in most studies.
        let strong = coverage(&it, &pairs, &plans, &model(&it, 0.6), 6, 200);
        assert!(strong.planted_interaction);
        assert!(strong.interaction_rejections >= 4, "{strong:?}");
    }
}
