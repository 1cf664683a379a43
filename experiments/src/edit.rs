//! Chunked terrain in the runner (`rmt-terrain`): `extract --chunks C` (one chunked extraction,
//! checked against the whole volume extracted at once) and the manifest workload `edit` (random
//! brush strokes on a chunked world, with the latency of each edit).
//!
//! Both build a [`World`] from an [`Extraction`]: its box and resolution (cells must be cubes),
//! method, lattice and clustering. With integrated clustering of marching tetrahedra (checked or
//! not) the world has exact seams ([`Seams::Exact`]): its chunks are the whole volume's own
//! mesh, and an edit re-extracts a box around it; the other modes mesh every chunk under the
//! tile rule (no collapse crosses a chunk face). Either way the welded chunks equal the
//! whole-volume extraction with the world's rule; [`ChunkedExtraction::identical`] reports that comparison for every run.

use anyhow::{bail, Context, Result};
use rmt_extract::Method;
use rmt_fields::ScalarField;
use rmt_mesh::Mesh;
use rmt_terrain::{
    canonical_triangles, run_strokes, Seams, StrokeParams, StrokeReport, World, WorldSettings,
};

use crate::config::Extraction;
use crate::manifest::EditPlan;

/// The world settings of `e` in chunks of `chunk` cells on `threads` threads. Fails when the
/// cells are not cubes (a chunked world has one cell size) or the mode is meshopt.
pub fn world_settings(e: &Extraction, chunk: usize, threads: usize) -> Result<WorldSettings> {
    let settings = e.settings(threads);
    let spacing = settings.grid.spacing();
    let (lo, hi) = (spacing.min_element(), spacing.max_element());
    if hi > lo * (1.0 + 1e-4) || !hi.is_finite() {
        bail!(
            "a chunked world needs cubic cells, but the box and resolution give cell edges \
             {:.6} x {:.6} x {:.6}: choose bounds proportional to the resolution",
            spacing.x,
            spacing.y,
            spacing.z
        );
    }
    let cells = e.resolution.cells();
    let base = match e.method {
        Method::Mc => WorldSettings::marching_cubes(cells, e.bounds.min, spacing.x),
        Method::Mt => WorldSettings::new(cells, e.bounds.min, spacing.x, e.lattice, e.clustering),
        Method::SurfaceNets => {
            bail!("a chunked world takes method mt or mc: surface nets has no chunked terrain")
        }
    };
    Ok(WorldSettings {
        collapse_threshold: e.collapse_threshold,
        iso: e.iso,
        ..base
    }
    .with_chunk(chunk)
    .with_threads(threads))
}

/// One chunked extraction next to the whole volume extracted at once.
pub struct ChunkedExtraction {
    /// The chunk meshes welded into one, world coordinates, area-weighted normals.
    pub mesh: Mesh,
    /// Number of chunks.
    pub chunks: usize,
    /// Wall time of meshing every chunk (first, cold call), seconds.
    pub t_chunked_s: f64,
    /// Wall time of the whole-volume extraction with the same settings, seconds.
    pub t_whole_s: f64,
    /// Triangles of the whole-volume extraction.
    pub whole_triangles: usize,
    /// Whether the welded chunks have exactly the whole extraction's triangles.
    pub identical: bool,
}

/// Builds the world of `e` and meshes it chunk by chunk and at once.
pub fn extract_chunked(
    field: &dyn ScalarField,
    e: &Extraction,
    chunk: usize,
    threads: usize,
) -> Result<(World, ChunkedExtraction)> {
    let settings = world_settings(e, chunk, threads)?;
    let mut world = World::new(field, settings).context("building the chunked world")?;
    let stats = world.remesh_dirty().context("meshing the chunks")?;
    let mesh = world.mesh_welded();
    let (whole, t_whole_s) = world
        .extract_whole()
        .context("extracting the whole volume")?;
    let identical = canonical_triangles(&mesh) == canonical_triangles(&whole);
    let chunked = ChunkedExtraction {
        chunks: world.chunk_count(),
        t_chunked_s: stats.seconds,
        t_whole_s,
        whole_triangles: whole.triangle_count(),
        identical,
        mesh,
    };
    Ok((world, chunked))
}

/// What one `edit` session measured.
pub struct EditSession {
    /// The chunked extraction before the strokes.
    pub initial: ChunkedExtraction,
    /// One entry per timed stroke.
    pub strokes: StrokeReport,
    /// Whether the world after the strokes equals a whole-volume extraction of the edited
    /// samples.
    pub identical_after: bool,
    /// How the world's chunks meet.
    pub seams: Seams,
}

/// Runs the `edit` workload on `e`: builds and meshes the world, runs `plan.warmup` untimed
/// strokes, then `plan.strokes` timed ones (brush radius `plan.radius` cells), and compares the
/// final world with a whole-volume extraction.
pub fn run_edit_session(
    field: &dyn ScalarField,
    e: &Extraction,
    plan: &EditPlan,
    threads: usize,
) -> Result<EditSession> {
    let (mut world, initial) = extract_chunked(field, e, plan.chunk, threads)?;
    let h = world.settings().h;
    let params = |strokes: usize, seed: u64| StrokeParams {
        radius: plan.radius * h,
        ..StrokeParams::for_cells(h, strokes, seed)
    };
    if plan.warmup > 0 {
        // A different seed: the timed strokes are the same with or without warm-up.
        run_strokes(&mut world, &params(plan.warmup, plan.seed ^ 0x5EED_5EED))
            .context("warm-up strokes")?;
    }
    let strokes = run_strokes(&mut world, &params(plan.strokes, plan.seed)).context("strokes")?;
    let (whole, _) = world
        .extract_whole()
        .context("extracting the edited volume")?;
    let identical_after = canonical_triangles(&world.mesh_welded()) == canonical_triangles(&whole);
    Ok(EditSession {
        initial,
        strokes,
        identical_after,
        seams: world.settings().seams,
    })
}

/// The `edits.csv` rows of one session (columns of [`EDITS`](rmt_runfolder::schema::EDITS)).
pub fn edit_rows(id: &str, s: &EditSession) -> Vec<Vec<String>> {
    let r = &s.strokes;
    let per_chunk = r.triangles_per_chunk();
    (0..r.latencies_s.len())
        .map(|i| {
            vec![
                id.to_string(),
                i.to_string(),
                format!("{:.9}", r.latencies_s[i]),
                r.chunks[i].to_string(),
                r.triangles[i].to_string(),
                format!("{:.3}", per_chunk[i]),
                r.boxes.get(i).copied().unwrap_or(0).to_string(),
                r.box_cells.get(i).copied().unwrap_or(0).to_string(),
            ]
        })
        .collect()
}

/// The summary row of one session (columns of
/// [`EDIT_SUMMARY`](rmt_runfolder::schema::EDIT_SUMMARY)).
pub fn edit_summary_row(
    id: &str,
    e: &Extraction,
    plan: &EditPlan,
    threads: usize,
    s: &EditSession,
) -> Vec<String> {
    let r = &s.strokes;
    let ms = |q: f64| format!("{:.4}", r.latency_quantile(q) * 1e3);
    let n = r.chunks.len().max(1) as f64;
    let chunks_mean = r.chunks.iter().sum::<usize>() as f64 / n;
    let per_chunk: Vec<f64> = r.triangles_per_chunk();
    let per_chunk_mean = per_chunk.iter().sum::<f64>() / per_chunk.len().max(1) as f64;
    let [rx, ry, rz] = e.resolution.cells();
    vec![
        id.to_string(),
        e.object.kind.name().to_string(),
        crate::config::method_name(e.method).to_string(),
        crate::config::lattice_name(e.method, e.lattice).to_string(),
        e.clustering.name().to_string(),
        rx.to_string(),
        ry.to_string(),
        rz.to_string(),
        plan.chunk.to_string(),
        threads.to_string(),
        r.latencies_s.len().to_string(),
        ms(0.5),
        ms(0.95),
        ms(0.99),
        ms(1.0),
        format!("{chunks_mean:.3}"),
        r.chunks.iter().max().copied().unwrap_or(0).to_string(),
        format!("{per_chunk_mean:.1}"),
        s.initial.mesh.triangle_count().to_string(),
        s.initial.whole_triangles.to_string(),
        s.initial.chunks.to_string(),
        format!("{:.6}", s.initial.t_chunked_s),
        format!("{:.6}", s.initial.t_whole_s),
        (s.initial.identical && s.identical_after).to_string(),
        match s.seams {
            Seams::Exact => "exact",
            Seams::Tiles => "tiles",
        }
        .to_string(),
    ]
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::config::Normals;
    use crate::objects::{Bounds, ObjectKind, ObjectParams, ObjectSpec, Resolution};
    use rmt_extract::{Clustering, Lattice};
    use rmt_runfolder::schema::{EDITS, EDIT_SUMMARY};

    fn extraction(cells: [usize; 3], bounds: [f32; 6], clustering: Clustering) -> Extraction {
        Extraction {
            // Radius 0.8: the inscribed sphere would touch the box at sample points, where
            // welding by position joins crossings that coincide (see `rmt_terrain::weld`).
            object: ObjectSpec::new(
                ObjectKind::Sphere,
                ObjectParams {
                    radius: Some(0.8),
                    ..ObjectParams::default()
                },
            )
            .unwrap(),
            bounds: Bounds::try_from(bounds).unwrap(),
            resolution: Resolution::Axes(cells),
            method: Method::Mt,
            lattice: Lattice::BodyCentred,
            clustering,
            collapse_threshold: 0.5,
            iso: 0.0,
            normals: Normals::Area,
            simplify: None,
            vertex_cache: false,
        }
    }

    #[test]
    fn chunked_sphere_equals_the_whole_and_is_closed() {
        let e = extraction(
            [16; 3],
            [-1.0, -1.0, -1.0, 1.0, 1.0, 1.0],
            Clustering::Integrated,
        );
        let field = e.object.build(&e.bounds, &[]).unwrap();
        let (_, c) = extract_chunked(field.as_ref(), &e, 6, 2).unwrap();
        assert_eq!(c.chunks, 27);
        assert!(c.identical);
        assert_eq!(c.mesh.triangle_count(), c.whole_triangles);
        let grid = e.settings(1).grid;
        let r = rmt_mesh::validate(&c.mesh, &|p| {
            rmt_extract::measure::on_box_boundary(&grid, p)
        });
        assert!(r.is_watertight_manifold(), "{r:?}");
        assert_eq!(r.euler, 2);
    }

    #[test]
    fn non_cubic_cells_are_refused_with_the_cell_edges() {
        let e = extraction(
            [16, 8, 16],
            [-1.0, -1.0, -1.0, 1.0, 1.0, 1.0],
            Clustering::None,
        );
        let err = world_settings(&e, 8, 1).unwrap_err().to_string();
        assert!(err.contains("cubic cells") && err.contains("0.25"), "{err}");
    }

    #[test]
    fn an_edit_session_reports_every_stroke_and_stays_equal_to_the_whole() {
        let e = extraction(
            [16, 8, 16],
            [-2.0, -1.0, -2.0, 2.0, 1.0, 2.0],
            Clustering::Integrated,
        );
        let field = e.object.build(&e.bounds, &[]).unwrap();
        let plan = EditPlan {
            chunk: 8,
            strokes: 6,
            warmup: 2,
            seed: 3,
            radius: 2.0,
        };
        let s = run_edit_session(field.as_ref(), &e, &plan, 1).unwrap();
        assert_eq!(s.strokes.latencies_s.len(), 6);
        assert!(s.initial.identical && s.identical_after);
        let rows = edit_rows("x", &s);
        assert_eq!(rows.len(), 6);
        assert!(rows.iter().all(|r| r.len() == EDITS.len()));
        let summary = edit_summary_row("x", &e, &plan, 1, &s);
        assert_eq!(summary.len(), EDIT_SUMMARY.len());
        let col = |name: &str| EDIT_SUMMARY.iter().position(|h| *h == name);
        let at = |name: &str| col(name).map(|i| summary[i].as_str());
        assert_eq!(at("chunked_equals_whole"), Some("true"));
        // Integrated clustering of marching tetrahedra: the whole volume's own mesh.
        assert_eq!(at("seams"), Some("exact"));
        assert_eq!(at("triangles"), at("whole_triangles"));
    }
}
