//! The cost of the exact check: plain MT, the dissertation's integrated clustering without our
//! check (`integrated-unchecked`) and RMT with it (`integrated`), side by side per object and
//! lattice: what the passes cost, what the dissertation measured for its own rules, and which
//! defects each mesh has.
//!
//! The input is a run of `experiments/manifests/check-cost.toml` (kept in a report as
//! `data/check-cost/`). Its `paper_comparison.csv` pairs each unchecked configuration with the
//! dissertation's integrated one, which is where the dissertation's times come from.

use crate::data::{lattice_name, Configuration, PaperRow, Run};
use crate::format::{count, fixed, sig};
use crate::output::{Block, TextTable};
use crate::tables::ratio_text;

/// The three clustering modes compared, in column order.
pub const MODES: [&str; 3] = ["none", "integrated-unchecked", "integrated"];

/// One object and lattice: its three configurations.
#[derive(Clone, Debug)]
pub struct Trio<'a> {
    /// Object name.
    pub object: String,
    /// Lattice (`bcdl`, `simple`).
    pub lattice: String,
    /// Configurations in [`MODES`] order; `integrated` may be missing.
    pub modes: [Option<&'a Configuration>; 3],
    /// The dissertation's integrated passes over its unclustered passes, when the run's
    /// comparison has both.
    pub dissertation_ratio: Option<f64>,
}

/// Vertex plus geometry pass, mean seconds.
pub fn passes(c: &Configuration) -> f64 {
    c.mean_time("vertex") + c.mean_time("geometry")
}

/// The dissertation's vertex plus geometry pass for configuration `id`, from the comparison.
fn their_passes(rows: &[PaperRow], id: &str) -> Option<f64> {
    let theirs = |metric: &str| {
        rows.iter()
            .find(|r| r.id == id && r.metric == metric)
            .and_then(|r| r.theirs)
    };
    Some(theirs("t_vertex_s_mean")? + theirs("t_geometry_s_mean")?)
}

/// The trios of `run`: every marching-tetrahedra object, lattice and resolution that has both a
/// `none` and an `integrated-unchecked` configuration, in the order of the `none` ones.
pub fn trios(run: &Run) -> Vec<Trio<'_>> {
    let mt: Vec<&Configuration> = run
        .configurations
        .iter()
        .filter(|c| !c.is_marching_cubes())
        .collect();
    let mut out = Vec::new();
    for base in mt.iter().filter(|c| c.clustering == "none") {
        let find = |mode: &str| {
            mt.iter().copied().find(|c| {
                c.clustering == mode
                    && c.object == base.object
                    && c.lattice == base.lattice
                    && c.resolution == base.resolution
            })
        };
        let modes = [Some(*base), find(MODES[1]), find(MODES[2])];
        let Some(unchecked) = modes[1] else { continue };
        let dissertation_ratio = run.paper.as_deref().and_then(|rows| {
            let none = their_passes(rows, &base.id)?;
            let integrated = their_passes(rows, &unchecked.id)?;
            (none > 0.0).then(|| integrated / none)
        });
        out.push(Trio {
            object: base.object.clone(),
            lattice: base.lattice.clone(),
            modes,
            dissertation_ratio,
        });
    }
    out
}

/// Whether a configuration's mesh has any defect (a hole, a non-manifold edge or vertex, an
/// orientation error or a duplicate triangle).
pub fn has_defects(c: &Configuration) -> bool {
    !c.closed_manifold || c.defects.duplicate_triangles.unwrap_or(0.0) > 0.0
}

/// The `check_cost` table, when `run` has at least one trio.
pub fn check_cost_table(run: &Run) -> Option<TextTable> {
    let trios = trios(run);
    if trios.is_empty() {
        return None;
    }
    let csv_header = [
        "object",
        "lattice",
        "clustering",
        "id",
        "passes_s",
        "passes_over_none",
        "total_s",
        "total_over_none",
        "dissertation_passes_over_none",
        "triangles",
        "boundary_edges_interior",
        "non_manifold_edges",
        "non_manifold_vertices",
        "orientation_errors",
        "duplicate_triangles",
        "euler",
        "components",
    ]
    .map(String::from)
    .to_vec();
    let mut csv_rows = Vec::new();
    let mut cost_rows = Vec::new();
    let mut defect_rows = Vec::new();
    for t in &trios {
        let Some(none) = t.modes[0] else { continue };
        let name = format!("{}, {}", t.object, lattice_name(&t.lattice));
        let over = |c: &Configuration, f: fn(&Configuration) -> f64| {
            let base = f(none);
            (base > 0.0).then(|| f(c) / base)
        };
        let total = |c: &Configuration| c.mean_time("total");
        let mut cost = vec![name.clone(), format!("{} ms", fixed(passes(none) * 1e3, 2))];
        for (i, mode) in t.modes.iter().enumerate() {
            let Some(c) = mode else {
                if i > 0 {
                    cost.push(String::new());
                }
                continue;
            };
            if i > 0 {
                cost.push(over(c, passes).map(ratio_text).unwrap_or_default());
            }
            let d = c.defects;
            csv_rows.push(vec![
                t.object.clone(),
                t.lattice.clone(),
                c.clustering.clone(),
                c.id.clone(),
                sig(passes(c), 6),
                over(c, passes).map(|v| sig(v, 6)).unwrap_or_default(),
                sig(total(c), 6),
                over(c, total).map(|v| sig(v, 6)).unwrap_or_default(),
                if i == 1 {
                    t.dissertation_ratio.map(|v| sig(v, 6)).unwrap_or_default()
                } else {
                    String::new()
                },
                sig(c.triangles, 12),
                sig(d.boundary_edges_interior, 12),
                sig(d.non_manifold_edges, 12),
                sig(d.non_manifold_vertices, 12),
                sig(d.orientation_errors, 12),
                d.duplicate_triangles
                    .map(|v| sig(v, 12))
                    .unwrap_or_default(),
                sig(c.euler, 12),
                sig(c.components, 12),
            ]);
            defect_rows.push(vec![
                format!("{name}, {}", c.clustering),
                count(c.triangles),
                count(d.boundary_edges_interior),
                count(d.non_manifold_edges),
                count(d.non_manifold_vertices),
                count(d.orientation_errors),
                d.duplicate_triangles.map(count).unwrap_or_default(),
                fixed(c.euler, 0),
                fixed(c.components, 0),
            ]);
        }
        cost.push(t.dissertation_ratio.map(ratio_text).unwrap_or_default());
        let total_ratio = |i: usize| {
            t.modes[i]
                .and_then(|c| over(c, total))
                .map(ratio_text)
                .unwrap_or_default()
        };
        cost.push(format!("{} ms", fixed(total(none) * 1e3, 2)));
        cost.push(total_ratio(1));
        cost.push(total_ratio(2));
        cost_rows.push(cost);
    }
    let header = |cells: &[&str]| cells.iter().map(|s| s.to_string()).collect::<Vec<_>>();
    Some(TextTable {
        name: "check_cost".into(),
        title: "The cost of the exact check".into(),
        notes: vec![format!(
            "From run `{}` on {}. `integrated-unchecked` applies the dissertation's clustering \
             rules without our exact test; `integrated` is RMT with it. Passes are the vertex \
             plus the geometry pass (sampling and normals left out), means over the timed \
             repetitions; ratios are over plain MT (`none`) on the same object and lattice. The \
             dissertation's ratio is its integrated passes over its unclustered passes \
             (`data/paper/benchmark.csv`; its integrated clustering had no check). Defects are \
             counted on the mesh of the last repetition: holes are boundary edges off the \
             sampled box. A closed manifold mesh has none of them, and keeps plain MT's Euler \
             characteristic and components.",
            run.info.run_id,
            run.info.machine()
        )],
        csv_header,
        csv_rows,
        blocks: vec![
            Block {
                caption: Some("Cost".into()),
                header: header(&[
                    "object, lattice",
                    "passes, none",
                    "unchecked ÷ none",
                    "integrated ÷ none",
                    "dissertation: integrated ÷ none",
                    "total, none",
                    "unchecked ÷ none (total)",
                    "integrated ÷ none (total)",
                ]),
                rows: cost_rows,
            },
            Block {
                caption: Some("Defects".into()),
                header: header(&[
                    "object, lattice, clustering",
                    "triangles",
                    "holes",
                    "non-manifold edges",
                    "non-manifold vertices",
                    "orientation errors",
                    "duplicate triangles",
                    "Euler",
                    "components",
                ]),
                rows: defect_rows,
            },
        ],
    })
}

/// One paragraph for the report's README: the range of each cost ratio, and which meshes have
/// defects.
pub fn summary_sentence(run: &Run) -> Option<String> {
    let trios = trios(run);
    if trios.is_empty() {
        return None;
    }
    let range = |values: Vec<f64>| -> Option<String> {
        let min = values.iter().copied().fold(f64::INFINITY, f64::min);
        let max = values.iter().copied().fold(f64::NEG_INFINITY, f64::max);
        if values.is_empty() {
            None
        } else if ratio_text(min) == ratio_text(max) {
            Some(ratio_text(min))
        } else {
            Some(format!("{}-{}", ratio_text(min), ratio_text(max)))
        }
    };
    let ratios = |i: usize| -> Vec<f64> {
        trios
            .iter()
            .filter_map(|t| {
                let none = passes(t.modes[0]?);
                let c = t.modes[i]?;
                (none > 0.0).then(|| passes(c) / none)
            })
            .collect()
    };
    let mut text = format!(
        "Over {} objects and lattices, the passes of the unchecked rules cost {} those of plain MT",
        trios.len(),
        range(ratios(1)).unwrap_or_default()
    );
    if let Some(theirs) = range(trios.iter().filter_map(|t| t.dissertation_ratio).collect()) {
        text.push_str(&format!(" (the dissertation measured {theirs})"));
    }
    if let Some(checked) = range(ratios(2)) {
        text.push_str(&format!(", and RMT with the exact check {checked}"));
    }
    text.push_str(". ");
    let unchecked: Vec<&Configuration> = trios.iter().filter_map(|t| t.modes[1]).collect();
    let broken: Vec<&&Configuration> = unchecked.iter().filter(|c| has_defects(c)).collect();
    // Meshes of mode `i` whose Euler characteristic or components differ from plain MT's.
    let topology_changed = |i: usize| {
        trios
            .iter()
            .filter(|t| match (t.modes[0], t.modes[i]) {
                (Some(n), Some(c)) => n.euler != c.euler || n.components != c.components,
                _ => false,
            })
            .count()
    };
    let sum = |f: fn(&Configuration) -> f64| -> f64 { broken.iter().map(|c| f(c)).sum() };
    text.push_str(&format!(
        "Without the check, {} of {} meshes have defects ({} non-manifold edges, {} duplicate \
         triangles and {} holes in all) and {} change the Euler characteristic or the number of \
         components",
        broken.len(),
        unchecked.len(),
        count(sum(|c| c.defects.non_manifold_edges)),
        count(sum(|c| c.defects.duplicate_triangles.unwrap_or(0.0))),
        count(sum(|c| c.defects.boundary_edges_interior)),
        topology_changed(1)
    ));
    let checked: Vec<&Configuration> = trios.iter().filter_map(|t| t.modes[2]).collect();
    if !checked.is_empty() {
        let checked_broken = checked.iter().filter(|c| has_defects(c)).count();
        let checked_changed = topology_changed(2);
        text.push_str(&format!(
            "; with it, {checked_broken} of {} have defects and {checked_changed} change the \
             topology",
            checked.len()
        ));
    }
    text.push('.');
    Some(text)
}
