//! The analysis of a study's answers.
//!
//! - **Strengths per shading**: one Bradley-Terry model with Davidson's ties and a left-side
//!   parameter ([`crate::bradley_terry_position`]) fitted to the method pairs, one block of
//!   strengths per object and shading (questions never compare objects, nor methods across
//!   shadings), the left-side and tie parameters shared. Each configuration's log-strength is
//!   reported centred within its block with a Wald 95% interval; the per-shading summary is
//!   the mean over objects (its standard error from the full covariance).
//! - **Does the ranking change with shading?** A likelihood-ratio test of that model against
//!   the one where each method has one strength per object in both shadings: twice the gain in
//!   log-likelihood, chi-square with objects x (methods - 1) x (shadings - 1) degrees of freedom.
//! - **Position**: the fitted left-side odds ratio α with its interval and Wald test, the
//!   screen side clicked among decided answers (binomial test), and the controls.
//! - **Order**: tie rate by thirds of the session, and the Cochran-Armitage trend of ties over
//!   positions (answers treated as independent).
//! - **Shading pairs**: per method, pooled over objects, the share of decided answers for each
//!   shading with a Wilson interval and the sign test.

use super::chi_square_sf;
use super::design::{PairKind, StudyItems, StudyPair};
use crate::bradley_terry_position::{fit, Parametrisation, PositionFit, ShownCounts};
use crate::data::Answer;
use crate::effects::normal_cdf;
use crate::stats::{sign_test, wilson_interval, Interval, Z_95};

/// One answer to a pair, canonical: `Left` prefers the pair's `first`.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct StudyAnswer {
    /// Participant number (0-based).
    pub participant: usize,
    /// The pair (index into the study's pairs).
    pub pair: usize,
    /// 1-based position in the participant's session.
    pub order: u32,
    /// Whether the canonical sides were swapped on screen.
    pub swapped: bool,
    /// The canonical answer.
    pub response: Answer,
}

/// One answer to a control question (one configuration on both sides), as the screen side.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct StudyControl {
    /// Participant number (0-based).
    pub participant: usize,
    /// The configuration shown.
    pub item: usize,
    /// 1-based position in the session.
    pub order: u32,
    /// The screen side clicked.
    pub response: Answer,
}

/// One configuration's strength.
#[derive(Clone, Debug, PartialEq)]
pub struct StrengthRow {
    /// The configuration.
    pub item: usize,
    /// Log-strength centred within its object and shading.
    pub log_strength: f64,
    /// Its standard error.
    pub se: f64,
    /// Wald 95% interval.
    pub low: f64,
    /// Wald 95% interval.
    pub high: f64,
}

/// A method's strength in one shading, averaged over objects.
#[derive(Clone, Debug, PartialEq)]
pub struct MethodStrength {
    /// Method index.
    pub method: usize,
    /// Shading index.
    pub shading: usize,
    /// Mean over objects of the centred log-strengths.
    pub log_strength: f64,
    /// Its standard error.
    pub se: f64,
}

/// The interaction test.
#[derive(Clone, Debug, PartialEq)]
pub struct InteractionTest {
    /// Twice the log-likelihood gain of strengths per shading.
    pub statistic: f64,
    /// Degrees of freedom.
    pub df: usize,
    /// Chi-square p-value.
    pub p_value: f64,
    /// Whether both fits converged.
    pub converged: bool,
}

/// The position effect.
#[derive(Clone, Debug, PartialEq)]
pub struct StudyPosition {
    /// Fitted left-side log-odds `a = ln α`.
    pub log_odds: f64,
    /// Its standard error.
    pub se: f64,
    /// Wald test of `a = 0`.
    pub p_value: f64,
    /// Decided answers on pairs that chose the left screen / the right screen.
    pub screen: [u64; 2],
    /// Binomial test of the screen sides against 1/2.
    pub screen_p: f64,
    /// Control answers: left screen, no preference, right screen.
    pub controls: [u64; 3],
    /// Binomial test of the controls' decided sides.
    pub controls_p: f64,
}

/// Ties over a third of the session.
#[derive(Clone, Debug, PartialEq)]
pub struct OrderThird {
    /// First position.
    pub first: u32,
    /// Last position.
    pub last: u32,
    /// Answers.
    pub answers: u64,
    /// No-preference answers.
    pub ties: u64,
    /// Wilson interval of the tie rate.
    pub wilson: Interval,
}

/// The order effect.
#[derive(Clone, Debug, PartialEq)]
pub struct StudyOrder {
    /// The three thirds.
    pub thirds: Vec<OrderThird>,
    /// Cochran-Armitage z of ties over positions (positive: more ties later).
    pub trend_z: f64,
    /// Its two-sided p-value.
    pub trend_p: f64,
}

/// Shading pairs of one method, pooled over objects.
#[derive(Clone, Debug, PartialEq)]
pub struct ShadingPreference {
    /// Method index.
    pub method: usize,
    /// The pair's shadings (first, second).
    pub shadings: (usize, usize),
    /// Answers for the first shading, ties, for the second.
    pub counts: [u64; 3],
    /// Share of decided answers for the first shading.
    pub share_first: f64,
    /// Its Wilson interval.
    pub wilson: Interval,
    /// Sign test.
    pub p_value: f64,
}

/// Everything [`analyse_study`] finds.
#[derive(Clone, Debug, PartialEq)]
pub struct StudyAnalysis {
    /// Participants with at least one answer.
    pub participants: usize,
    /// Answers to pairs.
    pub answers: usize,
    /// Per configuration in a method pair.
    pub strengths: Vec<StrengthRow>,
    /// Per method and shading, mean over objects.
    pub methods: Vec<MethodStrength>,
    /// The tie parameter v.
    pub tie_parameter: f64,
    /// Whether the strengths' fit converged.
    pub converged: bool,
    /// Method x shading interaction (`None` with one shading).
    pub interaction: Option<InteractionTest>,
    /// Position effect.
    pub position: StudyPosition,
    /// Order effect.
    pub order: StudyOrder,
    /// Shading pairs.
    pub shading_pairs: Vec<ShadingPreference>,
}

/// Answers to method pairs counted per shown (left, right) item pair.
fn shown_counts(pairs: &[StudyPair], answers: &[StudyAnswer]) -> Vec<ShownCounts> {
    let mut map: std::collections::BTreeMap<(usize, usize), [f64; 3]> = Default::default();
    for a in answers {
        let p = pairs[a.pair];
        if p.kind != PairKind::Method {
            continue;
        }
        let (left, right) = if a.swapped {
            (p.second, p.first)
        } else {
            (p.first, p.second)
        };
        // The screen side: a canonical "left" on a swapped question was clicked on the right.
        let screen = match (a.response, a.swapped) {
            (Answer::Left, true) => 2,
            (Answer::Right, true) => 0,
            (r, _) => r.index(),
        };
        map.entry((left, right)).or_insert([0.0; 3])[screen] += 1.0;
    }
    map.into_iter()
        .map(|((left, right), counts)| ShownCounts {
            left,
            right,
            counts,
        })
        .collect()
}

/// The strength model: one block per (object, shading).
pub fn per_shading_parametrisation(items: &StudyItems) -> Parametrisation {
    let blocks: Vec<usize> = (0..items.len())
        .map(|i| {
            let (o, _, s) = items.parts(i);
            o * items.shadings.len() + s
        })
        .collect();
    Parametrisation::per_item(&blocks)
}

/// The model without interaction: one block per object, a method's strength shared by its
/// shadings.
pub fn shared_parametrisation(items: &StudyItems) -> Parametrisation {
    let blocks: Vec<usize> = (0..items.len()).map(|i| items.parts(i).0).collect();
    let share: Vec<usize> = (0..items.len())
        .map(|i| {
            let (o, m, _) = items.parts(i);
            o * items.methods.len() + m
        })
        .collect();
    Parametrisation::shared(&blocks, &share)
}

/// Two-sided p-value of a standard normal statistic.
fn two_sided(z: f64) -> f64 {
    if z.is_finite() {
        2.0 * normal_cdf(-z.abs())
    } else {
        f64::NAN
    }
}

/// Analyses the answers of a study with configurations `items` and pairs `pairs`.
pub fn analyse_study(
    items: &StudyItems,
    pairs: &[StudyPair],
    answers: &[StudyAnswer],
    controls: &[StudyControl],
) -> StudyAnalysis {
    let data = shown_counts(pairs, answers);
    let full = per_shading_parametrisation(items);
    let fitted = fit(&full, &data);
    let in_method_pair: Vec<bool> = (0..items.len())
        .map(|i| {
            pairs
                .iter()
                .any(|p| p.kind == PairKind::Method && (p.first == i || p.second == i))
        })
        .collect();
    let strengths: Vec<StrengthRow> = (0..items.len())
        .filter(|&i| in_method_pair[i])
        .map(|item| {
            let (log_strength, se) = fitted.centred(&full, item);
            StrengthRow {
                item,
                log_strength,
                se,
                low: log_strength - Z_95 * se,
                high: log_strength + Z_95 * se,
            }
        })
        .collect();
    let methods = method_means(items, &full, &fitted, &in_method_pair);
    let interaction = (items.shadings.len() > 1).then(|| {
        let shared = shared_parametrisation(items);
        let reduced = fit(&shared, &data);
        let statistic = (2.0 * (fitted.log_likelihood - reduced.log_likelihood)).max(0.0);
        // Parameters that appear in the data only (methods never compared add nothing).
        let df = full.len() - shared.len();
        InteractionTest {
            statistic,
            df,
            p_value: chi_square_sf(statistic, df as f64),
            converged: fitted.converged && reduced.converged,
        }
    });
    let (log_odds, se) = fitted.position(&full);
    let screen = data.iter().fold([0u64; 2], |[l, r], d| {
        [l + d.counts[0] as u64, r + d.counts[2] as u64]
    });
    let mut control_counts = [0u64; 3];
    for c in controls {
        control_counts[c.response.index()] += 1;
    }
    let position = StudyPosition {
        log_odds,
        se,
        p_value: two_sided(log_odds / se),
        screen,
        screen_p: sign_test(screen[0], screen[1]),
        controls: control_counts,
        controls_p: sign_test(control_counts[0], control_counts[2]),
    };
    let mut participants: Vec<usize> = answers.iter().map(|a| a.participant).collect();
    participants.sort_unstable();
    participants.dedup();
    StudyAnalysis {
        participants: participants.len(),
        answers: answers.len(),
        strengths,
        methods,
        tie_parameter: fitted.tie_parameter(&full),
        converged: fitted.converged,
        interaction,
        position,
        order: order_effect(answers),
        shading_pairs: shading_preferences(items, pairs, answers),
    }
}

fn method_means(
    items: &StudyItems,
    p: &Parametrisation,
    f: &PositionFit,
    in_method_pair: &[bool],
) -> Vec<MethodStrength> {
    let mut out = Vec::new();
    for s in 0..items.shadings.len() {
        for m in 0..items.methods.len() {
            let members: Vec<usize> = (0..items.objects.len())
                .map(|o| items.item(o, m, s))
                .filter(|&i| in_method_pair[i])
                .collect();
            if members.is_empty() {
                continue;
            }
            let k = members.len() as f64;
            let mut w = vec![0.0; p.len()];
            for &i in &members {
                let block = p.block_of[i];
                let block_members: Vec<usize> = (0..items.len())
                    .filter(|&j| p.block_of[j] == block && in_method_pair[j])
                    .collect();
                let n = block_members.len() as f64;
                if let Some(c) = p.strength_of[i] {
                    w[c] += 1.0 / k;
                }
                for &j in &block_members {
                    if let Some(c) = p.strength_of[j] {
                        w[c] -= 1.0 / (n * k);
                    }
                }
            }
            let value: f64 = w.iter().zip(&f.beta).map(|(a, b)| a * b).sum();
            out.push(MethodStrength {
                method: m,
                shading: s,
                log_strength: value,
                se: f.standard_error(&w),
            });
        }
    }
    out
}

fn order_effect(answers: &[StudyAnswer]) -> StudyOrder {
    let last = answers.iter().map(|a| a.order).max().unwrap_or(0);
    let bin = |o: u32| -> usize {
        if last == 0 {
            0
        } else {
            ((o.saturating_sub(1)) as u64 * 3 / last as u64) as usize
        }
    };
    let mut thirds: Vec<OrderThird> = (0..3)
        .map(|b| OrderThird {
            first: (1..=last).find(|&o| bin(o) == b).unwrap_or(0),
            last: (1..=last).rev().find(|&o| bin(o) == b).unwrap_or(0),
            answers: 0,
            ties: 0,
            wilson: None,
        })
        .collect();
    // Cochran-Armitage over positions: scores are the positions.
    let (mut n, mut t, mut sx, mut sxx, mut sxt) = (0.0, 0.0, 0.0, 0.0, 0.0);
    for a in answers {
        let tie = a.response == Answer::NoPreference;
        let b = bin(a.order);
        thirds[b].answers += 1;
        thirds[b].ties += u64::from(tie);
        let x = f64::from(a.order);
        n += 1.0;
        sx += x;
        sxx += x * x;
        if tie {
            t += 1.0;
            sxt += x;
        }
    }
    for third in &mut thirds {
        third.wilson = wilson_interval(third.ties, third.answers, Z_95);
    }
    let pbar = if n > 0.0 { t / n } else { f64::NAN };
    let num = sxt - pbar * sx;
    let var = pbar * (1.0 - pbar) * (sxx - sx * sx / n);
    let trend_z = if var > 0.0 {
        num / var.sqrt()
    } else {
        f64::NAN
    };
    StudyOrder {
        thirds,
        trend_z,
        trend_p: two_sided(trend_z),
    }
}

fn shading_preferences(
    items: &StudyItems,
    pairs: &[StudyPair],
    answers: &[StudyAnswer],
) -> Vec<ShadingPreference> {
    let mut out = Vec::new();
    for m in 0..items.methods.len() {
        for s in 0..items.shadings.len() {
            for t in s + 1..items.shadings.len() {
                let mut counts = [0u64; 3];
                let mut any = false;
                for a in answers {
                    let p = pairs[a.pair];
                    if p.kind != PairKind::Shading {
                        continue;
                    }
                    let (f, g) = (items.parts(p.first), items.parts(p.second));
                    if f.1 != m {
                        continue;
                    }
                    let response = match (f.2, g.2) {
                        (x, y) if (x, y) == (s, t) => a.response.index(),
                        (x, y) if (x, y) == (t, s) => 2 - a.response.index(),
                        _ => continue,
                    };
                    any = true;
                    counts[response] += 1;
                }
                if !any {
                    continue;
                }
                let decided = counts[0] + counts[2];
                out.push(ShadingPreference {
                    method: m,
                    shadings: (s, t),
                    counts,
                    share_first: if decided > 0 {
                        counts[0] as f64 / decided as f64
                    } else {
                        f64::NAN
                    },
                    wilson: wilson_interval(counts[0], decided, Z_95),
                    p_value: sign_test(counts[0], counts[2]),
                });
            }
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::super::design::study_pairs;
    use super::*;

    #[test]
    fn shown_counts_undo_the_swap_into_screen_sides() {
        let items = StudyItems {
            objects: vec!["a".into()],
            methods: vec!["x".into(), "y".into()],
            shadings: vec!["smooth".into()],
        };
        let pairs = study_pairs(&items, None, false);
        let answers = [
            StudyAnswer {
                participant: 0,
                pair: 0,
                order: 1,
                swapped: true,
                response: Answer::Left,
            },
            StudyAnswer {
                participant: 1,
                pair: 0,
                order: 1,
                swapped: false,
                response: Answer::Left,
            },
        ];
        let c = shown_counts(&pairs, &answers);
        // Swapped: y was on the left and x (canonical left, preferred) on the right.
        assert_eq!(
            c,
            [
                ShownCounts {
                    left: 0,
                    right: 1,
                    counts: [1.0, 0.0, 0.0]
                },
                ShownCounts {
                    left: 1,
                    right: 0,
                    counts: [0.0, 0.0, 1.0]
                }
            ]
        );
    }

    #[test]
    fn the_reduced_model_shares_strengths_across_shadings() {
        let items = StudyItems {
            objects: vec!["a".into(), "b".into()],
            methods: vec!["x".into(), "y".into(), "z".into()],
            shadings: vec!["smooth".into(), "flat".into()],
        };
        let full = per_shading_parametrisation(&items);
        let shared = shared_parametrisation(&items);
        // Full: 4 blocks of 3 methods, 2 free each; shared: 2 blocks, 2 free each.
        assert_eq!(full.strengths, 8);
        assert_eq!(shared.strengths, 4);
        assert_eq!(
            shared.strength_of[items.item(1, 2, 0)],
            shared.strength_of[items.item(1, 2, 1)]
        );
    }
}
