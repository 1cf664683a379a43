//! Topology tallies of seed studies: `topology.csv` counts, for every configuration without seed,
//! the fields (seeds) whose mesh fails a check of the property tests, and
//! `topology_failures.csv` lists each failing field so that it can be rebuilt from its seed
//! (`experiments extract --object random --seed S ...`).
//!
//! The checks, per mesh (from the validation columns of `summary.csv`):
//!
//! - `open`: boundary edges inside the box (holes; edges on the box faces are the box's cut);
//! - `non_manifold`: non-manifold edges or vertices;
//! - `orientation`: neighbouring triangles that disagree on orientation;
//! - `duplicates`: duplicate triangles, non-finite or unreferenced vertices;
//! - `euler` and `components`: a clustered mesh whose Euler characteristic or number of connected
//!   components differs from the unclustered marching-tetrahedra mesh of the same object, seed,
//!   lattice, resolution and isovalue (its *reference*, when the study has it): clustering must
//!   keep the topology.
//!
//! With the `random` object (the property tests' field families, see [`rmt_fields::RandomField`])
//! this is the topology sweep of `experiments/manifests/topology.toml`: thousands of fields, run
//! on one machine or sharded on a cluster like any manifest, merged, and tallied here.

use std::collections::HashMap;

use anyhow::Result;

use rmt_runfolder::schema::{
    TOPOLOGY_CHECKS as CHECKS, TOPOLOGY_COUNTS, TOPOLOGY_FAILED, TOPOLOGY_FAILURES,
    TOPOLOGY_PREFIX as PREFIX,
};
use rmt_runfolder::Table;

use crate::manifest::Plan;

/// Integer value of a summary column (0 when absent or not a number).
fn int(summary: &Table, row: usize, column: &str) -> i64 {
    summary
        .get(row, column)
        .and_then(|v| v.parse::<i64>().ok())
        .unwrap_or(0)
}

/// The checks a summary row fails, given its reference row (None for a reference itself, or
/// when the study has none).
fn failures(summary: &Table, row: usize, reference: Option<usize>) -> Vec<(&'static str, String)> {
    let mut out = Vec::new();
    let n = |c: &str| int(summary, row, c);
    if n("boundary_edges_interior") > 0 {
        out.push((
            "open",
            format!("{} interior boundary edges", n("boundary_edges_interior")),
        ));
    }
    if n("non_manifold_edges") + n("non_manifold_vertices") > 0 {
        out.push((
            "non_manifold",
            format!(
                "{} non-manifold edges, {} non-manifold vertices",
                n("non_manifold_edges"),
                n("non_manifold_vertices")
            ),
        ));
    }
    if n("orientation_errors") > 0 {
        out.push((
            "orientation",
            format!("{} orientation errors", n("orientation_errors")),
        ));
    }
    let dup = n("duplicate_triangles") + n("non_finite_vertices") + n("unreferenced_vertices");
    if dup > 0 {
        out.push((
            "duplicates",
            format!(
                "{} duplicate triangles, {} non-finite and {} unreferenced vertices",
                n("duplicate_triangles"),
                n("non_finite_vertices"),
                n("unreferenced_vertices")
            ),
        ));
    }
    if let Some(r) = reference {
        for (check, column) in [("euler", "euler"), ("components", "components")] {
            let (mine, theirs) = (n(column), int(summary, r, column));
            if mine != theirs {
                out.push((check, format!("{column} {mine}, unclustered {theirs}")));
            }
        }
    }
    out
}

/// `topology.csv` and `topology_failures.csv` of a seed study from its `summary.csv` (None when
/// the plan has no seed study).
///
/// `topology.csv`: one row per configuration without seed (plan order): the configuration
/// columns, `fields` (seeds run), `reference` (the id of its unclustered reference, empty for a
/// reference or when the study has none), one count per check of
/// [`TOPOLOGY_CHECKS`](rmt_runfolder::schema::TOPOLOGY_CHECKS), and
/// `failed_fields` (fields failing any check). `topology_failures.csv`: `id`, `base_id`, `seed`,
/// `check`, `detail`, in plan order.
pub fn topology_tables(summary: &Table, plan: &Plan) -> Result<Option<(Table, Table)>> {
    let members: Vec<(&str, &str, u32)> = plan
        .configurations
        .iter()
        .filter_map(|c| {
            c.seed_of
                .as_ref()
                .map(|s| (c.id.as_str(), s.base_id.as_str(), s.seed))
        })
        .collect();
    Ok(tally(summary, &members))
}

/// [`topology_tables`] for the seed-study configurations `(id, id without seed, seed)`, in plan
/// order; configurations missing from `summary` are left out.
pub fn tally(summary: &Table, configurations: &[(&str, &str, u32)]) -> Option<(Table, Table)> {
    let row_of: HashMap<&str, usize> = (0..summary.rows.len())
        .filter_map(|r| summary.get(r, "id").map(|id| (id, r)))
        .collect();
    // (configuration key without clustering, seed) -> row of the unclustered reference.
    let key = |r: usize| -> Vec<String> {
        ["object", "method", "lattice", "rx", "ry", "rz", "iso"]
            .iter()
            .map(|c| summary.get(r, c).unwrap_or_default().to_string())
            .collect()
    };
    let mut references: HashMap<(Vec<String>, u32), (usize, &str)> = HashMap::new();
    let mut order: Vec<&str> = Vec::new();
    let mut members: HashMap<&str, Vec<(u32, &str, usize)>> = HashMap::new();
    for &(id, base, seed) in configurations {
        let Some(&row) = row_of.get(id) else {
            continue;
        };
        if summary.get(row, "method") == Some("mt")
            && summary.get(row, "clustering") == Some("none")
        {
            references.insert((key(row), seed), (row, base));
        }
        if !members.contains_key(base) {
            order.push(base);
        }
        members.entry(base).or_default().push((seed, id, row));
    }
    if order.is_empty() {
        return None;
    }
    let mut header: Vec<String> = PREFIX.iter().map(|s| s.to_string()).collect();
    header.extend(TOPOLOGY_COUNTS.map(String::from));
    header.extend(CHECKS.iter().map(|s| s.to_string()));
    header.push(TOPOLOGY_FAILED.into());
    let mut rows = Vec::new();
    let mut failed_rows = Vec::new();
    for base in order {
        let list = &members[base];
        let first = list[0].2;
        let mut row: Vec<String> = PREFIX
            .iter()
            .map(|k| summary.get(first, k).unwrap_or_default().to_string())
            .collect();
        row[0] = base.to_string();
        let mut counts = [0usize; CHECKS.len()];
        let mut failed = 0usize;
        let mut reference_id = String::new();
        for &(seed, id, r) in list {
            let reference = references
                .get(&(key(r), seed))
                .filter(|&&(ref_row, _)| ref_row != r);
            if let Some(&(_, ref_base)) = reference {
                reference_id = ref_base.to_string();
            }
            let found = failures(summary, r, reference.map(|&(ref_row, _)| ref_row));
            if !found.is_empty() {
                failed += 1;
            }
            for (check, detail) in found {
                if let Some(i) = CHECKS.iter().position(|c| *c == check) {
                    counts[i] += 1;
                }
                failed_rows.push(vec![
                    id.to_string(),
                    base.to_string(),
                    seed.to_string(),
                    check.to_string(),
                    detail,
                ]);
            }
        }
        row.extend([list.len().to_string(), reference_id]);
        row.extend(counts.iter().map(|c| c.to_string()));
        row.push(failed.to_string());
        rows.push(row);
    }
    Some((
        Table { header, rows },
        Table {
            header: TOPOLOGY_FAILURES.map(String::from).to_vec(),
            rows: failed_rows,
        },
    ))
}

#[cfg(test)]
mod tests {
    use super::*;

    const COLUMNS: [&str; 17] = [
        "id",
        "object",
        "kind",
        "method",
        "lattice",
        "clustering",
        "rx",
        "ry",
        "rz",
        "iso",
        "boundary_edges_interior",
        "non_manifold_edges",
        "non_manifold_vertices",
        "orientation_errors",
        "duplicate_triangles",
        "euler",
        "components",
    ];

    /// A summary row: `(id, lattice, clustering, holes, non-manifold edges, euler, components)`.
    fn row(
        id: &str,
        lattice: &str,
        clustering: &str,
        holes: i64,
        nm: i64,
        euler: i64,
        comp: i64,
    ) -> Vec<String> {
        [
            id, "random10", "random", "mt", lattice, clustering, "10", "10", "10", "0",
        ]
        .iter()
        .map(|s| s.to_string())
        .chain(
            [holes, nm, 0, 0, 0, euler, comp]
                .iter()
                .map(|v| v.to_string()),
        )
        .collect()
    }

    #[test]
    fn failures_are_counted_per_check_against_the_unclustered_mesh_of_the_same_seed() {
        let summary = Table {
            header: COLUMNS.map(String::from).to_vec(),
            rows: vec![
                row("b_u_s1", "bcdl", "none", 0, 0, 2, 1),
                row("b_i_s1", "bcdl", "integrated", 0, 0, 2, 1),
                row("b_u_s2", "bcdl", "none", 0, 0, 0, 1),
                // Seed 2: clustering changed the Euler characteristic and left a hole.
                row("b_i_s2", "bcdl", "integrated", 3, 0, 2, 1),
                // The simple lattice's reference of seed 2 is itself non-manifold; its
                // clustered mesh is compared with it, not with the body-centred one.
                row("s_u_s2", "simple", "none", 0, 1, 4, 2),
                row("s_i_s2", "simple", "integrated", 0, 0, 4, 2),
            ],
        };
        let configurations = [
            ("b_u_s1", "b_u", 1),
            ("b_i_s1", "b_i", 1),
            ("b_u_s2", "b_u", 2),
            ("b_i_s2", "b_i", 2),
            ("s_u_s2", "s_u", 2),
            ("s_i_s2", "s_i", 2),
            ("missing_s3", "b_i", 3),
        ];
        let (tally, failed) = tally(&summary, &configurations).unwrap();
        let get = |id: &str, col: &str| {
            let r = tally.rows.iter().position(|r| r[0] == id).unwrap();
            tally.get(r, col).unwrap().to_string()
        };
        assert_eq!(tally.rows.len(), 4);
        assert_eq!(get("b_i", "fields"), "2");
        assert_eq!(get("b_i", "reference"), "b_u");
        assert_eq!(get("b_u", "reference"), "");
        assert_eq!(
            (get("b_i", "open"), get("b_i", "euler")),
            ("1".into(), "1".into())
        );
        assert_eq!(get("b_i", "components"), "0");
        assert_eq!(get("b_i", "failed_fields"), "1");
        assert_eq!(get("b_u", "failed_fields"), "0");
        assert_eq!(get("s_u", "non_manifold"), "1");
        assert_eq!(get("s_i", "failed_fields"), "0");
        let listed: Vec<(&str, &str, &str)> = failed
            .rows
            .iter()
            .map(|r| (r[0].as_str(), r[2].as_str(), r[3].as_str()))
            .collect();
        assert_eq!(
            listed,
            [
                ("b_i_s2", "2", "open"),
                ("b_i_s2", "2", "euler"),
                ("s_u_s2", "2", "non_manifold")
            ]
        );
        assert!(
            failed.rows[1][4].contains("euler 2, unclustered 0"),
            "{:?}",
            failed.rows[1]
        );
    }

    #[test]
    fn a_study_without_seeds_has_no_tally() {
        let summary = Table {
            header: COLUMNS.map(String::from).to_vec(),
            rows: vec![row("b_u", "bcdl", "none", 0, 0, 2, 1)],
        };
        assert!(tally(&summary, &[]).is_none());
    }
}
