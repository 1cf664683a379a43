//! What survey-server data adds to the analysis: the position (left/right) effect measured with
//! the sides swapped and with control questions, the order (fatigue) effect on "no preference"
//! and on answer times, and the participants needed for 80% power per comparison group.
//!
//! - **Position**: with swaps, every decided answer is turned back into the screen side that was
//!   clicked; the share of "left screen" is tested against 1/2 (exact binomial, Wilson interval).
//!   Controls (one animation on both sides) give the same test where no configuration can be
//!   preferred; their "no preference" rate measures attention.
//! - **Order**: answers are binned by the position they were shown at (thirds of the session).
//!   Per bin: the tie rate (Wilson interval) and the median answer time. Trend in ties:
//!   Cochran-Armitage (position as score, every answer a trial; participants' answers are
//!   treated as independent, so the p-value is optimistic). Times: per participant, the median
//!   time in the last third over the first third; the sign test counts participants who got
//!   faster against those who got slower.
//! - **Power**: per question, the pilot's decided share for the majority side `p` and tie rate
//!   `t`; decided answers needed for a two-sided sign test at level alpha and 80% power by the
//!   normal approximation `n = ((z_{1-α/2}·0.5 + z_{0.8}·sqrt(p(1-p))) / (p - 0.5))²`, then
//!   participants `N = ceil(n / (1 - t))`; also at the Holm worst case alpha/m (m questions).
//!   The exact power of the sign test at that `N` (ties random, exact binomial sums) is reported
//!   beside it. Per comparison group: the participants needed for its strongest question (one
//!   difference detected) and for all of its questions.

use std::path::Path;

use crate::data::{Answer, Dataset};
use crate::design::Design;
use crate::error::{AnalysisError, Result};
use crate::stats::{sign_test, wilson_interval, Interval, Z_95};

/// Target power of the power table.
pub const TARGET_POWER: f64 = 0.8;
/// Above this many participants a question counts as out of reach.
pub const MAX_PARTICIPANTS: u64 = 100_000;

/// Screen sides chosen in one set of answers.
#[derive(Clone, Debug, PartialEq)]
pub struct PositionEffect {
    /// Where the answers come from.
    pub source: String,
    /// Chose the left screen.
    pub left: u64,
    /// No preference.
    pub none: u64,
    /// Chose the right screen.
    pub right: u64,
    /// left / (left + right).
    pub share_left: f64,
    /// Wilson 95% interval.
    pub wilson: Interval,
    /// Exact binomial test against 1/2.
    pub p_value: f64,
}

impl PositionEffect {
    fn new(source: &str, left: u64, none: u64, right: u64) -> Self {
        Self {
            source: source.into(),
            left,
            none,
            right,
            share_left: ratio(left, left + right),
            wilson: wilson_interval(left, left + right, Z_95),
            p_value: sign_test(left, right),
        }
    }

    /// Share of "no preference".
    pub fn tie_rate(&self) -> f64 {
        ratio(self.none, self.left + self.none + self.right)
    }
}

/// Answers shown in one range of positions.
#[derive(Clone, Debug, PartialEq)]
pub struct OrderBin {
    /// First position (1-based).
    pub first: u32,
    /// Last position.
    pub last: u32,
    /// Answers.
    pub answers: u64,
    /// "No preference" answers.
    pub ties: u64,
    /// ties / answers.
    pub tie_rate: f64,
    /// Wilson 95% interval of the tie rate.
    pub wilson: Interval,
    /// Median answer time in seconds (NaN without times).
    pub median_seconds: f64,
}

/// The order (fatigue) effect.
#[derive(Clone, Debug, PartialEq)]
pub struct OrderEffect {
    /// First, middle and last third of the positions.
    pub bins: Vec<OrderBin>,
    /// Cochran-Armitage z of the tie trend over positions (positive: more ties later).
    pub tie_trend_z: f64,
    /// Its two-sided p-value.
    pub tie_trend_p: f64,
    /// Median over participants of (median time, last third) / (median time, first third).
    pub time_ratio: f64,
    /// Participants faster in the last third than in the first.
    pub faster: u64,
    /// Participants slower in the last third.
    pub slower: u64,
    /// Sign test of faster against slower.
    pub time_p: f64,
}

/// Participants needed for one question.
#[derive(Clone, Debug, PartialEq)]
pub struct PowerQuestion {
    /// Question id.
    pub question: String,
    /// Comparison group label.
    pub group: String,
    /// Pilot participants who answered it.
    pub pilot: u64,
    /// Decided share of the majority side in the pilot.
    pub majority_share: f64,
    /// Tie rate in the pilot.
    pub tie_rate: f64,
    /// Participants needed at alpha (`None`: no effect observed, or beyond [`MAX_PARTICIPANTS`]).
    pub needed: Option<u64>,
    /// Exact power of the sign test with `needed` participants.
    pub exact_power: f64,
    /// Participants needed at alpha / m (Holm's worst case).
    pub needed_holm: Option<u64>,
}

/// Participants needed per comparison group.
#[derive(Clone, Debug, PartialEq)]
pub struct PowerGroup {
    /// Group label.
    pub group: String,
    /// Its questions.
    pub questions: usize,
    /// Needed to detect its strongest question's effect.
    pub strongest: Option<u64>,
    /// Needed for every question of the group (`None` if one is out of reach).
    pub all: Option<u64>,
    /// `strongest` at Holm's worst-case level.
    pub strongest_holm: Option<u64>,
    /// `all` at Holm's worst-case level.
    pub all_holm: Option<u64>,
}

/// The power table.
#[derive(Clone, Debug, PartialEq)]
pub struct Power {
    /// Level of each test.
    pub alpha: f64,
    /// Questions (m of the Holm level).
    pub m: usize,
    /// Per question.
    pub questions: Vec<PowerQuestion>,
    /// Per comparison group.
    pub groups: Vec<PowerGroup>,
}

/// Everything of this module that the data allows.
#[derive(Clone, Debug, PartialEq)]
pub struct SurveyEffects {
    /// Position effect from swaps (real questions) and from controls, when present.
    pub position: Vec<PositionEffect>,
    /// Order effect (needs the `order` column).
    pub order: Option<OrderEffect>,
    /// Power table (on request, and always with survey data).
    pub power: Option<Power>,
}

fn ratio(a: u64, b: u64) -> f64 {
    if b == 0 {
        f64::NAN
    } else {
        a as f64 / b as f64
    }
}

/// Standard normal CDF, through `libm`'s `erfc` (a port of musl's, accurate to about one unit in
/// the last place of an f64).
pub fn normal_cdf(x: f64) -> f64 {
    0.5 * libm::erfc(-x / std::f64::consts::SQRT_2)
}

/// Standard normal quantile by bisection of [`normal_cdf`].
pub fn normal_quantile(p: f64) -> f64 {
    let (mut lo, mut hi) = (-10.0f64, 10.0f64);
    for _ in 0..100 {
        let mid = 0.5 * (lo + hi);
        if normal_cdf(mid) < p {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    0.5 * (lo + hi)
}

/// Participants needed for a two-sided sign test at `alpha` with power [`TARGET_POWER`], when
/// the majority side takes `p` of decided answers and `t` of answers are ties.
pub fn participants_needed(p: f64, t: f64, alpha: f64) -> Option<u64> {
    if !(p > 0.5 && p <= 1.0 && (0.0..1.0).contains(&t)) {
        return None;
    }
    let za = normal_quantile(1.0 - alpha / 2.0);
    let zb = normal_quantile(TARGET_POWER);
    let n = ((za * 0.5 + zb * (p * (1.0 - p)).sqrt()) / (p - 0.5)).powi(2);
    let participants = (n / (1.0 - t)).ceil();
    (participants.is_finite() && participants <= MAX_PARTICIPANTS as f64)
        .then_some(participants.max(1.0) as u64)
}

/// Exact power of the two-sided sign test at `alpha` with `participants`, each answering "for
/// the majority side" with probability `(1 - t) p`, tie `t`. Sums over the decided count within
/// 8 standard deviations of its mean; binomial terms in log space (no underflow).
pub fn sign_test_power(participants: u64, p: f64, t: f64, alpha: f64) -> f64 {
    let big = participants as usize;
    let mut ln_fact = vec![0.0f64; big + 1];
    for i in 1..=big {
        ln_fact[i] = ln_fact[i - 1] + (i as f64).ln();
    }
    let pmf = |k: usize, n: usize, prob: f64| -> f64 {
        if prob <= 0.0 {
            return f64::from(u8::from(k == 0));
        }
        if prob >= 1.0 {
            return f64::from(u8::from(k == n));
        }
        (ln_fact[n] - ln_fact[k] - ln_fact[n - k]
            + k as f64 * prob.ln()
            + (n - k) as f64 * (1.0 - prob).ln())
        .exp()
    };
    let q = 1.0 - t;
    let mean = big as f64 * q;
    let sd = (big as f64 * q * t).sqrt();
    let lo = (mean - 8.0 * sd - 1.0).floor().max(0.0) as usize;
    let hi = ((mean + 8.0 * sd + 1.0).ceil() as usize).min(big);
    let mut power = 0.0;
    for n in lo.max(1)..=hi {
        let weight = pmf(n, big, q);
        if weight < 1e-15 {
            continue;
        }
        // Largest c with 2 P(X <= c) < alpha under 1/2: reject when min(W, L) <= c.
        let mut c: Option<usize> = None;
        let mut cdf = 0.0;
        for k in 0..n {
            cdf += pmf(k, n, 0.5);
            if 2.0 * cdf < alpha {
                c = Some(k);
            } else {
                break;
            }
        }
        let Some(c) = c else {
            continue;
        };
        let low_tail: f64 = (0..=c).map(|k| pmf(k, n, p)).sum();
        let high_tail: f64 = (n - c..=n).map(|k| pmf(k, n, p)).sum();
        power += weight * (low_tail + high_tail).min(1.0);
    }
    power
}

/// The power table of a dataset used as a pilot.
pub fn power(dataset: &Dataset, design: &Design, alpha: f64) -> Power {
    let m = dataset.questions.len();
    let mut questions = Vec::with_capacity(m);
    for (q, question) in dataset.questions.iter().enumerate() {
        let mut counts = [0u64; 3];
        for row in &dataset.responses.answers {
            if let Some(a) = row[q] {
                counts[a.index()] += 1;
            }
        }
        let [w, t, l] = counts;
        let pilot = w + t + l;
        let majority_share = ratio(w.max(l), w + l);
        let tie_rate = ratio(t, pilot);
        let needed = participants_needed(majority_share, tie_rate, alpha);
        let exact_power = match needed {
            Some(n) if n <= 5_000 => sign_test_power(n, majority_share, tie_rate, alpha),
            _ => f64::NAN,
        };
        questions.push(PowerQuestion {
            question: question.id.clone(),
            group: design.question_group[q]
                .map(|g| design.group_label(g))
                .unwrap_or_default(),
            pilot,
            majority_share,
            tie_rate,
            needed,
            exact_power,
            needed_holm: participants_needed(majority_share, tie_rate, alpha / m as f64),
        });
    }
    let groups = (0..design.groups.len())
        .map(|g| {
            let label = design.group_label(g);
            let members: Vec<&PowerQuestion> =
                questions.iter().filter(|q| q.group == label).collect();
            let strongest = |f: &dyn Fn(&PowerQuestion) -> Option<u64>| {
                members.iter().filter_map(|q| f(q)).min()
            };
            let all = |f: &dyn Fn(&PowerQuestion) -> Option<u64>| {
                members
                    .iter()
                    .map(|q| f(q))
                    .collect::<Option<Vec<u64>>>()
                    .and_then(|v| v.into_iter().max())
            };
            PowerGroup {
                group: label.clone(),
                questions: members.len(),
                strongest: strongest(&|q| q.needed),
                all: all(&|q| q.needed),
                strongest_holm: strongest(&|q| q.needed_holm),
                all_holm: all(&|q| q.needed_holm),
            }
        })
        .collect();
    Power {
        alpha,
        m,
        questions,
        groups,
    }
}

/// Reads `controls.csv` (`participant,...,response,...`; the response is the screen side) and
/// counts the screen sides, leaving out excluded participants.
pub fn read_controls(path: &Path, excluded: &[String]) -> Result<PositionEffect> {
    let csv_error = |e: csv::Error| AnalysisError::Csv {
        path: path.to_path_buf(),
        message: e.to_string(),
    };
    let mut reader = csv::ReaderBuilder::new()
        .trim(csv::Trim::All)
        .from_path(path)
        .map_err(csv_error)?;
    let header = reader.headers().map_err(csv_error)?.clone();
    let column = |name: &str| {
        header
            .iter()
            .position(|h| h.eq_ignore_ascii_case(name))
            .ok_or_else(|| AnalysisError::MissingColumn {
                path: path.to_path_buf(),
                column: name.into(),
                hint: format!(
                    "a controls file needs participant and response; the header is {header:?}"
                ),
            })
    };
    let (pc, rc) = (column("participant")?, column("response")?);
    let mut counts = [0u64; 3];
    for (row, record) in reader.records().enumerate() {
        let record = record.map_err(csv_error)?;
        let participant = record.get(pc).unwrap_or("");
        if excluded.iter().any(|e| e == participant) {
            continue;
        }
        let value = record.get(rc).unwrap_or("");
        let answer = Answer::parse(value).ok_or_else(|| AnalysisError::InvalidValue {
            path: path.to_path_buf(),
            row: row + 1,
            column: header.get(rc).unwrap_or("response").to_string(),
            value: value.to_string(),
            expected: "L, N or R".into(),
        })?;
        counts[answer.index()] += 1;
    }
    Ok(PositionEffect::new(
        "controls (same animation on both sides)",
        counts[0],
        counts[1],
        counts[2],
    ))
}

fn median(values: &mut [f64]) -> f64 {
    if values.is_empty() {
        return f64::NAN;
    }
    values.sort_by(f64::total_cmp);
    let n = values.len();
    if n % 2 == 1 {
        values[n / 2]
    } else {
        0.5 * (values[n / 2 - 1] + values[n / 2])
    }
}

/// Position and order effects from the survey columns (`None` without them), plus controls and
/// power when given.
pub fn survey_effects(
    dataset: &Dataset,
    design: &Design,
    controls: Option<PositionEffect>,
    power: Option<Power>,
) -> SurveyEffects {
    let mut position = Vec::new();
    let mut order = None;
    if let Some(meta) = &dataset.responses.meta {
        // Screen sides: a canonical answer on a swapped question was clicked on the other side.
        let mut sides = [0u64; 3];
        // (position, tie, seconds, participant)
        let mut shown: Vec<(u32, bool, Option<f64>, usize)> = Vec::new();
        for (p, (answers, metas)) in dataset.responses.answers.iter().zip(meta).enumerate() {
            for (a, m) in answers.iter().zip(metas) {
                let (Some(a), Some(m)) = (a, m) else {
                    continue;
                };
                let screen = match (a, m.swapped) {
                    (Answer::Left, true) => Answer::Right,
                    (Answer::Right, true) => Answer::Left,
                    (a, _) => *a,
                };
                sides[screen.index()] += 1;
                shown.push((m.order, *a == Answer::NoPreference, m.seconds, p));
            }
        }
        position.push(PositionEffect::new(
            "questions (swaps undone: the side clicked)",
            sides[0],
            sides[1],
            sides[2],
        ));
        order = order_effect(&shown, dataset.responses.participants.len());
    }
    position.extend(controls);
    let _ = design;
    SurveyEffects {
        position,
        order,
        power,
    }
}

fn order_effect(
    shown: &[(u32, bool, Option<f64>, usize)],
    participants: usize,
) -> Option<OrderEffect> {
    let last = shown.iter().map(|s| s.0).max()?;
    let bin_of = |o: u32| ((o - 1) as u64 * 3 / last as u64) as usize;
    let mut bins: Vec<OrderBin> = (0..3)
        .map(|b| {
            let first = (1..=last).find(|&o| bin_of(o) == b).unwrap_or(0);
            let end = (1..=last).rev().find(|&o| bin_of(o) == b).unwrap_or(0);
            OrderBin {
                first,
                last: end,
                answers: 0,
                ties: 0,
                tie_rate: f64::NAN,
                wilson: None,
                median_seconds: f64::NAN,
            }
        })
        .collect();
    let mut times: Vec<Vec<f64>> = vec![Vec::new(); 3];
    // Per participant and bin: times.
    let mut per_participant: Vec<[Vec<f64>; 2]> = vec![[Vec::new(), Vec::new()]; participants];
    for &(o, tie, seconds, p) in shown {
        let b = bin_of(o);
        bins[b].answers += 1;
        bins[b].ties += u64::from(tie);
        if let Some(s) = seconds {
            times[b].push(s);
            if b == 0 {
                per_participant[p][0].push(s);
            } else if b == 2 {
                per_participant[p][1].push(s);
            }
        }
    }
    for (bin, t) in bins.iter_mut().zip(times.iter_mut()) {
        bin.tie_rate = ratio(bin.ties, bin.answers);
        bin.wilson = wilson_interval(bin.ties, bin.answers, Z_95);
        bin.median_seconds = median(t);
    }
    // Cochran-Armitage trend of ties over positions.
    let n = shown.len() as f64;
    let x_mean = shown.iter().map(|s| f64::from(s.0)).sum::<f64>() / n;
    let y_mean = shown.iter().filter(|s| s.1).count() as f64 / n;
    let t: f64 = shown
        .iter()
        .map(|s| (f64::from(s.0) - x_mean) * f64::from(u8::from(s.1)))
        .sum();
    let sxx: f64 = shown
        .iter()
        .map(|s| (f64::from(s.0) - x_mean).powi(2))
        .sum();
    let var = y_mean * (1.0 - y_mean) * sxx;
    let (z, p) = if var > 0.0 {
        let z = t / var.sqrt();
        (z, (2.0 * (1.0 - normal_cdf(z.abs()))).min(1.0))
    } else {
        (f64::NAN, f64::NAN)
    };
    let mut ratios = Vec::new();
    let (mut faster, mut slower) = (0u64, 0u64);
    for [early, late] in per_participant.iter_mut() {
        let (e, l) = (median(early), median(late));
        if e.is_finite() && l.is_finite() && e > 0.0 {
            ratios.push(l / e);
            if l < e {
                faster += 1;
            } else if l > e {
                slower += 1;
            }
        }
    }
    Some(OrderEffect {
        bins,
        tie_trend_z: z,
        tie_trend_p: p,
        time_ratio: median(&mut ratios),
        faster,
        slower,
        time_p: sign_test(faster, slower),
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn normal_quantiles_match_tables() {
        assert!((normal_quantile(0.975) - 1.959_964).abs() < 1e-5);
        assert!((normal_quantile(0.8) - 0.841_621).abs() < 1e-5);
        assert!((normal_cdf(0.0) - 0.5).abs() < 1e-9);
    }

    #[test]
    fn sample_size_matches_the_textbook_formula_and_exact_power_is_near_80() {
        // p = 0.7, no ties, alpha 0.05:
        // n = ((1.959964*0.5 + 0.841621*sqrt(0.21)) / 0.2)^2 = 46.63
        assert_eq!(participants_needed(0.7, 0.0, 0.05), Some(47));
        // Half the answers ties: twice the participants, 93.25 rounded up.
        assert_eq!(participants_needed(0.7, 0.5, 0.05), Some(94));
        assert_eq!(participants_needed(0.5, 0.1, 0.05), None);
        assert_eq!(participants_needed(f64::NAN, 0.1, 0.05), None);
        let exact = sign_test_power(47, 0.7, 0.0, 0.05);
        assert!(exact > 0.7 && exact < 0.9, "{exact}");
        // Power grows with participants and with the effect.
        assert!(sign_test_power(200, 0.7, 0.0, 0.05) > 0.99);
        assert!(sign_test_power(47, 0.6, 0.0, 0.05) < exact);
        // Under the null the power is the size, at most alpha.
        assert!(sign_test_power(60, 0.5, 0.2, 0.05) <= 0.05);
    }
}
