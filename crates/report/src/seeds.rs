//! Seed studies: a run whose manifest has `seeds = { from, count }` writes `seeds.csv` (one row
//! per configuration without seed: mean, sd, 95% confidence interval, min and max over the seeds
//! of triangles, reduction, radius ratio, fidelity and time, and the dissertation's
//! single-asteroid values). The report then shows a section "Across N asteroids": a table and
//! interval plots (mean with its 95% CI, the dissertation's value as a marker), beside the
//! single-seed tables, which show one seed of each configuration ([`representative_seed`]).

use std::collections::BTreeSet;
use std::path::Path;

use crate::csv_file::CsvFile;
use crate::data::{lattice_name, Run};
use crate::error::Result;
use crate::format::{fixed, sig};
use crate::output::{Block, TextTable};
use crate::plot::{palette, Axis, Bar, LegendEntry, Marker, RowChart, RowLine, Swatch, INK};

/// `seeds.csv`.
pub const SEEDS_CSV: &str = "seeds.csv";

/// The seed the single-seed tables show: 7 (the dissertation's asteroid, the asteroid's default
/// seed) when the study has it, else the study's first seed.
pub fn representative_seed(from: u64, to: u64) -> u64 {
    if (from..=to).contains(&7) {
        7
    } else {
        from
    }
}

/// A metric's distribution over the seeds.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Spread {
    /// Mean.
    pub mean: f64,
    /// Sample standard deviation.
    pub sd: Option<f64>,
    /// 95% confidence interval of the mean.
    pub ci: Option<(f64, f64)>,
    /// Smallest and largest value.
    pub range: (f64, f64),
}

/// One row of `seeds.csv`.
#[derive(Clone, Debug, PartialEq)]
pub struct SeedRow {
    /// Configuration id without seed.
    pub id: String,
    /// Object name.
    pub object: String,
    /// `mt` or `mc`.
    pub method: String,
    /// Lattice.
    pub lattice: String,
    /// Clustering.
    pub clustering: String,
    /// Number of seeds, first and last.
    pub seeds: (u64, u64, u64),
    /// Output triangles.
    pub triangles: Option<Spread>,
    /// Triangle reduction against no clustering.
    pub reduction: Option<Spread>,
    /// Mean radius ratio.
    pub radius_ratio: Option<Spread>,
    /// Mean distance to the surface, grid spacings.
    pub fidelity: Option<Spread>,
    /// The dissertation's triangles, reduction and radius ratio (single asteroid).
    pub paper: [Option<f64>; 3],
}

impl SeedRow {
    /// `BCDL, integrated` or `marching cubes`.
    pub fn description(&self) -> String {
        if self.method == "mc" {
            "marching cubes".into()
        } else {
            format!("{}, {}", lattice_name(&self.lattice), self.clustering)
        }
    }

    fn variant(&self) -> String {
        if self.method == "mc" {
            "marching cubes".into()
        } else {
            self.clustering.clone()
        }
    }
}

/// Reads `seeds.csv`.
pub fn read_seeds(path: &Path) -> Result<Vec<SeedRow>> {
    let file = CsvFile::read(path)?;
    let mut rows = Vec::with_capacity(file.rows.len());
    for r in 0..file.rows.len() {
        let spread = |m: &str| -> Result<Option<Spread>> {
            let Some(mean) = file.number(r, &format!("{m}_mean"))? else {
                return Ok(None);
            };
            let lo = file.number(r, &format!("{m}_ci_low"))?;
            let hi = file.number(r, &format!("{m}_ci_high"))?;
            Ok(Some(Spread {
                mean,
                sd: file.number(r, &format!("{m}_sd"))?,
                ci: lo.zip(hi),
                range: (
                    file.number(r, &format!("{m}_min"))?.unwrap_or(mean),
                    file.number(r, &format!("{m}_max"))?.unwrap_or(mean),
                ),
            }))
        };
        let int = |name: &str| -> Result<u64> { Ok(file.required(r, name)? as u64) };
        let paper = |m: &str| -> Result<Option<f64>> {
            if file.has(&format!("paper_{m}")) {
                file.number(r, &format!("paper_{m}"))
            } else {
                Ok(None)
            }
        };
        rows.push(SeedRow {
            id: file.text(r, "id")?.to_string(),
            object: file.text(r, "object")?.to_string(),
            method: file.text(r, "method")?.to_string(),
            lattice: file.text(r, "lattice")?.to_string(),
            clustering: file.text(r, "clustering")?.to_string(),
            seeds: (int("seeds")?, int("seed_from")?, int("seed_to")?),
            triangles: spread("triangles")?,
            reduction: spread("triangle_reduction")?,
            radius_ratio: spread("ar_mean")?,
            fidelity: spread("fidelity_mean_h")?,
            paper: [
                paper("triangles")?,
                paper("triangle_reduction")?,
                paper("ar_mean")?,
            ],
        });
    }
    Ok(rows)
}

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

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_dissertation_seed_is_shown_when_the_study_has_it() {
        assert_eq!(representative_seed(1, 200), 7);
        assert_eq!(representative_seed(8, 20), 8);
        assert_eq!(representative_seed(7, 7), 7);
    }
}
