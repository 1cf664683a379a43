//! Statistics of a run: `summary.csv` from `raw.csv`, one row per configuration (in order of
//! first appearance): the columns of [`SUMMARY_PREFIX`], `repetitions`, then for each time column
//! its `_mean`, `_sd`, `_min`, `_median`, `_max`, for every other measurement column its value
//! (the mean if repetitions disagree), then the derived columns of [`SUMMARY_DERIVED`]:
//!
//! - `triangle_reduction`: 1 - triangles / triangles of the same object, method, lattice and
//!   resolution without clustering (empty when that configuration is not in the run);
//! - `discard_share`: discarded / (triangles + discarded);
//! - `tetrahedra_share`: processed / total;
//!
//! and `share_<stage>` (mean stage time / mean total time) per stage time.

use std::collections::HashMap;
use std::path::Path;

use anyhow::{bail, Context, Result};
use rmt_runfolder::schema::{
    is_time_column, NOT_STAGES, RAW_PREFIX, SUMMARY_DERIVED, SUMMARY_PREFIX, SUMMARY_REPETITIONS,
    TIME_STATISTICS,
};
use rmt_runfolder::Table;

/// Mean, sample standard deviation (None below two values), min, median, max.
pub fn describe(values: &[f64]) -> (f64, Option<f64>, f64, f64, f64) {
    let n = values.len();
    if n == 0 {
        return (f64::NAN, None, f64::NAN, f64::NAN, f64::NAN);
    }
    let mean = values.iter().sum::<f64>() / n as f64;
    let sd = (n >= 2).then(|| {
        (values.iter().map(|v| (v - mean) * (v - mean)).sum::<f64>() / (n - 1) as f64).sqrt()
    });
    let mut sorted = values.to_vec();
    sorted.sort_by(f64::total_cmp);
    let median = if n % 2 == 1 {
        sorted[n / 2]
    } else {
        (sorted[n / 2 - 1] + sorted[n / 2]) / 2.0
    };
    (mean, sd, sorted[0], median, sorted[n - 1])
}

/// The summary of a `raw.csv` (see the [module documentation](self)).
pub fn summarise(raw_path: &Path) -> Result<Table> {
    summarise_seeded(raw_path, &HashMap::new())
}

/// Like [`summarise`] for a seed study: `seeds` maps configuration ids to their noise seed, and
/// `triangle_reduction` compares with the unclustered configuration of the same seed.
pub fn summarise_seeded(raw_path: &Path, seeds: &HashMap<String, u32>) -> Result<Table> {
    let raw = Raw::read(raw_path)?;
    let (header, stages) = summary_header(raw.measures());
    let mut rows = Vec::new();
    // Numeric values per configuration, for the derived columns: mean times, values.
    let mut numbers: Vec<HashMap<String, f64>> = Vec::new();
    for members in raw.groups() {
        let (row, nums) = raw.summary_row(&members)?;
        rows.push(row);
        numbers.push(nums);
    }
    let derived = Derived {
        header: &header,
        stages: &stages,
        seeds,
    };
    derived.append(&mut rows, &numbers);
    Ok(Table { header, rows })
}

/// A summary cell: the number, or empty when not finite.
fn cell(v: f64) -> String {
    if v.is_finite() {
        v.to_string()
    } else {
        String::new()
    }
}

/// The summary's header for the measurement columns `measures`, and the stage times (every
/// time but the total) that get a `share_` column.
fn summary_header(measures: &[String]) -> (Vec<String>, Vec<String>) {
    let mut header: Vec<String> = SUMMARY_PREFIX.iter().map(|s| s.to_string()).collect();
    header.push(SUMMARY_REPETITIONS.into());
    for m in measures {
        if is_time_column(m) {
            header.extend(TIME_STATISTICS.iter().map(|stat| format!("{m}_{stat}")));
        } else {
            header.push(m.clone());
        }
    }
    let stages: Vec<String> = measures
        .iter()
        .filter(|m| is_time_column(m) && !NOT_STAGES.contains(&m.as_str()))
        .cloned()
        .collect();
    header.extend(SUMMARY_DERIVED.map(String::from));
    header.extend(
        stages
            .iter()
            .map(|s| format!("share_{}", &s[2..s.len() - 2])),
    );
    (header, stages)
}

/// A `raw.csv` read and checked against [`RAW_PREFIX`].
struct Raw<'a> {
    path: &'a Path,
    table: Table,
}

impl<'a> Raw<'a> {
    fn read(path: &'a Path) -> Result<Raw<'a>> {
        let table = Table::read(path)?;
        let n = RAW_PREFIX.len();
        if table.header.len() < n || table.header[..n] != RAW_PREFIX {
            bail!(
                "{}: not a raw.csv of this runner (unexpected columns)",
                path.display()
            );
        }
        Ok(Raw { path, table })
    }

    /// The measurement columns (after [`RAW_PREFIX`]).
    fn measures(&self) -> &[String] {
        &self.table.header[RAW_PREFIX.len()..]
    }

    /// The rows of each configuration, in order of first appearance.
    fn groups(&self) -> Vec<Vec<usize>> {
        let id_col = 1;
        let mut order: Vec<&str> = Vec::new();
        let mut groups: HashMap<&str, Vec<usize>> = HashMap::new();
        for (i, row) in self.table.rows.iter().enumerate() {
            let id = row[id_col].as_str();
            if !groups.contains_key(id) {
                order.push(id);
            }
            groups.entry(id).or_default().push(i);
        }
        order.iter().map(|id| groups[id].clone()).collect()
    }

    /// The number in `row`, `col` (None when empty).
    fn number(&self, row: usize, col: usize) -> Result<Option<f64>> {
        let cell = &self.table.rows[row][col];
        if cell.is_empty() {
            return Ok(None);
        }
        cell.parse::<f64>().map(Some).with_context(|| {
            format!(
                "{}: row {}, column {}: `{cell}` is not a number",
                self.path.display(),
                row + 2,
                self.table.header[col]
            )
        })
    }

    /// The numbers of column `col` in rows `members` (empty cells left out).
    fn numbers(&self, members: &[usize], col: usize) -> Result<Vec<f64>> {
        let mut values = Vec::with_capacity(members.len());
        for &r in members {
            if let Some(v) = self.number(r, col)? {
                values.push(v);
            }
        }
        Ok(values)
    }

    /// The summary row of one configuration's rows `members` (without the derived columns),
    /// and its numbers by measurement column (the mean of times).
    fn summary_row(&self, members: &[usize]) -> Result<(Vec<String>, HashMap<String, f64>)> {
        let first = members[0];
        let mut row: Vec<String> = SUMMARY_PREFIX
            .iter()
            .map(|k| self.table.get(first, k).unwrap_or_default().to_string())
            .collect();
        row.push(members.len().to_string());
        let mut nums = HashMap::new();
        for (j, m) in self.measures().iter().enumerate() {
            let col = RAW_PREFIX.len() + j;
            if is_time_column(m) {
                let (mean, sd, min, median, max) = describe(&self.numbers(members, col)?);
                nums.insert(m.clone(), mean);
                row.extend([
                    cell(mean),
                    sd.map(cell).unwrap_or_default(),
                    cell(min),
                    cell(median),
                    cell(max),
                ]);
                continue;
            }
            let cells: Vec<&String> = members.iter().map(|&r| &self.table.rows[r][col]).collect();
            if cells.iter().all(|c| *c == cells[0]) {
                if let Some(v) = self.number(first, col)? {
                    nums.insert(m.clone(), v);
                }
                row.push(cells[0].clone());
            } else {
                let mean = describe(&self.numbers(members, col)?).0;
                nums.insert(m.clone(), mean);
                row.push(cell(mean));
            }
        }
        Ok((row, nums))
    }
}

/// What the derived columns need: the summary's header, its stage times, the seeds of a seed
/// study.
struct Derived<'a> {
    header: &'a [String],
    stages: &'a [String],
    seeds: &'a HashMap<String, u32>,
}

impl Derived<'_> {
    /// The key that finds a row's unclustered (and unsimplified) baseline: object, method,
    /// lattice, resolution, isovalue, normals, threads (and the collapse threshold when `with_threshold`), and the
    /// seed in a seed study.
    fn key(&self, row: &[String], with_threshold: bool) -> Vec<String> {
        let mut cols = vec![
            "object", "method", "lattice", "rx", "ry", "rz", "iso", "normals", "threads",
        ];
        if with_threshold {
            cols.push("collapse_threshold");
        }
        let mut key: Vec<String> = cols
            .iter()
            .map(|c| {
                self.header
                    .iter()
                    .position(|h| h == c)
                    .map(|i| row[i].clone())
                    .unwrap_or_default()
            })
            .collect();
        if let Some(seed) = self.seeds.get(&row[0]) {
            key.push(seed.to_string());
        }
        key
    }

    /// Appends the derived columns to every row; `numbers` holds each row's numbers.
    fn append(&self, rows: &mut [Vec<String>], numbers: &[HashMap<String, f64>]) {
        let clustering_col = self
            .header
            .iter()
            .position(|h| h == "clustering")
            .unwrap_or(0);
        // A simplified mesh's baseline is its method's unsimplified one.
        let simplify_col = self.header.iter().position(|h| h == "simplify");
        let unsimplified =
            |row: &[String]| simplify_col.is_none_or(|c| matches!(row[c].as_str(), "" | "none"));
        let mut baselines: HashMap<(Vec<String>, bool), usize> = HashMap::new();
        for (i, row) in rows.iter().enumerate() {
            if row[clustering_col] == "none" && unsimplified(row) {
                for with in [true, false] {
                    baselines.entry((self.key(row, with), with)).or_insert(i);
                }
            }
        }
        for i in 0..rows.len() {
            let baseline = baselines
                .get(&(self.key(&rows[i], true), true))
                .or_else(|| baselines.get(&(self.key(&rows[i], false), false)))
                .map(|&b| &numbers[b]);
            let cells = self.cells(&numbers[i], baseline);
            rows[i].extend(cells);
        }
    }

    /// The derived cells of a row with numbers `n`, given its baseline's numbers.
    fn cells(
        &self,
        n: &HashMap<String, f64>,
        baseline: Option<&HashMap<String, f64>>,
    ) -> Vec<String> {
        let get = |k: &str| n.get(k).copied();
        let reduction = match (
            baseline.and_then(|b| b.get("triangles").copied()),
            get("triangles"),
        ) {
            (Some(base), Some(t)) if base > 0.0 => cell(1.0 - t / base),
            _ => String::new(),
        };
        let ratio = |a: Option<f64>, b: Option<f64>| match (a, b) {
            (Some(a), Some(b)) if b > 0.0 => cell(a / b),
            _ => String::new(),
        };
        let discard = ratio(
            get("discarded"),
            get("triangles").zip(get("discarded")).map(|(t, d)| t + d),
        );
        let tets = ratio(get("tetrahedra_processed"), get("tetrahedra_total"));
        let mut out = vec![reduction, discard, tets];
        out.extend(self.stages.iter().map(|s| ratio(get(s), get("t_total_s"))));
        out
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn describe_gives_mean_sd_min_median_max() {
        let (mean, sd, min, median, max) = describe(&[4.0, 1.0, 3.0, 2.0]);
        assert_eq!((mean, min, median, max), (2.5, 1.0, 2.5, 4.0));
        assert!((sd.unwrap() - (5.0f64 / 3.0).sqrt()).abs() < 1e-12);
        assert_eq!(describe(&[7.0]).1, None);
        assert_eq!(describe(&[3.0, 1.0, 2.0]).3, 2.0);
    }
}
