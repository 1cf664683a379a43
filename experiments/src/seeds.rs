//! Seed studies (`seeds = { from = 1, count = 200 }` in a manifest): every configuration of a
//! noise object (asteroid, terrain, caves) runs once per seed, as configuration `<id>_s<seed>`;
//! `summary.csv` keeps one row per seed, and `seeds.csv` gives each configuration's distribution
//! over the seeds: for each of [`SEED_METRICS`] the mean, sample standard deviation, the 95%
//! confidence interval of the mean (Student's t), the minimum and the maximum; and, when the
//! manifest names the dissertation's table and a configuration is in it at the same resolution,
//! the dissertation's single-asteroid value beside (`paper_triangles`,
//! `paper_triangle_reduction`, `paper_ar_mean`).

use std::collections::HashMap;

use anyhow::Result;

use rmt_runfolder::schema::{SEEDS_COUNTS, SEEDS_PREFIX, SEED_STATISTICS};
use rmt_runfolder::Table;

use crate::manifest::Plan;
use crate::paper::paper_comparison;

/// Summary columns whose distribution over seeds `seeds.csv` gives: triangles, vertices,
/// triangle reduction, radius ratio (mean and 95th percentile per mesh), fidelity (mean and
/// largest vertex distance in grid spacings), the mean extraction time and the mean time with
/// the finish steps, then the rendering cost (quad occupancy at the four screen sizes, ACMR as
/// extracted and after meshoptimizer's reordering) and the defects (non-manifold edges, holes).
/// Columns a run lacks (rendering cost turned off) give empty cells.
pub const SEED_METRICS: [&str; 17] = [
    "triangles",
    "vertices",
    "triangle_reduction",
    "ar_mean",
    "fidelity_mean_h",
    "fidelity_max_h",
    "t_total_s_mean",
    "ar_p95",
    "t_pipeline_s_mean",
    "quad_occupancy_1080",
    "quad_occupancy_540",
    "quad_occupancy_270",
    "quad_occupancy_135",
    "acmr_16",
    "acmr_16_optimized",
    "non_manifold_edges",
    "boundary_edges_interior",
];

/// The 97.5% quantile of Student's t with `df` degrees of freedom (two-sided 95% intervals):
/// tabulated to 3 decimals up to 30, then the Cornish-Fisher expansion around the normal
/// quantile (error below 1e-4 there).
pub fn t975(df: usize) -> f64 {
    const TABLE: [f64; 30] = [
        12.706, 4.303, 3.182, 2.776, 2.571, 2.447, 2.365, 2.306, 2.262, 2.228, 2.201, 2.179, 2.160,
        2.145, 2.131, 2.120, 2.110, 2.101, 2.093, 2.086, 2.080, 2.074, 2.069, 2.064, 2.060, 2.056,
        2.052, 2.048, 2.045, 2.042,
    ];
    if df == 0 {
        return f64::NAN;
    }
    if df <= 30 {
        return TABLE[df - 1];
    }
    let z = 1.959_964_f64;
    let n = df as f64;
    let (z3, z5, z7, z9) = (z.powi(3), z.powi(5), z.powi(7), z.powi(9));
    z + (z3 + z) / (4.0 * n)
        + (5.0 * z5 + 16.0 * z3 + 3.0 * z) / (96.0 * n * n)
        + (3.0 * z7 + 19.0 * z5 + 17.0 * z3 - 15.0 * z) / (384.0 * n.powi(3))
        + (79.0 * z9 + 776.0 * z7 + 1482.0 * z5 - 1920.0 * z3 - 945.0 * z) / (92160.0 * n.powi(4))
}

/// Mean, sample sd, 95% CI of the mean (low, high), min, max of `v` (NaN where undefined).
pub fn distribution(v: &[f64]) -> [f64; 6] {
    let n = v.len();
    if n == 0 {
        return [f64::NAN; 6];
    }
    let mean = v.iter().sum::<f64>() / n as f64;
    let sd = if n >= 2 {
        (v.iter().map(|x| (x - mean) * (x - mean)).sum::<f64>() / (n - 1) as f64).sqrt()
    } else {
        f64::NAN
    };
    let half = t975(n.saturating_sub(1)) * sd / (n as f64).sqrt();
    let min = v.iter().cloned().fold(f64::INFINITY, f64::min);
    let max = v.iter().cloned().fold(f64::NEG_INFINITY, f64::max);
    [mean, sd, mean - half, mean + half, min, max]
}

/// The dissertation's asteroid: the asteroid's default noise seed.
pub const PAPER_SEED: u32 = crate::objects::DEFAULT_SEED;

/// The summary rows `paper_comparison.csv` is built from: in a seed study, the configurations
/// of seed [`PAPER_SEED`] (the dissertation's asteroid) under their id without seed, the other
/// seeds left out; unchanged without a seed study.
pub fn single_seed_view(summary: &Table, plan: &Plan) -> Table {
    let seeds: HashMap<&str, (&str, u32)> = plan
        .configurations
        .iter()
        .filter_map(|c| {
            c.seed_of
                .as_ref()
                .map(|s| (c.id.as_str(), (s.base_id.as_str(), s.seed)))
        })
        .collect();
    if seeds.is_empty() {
        return summary.clone();
    }
    let rows = summary
        .rows
        .iter()
        .filter_map(|r| match seeds.get(r[0].as_str()) {
            None => Some(r.clone()),
            Some(&(base, seed)) if seed == PAPER_SEED => {
                let mut r = r.clone();
                r[0] = base.to_string();
                Some(r)
            }
            Some(_) => None,
        })
        .collect();
    Table {
        header: summary.header.clone(),
        rows,
    }
}

/// Seed of every configuration of a seed study (empty without one).
pub fn seed_map(plan: &Plan) -> HashMap<String, u32> {
    plan.configurations
        .iter()
        .filter_map(|c| c.seed_of.as_ref().map(|s| (c.id.clone(), s.seed)))
        .collect()
}

/// `seeds.csv` of a seed study from its `summary.csv`: one row per configuration without seed
/// (plan order), `seeds`, `seed_from`, `seed_to`, then `<metric>_mean, _sd, _ci_low, _ci_high,
/// _min, _max` for each of [`SEED_METRICS`], then the dissertation's values (see the
/// [module documentation](self)). None when the plan has no seed study.
pub fn seed_summary(summary: &Table, plan: &Plan) -> Result<Option<Table>> {
    let mut order: Vec<&str> = Vec::new();
    let mut members: HashMap<&str, Vec<(u32, usize)>> = HashMap::new();
    let row_of: HashMap<&str, usize> = (0..summary.rows.len())
        .filter_map(|r| summary.get(r, "id").map(|id| (id, r)))
        .collect();
    for c in &plan.configurations {
        let Some(s) = &c.seed_of else { continue };
        let Some(&row) = row_of.get(c.id.as_str()) else {
            continue;
        };
        let key = s.base_id.as_str();
        if !members.contains_key(key) {
            order.push(key);
        }
        members.entry(key).or_default().push((s.seed, row));
    }
    if order.is_empty() {
        return Ok(None);
    }
    let mut header: Vec<String> = SEEDS_PREFIX.iter().map(|s| s.to_string()).collect();
    header.extend(SEEDS_COUNTS.map(String::from));
    for m in SEED_METRICS {
        for stat in SEED_STATISTICS {
            header.push(format!("{m}_{stat}"));
        }
    }
    let fmt = |v: f64| {
        if v.is_finite() {
            v.to_string()
        } else {
            String::new()
        }
    };
    let mut rows = Vec::new();
    for base in order {
        let list = &members[base];
        let first = list[0].1;
        let mut row: Vec<String> = SEEDS_PREFIX
            .iter()
            .map(|k| summary.get(first, k).unwrap_or_default().to_string())
            .collect();
        row[0] = base.to_string();
        let lo = list.iter().map(|s| s.0).min().unwrap_or(0);
        let hi = list.iter().map(|s| s.0).max().unwrap_or(0);
        row.extend([list.len().to_string(), lo.to_string(), hi.to_string()]);
        for m in SEED_METRICS {
            let values: Vec<f64> = list
                .iter()
                .filter_map(|&(_, r)| summary.get(r, m).and_then(|v| v.parse::<f64>().ok()))
                .filter(|v| v.is_finite())
                .collect();
            row.extend(distribution(&values).map(fmt));
        }
        rows.push(row);
    }
    // The dissertation's values, joined on the configuration id without seed.
    const PAPER: [&str; 3] = ["triangles", "triangle_reduction", "ar_mean"];
    header.extend(PAPER.iter().map(|m| format!("paper_{m}")));
    let theirs: HashMap<(String, String), String> = match &plan.paper_benchmark {
        Some(bench) => {
            let col = |name: &str| header.iter().position(|h| h == name).unwrap_or(0);
            let means: Vec<usize> = PAPER.iter().map(|m| col(&format!("{m}_mean"))).collect();
            let base = Table {
                header: ["id", "rx", "ry", "rz"]
                    .iter()
                    .chain(PAPER.iter())
                    .map(|s| s.to_string())
                    .collect(),
                rows: rows
                    .iter()
                    .map(|r| {
                        [col("id"), col("rx"), col("ry"), col("rz")]
                            .iter()
                            .chain(means.iter())
                            .map(|&i| r[i].clone())
                            .collect()
                    })
                    .collect(),
            };
            let cmp = paper_comparison(&base, bench)?;
            cmp.rows
                .into_iter()
                .map(|r| ((r[0].clone(), r[1].clone()), r[3].clone()))
                .collect()
        }
        None => HashMap::new(),
    };
    for row in &mut rows {
        let id = row[0].clone();
        for m in PAPER {
            row.push(
                theirs
                    .get(&(id.clone(), m.to_string()))
                    .cloned()
                    .unwrap_or_default(),
            );
        }
    }
    Ok(Some(Table { header, rows }))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn t_quantiles_match_the_table_and_approach_the_normal() {
        assert_eq!(t975(1), 12.706);
        assert_eq!(t975(30), 2.042);
        // Published values: t(0.975; 40) = 2.0211, 60: 2.0003, 120: 1.9799.
        assert!((t975(40) - 2.0211).abs() < 2e-4, "{}", t975(40));
        assert!((t975(60) - 2.0003).abs() < 2e-4, "{}", t975(60));
        assert!((t975(120) - 1.9799).abs() < 2e-4, "{}", t975(120));
        assert!((t975(100_000) - 1.96).abs() < 1e-3);
        assert!(t975(0).is_nan());
    }

    #[test]
    fn distribution_gives_mean_sd_and_the_t_interval() {
        let [mean, sd, lo, hi, min, max] = distribution(&[1.0, 2.0, 3.0, 4.0]);
        assert_eq!((mean, min, max), (2.5, 1.0, 4.0));
        let want_sd = (5.0f64 / 3.0).sqrt();
        assert!((sd - want_sd).abs() < 1e-12);
        let half = 3.182 * want_sd / 2.0;
        assert!((lo - (2.5 - half)).abs() < 1e-12 && (hi - (2.5 + half)).abs() < 1e-12);
        let one = distribution(&[5.0]);
        assert_eq!(one[0], 5.0);
        assert!(one[1].is_nan() && one[2].is_nan());
    }
}
