//! The comparison with the dissertation: `paper_comparison.csv` joins a summary with the
//! dissertation's table (`data/paper/benchmark.csv`) on configuration id, one row per
//! [`PAPER_METRICS`] pair: `id,metric,ours,theirs,ratio` (ratio = ours / theirs, empty when
//! theirs is 0 or missing).

use std::path::Path;

use anyhow::{bail, Context, Result};
use rmt_runfolder::schema::PAPER_COMPARISON;
use rmt_runfolder::Table;

/// Pairs of (our summary column, the dissertation's column) compared in `paper_comparison.csv`;
/// `triangle_reduction` and `discard_share` are derived on their side too.
pub const PAPER_METRICS: [(&str, &str); 16] = [
    ("vertices", "n_vertices"),
    ("triangles", "n_triangles"),
    ("discarded", "n_discarded"),
    ("tetrahedra_processed", "n_tetrahedra"),
    ("triangle_reduction", ""),
    ("discard_share", "f_discard"),
    ("ar_mean", "ar_mean"),
    ("ar_sd", "ar_sd"),
    ("t_total_s_mean", "t_total_s"),
    ("t_sampling_s_mean", "t_sampling_s"),
    ("t_vertex_s_mean", "t_vertex_s"),
    ("t_geometry_s_mean", "t_geometry_s"),
    ("bytes_lattice", "b_lattice"),
    ("bytes_edges", "b_edges"),
    ("bytes_vertices", "b_vertices"),
    ("bytes_indices", "b_indices"),
];

/// The dissertation's id of our configuration `id`. Its integrated clustering had no exact
/// check: its rules are our `integrated-unchecked` (letter `c`), so those rows compare with its
/// `i` rows.
fn dissertation_id(id: &str) -> String {
    match id.split_once('_') {
        Some((prefix, rest)) => {
            let mut letters = rest.chars();
            match (letters.next(), letters.next()) {
                (Some(lattice), Some('c')) => {
                    format!("{prefix}_{lattice}i{}", letters.as_str())
                }
                _ => id.to_string(),
            }
        }
        None => id.to_string(),
    }
}

/// The unclustered baseline of configuration `id`: the clustering letter replaced by `u`.
fn baseline_id(id: &str) -> Option<String> {
    let (prefix, rest) = id.split_once('_')?;
    let mut letters = rest.chars();
    let lattice = letters.next()?;
    let tail: String = letters.skip(1).collect();
    Some(format!("{prefix}_{lattice}u{tail}"))
}

/// The dissertation's table, read once.
struct Dissertation<'a> {
    path: &'a Path,
    table: Table,
    id_col: usize,
}

impl Dissertation<'_> {
    /// The number in row `row`, column `col` (None when empty).
    fn number(&self, row: usize, col: &str) -> Result<Option<f64>> {
        let Some(cell) = self.table.get(row, col) else {
            bail!("{}: no column `{col}`", self.path.display());
        };
        if cell.is_empty() {
            return Ok(None);
        }
        cell.parse().map(Some).with_context(|| {
            format!(
                "{}: row {}, column {col}: `{cell}` is not a number",
                self.path.display(),
                row + 2
            )
        })
    }

    /// The row of id `id`.
    fn row(&self, id: &str) -> Option<usize> {
        self.table.rows.iter().position(|r| r[self.id_col] == id)
    }

    /// Their value of metric `ours_col` (their column `theirs_col`) in row `pr`; `ours_id` is
    /// our configuration's id (for the baseline of `triangle_reduction`).
    fn value(
        &self,
        pr: usize,
        ours_col: &str,
        theirs_col: &str,
        ours_id: &str,
    ) -> Result<Option<f64>> {
        Ok(match ours_col {
            "triangle_reduction" => match baseline_id(ours_id).and_then(|b| self.row(&b)) {
                Some(b) => match (
                    self.number(pr, "n_triangles")?,
                    self.number(b, "n_triangles")?,
                ) {
                    (Some(t), Some(bt)) if bt > 0.0 => Some(1.0 - t / bt),
                    _ => None,
                },
                None => None,
            },
            // The dissertation gives the discarded share in percent.
            "discard_share" => self.number(pr, theirs_col)?.map(|p| p / 100.0),
            _ => self.number(pr, theirs_col)?,
        })
    }
}

/// Joins a summary with the dissertation's table (`data/paper/benchmark.csv`) on configuration
/// id: `id,metric,ours,theirs,ratio` (ratio = ours / theirs, empty when theirs is 0 or missing).
/// Our `integrated-unchecked` rows (`as_bc`) join the dissertation's integrated rows (`as_bi`):
/// its clustering had no exact check.
/// Rows whose resolution (`rx`, `ry`, `rz`) differs from the dissertation's are left out.
pub fn paper_comparison(summary: &Table, benchmark: &Path) -> Result<Table> {
    let table = Table::read(benchmark)?;
    let id_col = table
        .column("id")
        .with_context(|| format!("{}: no `id` column", benchmark.display()))?;
    let paper = Dissertation {
        path: benchmark,
        table,
        id_col,
    };
    let cell = |v: Option<f64>| {
        v.filter(|v| v.is_finite())
            .map(|v| v.to_string())
            .unwrap_or_default()
    };
    let mut rows = Vec::new();
    for r in 0..summary.rows.len() {
        let Some(id) = summary.get(r, "id") else {
            continue;
        };
        let Some(pr) = paper.row(&dissertation_id(id)) else {
            continue;
        };
        // Same id at another resolution (e.g. the CI manifest's small grids) is not comparable.
        let same_resolution = ["rx", "ry", "rz"].iter().all(|axis| {
            match (summary.get(r, axis), paper.table.get(pr, axis)) {
                (Some(a), Some(b)) => a.trim() == b.trim(),
                _ => true,
            }
        });
        if !same_resolution {
            continue;
        }
        for (ours_col, theirs_col) in PAPER_METRICS {
            let ours: Option<f64> = summary.get(r, ours_col).and_then(|c| c.parse().ok());
            let theirs = paper.value(pr, ours_col, theirs_col, id)?;
            let ratio = match (ours, theirs) {
                (Some(o), Some(t)) if t != 0.0 => Some(o / t),
                _ => None,
            };
            rows.push(vec![
                id.to_string(),
                ours_col.to_string(),
                cell(ours),
                cell(theirs),
                cell(ratio),
            ]);
        }
    }
    Ok(Table {
        header: PAPER_COMPARISON.map(String::from).to_vec(),
        rows,
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::path::PathBuf;

    /// A dissertation table in `dir` with an unclustered (100 triangles) and an integrated (25
    /// triangles) row of object code `object` at 50^3.
    fn dissertation_table(dir: &Path, object: &str) -> PathBuf {
        let bench = dir.join("benchmark.csv");
        std::fs::write(
            &bench,
            format!(
                "id,rx,ry,rz,n_tetrahedra,n_vertices,n_triangles,n_discarded,f_discard,ar_mean,\
                 ar_sd,t_total_s,t_sampling_s,t_vertex_s,t_geometry_s,b_lattice,b_edges,b_vertices,\
                 b_indices\n\
                 {object}_bu,50,50,50,9,52,100,0,0,2,1,1,1,1,1,1,1,1,1\n\
                 {object}_bi,50,50,50,9,14,25,75,75,2,1,1,1,1,1,1,1,1,1\n"
            ),
        )
        .unwrap();
        bench
    }

    #[test]
    fn paper_comparison_skips_rows_at_another_resolution() {
        let dir = tempfile::tempdir().unwrap();
        let bench = dissertation_table(dir.path(), "ss");
        let summary = |res: &str| Table {
            header: ["id", "rx", "ry", "rz", "triangles", "vertices"]
                .map(String::from)
                .to_vec(),
            rows: vec![
                ["ss_bu", res, res, res, "90", "50"]
                    .map(String::from)
                    .to_vec(),
                ["ss_bi", res, res, res, "20", "12"]
                    .map(String::from)
                    .to_vec(),
            ],
        };
        let same = paper_comparison(&summary("50"), &bench).unwrap();
        let tri = same
            .rows
            .iter()
            .find(|r| r[0] == "ss_bi" && r[1] == "triangles")
            .unwrap();
        assert_eq!((tri[2].as_str(), tri[3].as_str()), ("20", "25"));
        let reduction = same
            .rows
            .iter()
            .find(|r| r[0] == "ss_bi" && r[1] == "triangle_reduction")
            .unwrap();
        assert_eq!(reduction[3], "0.75");
        let other = paper_comparison(&summary("8"), &bench).unwrap();
        assert!(other.rows.is_empty(), "{:?}", other.rows);
    }

    #[test]
    fn unchecked_rows_compare_with_the_dissertations_integrated_rows() {
        let dir = tempfile::tempdir().unwrap();
        let bench = dissertation_table(dir.path(), "as");
        let summary = Table {
            header: ["id", "rx", "ry", "rz", "triangles"]
                .map(String::from)
                .to_vec(),
            rows: vec![
                ["as_bu", "50", "50", "50", "90"].map(String::from).to_vec(),
                ["as_bc", "50", "50", "50", "30"].map(String::from).to_vec(),
                ["as_bc_t0.3", "50", "50", "50", "31"]
                    .map(String::from)
                    .to_vec(),
            ],
        };
        let table = paper_comparison(&summary, &bench).unwrap();
        let find = |id: &str, metric: &str| {
            table
                .rows
                .iter()
                .find(|r| r[0] == id && r[1] == metric)
                .cloned()
        };
        let tri = find("as_bc", "triangles").unwrap();
        assert_eq!((tri[2].as_str(), tri[3].as_str()), ("30", "25"));
        // Reduction: ours against our `as_bu`, theirs against their `as_bu`.
        assert_eq!(find("as_bc", "triangle_reduction").unwrap()[3], "0.75");
        // A sweep id keeps its suffix and so has no counterpart.
        assert!(find("as_bc_t0.3", "triangles").is_none());
    }

    #[test]
    fn ids_map_to_the_dissertations_and_to_their_baselines() {
        assert_eq!(dissertation_id("as_bc"), "as_bi");
        assert_eq!(dissertation_id("as_bc_r64"), "as_bi_r64");
        assert_eq!(dissertation_id("as_bp"), "as_bp");
        assert_eq!(dissertation_id("plain"), "plain");
        assert_eq!(baseline_id("as_bi_t0.3").as_deref(), Some("as_bu_t0.3"));
        assert_eq!(baseline_id("plain"), None);
    }
}
