//! Seed studies: a run whose manifest has `seeds = { from, count }` writes `seeds.csv` (one row
//! per configuration without seed: mean, sd, 95% confidence interval, min and max over the seeds
//! of triangles, reduction, radius ratio, fidelity and time, and the dissertation's
//! single-asteroid values). The report then shows a section "Across N asteroids": a table and
//! interval plots (mean with its 95% CI, the dissertation's value as a marker), beside the
//! single-seed tables, which show one seed of each configuration ([`representative_seed`]).
//!
//! `seeds.csv` is read with the rest of the run folder ([`crate::data`]); this module draws it.

use std::collections::BTreeSet;

use crate::data::Run;
pub use crate::data::{read_seeds, representative_seed, SeedRow, Spread, SEEDS_CSV};
use crate::format::{fixed, sig};
use crate::output::{Block, TextTable};
use crate::plot::{palette, Axis, Bar, LegendEntry, Marker, RowChart, RowLine, Swatch, INK};

/// `N asteroids` (or `N seeds` when the study has no asteroid): the section's noun.
pub fn heading(rows: &[SeedRow]) -> String {
    let n = rows.iter().map(|r| r.seeds.0).max().unwrap_or(0);
    if rows.iter().any(|r| r.object == "asteroid") {
        format!("Across {n} asteroids")
    } else {
        format!("Across {n} seeds")
    }
}

fn interval_text(s: Option<Spread>, f: impl Fn(f64) -> String) -> String {
    match s {
        Some(Spread {
            mean,
            ci: Some((lo, hi)),
            ..
        }) => format!("{} [{}, {}]", f(mean), f(lo), f(hi)),
        Some(s) => f(s.mean),
        None => String::new(),
    }
}

/// The table `seed_distributions`: per configuration, mean and 95% CI over the seeds, the
/// dissertation's single-asteroid value beside.
pub fn seed_table(rows: &[SeedRow]) -> TextTable {
    let csv_header: Vec<String> = [
        "id",
        "object",
        "seeds",
        "triangles_mean",
        "triangles_ci_low",
        "triangles_ci_high",
        "triangles_sd",
        "reduction_mean",
        "reduction_ci_low",
        "reduction_ci_high",
        "radius_ratio_mean",
        "radius_ratio_ci_low",
        "radius_ratio_ci_high",
        "fidelity_mean_h_mean",
        "fidelity_mean_h_ci_low",
        "fidelity_mean_h_ci_high",
        "paper_triangles",
        "paper_reduction",
        "paper_radius_ratio",
    ]
    .map(String::from)
    .to_vec();
    let num = |v: Option<f64>| v.map(|v| sig(v, 6)).unwrap_or_default();
    let parts = |s: Option<Spread>| -> [String; 3] {
        [
            num(s.map(|s| s.mean)),
            num(s.and_then(|s| s.ci).map(|c| c.0)),
            num(s.and_then(|s| s.ci).map(|c| c.1)),
        ]
    };
    let mut csv_rows = Vec::new();
    let mut md = Vec::new();
    for r in rows {
        let mut row = vec![r.id.clone(), r.object.clone(), r.seeds.0.to_string()];
        row.extend(parts(r.triangles)[..].iter().cloned());
        row.push(num(r.triangles.and_then(|s| s.sd)));
        row.extend(parts(r.reduction));
        row.extend(parts(r.radius_ratio));
        row.extend(parts(r.fidelity));
        row.extend(r.paper.map(num));
        csv_rows.push(row);
        let paper = |i: usize, f: &dyn Fn(f64) -> String| r.paper[i].map(f).unwrap_or_default();
        md.push(vec![
            format!("{} ({})", r.description(), r.id),
            r.object.clone(),
            r.seeds.0.to_string(),
            interval_text(r.triangles, |v| fixed(v, 0)),
            paper(0, &|v| fixed(v, 0)),
            interval_text(r.reduction, |v| fixed(100.0 * v, 1)),
            paper(1, &|v| fixed(100.0 * v, 1)),
            interval_text(r.radius_ratio, |v| fixed(v, 3)),
            paper(2, &|v| fixed(v, 3)),
            interval_text(r.fidelity, |v| fixed(v, 3)),
        ]);
    }
    TextTable {
        name: "seed_distributions".into(),
        title: heading(rows),
        notes: vec![
            "Every configuration over many noise seeds: mean [95% confidence interval of the \
             mean, Student's t] over the seeds. `paper` is the dissertation's single asteroid \
             (seed 7) where it has the configuration at this resolution. Reduction in percent \
             of the triangles without clustering (same seed); radius ratio R / (2r), mean per \
             mesh; fidelity in grid spacings."
                .into(),
        ],
        csv_header,
        csv_rows,
        blocks: vec![Block {
            caption: None,
            header: [
                "configuration",
                "object",
                "seeds",
                "triangles",
                "paper",
                "reduction %",
                "paper",
                "radius ratio",
                "paper",
                "fidelity (h)",
            ]
            .map(String::from)
            .to_vec(),
            rows: md,
        }],
    }
}

/// An interval plot of one metric: a dot at the mean, whiskers over its 95% CI, the
/// dissertation's value as a diamond; one row per configuration under its object.
fn interval_chart(
    run: &Run,
    rows: &[SeedRow],
    title: &str,
    axis_label: &str,
    percent: bool,
    pick: impl Fn(&SeedRow) -> (Option<Spread>, Option<f64>),
) -> Option<RowChart> {
    let mut values = Vec::new();
    let mut lines = Vec::new();
    let objects: Vec<&str> = {
        let mut seen = BTreeSet::new();
        rows.iter()
            .map(|r| r.object.as_str())
            .filter(|o| seen.insert(*o))
            .collect()
    };
    let mut variants: Vec<String> = Vec::new();
    let mut with_paper = false;
    for object in objects {
        let members: Vec<&SeedRow> = rows.iter().filter(|r| r.object == object).collect();
        let bars: Vec<(String, Bar)> = members
            .iter()
            .filter_map(|r| {
                let (spread, paper) = pick(r);
                let s = spread?;
                values.push(s.mean);
                if let Some((lo, hi)) = s.ci {
                    values.extend([lo, hi]);
                }
                if let Some(p) = paper {
                    values.push(p);
                    with_paper = true;
                }
                if !variants.contains(&r.variant()) {
                    variants.push(r.variant());
                }
                let text = if percent {
                    format!("{}%", fixed(100.0 * s.mean, 1))
                } else {
                    sig(s.mean, 4)
                };
                Some((
                    format!("{} ({})", r.description(), r.id),
                    Bar {
                        value: s.mean,
                        colour: palette::variant(&r.variant()),
                        interval: s.ci,
                        reference: paper.map(|p| (p, Marker::OpenDiamond)),
                        text,
                    },
                ))
            })
            .collect();
        if bars.is_empty() {
            continue;
        }
        let n = members.iter().map(|r| r.seeds.0).max().unwrap_or(0);
        lines.push(RowLine::Heading(format!("{object}, {n} seeds")));
        lines.extend(bars.into_iter().map(|(label, bar)| RowLine::Bars {
            label,
            bars: vec![bar],
        }));
    }
    if values.is_empty() {
        return None;
    }
    let axis = Axis::linear(&values, percent);
    let mut legend: Vec<LegendEntry> = variants
        .iter()
        .map(|v| {
            LegendEntry::new(
                Swatch::Marker(Marker::Circle, palette::variant(v)),
                crate::figures::variant_label(v),
            )
        })
        .collect();
    legend.push(LegendEntry::new(
        Swatch::Whisker,
        "mean and its 95% confidence interval over the seeds",
    ));
    if with_paper {
        legend.push(LegendEntry::new(
            Swatch::Marker(Marker::OpenDiamond, INK),
            "dissertation (one asteroid, seed 7)",
        ));
    }
    Some(RowChart {
        title: title.to_string(),
        subtitle: vec![format!(
            "Run {} ({} manifest): every configuration over many noise seeds.",
            run.info.run_id, run.info.name
        )],
        axis_label: axis_label.to_string(),
        axis,
        percent_axis: percent,
        dots: true,
        lines,
        legend,
    })
}

/// The interval plots of a seed study: `seed_triangles`, `seed_reduction`,
/// `seed_radius_ratio`.
pub fn seed_figures(run: &Run, rows: &[SeedRow]) -> Vec<(String, RowChart)> {
    let mut out = Vec::new();
    let n = heading(rows);
    if let Some(c) = interval_chart(
        run,
        rows,
        &format!("Output triangles {}", n.to_lowercase()),
        "triangles",
        false,
        |r| (r.triangles, r.paper[0]),
    ) {
        out.push(("seed_triangles".to_string(), c));
    }
    if let Some(c) = interval_chart(
        run,
        rows,
        &format!("Triangle reduction {}", n.to_lowercase()),
        "fewer triangles than without clustering",
        true,
        |r| (r.reduction.filter(|s| s.mean != 0.0), r.paper[1]),
    ) {
        out.push(("seed_reduction".to_string(), c));
    }
    if let Some(c) = interval_chart(
        run,
        rows,
        &format!("Radius ratio {}", n.to_lowercase()),
        "mean radius ratio R / (2r)",
        false,
        |r| (r.radius_ratio, r.paper[2]),
    ) {
        out.push(("seed_radius_ratio".to_string(), c));
    }
    out
}

/// The README section (a level-2 heading, a sentence, the table link and the figures).
pub fn readme_section(rows: &[SeedRow], figures: &[String], table_link: Option<String>) -> String {
    let mut out = format!("## {}\n\n", heading(rows));
    let (n, from, to) = rows.first().map(|r| r.seeds).unwrap_or((0, 0, 0));
    out.push_str(&format!(
        "The dissertation measured one asteroid. This run repeats every configuration of a noise \
         object over {n} seeds ({from} to {to}); the tables above show seed {} of each. Dots are \
         means over the seeds, whiskers their 95% confidence intervals, diamonds the \
         dissertation's single asteroid.\n\n",
        representative_seed(from, to)
    ));
    if let Some(link) = table_link {
        out.push_str(&format!("Table: {link}.\n\n"));
    }
    for (name, heading) in [
        ("seed_triangles", "Triangles over the seeds"),
        ("seed_reduction", "Triangle reduction over the seeds"),
        ("seed_radius_ratio", "Radius ratio over the seeds"),
    ] {
        if figures.iter().any(|f| f == name) {
            out.push_str(&format!(
                "### {heading}\n\n![{heading}](figures/{name}.png)\n\n[SVG](figures/{name}.svg)\n\n"
            ));
        }
    }
    out
}
