//! Emission, the geometry pass (parallel over z-layers): every tetrahedron whose corners disagree
//! gives one or two triangles from the case table. Each layer's triangles are counted first,
//! from the crossed edges of the face or cube anchors (`TetGroup` tables), so that every layer
//! writes into its own slice of the output in layer order: the same output for any thread count,
//! and the triangles stored once. Cubes (or body-centred faces) whose anchor has no crossed edge
//! are skipped before any tetrahedron is looked at.
//!
//! With integrated clustering the same pass lists plain MT's triangles once
//! ([`plain_triangles`], with each triangle's tetrahedron gradient and every crossing's
//! triangles: the stars of the quotient test), and the emission maps that list through the
//! output vertices, leaving out the triangles that collapsed ([`emit`]).
//!
//! ```text
//!   layer k:  count (anchors' crossed edges -> triangles)  ->  slice k of the output
//!             write (tetrahedra of each anchor, case table) ->  [ layer 0 | layer 1 | ... ]
//! ```

use super::*;

/// The geometry pass over the lattice, writing the final triangles into `mesh` (with `propose`,
/// through the groups' vertex map, collapsed triangles dropped), only those of the cells `keep`;
/// with `cells`, each written triangle's anchor cell too (linear index over the grid's cells).
#[allow(clippy::too_many_arguments)]
pub(crate) fn emit_layers(
    layout: &Layout,
    iso: f32,
    keep: Option<CellRange>,
    crossed: &CrossedIndex,
    propose: bool,
    buf: &MtBuffers,
    mesh: &mut Mesh,
    mut cells: Option<&mut Vec<u32>>,
    pool: &rayon::ThreadPool,
    stats: &mut Stats,
) {
    // Triangles of plain MT per layer, counted from the anchors' crossed edges, so that every
    // layer writes its triangles straight into its own slice of the output (with clustering,
    // collapsed triangles leave the slice's end unused; the layers are then moved together).
    let counts = layer_counts(layout, keep, crossed, pool);
    let layers = counts.len();
    let triangles: usize = counts.iter().sum();
    let Mesh {
        positions, indices, ..
    } = mesh;
    overwritten(indices, 3 * triangles, 0, pool);
    let record = cells.is_some();
    if let Some(cells) = cells.as_deref_mut() {
        overwritten(cells, triangles, 0, pool);
    }
    let mut parts = Vec::with_capacity(layers);
    let mut rest = &mut indices[..];
    let mut rest_cells = cells.as_deref_mut().map_or(&mut [][..], |c| &mut c[..]);
    for &n in &counts {
        let (head, tail) = rest.split_at_mut(3 * n);
        let (head_cells, tail_cells) = rest_cells.split_at_mut(if record { n } else { 0 });
        parts.push((head, record.then_some(head_cells)));
        rest = tail;
        rest_cells = tail_cells;
    }
    let (positions, map) = if propose {
        (&buf.cpos[..], Some(&buf.vertex_of[..]))
    } else {
        (&positions[..], None)
    };
    let written: Vec<(usize, usize)> = pool.install(|| {
        parts
            .into_par_iter()
            .enumerate()
            .map(|(k, (out, cells))| {
                geometry_layer(
                    layout, k, iso, keep, crossed, positions, map, out, None, cells,
                )
            })
            .collect()
    });
    stats.tetrahedra_processed += written.iter().map(|w| w.0).sum::<usize>();
    if propose {
        // Move the layers' triangles together.
        let (mut from, mut to) = (0, 0);
        for (&n, &(_, w)) in counts.iter().zip(&written) {
            indices.copy_within(3 * from..3 * (from + w), 3 * to);
            if let Some(cells) = cells.as_deref_mut() {
                cells.copy_within(from..from + w, to);
            }
            from += n;
            to += w;
        }
        indices.truncate(3 * to);
        if let Some(cells) = cells {
            cells.truncate(to);
        }
        stats.discarded += triangles - to;
    }
}

/// Emission: the final triangles, written straight into `mesh.indices`. With integrated
/// clustering, the listed plain MT triangles ([`plain_triangles`]) mapped through the output
/// vertices (`buf.vertex_of`), in order, the collapsed ones dropped (in a chunk, only those of
/// the kept cells); otherwise the geometry pass ([`emit_layers`]).
#[allow(clippy::too_many_arguments)]
pub(crate) fn emit(
    layout: &Layout,
    samples: &Samples,
    settings: &ExtractSettings,
    propose: bool,
    plain_processed: usize,
    buf: &mut MtBuffers,
    mesh: &mut Mesh,
    pool: &rayon::ThreadPool,
    stats: &mut Stats,
) {
    let (iso, lattice, clustering) = (settings.iso, settings.lattice, settings.clustering);
    let crossed = &buf.crossed;
    let keep = settings.keep_cells;
    if propose && !buf.plain.is_empty() {
        // The plain triangles are at hand (the quotient test read them): map them through the
        // groups, in order, dropping the collapsed ones (and, in a chunk, those of cells not
        // kept: the listing walked every anchor in the order the geometry pass would walk the
        // kept ones).
        let (plain, map) = (&buf.plain[..], &buf.vertex_of[..]);
        let kept = (keep.is_some()).then_some(&buf.plain_kept[..]);
        const CHUNK: usize = 3 << 14;
        let mapped = |t: &[u32], i: usize| {
            if kept.is_some_and(|k| k[i] == 0) {
                return None;
            }
            let q = [t[0], t[1], t[2]].map(|i| map[i as usize]);
            (q[0] != q[1] && q[1] != q[2] && q[0] != q[2]).then_some(q)
        };
        // One pass: each run of listed triangles maps its own into its part (reused between
        // extractions), then the parts are joined in order.
        let runs = plain.len().div_ceil(CHUNK);
        let parts = &mut buf.emit_parts;
        if parts.len() < runs {
            parts.resize_with(runs, Vec::new);
        }
        pool.install(|| {
            plain
                .par_chunks(CHUNK)
                .zip(parts[..runs].par_iter_mut())
                .enumerate()
                .for_each(|(c, (ts, out))| {
                    out.clear();
                    let first = c * CHUNK / 3;
                    for (i, t) in ts.chunks_exact(3).enumerate() {
                        if let Some(q) = mapped(t, first + i) {
                            out.extend_from_slice(&q);
                        }
                    }
                })
        });
        // The plain triangles the emission stands for: all, or the kept cells' ones.
        let listed = match kept {
            Some(k) => k.iter().filter(|&&f| f != 0).count(),
            None => plain.len() / 3,
        };
        let indices = &mut mesh.indices;
        indices.clear();
        indices.reserve(parts[..runs].iter().map(Vec::len).sum());
        for part in &parts[..runs] {
            indices.extend_from_slice(part);
        }
        let emitted = indices.len() / 3;
        stats.tetrahedra_processed += plain_processed;
        stats.discarded += listed - emitted;
        if buf.record {
            // The anchor cells of the emitted triangles, in their order.
            let cells = &buf.plain_cell;
            buf.tri_cells.clear();
            buf.tri_cells.extend(
                plain
                    .chunks_exact(3)
                    .enumerate()
                    .filter(|&(i, t)| mapped(t, i).is_some())
                    .map(|(i, _)| cells[i]),
            );
        }
    } else {
        // Recording: the anchor cells, unless a post-process changes the triangles after.
        let record = buf.record
            && matches!(
                clustering,
                Clustering::None | Clustering::Integrated | Clustering::IntegratedUnchecked
            );
        let mut cells = std::mem::take(&mut buf.tri_cells);
        let out = record.then_some(&mut cells);
        emit_layers(
            layout, iso, keep, crossed, propose, buf, mesh, out, pool, stats,
        );
        buf.tri_cells = cells;
    }
    if clustering == Clustering::IntegratedUnchecked {
        // Without the test a vertex may lose all its triangles.
        mesh.drop_unused_vertices(&mut buf.scratch);
    }
    let [nx, ny, nz] = samples.cells;
    stats.tetrahedra_total = match lattice {
        Lattice::BodyCentred => 4 * ((nx + 1) * ny * nz + nx * (ny + 1) * nz + nx * ny * (nz + 1)),
        Lattice::Simple => 6 * nx * ny * nz,
    };
}
