//! A study of methods under shadings: its configurations (objects x methods x shadings), the
//! pairs it asks, each participant's balanced subset of them, the analysis of the answers, the
//! power table, and simulated participants that check the analysis.
//!
//! - [`design`]: configurations, the pairs (method pairs within an object and shading; shading
//!   pairs within an object and method), and each participant's questions: a balanced subset
//!   (every pair seen by the same number of participants, up to one), sides counterbalanced per
//!   pair (up to one), order shuffled per participant, controls added;
//! - [`fit`]: the analysis of the answers: Bradley-Terry with ties and a left-side parameter
//!   per shading ([`crate::bradley_terry_position`]), the likelihood-ratio test of a method x
//!   shading interaction, the position and order effects, the shading pairs;
//! - [`power`]: participants needed for 80% power to detect a 60/40 preference between the
//!   reference method and each peer, per shading, for a design;
//! - [`simulate`]: answers drawn from a planted model (strengths per configuration, a tie rate,
//!   a left-side bias, a fatigue drift), and the coverage check over many simulated studies.

pub mod design;
pub mod fit;
pub mod power;
pub mod simulate;

pub use design::{assign, study_pairs, PairKind, ParticipantPlan, Shown, StudyItems, StudyPair};
pub use fit::{analyse_study, StudyAnalysis, StudyAnswer, StudyControl};

/// Survival function of the chi-square distribution with `df` degrees of freedom at `x`: the
/// regularised upper incomplete gamma function Q(df/2, x/2) (series below a + 1, Lentz's
/// continued fraction above, as in Numerical Recipes' `gammq`).
pub fn chi_square_sf(x: f64, df: f64) -> f64 {
    if x.is_nan() || x <= 0.0 {
        return 1.0;
    }
    let (a, x) = (df / 2.0, x / 2.0);
    let ln_gamma_a = libm::lgamma(a);
    if x < a + 1.0 {
        let (mut sum, mut term, mut ap) = (1.0 / a, 1.0 / a, a);
        for _ in 0..10_000 {
            ap += 1.0;
            term *= x / ap;
            sum += term;
            if term.abs() < sum.abs() * 1e-16 {
                break;
            }
        }
        let p = sum * (-x + a * x.ln() - ln_gamma_a).exp();
        (1.0 - p).clamp(0.0, 1.0)
    } else {
        let tiny = 1e-300;
        let mut b = x + 1.0 - a;
        let mut c = 1.0 / tiny;
        let mut d = 1.0 / b;
        let mut h = d;
        for i in 1..10_000 {
            let an = -(i as f64) * (i as f64 - a);
            b += 2.0;
            d = an * d + b;
            if d.abs() < tiny {
                d = tiny;
            }
            c = b + an / c;
            if c.abs() < tiny {
                c = tiny;
            }
            d = 1.0 / d;
            let delta = d * c;
            h *= delta;
            if (delta - 1.0).abs() < 1e-16 {
                break;
            }
        }
        ((-x + a * x.ln() - ln_gamma_a).exp() * h).clamp(0.0, 1.0)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn chi_square_survival_matches_known_values() {
        // df 1: P(X > 3.841459) = 0.05; df 2: exp(-x/2); df 6: P(X > 12.59159) = 0.05.
        assert!((chi_square_sf(3.841_458_820_694_124, 1.0) - 0.05).abs() < 1e-9);
        assert!((chi_square_sf(3.0, 2.0) - (-1.5f64).exp()).abs() < 1e-12);
        assert!((chi_square_sf(12.591_587_243_743_977, 6.0) - 0.05).abs() < 1e-9);
        // df 4: Q = exp(-x/2) (1 + x/2), on both sides of the series/fraction switch.
        for x in [1.0f64, 5.0, 30.0] {
            let q = (-x / 2.0).exp() * (1.0 + x / 2.0);
            assert!((chi_square_sf(x, 4.0) - q).abs() < 1e-12, "{x}");
        }
        assert_eq!(chi_square_sf(0.0, 3.0), 1.0);
    }
}
