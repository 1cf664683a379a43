//! The whole analysis: the dissertation's tables, per-question statistics, Bradley-Terry-Davidson
//! strengths, position bias and agreement, with participant-bootstrap intervals.
//!
//! Point estimates and every bootstrap resample go through the same function (`estimate`) on
//! per-question counts, so an interval always describes exactly the statistic next to it.

use polars::prelude::*;

use crate::bradley_terry::{fit_davidson, DavidsonFit, PairCounts};
use crate::data::{Dataset, InputFormat};
use crate::design::Design;
use crate::error::{AnalysisError, Result};
use crate::input::{load, Inputs, LoadOptions};
use crate::method::{mean, preference_factors, tally, MethodResult, QuestionCounts};
use crate::stats::{
    clopper_pearson, fleiss_kappa, holm, percentile_interval, sign_test, wilson_interval,
    SplitMix64, Z_95,
};

pub use crate::stats::Interval;

/// How to analyse.
#[derive(Clone, Debug, PartialEq)]
pub struct Options {
    /// Participants to leave out, by id (e.g. `P18`).
    pub exclude: Vec<String>,
    /// Drop missing answers (and count them) instead of failing.
    pub allow_missing: bool,
    /// Report questions whose sides differ in zero or several variables outside all groups
    /// instead of failing.
    pub allow_ungrouped: bool,
    /// The variable whose groups are combined by the arithmetic mean (`object`); `None` keeps
    /// every group as its own table row.
    pub mean_over: Option<String>,
    /// Participant-bootstrap resamples: 0 (no intervals) or at least 1,000.
    pub resamples: usize,
    /// Seed of the bootstrap.
    pub seed: u64,
    /// Family-wise error rate for the Holm-corrected sign tests.
    pub alpha: f64,
    /// Virtual wins each way between every two items when a Bradley-Terry fit has no finite
    /// estimate without them.
    pub prior: f64,
    /// Control answers (`controls.csv` of a survey export) for the position effect.
    pub controls: Option<std::path::PathBuf>,
    /// Add the power table (participants needed for 80% power, this data as the pilot); always
    /// on for survey data (responses with `order` and `swapped` columns).
    pub power: bool,
}

impl Default for Options {
    fn default() -> Self {
        Self {
            exclude: Vec::new(),
            allow_missing: false,
            allow_ungrouped: false,
            mean_over: Some("object".into()),
            resamples: 10_000,
            seed: 1,
            alpha: 0.05,
            prior: 0.5,
            controls: None,
            power: false,
        }
    }
}

/// Statistics of one question ("for X" = left configuration, "for Y" = right).
#[derive(Clone, Debug, PartialEq)]
pub struct QuestionStats {
    /// Question id.
    pub id: String,
    /// Left configuration (X).
    pub left: String,
    /// Right configuration (Y).
    pub right: String,
    /// Its comparison group's label, if any.
    pub group: Option<String>,
    /// W (left), T (none), L (right).
    pub counts: QuestionCounts,
    /// T / N.
    pub tie_rate: f64,
    /// W / n among decided answers (NaN when n = 0).
    pub share_left: f64,
    /// Wilson 95% interval of `share_left`.
    pub wilson: Interval,
    /// Clopper-Pearson 95% interval of `share_left`.
    pub clopper_pearson: Interval,
    /// (W − L) / N.
    pub net_preference: f64,
    /// Participant-bootstrap 95% interval of `net_preference`.
    pub net_interval: Interval,
    /// Exact two-sided sign test, ties excluded.
    pub p_value: f64,
    /// Holm-adjusted across all questions.
    pub p_holm: f64,
    /// `p_holm < alpha`.
    pub significant: bool,
    /// The configuration with more votes, when significant.
    pub preferred: Option<String>,
}

/// Mean factor of one level in a table row.
#[derive(Clone, Debug, PartialEq)]
pub struct LevelFactor {
    /// The varied variable's value.
    pub level: String,
    /// Mean preference factor over the row's groups.
    pub factor: f64,
    /// Participant-bootstrap 95% interval.
    pub interval: Interval,
}

/// One row of the mean-factor table.
#[derive(Clone, Debug, PartialEq)]
pub struct RowFactors {
    /// "clustering | lattice=bcdl".
    pub label: String,
    /// The varied variable.
    pub varied: String,
    /// "lattice=bcdl".
    pub fixed: String,
    /// Mean factors per level.
    pub levels: Vec<LevelFactor>,
    /// Groups averaged.
    pub groups: usize,
    /// Answers behind the row (ties included).
    pub responses: u64,
    /// Participants behind the row.
    pub participants: usize,
}

/// Factor of one configuration in one comparison group.
#[derive(Clone, Debug, PartialEq)]
pub struct ConfigurationFactor {
    /// Configuration name.
    pub configuration: String,
    /// Its value of the varied variable.
    pub level: String,
    /// Votes for it / all responses in the group.
    pub factor: f64,
    /// Participant-bootstrap 95% interval.
    pub interval: Interval,
}

/// One comparison group before averaging.
#[derive(Clone, Debug, PartialEq)]
pub struct GroupFactorsRow {
    /// "clustering | object=sphere, lattice=bcdl".
    pub label: String,
    /// Question ids in the group.
    pub questions: Vec<String>,
    /// Factors of its configurations.
    pub configurations: Vec<ConfigurationFactor>,
    /// Answers behind the group.
    pub responses: u64,
    /// Participants behind the group.
    pub participants: usize,
}

/// The overall-weights table: the first non-averaged variable across, the others down.
#[derive(Clone, Debug, PartialEq)]
pub struct WeightsTable {
    /// The variable across (`lattice`).
    pub column_variable: String,
    /// The variables down (`clustering`).
    pub row_variables: Vec<String>,
    /// Column levels.
    pub columns: Vec<String>,
    /// Row labels (values of the row variables joined by ", ").
    pub rows: Vec<String>,
    /// `values[row][column]`: overall weight (NaN for a cell no configuration has).
    pub values: Vec<Vec<f64>>,
    /// Participant-bootstrap 95% intervals of `values`.
    pub intervals: Vec<Vec<Interval>>,
    /// Mean over each row's defined cells.
    pub row_means: Vec<f64>,
    /// Mean over each column's defined cells.
    pub column_means: Vec<f64>,
    /// Mean over all defined cells.
    pub grand_mean: f64,
}

/// Which answers a Bradley-Terry fit uses.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum StrengthScope {
    /// One comparison group (one object).
    Group,
    /// A table row: the row's groups pooled over the averaged variable.
    Pooled,
}

/// Strength of one item.
#[derive(Clone, Debug, PartialEq)]
pub struct ItemStrength {
    /// Configuration name (groups) or level (pooled rows).
    pub item: String,
    /// Centred ln g.
    pub log_strength: f64,
    /// Participant-bootstrap 95% interval.
    pub interval: Interval,
}

/// A Bradley-Terry-Davidson fit with intervals.
#[derive(Clone, Debug, PartialEq)]
pub struct StrengthFit {
    /// Group or pooled row.
    pub scope: StrengthScope,
    /// The group's or row's label.
    pub label: String,
    /// Item strengths.
    pub items: Vec<ItemStrength>,
    /// Davidson's v.
    pub tie_parameter: f64,
    /// Participant-bootstrap 95% interval of v.
    pub tie_interval: Interval,
    /// Whether the point fit needed the prior.
    pub prior_used: bool,
    /// Resamples whose fit needed the prior.
    pub prior_resamples: usize,
    /// Whether the point fit converged.
    pub converged: bool,
    /// Answers behind the fit.
    pub responses: u64,
}

/// Left screen vs right screen among all decided answers.
#[derive(Clone, Debug, PartialEq)]
pub struct PositionBias {
    /// Answers choosing the left screen.
    pub left: u64,
    /// Answers choosing the right screen.
    pub right: u64,
    /// left / (left + right).
    pub share_left: f64,
    /// Wilson 95% interval of `share_left`.
    pub wilson: Interval,
    /// Exact binomial test against 1/2.
    pub p_value: f64,
}

/// Fleiss' kappa with questions as subjects and the three answers as categories.
#[derive(Clone, Debug, PartialEq)]
pub struct Agreement {
    /// κ (NaN when undefined).
    pub kappa: f64,
    /// Participant-bootstrap 95% interval.
    pub interval: Interval,
    /// Questions (subjects).
    pub subjects: usize,
    /// Participants (raters).
    pub raters: usize,
}

/// Participants and answers behind a table.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct TableBasis {
    /// Participants with at least one answer in the table.
    pub participants: usize,
    /// Answers (ties included).
    pub responses: u64,
}

/// Everything [`analyse`] computes; [`crate::write_outputs`] turns it into files.
#[derive(Clone, Debug)]
pub struct Analysis {
    /// The inputs.
    pub inputs: Inputs,
    /// The options.
    pub options: Options,
    /// Layout the responses were read in.
    pub format: InputFormat,
    /// Participants analysed.
    pub participants: Vec<String>,
    /// Participants excluded on request.
    pub excluded: Vec<String>,
    /// Missing answers dropped.
    pub dropped_missing: usize,
    /// Answers analysed (all questions).
    pub responses: u64,
    /// Groups, rows and cells.
    pub design: Design,
    /// Per question.
    pub questions: Vec<QuestionStats>,
    /// Questions outside all groups, described.
    pub ungrouped: Vec<String>,
    /// The mean-factor table (the dissertation's first table).
    pub factors: Vec<RowFactors>,
    /// Participants and answers behind the factor and weight tables.
    pub basis: TableBasis,
    /// Factors per comparison group before averaging.
    pub group_factors: Vec<GroupFactorsRow>,
    /// The overall-weights table (the dissertation's second table).
    pub weights: WeightsTable,
    /// Per configuration: the sum of its factors before averaging.
    pub configuration_weights: Vec<(String, f64)>,
    /// Bradley-Terry-Davidson fits: every group, then every pooled row.
    pub strengths: Vec<StrengthFit>,
    /// Position bias.
    pub position: PositionBias,
    /// Agreement.
    pub agreement: Agreement,
    /// Position, order and power from survey data (`None` for data without the survey columns,
    /// controls or a power request: the output is then as before).
    pub survey: Option<crate::effects::SurveyEffects>,
}

/// Looks up the bootstrap interval of the statistic that a closure picks from each resample.
type IntervalOf<'a> = &'a dyn Fn(&dyn Fn(&Estimates) -> f64) -> Interval;

/// Statistics recomputed on every resample.
#[derive(Clone, Debug)]
struct Estimates {
    method: MethodResult,
    net: Vec<f64>,
    kappa: f64,
    fits: Vec<DavidsonFit>,
}

/// Reads, validates and analyses the inputs.
pub fn analyse(inputs: &Inputs, options: &Options) -> Result<Analysis> {
    if options.resamples != 0 && options.resamples < 1_000 {
        return Err(AnalysisError::InvalidOption(format!(
            "{} bootstrap resamples: use 0 (no intervals) or at least 1,000",
            options.resamples
        )));
    }
    if !(options.alpha > 0.0 && options.alpha < 1.0) {
        return Err(AnalysisError::InvalidOption(format!(
            "alpha {} is not between 0 and 1",
            options.alpha
        )));
    }
    if !(options.prior > 0.0 && options.prior.is_finite()) {
        return Err(AnalysisError::InvalidOption(format!(
            "Bradley-Terry prior {} must be positive",
            options.prior
        )));
    }
    let dataset = load(
        inputs,
        &LoadOptions {
            exclude: options.exclude.clone(),
            allow_missing: options.allow_missing,
        },
    )?;
    analyse_dataset(inputs, options, &dataset)
}

/// Analyses an already loaded dataset.
pub fn analyse_dataset(inputs: &Inputs, options: &Options, dataset: &Dataset) -> Result<Analysis> {
    let configurations = &dataset.configurations;
    let questions = &dataset.questions;
    let responses = &dataset.responses;
    if questions.is_empty() {
        return Err(AnalysisError::Empty(format!(
            "{}: no questions",
            inputs.questions.display()
        )));
    }
    let design = Design::build(
        configurations,
        questions,
        &inputs.questions,
        options.mean_over.as_deref(),
        options.allow_ungrouped,
    )?;
    let counts = question_counts(&responses.long, questions.len())?;
    let point = estimate(&design, dataset, &counts, options.prior);

    // Bootstrap over participants.
    let participants = responses.participants.len();
    let mut rng = SplitMix64::new(options.seed);
    let mut samples: Vec<Estimates> = Vec::with_capacity(options.resamples);
    let mut sample = vec![0; participants];
    for _ in 0..options.resamples {
        for slot in sample.iter_mut() {
            *slot = rng.next_index(participants);
        }
        let counts = tally(&responses.answers, questions.len(), &sample);
        samples.push(estimate(&design, dataset, &counts, options.prior));
    }
    let interval = |f: &dyn Fn(&Estimates) -> f64| -> Interval {
        if samples.is_empty() {
            return None;
        }
        let values: Vec<f64> = samples.iter().map(f).collect();
        percentile_interval(&values)
    };

    // Per question.
    let p_values: Vec<f64> = counts.iter().map(|c| sign_test(c.left, c.right)).collect();
    let adjusted = holm(&p_values);
    let name = |c: usize| configurations.names[c].clone();
    let question_stats: Vec<QuestionStats> = questions
        .iter()
        .enumerate()
        .map(|(q, question)| {
            let c = counts[q];
            let significant = adjusted[q] < options.alpha;
            QuestionStats {
                id: question.id.clone(),
                left: name(question.left),
                right: name(question.right),
                group: design.question_group[q].map(|g| design.group_label(g)),
                counts: c,
                tie_rate: ratio(c.none, c.total()),
                share_left: ratio(c.left, c.decided()),
                wilson: wilson_interval(c.left, c.decided(), Z_95),
                clopper_pearson: clopper_pearson(c.left, c.decided(), 0.05),
                net_preference: point.net[q],
                net_interval: interval(&|e| e.net[q]),
                p_value: p_values[q],
                p_holm: adjusted[q],
                significant,
                preferred: match (significant, c.left.cmp(&c.right)) {
                    (true, std::cmp::Ordering::Greater) => Some(name(question.left)),
                    (true, std::cmp::Ordering::Less) => Some(name(question.right)),
                    _ => None,
                },
            }
        })
        .collect();
    let ungrouped = design
        .ungrouped
        .iter()
        .map(|u| {
            let q = &questions[u.question];
            let vars: Vec<&str> = u
                .differing
                .iter()
                .map(|&v| design.variables[v].as_str())
                .collect();
            format!(
                "{} ({} vs {}): differs in {} variable(s) [{}]",
                q.id,
                name(q.left),
                name(q.right),
                u.differing.len(),
                vars.join(", ")
            )
        })
        .collect();

    // Participants and answers behind rows, groups and the tables, with polars.
    let (row_basis, group_basis, basis) = table_basis(&responses.long, &design)?;

    let factors = design
        .rows
        .iter()
        .enumerate()
        .map(|(r, row)| RowFactors {
            label: design.row_label(r),
            varied: design.variables[row.varied].clone(),
            fixed: design.row_fixed_label(r),
            levels: row
                .levels
                .iter()
                .enumerate()
                .map(|(l, level)| LevelFactor {
                    level: level.clone(),
                    factor: point.method.rows[r][l],
                    interval: interval(&|e| e.method.rows[r][l]),
                })
                .collect(),
            groups: row.groups.len(),
            responses: row_basis[r].responses,
            participants: row_basis[r].participants,
        })
        .collect();

    let group_factors = design
        .groups
        .iter()
        .enumerate()
        .map(|(g, group)| GroupFactorsRow {
            label: design.group_label(g),
            questions: group
                .questions
                .iter()
                .map(|&q| questions[q].id.clone())
                .collect(),
            configurations: group
                .configurations
                .iter()
                .enumerate()
                .map(|(k, &c)| ConfigurationFactor {
                    configuration: name(c),
                    level: configurations.values[c][group.varied].clone(),
                    factor: point.method.groups[g].factors[k],
                    interval: interval(&|e| e.method.groups[g].factors[k]),
                })
                .collect(),
            responses: group_basis[g].responses,
            participants: group_basis[g].participants,
        })
        .collect();

    let weights = weights_table(&design, &point, &interval);
    let configuration_weights = configurations
        .names
        .iter()
        .zip(&point.method.configurations)
        .map(|(n, w)| (n.clone(), *w))
        .collect();

    let strengths = strength_fits(&design, dataset, &point, &samples, &counts, &interval);

    let left: u64 = counts.iter().map(|c| c.left).sum();
    let right: u64 = counts.iter().map(|c| c.right).sum();
    let position = PositionBias {
        left,
        right,
        share_left: ratio(left, left + right),
        wilson: wilson_interval(left, left + right, Z_95),
        p_value: sign_test(left, right),
    };
    let agreement = Agreement {
        kappa: point.kappa,
        interval: interval(&|e| e.kappa),
        subjects: questions.len(),
        raters: participants,
    };

    let controls = match &options.controls {
        // A controls file without rows (no controls asked) adds nothing.
        Some(path) => Some(crate::effects::read_controls(path, &responses.excluded)?)
            .filter(|c| c.left + c.none + c.right > 0),
        None => None,
    };
    let with_meta = responses.meta.is_some();
    let survey = (with_meta || controls.is_some() || options.power).then(|| {
        let power = (with_meta || options.power)
            .then(|| crate::effects::power(dataset, &design, options.alpha));
        crate::effects::survey_effects(dataset, &design, controls, power)
    });

    Ok(Analysis {
        inputs: inputs.clone(),
        options: options.clone(),
        format: responses.format,
        participants: responses.participants.clone(),
        excluded: responses.excluded.clone(),
        dropped_missing: responses.dropped_missing,
        responses: counts.iter().map(|c| c.total()).sum(),
        design,
        questions: question_stats,
        ungrouped,
        factors,
        basis,
        group_factors,
        weights,
        configuration_weights,
        strengths,
        position,
        agreement,
        survey,
    })
}

fn ratio(a: u64, b: u64) -> f64 {
    if b == 0 {
        f64::NAN
    } else {
        a as f64 / b as f64
    }
}

/// Per-question counts from the tidy answers: a polars group-by over (question, answer).
pub fn question_counts(long: &DataFrame, questions: usize) -> Result<Vec<QuestionCounts>> {
    let grouped = long
        .clone()
        .lazy()
        .group_by([col("question")])
        .agg([
            col("answer").eq(lit("L")).sum().alias("left"),
            col("answer").eq(lit("N")).sum().alias("none"),
            col("answer").eq(lit("R")).sum().alias("right"),
        ])
        .sort(["question"], SortMultipleOptions::default())
        .collect()?;
    let column = |name: &str| -> Result<Vec<u64>> {
        let c = grouped.column(name)?.cast(&DataType::UInt64)?;
        Ok(c.u64()?.iter().map(|v| v.unwrap_or(0)).collect())
    };
    let (index, left, none, right) = (
        column("question")?,
        column("left")?,
        column("none")?,
        column("right")?,
    );
    let mut counts = vec![QuestionCounts::default(); questions];
    for k in 0..index.len() {
        if let Some(c) = counts.get_mut(index[k] as usize) {
            *c = QuestionCounts {
                left: left[k],
                none: none[k],
                right: right[k],
            };
        }
    }
    Ok(counts)
}

/// Participants and answers per table row, per group and over all grouped questions: the tidy
/// answers joined with each question's group and row, then grouped.
fn table_basis(
    long: &DataFrame,
    design: &Design,
) -> Result<(Vec<TableBasis>, Vec<TableBasis>, TableBasis)> {
    let mut question = Vec::new();
    let mut group = Vec::new();
    let mut row = Vec::new();
    for (q, g) in design.question_group.iter().enumerate() {
        if let Some(g) = g {
            question.push(q as u32);
            group.push(*g as u32);
            row.push(design.groups[*g].row as u32);
        }
    }
    let membership = df!("question" => question, "group" => group, "table_row" => row)?;
    let grouped =
        long.clone()
            .lazy()
            .inner_join(membership.lazy(), col("question"), col("question"));
    let summarise = |by: Option<&str>, n: usize| -> Result<Vec<TableBasis>> {
        let aggregations = [
            len().alias("responses"),
            col("participant").n_unique().alias("participants"),
        ];
        let frame = match by {
            Some(key) => grouped
                .clone()
                .group_by([col(key)])
                .agg(aggregations)
                .sort([key], SortMultipleOptions::default())
                .collect()?,
            None => grouped.clone().select(aggregations).collect()?,
        };
        let numbers = |name: &str| -> Result<Vec<u64>> {
            let c = frame.column(name)?.cast(&DataType::UInt64)?;
            Ok(c.u64()?.iter().map(|v| v.unwrap_or(0)).collect())
        };
        let keys = match by {
            Some(key) => numbers(key)?,
            None => vec![0],
        };
        let (responses, participants) = (numbers("responses")?, numbers("participants")?);
        let mut out = vec![
            TableBasis {
                participants: 0,
                responses: 0
            };
            n
        ];
        for k in 0..keys.len() {
            if let Some(slot) = out.get_mut(keys[k] as usize) {
                *slot = TableBasis {
                    participants: participants[k] as usize,
                    responses: responses[k],
                };
            }
        }
        Ok(out)
    };
    let rows = summarise(Some("table_row"), design.rows.len())?;
    let groups = summarise(Some("group"), design.groups.len())?;
    let total = if design.groups.is_empty() {
        TableBasis {
            participants: 0,
            responses: 0,
        }
    } else {
        summarise(None, 1)?[0]
    };
    Ok((rows, groups, total))
}

/// Every statistic that gets a bootstrap interval, from per-question counts.
fn estimate(
    design: &Design,
    dataset: &Dataset,
    counts: &[QuestionCounts],
    prior: f64,
) -> Estimates {
    let questions = &dataset.questions;
    let method = preference_factors(
        design,
        questions,
        counts,
        dataset.configurations.names.len(),
    );
    let net = counts
        .iter()
        .map(|c| {
            if c.total() == 0 {
                f64::NAN
            } else {
                (c.left as f64 - c.right as f64) / c.total() as f64
            }
        })
        .collect();
    let table: Vec<Vec<u64>> = counts.iter().map(|c| c.as_array().to_vec()).collect();
    let kappa = fleiss_kappa(&table).unwrap_or(f64::NAN);
    let mut fits = Vec::with_capacity(design.groups.len() + design.rows.len());
    for group in &design.groups {
        let pairs: Vec<PairCounts> = group
            .questions
            .iter()
            .map(|&q| {
                let position = |c: usize| group.configurations.iter().position(|&x| x == c);
                pair_counts(
                    position(questions[q].left),
                    position(questions[q].right),
                    counts[q],
                )
            })
            .collect();
        fits.push(fit_davidson(group.configurations.len(), &pairs, prior));
    }
    for row in &design.rows {
        let level_of = |c: usize| {
            let value = &dataset.configurations.values[c][row.varied];
            row.levels.iter().position(|l| l == value)
        };
        let pairs: Vec<PairCounts> = row
            .groups
            .iter()
            .flat_map(|&g| design.groups[g].questions.iter())
            .map(|&q| {
                pair_counts(
                    level_of(questions[q].left),
                    level_of(questions[q].right),
                    counts[q],
                )
            })
            .collect();
        fits.push(fit_davidson(row.levels.len(), &pairs, prior));
    }
    Estimates {
        method,
        net,
        kappa,
        fits,
    }
}

fn pair_counts(i: Option<usize>, j: Option<usize>, c: QuestionCounts) -> PairCounts {
    PairCounts {
        i: i.unwrap_or(usize::MAX),
        j: j.unwrap_or(usize::MAX),
        wins_i: c.left as f64,
        wins_j: c.right as f64,
        ties: c.none as f64,
    }
}

fn weights_table(design: &Design, point: &Estimates, interval: IntervalOf<'_>) -> WeightsTable {
    let levels = |v: usize| {
        let mut levels: Vec<String> = Vec::new();
        for cell in &design.cells {
            let k = design
                .cell_variables
                .iter()
                .position(|&x| x == v)
                .unwrap_or(0);
            if !levels.contains(&cell[k]) {
                levels.push(cell[k].clone());
            }
        }
        levels
    };
    let column_variable = design.cell_variables.first().copied();
    let columns = column_variable.map(levels).unwrap_or_default();
    // Rows: the remaining cell variables' value combinations, in cell order.
    let row_key = |cell: &[String]| cell.iter().skip(1).cloned().collect::<Vec<_>>().join(", ");
    let mut rows: Vec<String> = Vec::new();
    for cell in &design.cells {
        let key = row_key(cell);
        if !rows.contains(&key) {
            rows.push(key);
        }
    }
    let mut values = vec![vec![f64::NAN; columns.len()]; rows.len()];
    let mut intervals = vec![vec![None; columns.len()]; rows.len()];
    for (k, cell) in design.cells.iter().enumerate() {
        let r = rows.iter().position(|x| *x == row_key(cell));
        let c = columns.iter().position(|x| Some(x) == cell.first());
        if let (Some(r), Some(c)) = (r, c) {
            values[r][c] = point.method.cells[k];
            intervals[r][c] = interval(&|e| e.method.cells[k]);
        }
    }
    let finite_mean =
        |xs: Vec<f64>| mean(&xs.into_iter().filter(|x| x.is_finite()).collect::<Vec<_>>());
    let row_means = values.iter().map(|row| finite_mean(row.clone())).collect();
    let column_means = (0..columns.len())
        .map(|c| finite_mean(values.iter().map(|row| row[c]).collect()))
        .collect();
    let grand_mean = finite_mean(values.iter().flatten().copied().collect());
    WeightsTable {
        column_variable: column_variable
            .map(|v| design.variables[v].clone())
            .unwrap_or_default(),
        row_variables: design
            .cell_variables
            .iter()
            .skip(1)
            .map(|&v| design.variables[v].clone())
            .collect(),
        columns,
        rows,
        values,
        intervals,
        row_means,
        column_means,
        grand_mean,
    }
}

fn strength_fits(
    design: &Design,
    dataset: &Dataset,
    point: &Estimates,
    samples: &[Estimates],
    counts: &[QuestionCounts],
    interval: IntervalOf<'_>,
) -> Vec<StrengthFit> {
    let names = &dataset.configurations.names;
    let mut fits = Vec::new();
    let scopes = design
        .groups
        .iter()
        .enumerate()
        .map(|(g, group)| {
            (
                StrengthScope::Group,
                design.group_label(g),
                group
                    .configurations
                    .iter()
                    .map(|&c| names[c].clone())
                    .collect::<Vec<_>>(),
                group.questions.clone(),
            )
        })
        .chain(design.rows.iter().enumerate().map(|(r, row)| {
            (
                StrengthScope::Pooled,
                design.row_label(r),
                row.levels.clone(),
                row.groups
                    .iter()
                    .flat_map(|&g| design.groups[g].questions.clone())
                    .collect(),
            )
        }));
    for (f, (scope, label, items, questions)) in scopes.enumerate() {
        let fit = &point.fits[f];
        fits.push(StrengthFit {
            scope,
            label,
            items: items
                .into_iter()
                .enumerate()
                .map(|(i, item)| ItemStrength {
                    item,
                    log_strength: fit.log_strengths[i],
                    interval: interval(&|e| e.fits[f].log_strengths[i]),
                })
                .collect(),
            tie_parameter: fit.tie_parameter,
            tie_interval: interval(&|e| e.fits[f].tie_parameter),
            prior_used: fit.prior_used,
            prior_resamples: samples.iter().filter(|e| e.fits[f].prior_used).count(),
            converged: fit.converged,
            responses: questions.iter().map(|&q| counts[q].total()).sum(),
        });
    }
    fits
}

/// Analysis summary lines for printing: the survey effects (position, order, power), if any.
pub fn summary_lines(analysis: &Analysis) -> Vec<String> {
    let Some(effects) = &analysis.survey else {
        return Vec::new();
    };
    let mut lines = Vec::new();
    for p in &effects.position {
        lines.push(format!(
            "Position, {}: left {} / none {} / right {}, share left {:.3}, p = {:.3}",
            p.source, p.left, p.none, p.right, p.share_left, p.p_value
        ));
    }
    if let Some(o) = &effects.order {
        let rates: Vec<String> = o
            .bins
            .iter()
            .map(|b| format!("{}-{}: {:.3}", b.first, b.last, b.tie_rate))
            .collect();
        lines.push(format!(
            "Order: no-preference rate by position {} (trend z = {:.2}, p = {:.3}); last/first \
             third answer time {:.2}x",
            rates.join(", "),
            o.tie_trend_z,
            o.tie_trend_p,
            o.time_ratio
        ));
    }
    if let Some(power) = &effects.power {
        for g in &power.groups {
            let show = |n: Option<u64>| n.map(|n| n.to_string()).unwrap_or_else(|| "-".into());
            lines.push(format!(
                "Power 80%, {}: {} participants for its strongest question, {} for all {} \
                 (Holm worst case: {} / {})",
                g.group,
                show(g.strongest),
                show(g.all),
                g.questions,
                show(g.strongest_holm),
                show(g.all_holm)
            ));
        }
    }
    lines
}
