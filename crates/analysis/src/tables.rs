//! Every result as a table, rendered to CSV (full precision, one header, long form where the
//! Markdown has several blocks) and to Markdown (rounded, the dissertation's layout).

use crate::analysis::{Analysis, Interval, StrengthScope};

/// One table cell.
#[derive(Clone, Debug, PartialEq)]
pub enum Cell {
    /// Text as is.
    Text(String),
    /// A count.
    Count(u64),
    /// A number: 6 decimals in CSV, 3 in Markdown; NaN is empty / "–".
    Number(f64),
    /// A number with its interval: CSV writes only the number (intervals have their own columns),
    /// Markdown writes "0.421 [0.352, 0.489]".
    WithInterval(f64, Interval),
    /// A p-value: 3 significant digits; "< 1e-4" style in Markdown when tiny.
    P(f64),
}

impl Cell {
    fn csv(&self) -> String {
        match self {
            Cell::Text(t) => t.clone(),
            Cell::Count(n) => n.to_string(),
            Cell::Number(x) | Cell::WithInterval(x, _) => number(*x, 6),
            Cell::P(p) => format!("{p:.6e}"),
        }
    }

    fn markdown(&self) -> String {
        match self {
            Cell::Text(t) => t.replace('|', "\\|"),
            Cell::Count(n) => n.to_string(),
            Cell::Number(x) => markdown_number(*x),
            Cell::WithInterval(x, interval) => match interval {
                Some((lo, hi)) => format!(
                    "{} [{}, {}]",
                    markdown_number(*x),
                    markdown_number(*lo),
                    markdown_number(*hi)
                ),
                None => markdown_number(*x),
            },
            Cell::P(p) => {
                if *p < 1e-4 {
                    format!("{p:.1e}")
                } else {
                    format!("{p:.4}")
                }
            }
        }
    }
}

/// `x` with a fixed number of decimals, trailing zeros kept (`0.50`), never `-0.000`; empty for
/// non-finite values. Shared with the report crate so that every table prints numbers alike.
pub fn number(x: f64, decimals: usize) -> String {
    if x.is_finite() {
        // Avoid "-0.000000".
        let text = format!("{x:.decimals$}");
        if text
            .trim_start_matches('-')
            .chars()
            .all(|c| c == '0' || c == '.')
        {
            text.trim_start_matches('-').to_string()
        } else {
            text
        }
    } else {
        String::new()
    }
}

/// CSV text of `header` and `rows` (RFC 4180 quoting, `\n` line ends).
pub fn csv_text<R, C>(header: &[String], rows: impl IntoIterator<Item = R>) -> Vec<u8>
where
    R: IntoIterator<Item = C>,
    C: AsRef<[u8]>,
{
    let mut writer = csv::WriterBuilder::new()
        .terminator(csv::Terminator::Any(b'\n'))
        .from_writer(Vec::new());
    // Writing to a Vec cannot fail; a failure would only drop the record.
    let _ = writer.write_record(header);
    for row in rows {
        let _ = writer.write_record(row);
    }
    writer.into_inner().unwrap_or_default()
}

fn markdown_number(x: f64) -> String {
    if x.is_finite() {
        number(x, 3)
    } else {
        "–".into()
    }
}

/// A header and rows.
#[derive(Clone, Debug, PartialEq)]
pub struct Block {
    /// A sub-heading, for Markdown.
    pub caption: Option<String>,
    /// Column titles.
    pub header: Vec<String>,
    /// Rows of cells.
    pub rows: Vec<Vec<Cell>>,
}

/// A named table with its CSV form and its Markdown form.
#[derive(Clone, Debug, PartialEq)]
pub struct Table {
    /// File stem (`preference_factors`).
    pub name: String,
    /// Heading.
    pub title: String,
    /// Lines printed under the heading (participants and responses behind the table, notes).
    pub notes: Vec<String>,
    /// The CSV form.
    pub csv: Block,
    /// The Markdown form (one or more blocks).
    pub markdown: Vec<Block>,
}

impl Table {
    /// The CSV text (RFC 4180 quoting, `\n` line ends).
    pub fn to_csv(&self) -> Vec<u8> {
        csv_text(
            &self.csv.header,
            self.csv.rows.iter().map(|row| row.iter().map(Cell::csv)),
        )
    }

    /// The Markdown text.
    pub fn to_markdown(&self) -> String {
        let mut out = format!("## {}\n\n", self.title);
        for note in &self.notes {
            out.push_str(note);
            out.push_str("\n\n");
        }
        for block in &self.markdown {
            if let Some(caption) = &block.caption {
                out.push_str(&format!("### {caption}\n\n"));
            }
            out.push_str(&markdown_block(block));
            out.push('\n');
        }
        out
    }
}

fn markdown_block(block: &Block) -> String {
    let rows: Vec<Vec<String>> = block
        .rows
        .iter()
        .map(|row| row.iter().map(Cell::markdown).collect())
        .collect();
    let mut out = format!("| {} |\n", block.header.join(" | "));
    out.push_str(&format!(
        "|{}\n",
        block
            .header
            .iter()
            .enumerate()
            .map(|(i, _)| if i == 0 { "---|" } else { "---:|" })
            .collect::<String>()
    ));
    for row in rows {
        out.push_str(&format!("| {} |\n", row.join(" | ")));
    }
    out
}

fn text(s: impl Into<String>) -> Cell {
    Cell::Text(s.into())
}

fn lo(i: &Interval) -> Cell {
    Cell::Number(i.map_or(f64::NAN, |(l, _)| l))
}

fn hi(i: &Interval) -> Cell {
    Cell::Number(i.map_or(f64::NAN, |(_, h)| h))
}

fn header(titles: &[&str]) -> Vec<String> {
    titles.iter().map(|t| t.to_string()).collect()
}

/// The basis line printed with the dissertation's two tables.
pub fn basis_note(analysis: &Analysis) -> String {
    let mut note = format!(
        "Participants: {}; responses: {} (answers to the {} grouped questions, \"no preference\" \
         included).",
        analysis.basis.participants,
        analysis.basis.responses,
        analysis.design.question_group.iter().flatten().count(),
    );
    if !analysis.excluded.is_empty() {
        note.push_str(&format!(" Excluded: {}.", analysis.excluded.join(", ")));
    }
    if analysis.dropped_missing > 0 {
        note.push_str(&format!(
            " Missing answers dropped: {}.",
            analysis.dropped_missing
        ));
    }
    note
}

fn interval_note(analysis: &Analysis) -> String {
    if analysis.options.resamples == 0 {
        "No bootstrap intervals (0 resamples).".into()
    } else {
        format!(
            "Brackets: 95% percentile intervals from {} participant-bootstrap resamples \
             (seed {}).",
            analysis.options.resamples, analysis.options.seed
        )
    }
}

/// The dissertation's first table: mean factors per row, one Markdown block per varied variable.
pub fn factors_table(analysis: &Analysis) -> Table {
    let mean_over = analysis
        .design
        .mean_over
        .map(|m| analysis.design.variables[m].clone());
    let mut csv_rows = Vec::new();
    for row in &analysis.factors {
        for level in &row.levels {
            csv_rows.push(vec![
                text(&row.varied),
                text(&row.fixed),
                text(&level.level),
                Cell::Number(level.factor),
                lo(&level.interval),
                hi(&level.interval),
                Cell::Count(row.groups as u64),
                Cell::Count(row.responses),
                Cell::Count(row.participants as u64),
            ]);
        }
    }
    let mut blocks = Vec::new();
    let mut varied_seen: Vec<&str> = Vec::new();
    for row in &analysis.factors {
        if varied_seen.contains(&row.varied.as_str()) {
            continue;
        }
        varied_seen.push(&row.varied);
        let rows: Vec<_> = analysis
            .factors
            .iter()
            .filter(|r| r.varied == row.varied)
            .collect();
        let mut levels: Vec<String> = Vec::new();
        for r in &rows {
            for l in &r.levels {
                if !levels.contains(&l.level) {
                    levels.push(l.level.clone());
                }
            }
        }
        let mut head = vec!["group".to_string()];
        head.extend(levels.iter().cloned());
        head.extend(header(&["sum", "responses", "participants"]));
        let body = rows
            .iter()
            .map(|r| {
                let fixed = if r.fixed.is_empty() {
                    "all".to_string()
                } else {
                    r.fixed.clone()
                };
                let mut cells = vec![text(fixed)];
                for level in &levels {
                    cells.push(match r.levels.iter().find(|l| &l.level == level) {
                        Some(l) => Cell::WithInterval(l.factor, l.interval),
                        None => Cell::Number(f64::NAN),
                    });
                }
                cells.push(Cell::Number(
                    r.levels
                        .iter()
                        .map(|l| l.factor)
                        .filter(|f| f.is_finite())
                        .sum(),
                ));
                cells.push(Cell::Count(r.responses));
                cells.push(Cell::Count(r.participants as u64));
                cells
            })
            .collect();
        blocks.push(Block {
            caption: Some(format!("{} groups", row.varied)),
            header: head,
            rows: body,
        });
    }
    let mut notes = vec![basis_note(analysis)];
    notes.push(format!(
        "Factor = votes for a configuration / all responses in its comparison group (\"no \
         preference\" counts for nobody, so a group's factors sum to at most 1){}.",
        match &mean_over {
            Some(m) => format!(
                "; the same group on different values of {m} combined by the arithmetic mean"
            ),
            None => String::new(),
        }
    ));
    notes.push(interval_note(analysis));
    Table {
        name: "preference_factors".into(),
        title: "Mean preference factors per comparison group".into(),
        notes,
        csv: Block {
            caption: None,
            header: header(&[
                "varied",
                "fixed",
                "level",
                "mean_factor",
                "ci_low",
                "ci_high",
                "groups",
                "responses",
                "participants",
            ]),
            rows: csv_rows,
        },
        markdown: blocks,
    }
}

/// The dissertation's second table: overall weights with row and column means.
pub fn weights_table(analysis: &Analysis) -> Table {
    let w = &analysis.weights;
    let row_title = if w.row_variables.is_empty() {
        "all".to_string()
    } else {
        w.row_variables.join(", ")
    };
    let mut head = vec![format!("{row_title} \\ {}", w.column_variable)];
    head.extend(w.columns.iter().cloned());
    head.push("mean".into());
    let mut csv_head = vec![row_title.clone()];
    csv_head.extend(w.columns.iter().cloned());
    csv_head.push("mean".into());
    let mut csv_rows = Vec::new();
    let mut md_rows = Vec::new();
    for (r, label) in w.rows.iter().enumerate() {
        let label = if label.is_empty() {
            "all".to_string()
        } else {
            label.clone()
        };
        let mut csv_row = vec![text(&label)];
        let mut md_row = vec![text(&label)];
        for c in 0..w.columns.len() {
            csv_row.push(Cell::Number(w.values[r][c]));
            md_row.push(Cell::WithInterval(w.values[r][c], w.intervals[r][c]));
        }
        csv_row.push(Cell::Number(w.row_means[r]));
        md_row.push(Cell::Number(w.row_means[r]));
        csv_rows.push(csv_row);
        md_rows.push(md_row);
    }
    let mut means = vec![text("mean")];
    means.extend(w.column_means.iter().map(|&m| Cell::Number(m)));
    means.push(Cell::Number(w.grand_mean));
    csv_rows.push(means.clone());
    md_rows.push(means);
    Table {
        name: "preference_weights".into(),
        title: "Overall preference weights".into(),
        notes: vec![
            basis_note(analysis),
            "Weight = sum of a configuration's mean factors over the groups it appears in.".into(),
            interval_note(analysis),
        ],
        csv: Block {
            caption: None,
            header: csv_head,
            rows: csv_rows,
        },
        markdown: vec![Block {
            caption: None,
            header: head,
            rows: md_rows,
        }],
    }
}

/// Bootstrap intervals of the overall weights, long form.
pub fn weight_intervals_table(analysis: &Analysis) -> Table {
    let w = &analysis.weights;
    let mut rows = Vec::new();
    for (r, label) in w.rows.iter().enumerate() {
        for (c, column) in w.columns.iter().enumerate() {
            rows.push(vec![
                text(label),
                text(column),
                Cell::Number(w.values[r][c]),
                lo(&w.intervals[r][c]),
                hi(&w.intervals[r][c]),
            ]);
        }
    }
    let row_title = w.row_variables.join(", ");
    let block = Block {
        caption: None,
        header: vec![
            if row_title.is_empty() {
                "row".into()
            } else {
                row_title
            },
            w.column_variable.clone(),
            "weight".into(),
            "ci_low".into(),
            "ci_high".into(),
        ],
        rows,
    };
    Table {
        name: "preference_weight_intervals".into(),
        title: "Overall preference weights with bootstrap intervals".into(),
        notes: vec![basis_note(analysis), interval_note(analysis)],
        csv: block.clone(),
        markdown: vec![block],
    }
}

/// Factors per comparison group before averaging.
pub fn group_factors_table(analysis: &Analysis) -> Table {
    let mut csv_rows = Vec::new();
    let mut md_rows = Vec::new();
    for group in &analysis.group_factors {
        for c in &group.configurations {
            csv_rows.push(vec![
                text(&group.label),
                text(group.questions.join(" ")),
                text(&c.configuration),
                text(&c.level),
                Cell::Number(c.factor),
                lo(&c.interval),
                hi(&c.interval),
                Cell::Count(group.responses),
                Cell::Count(group.participants as u64),
            ]);
            md_rows.push(vec![
                text(&group.label),
                text(&c.configuration),
                Cell::WithInterval(c.factor, c.interval),
                Cell::Count(group.responses),
                Cell::Count(group.participants as u64),
            ]);
        }
    }
    Table {
        name: "group_factors".into(),
        title: "Preference factors per comparison group (before averaging)".into(),
        notes: vec![basis_note(analysis), interval_note(analysis)],
        csv: Block {
            caption: None,
            header: header(&[
                "group",
                "questions",
                "configuration",
                "level",
                "factor",
                "ci_low",
                "ci_high",
                "responses",
                "participants",
            ]),
            rows: csv_rows,
        },
        markdown: vec![Block {
            caption: None,
            header: header(&[
                "group",
                "configuration",
                "factor",
                "responses",
                "participants",
            ]),
            rows: md_rows,
        }],
    }
}

/// Each configuration's sum of factors before averaging.
pub fn configuration_weights_table(analysis: &Analysis) -> Table {
    let block = Block {
        caption: None,
        header: header(&["configuration", "weight"]),
        rows: analysis
            .configuration_weights
            .iter()
            .map(|(name, w)| vec![text(name), Cell::Number(*w)])
            .collect(),
    };
    Table {
        name: "configuration_weights".into(),
        title: "Preference weight per configuration (before averaging)".into(),
        notes: vec![basis_note(analysis)],
        csv: block.clone(),
        markdown: vec![block],
    }
}

/// Per-question counts, shares, sign tests.
pub fn questions_table(analysis: &Analysis) -> Table {
    let mut csv_rows = Vec::new();
    let mut md_rows = Vec::new();
    for q in &analysis.questions {
        let c = q.counts;
        csv_rows.push(vec![
            text(&q.id),
            text(&q.left),
            text(&q.right),
            text(q.group.clone().unwrap_or_default()),
            Cell::Count(c.left),
            Cell::Count(c.none),
            Cell::Count(c.right),
            Cell::Count(c.total()),
            Cell::Number(q.tie_rate),
            Cell::Number(q.share_left),
            lo(&q.wilson),
            hi(&q.wilson),
            lo(&q.clopper_pearson),
            hi(&q.clopper_pearson),
            Cell::Number(q.net_preference),
            lo(&q.net_interval),
            hi(&q.net_interval),
            Cell::P(q.p_value),
            Cell::P(q.p_holm),
            text(if q.significant { "yes" } else { "no" }),
            text(q.preferred.clone().unwrap_or_default()),
        ]);
        md_rows.push(vec![
            text(&q.id),
            text(format!("{} vs {}", q.left, q.right)),
            text(format!("{} / {} / {}", c.left, c.none, c.right)),
            Cell::WithInterval(q.share_left, q.wilson),
            Cell::WithInterval(q.net_preference, q.net_interval),
            Cell::P(q.p_value),
            Cell::P(q.p_holm),
            text(q.preferred.clone().unwrap_or_else(|| "–".into())),
        ]);
    }
    Table {
        name: "questions".into(),
        title: "Per question: counts, shares and sign tests".into(),
        notes: vec![format!(
            "Participants: {}; responses: {}. L / N / R = prefer left / no preference / \
                 prefer right. Share = left among decided answers with its Wilson 95% interval; \
                 net = (L − R) / N with a participant-bootstrap interval; p = exact two-sided \
                 sign test (ties excluded), Holm-adjusted across {} questions; preferred = the \
                 winner where the adjusted p < {}.",
            analysis.participants.len(),
            analysis.responses,
            analysis.questions.len(),
            analysis.options.alpha
        )],
        csv: Block {
            caption: None,
            header: header(&[
                "question",
                "left",
                "right",
                "group",
                "prefer_left",
                "no_preference",
                "prefer_right",
                "responses",
                "tie_rate",
                "share_left",
                "wilson_low",
                "wilson_high",
                "clopper_pearson_low",
                "clopper_pearson_high",
                "net_preference",
                "net_ci_low",
                "net_ci_high",
                "p_sign_test",
                "p_holm",
                "significant",
                "preferred",
            ]),
            rows: csv_rows,
        },
        markdown: vec![Block {
            caption: None,
            header: header(&[
                "question",
                "left vs right",
                "L / N / R",
                "share left",
                "net",
                "p",
                "p (Holm)",
                "preferred",
            ]),
            rows: md_rows,
        }],
    }
}

/// Bradley-Terry-Davidson strengths per group and per pooled row.
pub fn strengths_table(analysis: &Analysis) -> Table {
    let mut csv_rows = Vec::new();
    let mut md_rows = Vec::new();
    for fit in &analysis.strengths {
        let scope = match fit.scope {
            StrengthScope::Group => "group",
            StrengthScope::Pooled => "pooled",
        };
        for item in &fit.items {
            csv_rows.push(vec![
                text(scope),
                text(&fit.label),
                text(&item.item),
                Cell::Number(item.log_strength),
                lo(&item.interval),
                hi(&item.interval),
                Cell::Number(fit.tie_parameter),
                lo(&fit.tie_interval),
                hi(&fit.tie_interval),
                Cell::Count(fit.responses),
                text(if fit.prior_used { "yes" } else { "no" }),
                Cell::Count(fit.prior_resamples as u64),
                text(if fit.converged { "yes" } else { "no" }),
            ]);
            md_rows.push(vec![
                text(scope),
                text(&fit.label),
                text(&item.item),
                Cell::WithInterval(item.log_strength, item.interval),
                Cell::WithInterval(fit.tie_parameter, fit.tie_interval),
                Cell::Count(fit.responses),
                text(format!(
                    "{}{}",
                    if fit.prior_used { "point fit; " } else { "" },
                    fit.prior_resamples
                )),
            ]);
        }
    }
    Table {
        name: "bradley_terry".into(),
        title: "Bradley-Terry strengths with Davidson ties".into(),
        notes: vec![
            format!(
                "Centred log-strengths (mean 0 within each fit; a difference of d means odds of \
                 e^d between two items among decided answers) and the tie parameter v, fitted by \
                 MM iterations. \"group\" fits use one comparison group; \"pooled\" fits pool a \
                 table row's groups. Prior: where a fit has no finite estimate, {} virtual wins \
                 each way are added between every two items; the last column counts such \
                 resamples.",
                analysis.options.prior
            ),
            interval_note(analysis),
        ],
        csv: Block {
            caption: None,
            header: header(&[
                "scope",
                "label",
                "item",
                "log_strength",
                "ci_low",
                "ci_high",
                "tie_parameter",
                "tie_ci_low",
                "tie_ci_high",
                "responses",
                "prior_used",
                "prior_resamples",
                "converged",
            ]),
            rows: csv_rows,
        },
        markdown: vec![Block {
            caption: None,
            header: header(&[
                "scope",
                "label",
                "item",
                "log-strength",
                "tie parameter v",
                "responses",
                "prior used",
            ]),
            rows: md_rows,
        }],
    }
}

/// Run facts, position bias, agreement and the significant preferences.
pub fn summary_table(analysis: &Analysis) -> Table {
    let pos = &analysis.position;
    let agreement = &analysis.agreement;
    let significant: Vec<String> = analysis
        .questions
        .iter()
        .filter(|q| q.significant)
        .map(|q| {
            format!(
                "{} ({} over {}, p_holm {})",
                q.id,
                q.preferred.clone().unwrap_or_default(),
                if q.preferred.as_deref() == Some(q.left.as_str()) {
                    &q.right
                } else {
                    &q.left
                },
                Cell::P(q.p_holm).markdown()
            )
        })
        .collect();
    let rows: Vec<Vec<Cell>> = vec![
        vec![
            text("responses file"),
            text(analysis.inputs.responses.display().to_string()),
        ],
        vec![text("format"), text(analysis.format.to_string())],
        vec![
            text("participants"),
            Cell::Count(analysis.participants.len() as u64),
        ],
        vec![text("excluded"), text(analysis.excluded.join(" "))],
        vec![
            text("missing answers dropped"),
            Cell::Count(analysis.dropped_missing as u64),
        ],
        vec![
            text("questions"),
            Cell::Count(analysis.questions.len() as u64),
        ],
        vec![text("responses"), Cell::Count(analysis.responses)],
        vec![
            text("comparison groups"),
            Cell::Count(analysis.design.groups.len() as u64),
        ],
        vec![
            text("questions outside all groups"),
            text(analysis.ungrouped.join("; ")),
        ],
        vec![
            text("participants behind the tables"),
            Cell::Count(analysis.basis.participants as u64),
        ],
        vec![
            text("responses behind the tables"),
            Cell::Count(analysis.basis.responses),
        ],
        vec![
            text("bootstrap resamples"),
            Cell::Count(analysis.options.resamples as u64),
        ],
        vec![text("seed"), Cell::Count(analysis.options.seed)],
        vec![text("position: chose left screen"), Cell::Count(pos.left)],
        vec![text("position: chose right screen"), Cell::Count(pos.right)],
        vec![
            text("position: share left"),
            Cell::WithInterval(pos.share_left, pos.wilson),
        ],
        vec![text("position: p (binomial vs 1/2)"), Cell::P(pos.p_value)],
        vec![
            text("agreement: Fleiss' kappa"),
            Cell::WithInterval(agreement.kappa, agreement.interval),
        ],
        vec![
            text("significant after Holm"),
            text(if significant.is_empty() {
                "none".into()
            } else {
                significant.join("; ")
            }),
        ],
    ];
    let block = Block {
        caption: None,
        header: header(&["item", "value"]),
        rows,
    };
    Table {
        name: "summary".into(),
        title: "Summary".into(),
        notes: vec![
            "Position bias pools every decided answer; when each pair is shown in one order only \
             (as here) it is confounded with which configuration was put on which side."
                .into(),
            format!(
                "Fleiss' kappa: {} questions as subjects, {} participants as raters, the three \
                 answers as categories. Its bootstrap interval leans high: a resample repeats \
                 some participants, and a repeated rater agrees with itself.",
                agreement.subjects, agreement.raters
            ),
        ],
        csv: block.clone(),
        markdown: vec![block],
    }
}

/// All tables in output order.
pub fn all_tables(analysis: &Analysis) -> Vec<Table> {
    let mut tables = vec![
        factors_table(analysis),
        weights_table(analysis),
        weight_intervals_table(analysis),
        group_factors_table(analysis),
        configuration_weights_table(analysis),
        questions_table(analysis),
        strengths_table(analysis),
        summary_table(analysis),
    ];
    tables.extend(survey_tables(analysis));
    tables
}

fn count_or_dash(n: Option<u64>) -> Cell {
    match n {
        Some(n) => Cell::Count(n),
        None => text("-"),
    }
}

/// The tables of [`crate::effects`] (none without survey data, controls or a power request).
pub fn survey_tables(analysis: &Analysis) -> Vec<Table> {
    let Some(effects) = &analysis.survey else {
        return Vec::new();
    };
    let mut tables = Vec::new();
    if !effects.position.is_empty() {
        let rows: Vec<Vec<Cell>> = effects
            .position
            .iter()
            .map(|p| {
                vec![
                    text(p.source.clone()),
                    Cell::Count(p.left),
                    Cell::Count(p.none),
                    Cell::Count(p.right),
                    Cell::Number(p.tie_rate()),
                    Cell::WithInterval(p.share_left, p.wilson),
                    lo(&p.wilson),
                    hi(&p.wilson),
                    Cell::P(p.p_value),
                ]
            })
            .collect();
        let csv = Block {
            caption: None,
            header: header(&[
                "source",
                "left_screen",
                "no_preference",
                "right_screen",
                "tie_rate",
                "share_left",
                "share_left_lo",
                "share_left_hi",
                "p_value",
            ]),
            rows: rows.clone(),
        };
        let markdown = Block {
            caption: None,
            header: header(&[
                "source",
                "left screen",
                "no preference",
                "right screen",
                "tie rate",
                "share left [95% CI]",
                "p (vs 1/2)",
            ]),
            rows: rows
                .into_iter()
                .map(|r| {
                    let mut r = r;
                    r.remove(7);
                    r.remove(6);
                    r
                })
                .collect(),
        };
        tables.push(Table {
            name: "position_effect".into(),
            title: "Position effect (left/right screen)".into(),
            notes: vec![
                "Decided answers by the screen side clicked, tested against 1/2 (exact                  binomial, Wilson interval). With swaps balanced across participants this                  separates a preference for a side from a preference for a configuration. On                  controls both sides show the same animation: any side chosen is position bias                  or inattention, and their tie rate measures attention."
                    .into(),
            ],
            csv,
            markdown: vec![markdown],
        });
    }
    if let Some(order) = &effects.order {
        let rows: Vec<Vec<Cell>> = order
            .bins
            .iter()
            .map(|b| {
                vec![
                    text(format!("{}-{}", b.first, b.last)),
                    Cell::Count(b.answers),
                    Cell::Count(b.ties),
                    Cell::WithInterval(b.tie_rate, b.wilson),
                    lo(&b.wilson),
                    hi(&b.wilson),
                    Cell::Number(b.median_seconds),
                ]
            })
            .collect();
        let csv = Block {
            caption: None,
            header: header(&[
                "positions",
                "answers",
                "no_preference",
                "tie_rate",
                "tie_rate_lo",
                "tie_rate_hi",
                "median_seconds",
            ]),
            rows: rows.clone(),
        };
        let markdown = Block {
            caption: None,
            header: header(&[
                "positions shown",
                "answers",
                "no preference",
                "tie rate [95% CI]",
                "median s",
            ]),
            rows: rows
                .into_iter()
                .map(|mut r| {
                    r.remove(5);
                    r.remove(4);
                    r
                })
                .collect(),
        };
        tables.push(Table {
            name: "order_effect".into(),
            title: "Order effect (fatigue)".into(),
            notes: vec![
                format!(
                    "Ties over positions: Cochran-Armitage z = {}, p = {} (answers treated as                      independent, so optimistic).",
                    Cell::Number(order.tie_trend_z).markdown(),
                    Cell::P(order.tie_trend_p).markdown()
                ),
                format!(
                    "Answer time, last third over first third (median over participants): {}x;                      {} participants faster, {} slower (sign test p = {}).",
                    Cell::Number(order.time_ratio).markdown(),
                    order.faster,
                    order.slower,
                    Cell::P(order.time_p).markdown()
                ),
            ],
            csv,
            markdown: vec![markdown],
        });
    }
    if let Some(power) = &effects.power {
        let group_rows: Vec<Vec<Cell>> = power
            .groups
            .iter()
            .map(|g| {
                vec![
                    text(g.group.clone()),
                    Cell::Count(g.questions as u64),
                    count_or_dash(g.strongest),
                    count_or_dash(g.all),
                    count_or_dash(g.strongest_holm),
                    count_or_dash(g.all_holm),
                ]
            })
            .collect();
        let block = Block {
            caption: None,
            header: header(&[
                "group",
                "questions",
                "strongest",
                "all",
                "strongest_holm",
                "all_holm",
            ]),
            rows: group_rows,
        };
        let pilot = analysis.participants.len();
        tables.push(Table {
            name: "power".into(),
            title: "Participants needed for 80% power".into(),
            notes: vec![format!(
                "Pilot: these {pilot} participants. Per comparison group: participants needed                  so that a two-sided sign test (alpha {}) detects the pilot's effect with 80%                  power, for the group's strongest question (strongest) and for every question                  of the group (all; '-' when a question showed no effect); the _holm columns use                  alpha/{} (Holm's worst case over all questions). Ties are assumed at the pilot's                  rate. Per question: power_questions.",
                power.alpha, power.m
            )],
            csv: block.clone(),
            markdown: vec![block],
        });
        let rows: Vec<Vec<Cell>> = power
            .questions
            .iter()
            .map(|q| {
                vec![
                    text(q.question.clone()),
                    text(q.group.clone()),
                    Cell::Count(q.pilot),
                    Cell::Number(q.majority_share),
                    Cell::Number(q.tie_rate),
                    count_or_dash(q.needed),
                    Cell::Number(q.exact_power),
                    count_or_dash(q.needed_holm),
                ]
            })
            .collect();
        let block = Block {
            caption: None,
            header: header(&[
                "question",
                "group",
                "pilot",
                "majority_share",
                "tie_rate",
                "needed",
                "exact_power",
                "needed_holm",
            ]),
            rows,
        };
        tables.push(Table {
            name: "power_questions".into(),
            title: "Participants needed for 80% power, per question".into(),
            notes: vec![
                "needed: normal approximation of the sign test's sample size, divided by the                  share of decided answers; exact_power: the exact power of the sign test with                  that many participants."
                    .into(),
            ],
            csv: block.clone(),
            markdown: vec![block],
        });
    }
    tables
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn cells_format_for_csv_and_markdown() {
        assert_eq!(Cell::Number(0.5).csv(), "0.500000");
        assert_eq!(Cell::Number(f64::NAN).csv(), "");
        assert_eq!(Cell::Number(f64::NAN).markdown(), "–");
        assert_eq!(Cell::Number(-0.0000001).markdown(), "0.000");
        assert_eq!(
            Cell::WithInterval(0.4211, Some((0.35, 0.489))).markdown(),
            "0.421 [0.350, 0.489]"
        );
        assert_eq!(Cell::P(0.012345).markdown(), "0.0123");
        assert_eq!(Cell::P(1.5e-6).markdown(), "1.5e-6");
        assert_eq!(Cell::Text("a|b".into()).markdown(), "a\\|b");
    }

    #[test]
    fn tables_render_header_and_rows() {
        let table = Table {
            name: "t".into(),
            title: "T".into(),
            notes: vec!["note".into()],
            csv: Block {
                caption: None,
                header: header(&["a", "b"]),
                rows: vec![vec![text("x,y"), Cell::Count(3)]],
            },
            markdown: vec![Block {
                caption: Some("c".into()),
                header: header(&["a", "b"]),
                rows: vec![vec![text("x"), Cell::Count(3)]],
            }],
        };
        assert_eq!(
            String::from_utf8(table.to_csv()).unwrap(),
            "a,b\n\"x,y\",3\n"
        );
        let md = table.to_markdown();
        assert!(
            md.contains("## T\n\nnote\n\n### c\n\n| a | b |\n|---|---:|\n| x | 3 |\n"),
            "{md}"
        );
    }
}
