//! Plain-Rust statistics for left / no preference / right answers: binomial tails, the exact sign
//! test, Holm's step-down correction, Wilson and Clopper-Pearson intervals, Fleiss' kappa,
//! percentiles and the seeded random numbers behind the participant bootstrap.
//!
//! Formulas follow `statistics.md`; each function says which.

/// A 95% interval (`None` when undefined, e.g. no bootstrap or no decided answers).
pub type Interval = Option<(f64, f64)>;

/// z for a two-sided 95% interval.
pub const Z_95: f64 = 1.959_963_984_540_054;

/// `ln(exp(a) + exp(b))` without overflow.
fn log_add(a: f64, b: f64) -> f64 {
    if a == f64::NEG_INFINITY {
        return b;
    }
    if b == f64::NEG_INFINITY {
        return a;
    }
    let (hi, lo) = if a > b { (a, b) } else { (b, a) };
    hi + (lo - hi).exp().ln_1p()
}

/// P(X <= k) for X ~ Binomial(n, p), summed in log space so that large n does not underflow.
pub fn binomial_cdf(k: u64, n: u64, p: f64) -> f64 {
    if k >= n {
        return 1.0;
    }
    if p <= 0.0 {
        return 1.0;
    }
    if p >= 1.0 {
        return 0.0;
    }
    let (ln_p, ln_q) = (p.ln(), (1.0 - p).ln());
    // ln pmf(0) = n ln q; pmf(i+1) = pmf(i) (n-i)/(i+1) p/q.
    let mut ln_pmf = n as f64 * ln_q;
    let mut ln_cdf = ln_pmf;
    for i in 0..k {
        ln_pmf += ((n - i) as f64 / (i + 1) as f64).ln() + ln_p - ln_q;
        ln_cdf = log_add(ln_cdf, ln_pmf);
    }
    ln_cdf.exp().min(1.0)
}

/// Exact two-sided sign test of `wins` against `losses` (ties already excluded):
/// p = min(1, 2 P(X <= min(W, L))), X ~ Bin(W + L, 1/2). With no decided answers p = 1.
pub fn sign_test(wins: u64, losses: u64) -> f64 {
    let n = wins + losses;
    if n == 0 {
        return 1.0;
    }
    (2.0 * binomial_cdf(wins.min(losses), n, 0.5)).min(1.0)
}

/// Holm's step-down adjusted p-values, returned in the input order:
/// sort ascending, p_adj(k) = max over j <= k of min(1, (m - j + 1) p(j)).
/// Ties between equal p-values keep their input order, so the result is deterministic.
pub fn holm(p_values: &[f64]) -> Vec<f64> {
    let m = p_values.len();
    let mut order: Vec<usize> = (0..m).collect();
    order.sort_by(|&a, &b| p_values[a].total_cmp(&p_values[b]).then(a.cmp(&b)));
    let mut adjusted = vec![0.0; m];
    let mut running_max: f64 = 0.0;
    for (rank, &index) in order.iter().enumerate() {
        let scaled = ((m - rank) as f64 * p_values[index]).min(1.0);
        running_max = running_max.max(scaled);
        adjusted[index] = running_max;
    }
    adjusted
}

/// Wilson score interval for `successes` out of `n` at normal quantile `z`:
/// [p + z²/2n ± z sqrt(p(1-p)/n + z²/4n²)] / (1 + z²/n). `None` when n = 0.
pub fn wilson_interval(successes: u64, n: u64, z: f64) -> Option<(f64, f64)> {
    if n == 0 {
        return None;
    }
    let n = n as f64;
    let p = successes as f64 / n;
    let z2 = z * z;
    let centre = p + z2 / (2.0 * n);
    let half = z * (p * (1.0 - p) / n + z2 / (4.0 * n * n)).sqrt();
    let scale = 1.0 + z2 / n;
    Some((
        ((centre - half) / scale).max(0.0),
        ((centre + half) / scale).min(1.0),
    ))
}

/// Exact (Clopper-Pearson) interval for `successes` out of `n` at level `1 - alpha`, found by
/// bisection on the binomial tails (equivalent to the Beta-quantile form). `None` when n = 0.
pub fn clopper_pearson(successes: u64, n: u64, alpha: f64) -> Option<(f64, f64)> {
    if n == 0 {
        return None;
    }
    let k = successes.min(n);
    let tail = alpha / 2.0;
    // Lower bound: P(X >= k | p) = tail, increasing in p.
    let lower = if k == 0 {
        0.0
    } else {
        bisect(|p| 1.0 - binomial_cdf(k - 1, n, p) - tail)
    };
    // Upper bound: P(X <= k | p) = tail, decreasing in p.
    let upper = if k == n {
        1.0
    } else {
        bisect(|p| tail - binomial_cdf(k, n, p))
    };
    Some((lower, upper))
}

/// Root of an increasing function on [0, 1] by bisection (to machine precision).
fn bisect(f: impl Fn(f64) -> f64) -> f64 {
    let (mut lo, mut hi) = (0.0_f64, 1.0_f64);
    for _ in 0..200 {
        let mid = 0.5 * (lo + hi);
        if f(mid) < 0.0 {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    0.5 * (lo + hi)
}

/// Fleiss' kappa with subjects as rows and categories as columns of `counts`
/// (`counts[i][j]` = raters putting subject i in category j):
/// P_i = (Σ_j n_ij² − n_i) / (n_i (n_i − 1)), P̄ = mean P_i, p_j = Σ_i n_ij / Σ_i n_i,
/// P_e = Σ p_j², κ = (P̄ − P_e) / (1 − P_e).
///
/// With the same number of raters per subject this is Fleiss (1971) exactly; subjects with
/// different numbers of raters (dropped answers) are weighted equally in P̄ and by their raters
/// in p_j. Subjects with fewer than two raters are skipped. `None` when no subject has two raters
/// or every rating falls in one category (P_e = 1).
pub fn fleiss_kappa(counts: &[Vec<u64>]) -> Option<f64> {
    let rated: Vec<&Vec<u64>> = counts
        .iter()
        .filter(|row| row.iter().sum::<u64>() >= 2)
        .collect();
    if rated.is_empty() {
        return None;
    }
    let categories = rated.iter().map(|row| row.len()).max().unwrap_or(0);
    let mut agreement_sum = 0.0;
    let mut category_totals = vec![0.0; categories];
    let mut ratings = 0.0;
    for row in &rated {
        let n = row.iter().sum::<u64>() as f64;
        let squares: f64 = row.iter().map(|&c| (c * c) as f64).sum();
        agreement_sum += (squares - n) / (n * (n - 1.0));
        for (total, &c) in category_totals.iter_mut().zip(row.iter()) {
            *total += c as f64;
        }
        ratings += n;
    }
    let p_bar = agreement_sum / rated.len() as f64;
    let p_e: f64 = category_totals.iter().map(|t| (t / ratings).powi(2)).sum();
    if (1.0 - p_e).abs() < 1e-15 {
        return None;
    }
    Some((p_bar - p_e) / (1.0 - p_e))
}

/// Percentile `q` in [0, 1] of already sorted finite values, interpolated linearly between order
/// statistics (R's type 7). `None` for an empty slice.
pub fn percentile_sorted(sorted: &[f64], q: f64) -> Option<f64> {
    if sorted.is_empty() {
        return None;
    }
    let h = (sorted.len() - 1) as f64 * q.clamp(0.0, 1.0);
    let lo = h.floor() as usize;
    let hi = (lo + 1).min(sorted.len() - 1);
    Some(sorted[lo] + (h - lo as f64) * (sorted[hi] - sorted[lo]))
}

/// The 2.5% and 97.5% percentiles of the finite values among `samples` (NaNs, from resamples in
/// which a statistic is undefined, are left out). `None` when no sample is finite.
pub fn percentile_interval(samples: &[f64]) -> Option<(f64, f64)> {
    let mut finite: Vec<f64> = samples.iter().copied().filter(|x| x.is_finite()).collect();
    finite.sort_by(f64::total_cmp);
    Some((
        percentile_sorted(&finite, 0.025)?,
        percentile_sorted(&finite, 0.975)?,
    ))
}

/// SplitMix64 (Steele, Lea and Flood 2014): a tiny, fully specified generator, so bootstrap
/// resamples are identical on every platform and every version of this crate's dependencies.
#[derive(Clone, Debug)]
pub struct SplitMix64 {
    state: u64,
}

impl SplitMix64 {
    /// A generator started from `seed`.
    pub fn new(seed: u64) -> Self {
        Self { state: seed }
    }

    /// The next 64 random bits.
    pub fn next_u64(&mut self) -> u64 {
        self.state = self.state.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = self.state;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        z ^ (z >> 31)
    }

    /// A uniform index in `0..n` (multiply-shift; the bias is below 2^-40 for any realistic n).
    pub fn next_index(&mut self, n: usize) -> usize {
        ((self.next_u64() as u128 * n as u128) >> 64) as usize
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn binomial_cdf_matches_hand_sums() {
        // Bin(4, 1/2): P(X <= 1) = (1 + 4) / 16.
        assert!((binomial_cdf(1, 4, 0.5) - 5.0 / 16.0).abs() < 1e-12);
        // Bin(3, 0.2): P(X <= 0) = 0.8^3.
        assert!((binomial_cdf(0, 3, 0.2) - 0.512).abs() < 1e-12);
        assert_eq!(binomial_cdf(3, 3, 0.2), 1.0);
        // Large n does not underflow: P(X <= 1000) for Bin(2000, 1/2) is just above 1/2.
        let half = binomial_cdf(1000, 2000, 0.5);
        assert!(half > 0.5 && half < 0.52, "{half}");
    }

    #[test]
    fn sign_test_matches_hand_computed_p_values() {
        // 9 vs 1: 2 (1 + 10) / 1024 = 22 / 1024.
        assert!((sign_test(9, 1) - 22.0 / 1024.0).abs() < 1e-12);
        assert!((sign_test(1, 9) - 22.0 / 1024.0).abs() < 1e-12);
        // 5 vs 0: 2 / 32.
        assert!((sign_test(5, 0) - 0.0625).abs() < 1e-12);
        // A balanced split is capped at 1.
        assert_eq!(sign_test(3, 3), 1.0);
        assert_eq!(sign_test(0, 0), 1.0);
        // 18 vs 1: 2 * 20 / 2^19.
        assert!((sign_test(18, 1) - 40.0 / 524_288.0).abs() < 1e-15);
    }

    #[test]
    fn holm_adjusts_in_step_down_order() {
        // Sorted: 0.01 (x4 = 0.04), 0.02 (x3 = 0.06), 0.03 (x2 = 0.06), 0.04 (x1 = 0.04 -> 0.06).
        let adjusted = holm(&[0.03, 0.01, 0.04, 0.02]);
        let expected = [0.06, 0.04, 0.06, 0.06];
        for (a, e) in adjusted.iter().zip(expected) {
            assert!((a - e).abs() < 1e-12, "{adjusted:?}");
        }
        // Capped at 1 and monotone.
        let adjusted = holm(&[0.5, 0.9]);
        assert_eq!(adjusted, vec![1.0, 1.0]);
    }

    #[test]
    fn wilson_interval_matches_hand_computation() {
        // 8 of 10 with z = 1.96: centre 0.8 + 0.19208, half 1.96 sqrt(0.016 + 0.009604),
        // scale 1.38416: (0.4902, 0.9433).
        let (lo, hi) = wilson_interval(8, 10, 1.96).unwrap();
        assert!((lo - 0.490_162).abs() < 1e-5, "{lo}");
        assert!((hi - 0.943_318).abs() < 1e-5, "{hi}");
        // 0 of 5: lower bound exactly 0, upper z²/(n + z²).
        let (lo, hi) = wilson_interval(0, 5, 1.96).unwrap();
        assert_eq!(lo, 0.0);
        assert!((hi - 3.8416 / 8.8416).abs() < 1e-12);
        assert!(wilson_interval(0, 0, 1.96).is_none());
    }

    #[test]
    fn clopper_pearson_matches_closed_forms() {
        // k = 0: upper = 1 - (alpha/2)^(1/n); k = n: lower = (alpha/2)^(1/n).
        let (lo, hi) = clopper_pearson(0, 10, 0.05).unwrap();
        assert_eq!(lo, 0.0);
        assert!((hi - (1.0 - 0.025_f64.powf(0.1))).abs() < 1e-10);
        let (lo, hi) = clopper_pearson(10, 10, 0.05).unwrap();
        assert!((lo - 0.025_f64.powf(0.1)).abs() < 1e-10);
        assert_eq!(hi, 1.0);
        // Symmetry: k of n mirrors n - k of n.
        let (a, b) = clopper_pearson(3, 12, 0.05).unwrap();
        let (c, d) = clopper_pearson(9, 12, 0.05).unwrap();
        assert!((a - (1.0 - d)).abs() < 1e-10 && (b - (1.0 - c)).abs() < 1e-10);
    }

    #[test]
    fn fleiss_kappa_matches_the_textbook_example() {
        // Fleiss (1971) as tabulated on Wikipedia's "Fleiss' kappa" page: 10 subjects,
        // 14 raters, 5 categories; P̄ = 0.378, P_e = 0.213, κ = 0.210.
        let table: Vec<Vec<u64>> = vec![
            vec![0, 0, 0, 0, 14],
            vec![0, 2, 6, 4, 2],
            vec![0, 0, 3, 5, 6],
            vec![0, 3, 9, 2, 0],
            vec![2, 2, 8, 1, 1],
            vec![7, 7, 0, 0, 0],
            vec![3, 2, 6, 3, 0],
            vec![2, 5, 3, 2, 2],
            vec![6, 5, 2, 1, 0],
            vec![0, 2, 2, 3, 7],
        ];
        let kappa = fleiss_kappa(&table).unwrap();
        assert!((kappa - 0.2099).abs() < 5e-4, "{kappa}");
        // Perfect agreement on varied categories gives 1; one category only is undefined.
        let perfect = vec![vec![3, 0, 0], vec![0, 3, 0]];
        assert!((fleiss_kappa(&perfect).unwrap() - 1.0).abs() < 1e-12);
        assert!(fleiss_kappa(&[vec![4, 0, 0]]).is_none());
    }

    #[test]
    fn percentiles_interpolate_between_order_statistics() {
        let sorted = [1.0, 2.0, 3.0, 4.0, 5.0];
        assert_eq!(percentile_sorted(&sorted, 0.5), Some(3.0));
        assert_eq!(percentile_sorted(&sorted, 0.125), Some(1.5));
        let (lo, hi) = percentile_interval(&[5.0, f64::NAN, 1.0, 3.0, 2.0, 4.0]).unwrap();
        assert!((lo - 1.1).abs() < 1e-12 && (hi - 4.9).abs() < 1e-12);
        assert!(percentile_interval(&[f64::NAN]).is_none());
    }

    #[test]
    fn splitmix_is_reproducible_and_covers_the_range() {
        let mut a = SplitMix64::new(7);
        let mut b = SplitMix64::new(7);
        let xs: Vec<u64> = (0..5).map(|_| a.next_u64()).collect();
        let ys: Vec<u64> = (0..5).map(|_| b.next_u64()).collect();
        assert_eq!(xs, ys);
        // Reference value of SplitMix64 from seed 0 (the published test vector).
        assert_eq!(SplitMix64::new(0).next_u64(), 0xE220_A839_7B1D_CDAF);
        let mut seen = [false; 5];
        for _ in 0..200 {
            seen[a.next_index(5)] = true;
        }
        assert!(seen.iter().all(|&s| s));
    }
}
