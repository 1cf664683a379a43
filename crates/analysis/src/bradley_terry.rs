//! Bradley-Terry strengths with Davidson's (1970) extension for ties, fitted by the MM
//! (minorise-maximise) iteration of Hunter (2004).
//!
//! Model, for items i and j with strengths g_i, g_j > 0 and tie parameter v >= 0:
//! D = g_i + g_j + v sqrt(g_i g_j); P(i beats j) = g_i / D; P(tie) = v sqrt(g_i g_j) / D.
//! Updates (statistics.md): g_i <- (2 W_i + T_i) / Σ_j n_ij (2 + v sqrt(g_j / g_i)) / D_ij, then
//! normalise; v <- T / Σ_{i<j} n_ij sqrt(g_i g_j) / D_ij, starting from v = 2T / (N − T).
//! Both are the stationarity conditions of the likelihood, so a fixed point is the maximum
//! likelihood estimate.
//!
//! The estimate exists only when every split of the items into two sets has a win across it in
//! both directions (the win graph is strongly connected). Ties do not help: an item that only
//! ties and loses drives its strength to 0 and v to infinity (e.g. 0 wins, 2 losses, 3 ties: the
//! fitted shares must be 0, 2/5, 3/5). Otherwise a weak prior of `prior` virtual wins each way
//! between every two items is added and the fit says so.

/// Answers to one pair of items (several entries for the same pair are added up).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PairCounts {
    /// First item.
    pub i: usize,
    /// Second item.
    pub j: usize,
    /// Answers preferring `i`.
    pub wins_i: f64,
    /// Answers preferring `j`.
    pub wins_j: f64,
    /// "No preference" answers.
    pub ties: f64,
}

/// A fitted Davidson model.
#[derive(Clone, Debug, PartialEq)]
pub struct DavidsonFit {
    /// ln g_i, centred so that their mean is 0 (the geometric mean strength is 1).
    pub log_strengths: Vec<f64>,
    /// v: the tie propensity (0 when there are no ties).
    pub tie_parameter: f64,
    /// MM iterations used.
    pub iterations: usize,
    /// Whether the change per iteration fell below the tolerance.
    pub converged: bool,
    /// Whether the prior had to be added (no maximum likelihood estimate without it).
    pub prior_used: bool,
}

/// Iteration limit of [`fit_davidson`].
pub const MAX_ITERATIONS: usize = 20_000;
/// Convergence tolerance on ln g and on v (relative).
pub const TOLERANCE: f64 = 1e-11;

/// Fits strengths for `items` items from `pairs`; `prior` (e.g. 0.5) is the number of virtual
/// wins each way added between every two items when the data alone have no finite estimate.
///
/// Items that appear in no pair get log-strength 0 (they are pulled to the mean only by the prior).
pub fn fit_davidson(items: usize, pairs: &[PairCounts], prior: f64) -> DavidsonFit {
    let mut wins = vec![vec![0.0; items]; items];
    let mut ties = vec![vec![0.0; items]; items];
    for pair in pairs {
        if pair.i == pair.j || pair.i >= items || pair.j >= items {
            continue;
        }
        wins[pair.i][pair.j] += pair.wins_i;
        wins[pair.j][pair.i] += pair.wins_j;
        ties[pair.i][pair.j] += pair.ties;
        ties[pair.j][pair.i] += pair.ties;
    }
    let decided: f64 = wins.iter().flatten().sum();
    let prior_used = items > 1 && (decided <= 0.0 || !strongly_connected(&wins));
    if prior_used {
        for (i, row) in wins.iter_mut().enumerate() {
            for (j, w) in row.iter_mut().enumerate() {
                if i != j {
                    *w += prior;
                }
            }
        }
    }
    mm_iterations(&wins, &ties, prior_used)
}

/// Whether every item can reach every other through "beat" edges, in both directions (one
/// forward and one backward search from item 0 suffice).
fn strongly_connected(wins: &[Vec<f64>]) -> bool {
    let k = wins.len();
    let credit = |a: usize, b: usize| wins[a][b] > 0.0;
    let reach_all = |forward: bool| {
        let mut seen = vec![false; k];
        let mut stack = vec![0];
        seen[0] = true;
        while let Some(a) = stack.pop() {
            for (b, seen_b) in seen.iter_mut().enumerate() {
                let edge = if forward { credit(a, b) } else { credit(b, a) };
                if !*seen_b && edge {
                    *seen_b = true;
                    stack.push(b);
                }
            }
        }
        seen.iter().all(|&s| s)
    };
    k <= 1 || (reach_all(true) && reach_all(false))
}

fn mm_iterations(wins: &[Vec<f64>], ties: &[Vec<f64>], prior_used: bool) -> DavidsonFit {
    let k = wins.len();
    let n = |i: usize, j: usize| wins[i][j] + wins[j][i] + ties[i][j];
    // Numerators 2 W_i + T_i (each tie is half a win for both sides).
    let numerators: Vec<f64> = (0..k)
        .map(|i| 2.0 * wins[i].iter().sum::<f64>() + ties[i].iter().sum::<f64>())
        .collect();
    let total_ties: f64 = (0..k)
        .flat_map(|i| (i + 1..k).map(move |j| (i, j)))
        .map(|(i, j)| ties[i][j])
        .sum();
    let total: f64 = (0..k)
        .flat_map(|i| (i + 1..k).map(move |j| (i, j)))
        .map(|(i, j)| n(i, j))
        .sum();
    let mut g: Vec<f64> = vec![1.0; k];
    let mut v = if total_ties > 0.0 && total > total_ties {
        2.0 * total_ties / (total - total_ties)
    } else {
        0.0
    };
    let mut iterations = 0;
    let mut converged = k <= 1;
    while !converged && iterations < MAX_ITERATIONS {
        iterations += 1;
        let mut next = vec![1.0; k];
        for i in 0..k {
            let denominator: f64 = (0..k)
                .filter(|&j| j != i && n(i, j) > 0.0)
                .map(|j| {
                    let d = g[i] + g[j] + v * (g[i] * g[j]).sqrt();
                    n(i, j) * (2.0 + v * (g[j] / g[i]).sqrt()) / d
                })
                .sum();
            next[i] = if denominator > 0.0 {
                numerators[i] / denominator
            } else {
                g[i]
            };
        }
        normalise(&mut next);
        let next_v = if total_ties > 0.0 {
            let mut expected = 0.0;
            for i in 0..k {
                for j in i + 1..k {
                    if n(i, j) > 0.0 {
                        let root = (next[i] * next[j]).sqrt();
                        expected += n(i, j) * root / (next[i] + next[j] + v * root);
                    }
                }
            }
            if expected > 0.0 {
                total_ties / expected
            } else {
                v
            }
        } else {
            0.0
        };
        let change = g
            .iter()
            .zip(&next)
            .map(|(a, b)| (a.ln() - b.ln()).abs())
            .fold(0.0, f64::max)
            .max((next_v - v).abs() / (1.0 + v));
        g = next;
        v = next_v;
        converged = change < TOLERANCE;
    }
    let logs: Vec<f64> = g.iter().map(|x| x.ln()).collect();
    let mean = logs.iter().sum::<f64>() / k.max(1) as f64;
    DavidsonFit {
        log_strengths: logs.iter().map(|l| l - mean).collect(),
        tie_parameter: v,
        iterations,
        converged,
        prior_used,
    }
}

/// Scales strengths to geometric mean 1; the model only sees their ratios.
fn normalise(g: &mut [f64]) {
    let positive: Vec<f64> = g.iter().copied().filter(|x| *x > 0.0).collect();
    if positive.is_empty() {
        return;
    }
    let log_mean = positive.iter().map(|x| x.ln()).sum::<f64>() / positive.len() as f64;
    let scale = (-log_mean).exp();
    for x in g.iter_mut() {
        *x *= scale;
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn pair(i: usize, j: usize, wins_i: f64, wins_j: f64, ties: f64) -> PairCounts {
        PairCounts {
            i,
            j,
            wins_i,
            wins_j,
            ties,
        }
    }

    fn assert_log_strengths(fit: &DavidsonFit, strengths: &[f64]) {
        let logs: Vec<f64> = strengths.iter().map(|s| s.ln()).collect();
        let mean = logs.iter().sum::<f64>() / logs.len() as f64;
        for (got, want) in fit.log_strengths.iter().zip(&logs) {
            assert!(
                (got - (want - mean)).abs() < 1e-7,
                "{fit:?} vs {strengths:?}"
            );
        }
    }

    #[test]
    fn recovers_strengths_from_counts_that_match_the_model_exactly() {
        // g = (1, 2, 4), no ties: P(i beats j) = g_i / (g_i + g_j); counts proportional to the
        // probabilities make the model saturated, so the estimate is exactly (1, 2, 4).
        let pairs = [
            pair(0, 1, 1.0, 2.0, 0.0),
            pair(0, 2, 1.0, 4.0, 0.0),
            pair(1, 2, 2.0, 4.0, 0.0),
        ];
        let fit = fit_davidson(3, &pairs, 0.5);
        assert!(fit.converged && !fit.prior_used);
        assert_log_strengths(&fit, &[1.0, 2.0, 4.0]);
        assert_eq!(fit.tie_parameter, 0.0);
    }

    #[test]
    fn recovers_strengths_and_tie_parameter_with_ties() {
        // g = (1, 4, 16), v = 1: pair (a, b) has win : tie : loss = g_a : sqrt(g_a g_b) : g_b,
        // i.e. (1, 2, 4), (1, 4, 16) and (4, 8, 16): exactly the model's expectations.
        let pairs = [
            pair(0, 1, 1.0, 4.0, 2.0),
            pair(0, 2, 1.0, 16.0, 4.0),
            pair(1, 2, 4.0, 16.0, 8.0),
        ];
        let fit = fit_davidson(3, &pairs, 0.5);
        assert!(fit.converged && !fit.prior_used);
        assert_log_strengths(&fit, &[1.0, 4.0, 16.0]);
        assert!((fit.tie_parameter - 1.0).abs() < 1e-7, "{fit:?}");
    }

    #[test]
    fn two_items_match_the_multinomial_shares() {
        // 6 wins, 2 losses, 2 ties: g_1/g_2 = 3 and v sqrt(g_1 g_2) / g_2 = 2/2, so v = 1/sqrt 3.
        let fit = fit_davidson(2, &[pair(0, 1, 6.0, 2.0, 2.0)], 0.5);
        assert!((fit.log_strengths[0] - fit.log_strengths[1] - 3.0_f64.ln()).abs() < 1e-8);
        assert!((fit.tie_parameter - 1.0 / 3.0_f64.sqrt()).abs() < 1e-8);
    }

    #[test]
    fn a_never_winning_item_triggers_the_prior_and_stays_finite() {
        let pairs = [pair(0, 1, 5.0, 0.0, 0.0), pair(1, 2, 3.0, 1.0, 0.0)];
        let fit = fit_davidson(3, &pairs, 0.5);
        assert!(fit.prior_used && fit.converged);
        assert!(fit.log_strengths.iter().all(|l| l.is_finite()));
        assert!(fit.log_strengths[0] > fit.log_strengths[1]);
        assert!(fit.log_strengths[1] > fit.log_strengths[2]);
        // Ties do not rescue an item that never wins (its strength would go to 0 and v to
        // infinity): the prior is used and the fit converges.
        let fit = fit_davidson(2, &[pair(0, 1, 0.0, 2.0, 3.0)], 0.5);
        assert!(fit.prior_used && fit.converged, "{fit:?}");
        assert!(fit.log_strengths[0] < fit.log_strengths[1]);
        assert!(fit.tie_parameter.is_finite());
    }

    #[test]
    fn recovers_a_simulated_tie_parameter_within_a_few_percent() {
        use crate::stats::SplitMix64;
        let strengths = [1.0_f64, 1.8, 0.6, 2.5];
        let v_true = 0.7;
        let mut rng = SplitMix64::new(42);
        let mut pairs = Vec::new();
        for i in 0..4 {
            for j in i + 1..4 {
                let root = (strengths[i] * strengths[j]).sqrt();
                let d = strengths[i] + strengths[j] + v_true * root;
                let (mut wi, mut wj, mut t) = (0.0, 0.0, 0.0);
                for _ in 0..800 {
                    let u = (rng.next_u64() >> 11) as f64 / (1u64 << 53) as f64;
                    if u < strengths[i] / d {
                        wi += 1.0;
                    } else if u < (strengths[i] + v_true * root) / d {
                        t += 1.0;
                    } else {
                        wj += 1.0;
                    }
                }
                pairs.push(pair(i, j, wi, wj, t));
            }
        }
        let fit = fit_davidson(4, &pairs, 0.5);
        assert!(fit.converged);
        assert!(
            (fit.tie_parameter - v_true).abs() / v_true < 0.05,
            "{fit:?}"
        );
        let logs: Vec<f64> = strengths.iter().map(|s| s.ln()).collect();
        let mean = logs.iter().sum::<f64>() / 4.0;
        for (got, want) in fit.log_strengths.iter().zip(&logs) {
            assert!((got - (want - mean)).abs() < 0.1, "{fit:?}");
        }
    }
}
