//! Bradley-Terry with Davidson's ties and a screen-position (left-side) parameter, fitted by
//! Newton's method to the answers as shown on screen, with Wald intervals from the observed
//! information.
//!
//! Model, for the configuration shown on the left `L` and on the right `R`, log-strengths
//! `λ`, left-side log-odds `a = ln α` and tie log-propensity `u = ln v`:
//!
//! ```text
//! η_left = a + λ_L,   η_right = λ_R,   η_tie = u + (a + λ_L + λ_R) / 2
//! P(answer) = exp(η_answer) / (exp(η_left) + exp(η_tie) + exp(η_right))
//! ```
//!
//! which is Davidson's model (`D = αg_L + g_R + v sqrt(αg_L g_R)`, statistics.md) with the
//! left strength multiplied by α (the "home advantage" form). With α = 1 it is the model of
//! [`crate::bradley_terry`]. Every η is linear in the parameters, so the log-likelihood is that
//! of a multinomial logit: concave, with gradient `Σ (x_y − Σ_c p_c x_c)` and information
//! `Σ (Σ_c p_c x_c x_cᵀ − x̄ x̄ᵀ)` over answers (x_c the coefficients of η_c).
//!
//! Strengths are identified only within a **block** of items that questions connect; each
//! block's first item is the reference (λ = 0 fixed). Several items may share one strength
//! parameter (`strength_of`): the interaction test fits one strength per method shared by both
//! shadings against one per method and shading. Reported strengths are centred per block (mean
//! 0), with the delta-method variance `wᵀ Σ w` of the centring contrast.

/// Answers counted per ordered pair of items as shown (left, right).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ShownCounts {
    /// The item on the left screen.
    pub left: usize,
    /// The item on the right screen.
    pub right: usize,
    /// Answers "prefer left", "no preference", "prefer right".
    pub counts: [f64; 3],
}

/// Which parameter each item's strength is.
#[derive(Clone, Debug, PartialEq)]
pub struct Parametrisation {
    /// Per item: its strength parameter, `None` when fixed at 0 (a block's reference).
    pub strength_of: Vec<Option<usize>>,
    /// Number of free strength parameters.
    pub strengths: usize,
    /// Per item: its block (for centring).
    pub block_of: Vec<usize>,
}

impl Parametrisation {
    /// One parameter per item, the first item of each block fixed. `block_of[i]` is item `i`'s
    /// block; blocks are numbered from 0.
    pub fn per_item(block_of: &[usize]) -> Self {
        Self::shared(block_of, &(0..block_of.len()).collect::<Vec<_>>())
    }

    /// Items with equal `share[i]` share one strength parameter; the first shared value seen in
    /// each block is the reference. Items that share must be in the same block.
    pub fn shared(block_of: &[usize], share: &[usize]) -> Self {
        let mut reference_of_block: Vec<Option<usize>> = Vec::new();
        let mut column_of_share: std::collections::BTreeMap<usize, Option<usize>> =
            std::collections::BTreeMap::new();
        let mut strengths = 0;
        let mut strength_of = Vec::with_capacity(block_of.len());
        for (i, &b) in block_of.iter().enumerate() {
            if reference_of_block.len() <= b {
                reference_of_block.resize(b + 1, None);
            }
            let column = *column_of_share.entry(share[i]).or_insert_with(|| {
                if reference_of_block[b].is_none() {
                    reference_of_block[b] = Some(share[i]);
                    None
                } else {
                    strengths += 1;
                    Some(strengths - 1)
                }
            });
            strength_of.push(column);
        }
        Self {
            strength_of,
            strengths,
            block_of: block_of.to_vec(),
        }
    }

    /// Parameters in all: strengths, then `a`, then `u`.
    pub fn len(&self) -> usize {
        self.strengths + 2
    }

    /// Whether there are no parameters (never: `a` and `u` are always there).
    pub fn is_empty(&self) -> bool {
        false
    }

    /// Index of the left-side parameter `a = ln α`.
    pub fn position(&self) -> usize {
        self.strengths
    }

    /// Index of the tie parameter `u = ln v`.
    pub fn tie(&self) -> usize {
        self.strengths + 1
    }
}

/// A fitted model.
#[derive(Clone, Debug, PartialEq)]
pub struct PositionFit {
    /// The parameters: free log-strengths, `a`, `u`.
    pub beta: Vec<f64>,
    /// Their covariance (inverse observed information); empty when not converged.
    pub covariance: Vec<Vec<f64>>,
    /// The maximised log-likelihood.
    pub log_likelihood: f64,
    /// Newton iterations used.
    pub iterations: usize,
    /// Whether Newton converged to a finite maximum.
    pub converged: bool,
}

impl PositionFit {
    /// Log-strength of item `i` (0 for a reference).
    pub fn log_strength(&self, p: &Parametrisation, i: usize) -> f64 {
        p.strength_of[i].map_or(0.0, |c| self.beta[c])
    }

    /// Item `i`'s log-strength centred within its block, and its standard error.
    pub fn centred(&self, p: &Parametrisation, i: usize) -> (f64, f64) {
        let block = p.block_of[i];
        let members: Vec<usize> = (0..p.block_of.len())
            .filter(|&j| p.block_of[j] == block)
            .collect();
        let n = members.len() as f64;
        // w: e_i - mean of the block's e_j, on the parameter columns.
        let mut w = vec![0.0; p.len()];
        if let Some(c) = p.strength_of[i] {
            w[c] += 1.0;
        }
        for &j in &members {
            if let Some(c) = p.strength_of[j] {
                w[c] -= 1.0 / n;
            }
        }
        let value: f64 = w.iter().zip(&self.beta).map(|(a, b)| a * b).sum();
        (value, self.standard_error(&w))
    }

    /// Standard error of the linear combination `w · β`.
    pub fn standard_error(&self, w: &[f64]) -> f64 {
        if self.covariance.is_empty() {
            return f64::NAN;
        }
        let mut v = 0.0;
        for (r, wr) in w.iter().enumerate() {
            if *wr == 0.0 {
                continue;
            }
            for (c, wc) in w.iter().enumerate() {
                v += wr * self.covariance[r][c] * wc;
            }
        }
        v.max(0.0).sqrt()
    }

    /// The left-side log-odds `a = ln α` and its standard error.
    pub fn position(&self, p: &Parametrisation) -> (f64, f64) {
        let a = p.position();
        let se = if self.covariance.is_empty() {
            f64::NAN
        } else {
            self.covariance[a][a].max(0.0).sqrt()
        };
        (self.beta[a], se)
    }

    /// The tie parameter `v`.
    pub fn tie_parameter(&self, p: &Parametrisation) -> f64 {
        self.beta[p.tie()].exp()
    }
}

/// Iteration limit of [`fit`].
pub const MAX_NEWTON: usize = 200;
/// A parameter beyond this magnitude means the maximum is at infinity (separation).
pub const DIVERGED: f64 = 30.0;

/// The three linear predictors' coefficient lists `(column, coefficient)` for one shown pair.
fn predictors(p: &Parametrisation, left: usize, right: usize) -> [Vec<(usize, f64)>; 3] {
    let (a, u) = (p.position(), p.tie());
    let mut left_eta = vec![(a, 1.0)];
    let mut right_eta = Vec::new();
    let mut tie_eta = vec![(u, 1.0), (a, 0.5)];
    if let Some(c) = p.strength_of[left] {
        left_eta.push((c, 1.0));
        tie_eta.push((c, 0.5));
    }
    if let Some(c) = p.strength_of[right] {
        right_eta.push((c, 1.0));
        tie_eta.push((c, 0.5));
    }
    [left_eta, tie_eta, right_eta]
}

fn eta(x: &[(usize, f64)], beta: &[f64]) -> f64 {
    x.iter().map(|&(c, k)| k * beta[c]).sum()
}

/// Log-likelihood, gradient and information (negative Hessian) at `beta`.
fn evaluate(
    p: &Parametrisation,
    data: &[ShownCounts],
    beta: &[f64],
    derivatives: bool,
) -> (f64, Vec<f64>, Vec<Vec<f64>>) {
    let k = p.len();
    let mut ll = 0.0;
    let mut grad = vec![0.0; if derivatives { k } else { 0 }];
    let mut info =
        vec![vec![0.0; if derivatives { k } else { 0 }]; if derivatives { k } else { 0 }];
    for d in data {
        let total: f64 = d.counts.iter().sum();
        if total <= 0.0 {
            continue;
        }
        let xs = predictors(p, d.left, d.right);
        let etas: Vec<f64> = xs.iter().map(|x| eta(x, beta)).collect();
        let max = etas.iter().copied().fold(f64::NEG_INFINITY, f64::max);
        let z: f64 = etas.iter().map(|e| (e - max).exp()).sum();
        let log_z = max + z.ln();
        let probs: Vec<f64> = etas.iter().map(|e| (e - log_z).exp()).collect();
        for (c, &n) in d.counts.iter().enumerate() {
            ll += n * (etas[c] - log_z);
        }
        if !derivatives {
            continue;
        }
        // Mean coefficient vector x̄ = Σ p_c x_c (dense, small).
        let mut mean = vec![0.0; k];
        for (x, &pc) in xs.iter().zip(&probs) {
            for &(col, coef) in x {
                mean[col] += pc * coef;
            }
        }
        for (x, &n) in xs.iter().zip(&d.counts) {
            for &(col, coef) in x {
                grad[col] += n * coef;
            }
        }
        for (g, m) in grad.iter_mut().zip(&mean) {
            *g -= total * m;
        }
        // Information: total (Σ p_c x_c x_cᵀ − x̄ x̄ᵀ).
        for (x, &pc) in xs.iter().zip(&probs) {
            for &(r, kr) in x {
                for &(c, kc) in x {
                    info[r][c] += total * pc * kr * kc;
                }
            }
        }
        let nonzero: Vec<usize> = (0..k).filter(|&c| mean[c] != 0.0).collect();
        for &r in &nonzero {
            for &c in &nonzero {
                info[r][c] -= total * mean[r] * mean[c];
            }
        }
    }
    (ll, grad, info)
}

/// Cholesky factor of a symmetric positive-definite matrix (`None` if it is not).
fn cholesky(m: &[Vec<f64>]) -> Option<Vec<Vec<f64>>> {
    let n = m.len();
    let mut l = vec![vec![0.0; n]; n];
    for i in 0..n {
        for j in 0..=i {
            let s: f64 = (0..j).map(|k| l[i][k] * l[j][k]).sum();
            if i == j {
                let d = m[i][i] - s;
                if d.is_nan() || d <= 1e-300 || !d.is_finite() {
                    return None;
                }
                l[i][j] = d.sqrt();
            } else {
                l[i][j] = (m[i][j] - s) / l[j][j];
            }
        }
    }
    Some(l)
}

/// Solves `L Lᵀ x = b`.
fn cholesky_solve(l: &[Vec<f64>], b: &[f64]) -> Vec<f64> {
    let n = l.len();
    let mut y = vec![0.0; n];
    for i in 0..n {
        let s: f64 = (0..i).map(|k| l[i][k] * y[k]).sum();
        y[i] = (b[i] - s) / l[i][i];
    }
    let mut x = vec![0.0; n];
    for i in (0..n).rev() {
        let s: f64 = (i + 1..n).map(|k| l[k][i] * x[k]).sum();
        x[i] = (y[i] - s) / l[i][i];
    }
    x
}

/// The inverse of a symmetric positive-definite matrix (`None` if it is not).
pub fn spd_inverse(m: &[Vec<f64>]) -> Option<Vec<Vec<f64>>> {
    let l = cholesky(m)?;
    let n = m.len();
    let mut inv = vec![vec![0.0; n]; n];
    for c in 0..n {
        let mut e = vec![0.0; n];
        e[c] = 1.0;
        let col = cholesky_solve(&l, &e);
        for r in 0..n {
            inv[r][c] = col[r];
        }
    }
    Some(inv)
}

/// Fits the model to `data` by Newton's method with step halving, from strengths 0, α = 1 and
/// `v` from the share of ties.
pub fn fit(p: &Parametrisation, data: &[ShownCounts]) -> PositionFit {
    let mut beta = vec![0.0; p.len()];
    let (ties, total) = data.iter().fold((0.0, 0.0), |(t, n), d| {
        (t + d.counts[1], n + d.counts.iter().sum::<f64>())
    });
    let share = if total > 0.0 { ties / total } else { 0.0 };
    beta[p.tie()] = (2.0 * share.clamp(0.01, 0.95) / (1.0 - share.clamp(0.01, 0.95))).ln();
    let (mut ll, mut grad, mut info) = evaluate(p, data, &beta, true);
    let mut iterations = 0;
    let mut converged = false;
    while iterations < MAX_NEWTON {
        iterations += 1;
        let Some(l) = cholesky(&info) else {
            break;
        };
        let step = cholesky_solve(&l, &grad);
        // Newton decrement: half of gᵀ I⁻¹ g, the log-likelihood still to gain.
        let decrement: f64 = step.iter().zip(&grad).map(|(s, g)| s * g).sum();
        if decrement.abs() < 1e-18 {
            converged = true;
            break;
        }
        let mut t = 1.0;
        let mut accepted = false;
        for _ in 0..40 {
            let trial: Vec<f64> = beta.iter().zip(&step).map(|(b, s)| b + t * s).collect();
            let (trial_ll, _, _) = evaluate(p, data, &trial, false);
            if trial_ll.is_finite() && trial_ll >= ll - 1e-12 {
                beta = trial;
                accepted = true;
                break;
            }
            t *= 0.5;
        }
        if !accepted || beta.iter().any(|b| !b.is_finite() || b.abs() > DIVERGED) {
            break;
        }
        (ll, grad, info) = evaluate(p, data, &beta, true);
        if decrement < 1e-14 {
            converged = true;
            break;
        }
    }
    let covariance = if converged {
        spd_inverse(&info).unwrap_or_default()
    } else {
        Vec::new()
    };
    let converged = converged && !covariance.is_empty();
    PositionFit {
        beta,
        covariance,
        log_likelihood: ll,
        iterations,
        converged,
    }
}

/// The expected information of `n` answers per shown pair in `shown` at parameters `beta`
/// (for planned power: the standard errors a design will give).
pub fn expected_information(
    p: &Parametrisation,
    shown: &[(usize, usize, f64)],
    beta: &[f64],
) -> Vec<Vec<f64>> {
    // The information of a multinomial logit does not depend on the answers, only on their
    // number: any split of the counts gives the same matrix.
    let data: Vec<ShownCounts> = shown
        .iter()
        .map(|&(left, right, n)| ShownCounts {
            left,
            right,
            counts: [n, 0.0, 0.0],
        })
        .collect();
    evaluate(p, &data, beta, true).2
}

/// The probabilities of "prefer left", "no preference", "prefer right" for log-strengths `lambda_left`,
/// `lambda_right`, left-side log-odds `a` and tie log-propensity `u`.
pub fn probabilities(lambda_left: f64, lambda_right: f64, a: f64, u: f64) -> [f64; 3] {
    let etas = [
        a + lambda_left,
        u + 0.5 * (a + lambda_left + lambda_right),
        lambda_right,
    ];
    let max = etas.iter().copied().fold(f64::NEG_INFINITY, f64::max);
    let z: f64 = etas.iter().map(|e| (e - max).exp()).sum();
    etas.map(|e| (e - max).exp() / z)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::bradley_terry::{fit_davidson, PairCounts};

    #[test]
    fn without_a_position_effect_it_matches_the_mm_fit_of_davidson() {
        // Three items, answers balanced over sides so that α = 1 is the maximum.
        let raw = [
            (0, 1, [30.0, 10.0, 20.0]),
            (0, 2, [25.0, 15.0, 20.0]),
            (1, 2, [22.0, 12.0, 26.0]),
        ];
        let mut data = Vec::new();
        let mut pairs = Vec::new();
        for (i, j, [w, t, l]) in raw {
            // Half shown each way, the same answers: no side is favoured.
            data.push(ShownCounts {
                left: i,
                right: j,
                counts: [w / 2.0, t / 2.0, l / 2.0],
            });
            data.push(ShownCounts {
                left: j,
                right: i,
                counts: [l / 2.0, t / 2.0, w / 2.0],
            });
            pairs.push(PairCounts {
                i,
                j,
                wins_i: w,
                wins_j: l,
                ties: t,
            });
        }
        let p = Parametrisation::per_item(&[0, 0, 0]);
        let f = fit(&p, &data);
        assert!(f.converged);
        let mm = fit_davidson(3, &pairs, 0.5);
        for i in 0..3 {
            let (c, se) = f.centred(&p, i);
            assert!((c - mm.log_strengths[i]).abs() < 1e-7, "{c} {:?}", mm);
            assert!(se > 0.0 && se < 1.0);
        }
        assert!(f.position(&p).0.abs() < 1e-9);
        assert!((f.tie_parameter(&p) - mm.tie_parameter).abs() < 1e-7);
    }

    #[test]
    fn a_left_bias_alone_is_estimated_as_its_log_odds() {
        // Two equal items, each shown on either side: left 54, tie 10, right 36 both ways. The
        // model is then saturated (α = L / R, v sqrt(α) = T / R), so a = ln 1.5 and its
        // standard error is that of a log odds ratio, sqrt(1/L + 1/R) over both orientations.
        let data = [
            ShownCounts {
                left: 0,
                right: 1,
                counts: [54.0, 10.0, 36.0],
            },
            ShownCounts {
                left: 1,
                right: 0,
                counts: [54.0, 10.0, 36.0],
            },
        ];
        let p = Parametrisation::per_item(&[0, 0]);
        let f = fit(&p, &data);
        assert!(f.converged);
        let (a, se) = f.position(&p);
        assert!((a - (1.5f64).ln()).abs() < 1e-8, "{a}");
        let expected = (1.0 / 108.0 + 1.0 / 72.0f64).sqrt();
        assert!((se - expected).abs() < 1e-6, "{se} {expected}");
        assert!(f.centred(&p, 0).0.abs() < 1e-9);
        assert!((f.tie_parameter(&p) * 1.5f64.sqrt() - 10.0 / 36.0).abs() < 1e-8);
    }

    #[test]
    fn separation_is_reported_not_hidden() {
        // Item 0 always wins: the maximum is at infinity.
        let data = [
            ShownCounts {
                left: 0,
                right: 1,
                counts: [10.0, 2.0, 0.0],
            },
            ShownCounts {
                left: 1,
                right: 0,
                counts: [0.0, 2.0, 10.0],
            },
        ];
        let p = Parametrisation::per_item(&[0, 0]);
        assert!(!fit(&p, &data).converged);
    }

    #[test]
    fn shared_parameters_follow_the_share_map_with_one_reference_per_block() {
        // Items 0..4: block 0 = {0, 1, 2, 3}, where 0/2 and 1/3 share.
        let p = Parametrisation::shared(&[0, 0, 0, 0, 1, 1], &[7, 8, 7, 8, 9, 10]);
        assert_eq!(p.strength_of, [None, Some(0), None, Some(0), None, Some(1)]);
        assert_eq!(p.len(), 4);
    }

    #[test]
    fn probabilities_sum_to_one_and_reduce_to_davidson() {
        let [l, t, r] = probabilities(0.3, -0.2, 0.0, (0.5f64).ln());
        assert!((l + t + r - 1.0).abs() < 1e-12);
        let (gl, gr, v) = (0.3f64.exp(), (-0.2f64).exp(), 0.5);
        let d = gl + gr + v * (gl * gr).sqrt();
        assert!((l - gl / d).abs() < 1e-12 && (r - gr / d).abs() < 1e-12);
    }
}
