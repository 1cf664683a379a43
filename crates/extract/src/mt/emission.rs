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

use rayon::prelude::*;
use rmt_mesh::Mesh;

use super::clustering::plain::PlainList;
use super::geometry::{geometry_layer, layer_counts, LayerOut, Surface, Vertices};
use crate::util::overwritten;
use crate::{Clustering, Lattice, Stats};

/// The emission's buffers, kept between extractions.
#[derive(Default)]
pub(crate) struct EmitBuffers {
    /// The output, one part per run of listed triangles ([`emit`]).
    parts: Vec<Vec<u32>>,
    /// Working memory of the vertex compaction (integrated-unchecked).
    pub(crate) scratch: Vec<u32>,
    /// Recorded: the anchor cell of every output triangle (linear index, x fastest).
    pub(crate) tri_cells: Vec<u32>,
}

/// What the emission reads from the clustering.
#[derive(Clone, Copy)]
pub(crate) struct Clustered<'a> {
    /// The crossings' positions (plain MT's vertices).
    pub(crate) cpos: &'a [[f32; 3]],
    /// Every crossing's output vertex.
    pub(crate) vertex_of: &'a [u32],
    /// Plain MT's triangles, when integrated clustering listed them (empty otherwise).
    pub(crate) plain: &'a PlainList,
    /// The tetrahedra with a triangle that the listing read (of the kept cells, in a chunk).
    pub(crate) processed: usize,
}

/// What the emission reads.
pub(crate) struct EmitIn<'a> {
    pub(crate) surface: Surface<'a>,
    pub(crate) clustering: Clustering,
    /// Record the anchor cell of every output triangle.
    pub(crate) record: bool,
    /// With integrated clustering (checked or not), its output.
    pub(crate) clustered: Option<Clustered<'a>>,
    /// Plain MT: write the triangles with their last two corners swapped (array order,
    /// [`crate::Extractor::set_array_order`]).
    pub(crate) flip: bool,
}

/// The geometry pass over the lattice, writing the final triangles into `mesh` (with
/// `clustered`, the crossings' positions and output vertices, through the groups' vertex map,
/// collapsed triangles dropped), only those of the cells `surface.keep`; with `cells`, each
/// written triangle's anchor cell too (linear index over the grid's cells); with `flip` (plain
/// MT only), each triangle with its last two corners swapped.
pub(crate) fn emit_layers(
    surface: &Surface,
    clustered: Option<Vertices>,
    mesh: &mut Mesh,
    mut cells: Option<&mut Vec<u32>>,
    flip: bool,
    pool: &rayon::ThreadPool,
    stats: &mut Stats,
) {
    debug_assert!(!flip || clustered.is_none(), "flip is plain MT's only");
    let propose = clustered.is_some();
    // Triangles of plain MT per layer, counted from the anchors' crossed edges, so that every
    // layer writes its triangles straight into its own slice of the output (with clustering,
    // collapsed triangles leave the slice's end unused; the layers are then moved together).
    let counts = layer_counts(surface.l, surface.keep, surface.crossed, pool);
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
    let vertices = clustered.unwrap_or(Vertices {
        positions: &positions[..],
        map: None,
    });
    let written: Vec<(usize, usize)> = pool.install(|| {
        parts
            .into_par_iter()
            .enumerate()
            .map(|(k, (out, cells))| {
                let out = LayerOut {
                    out,
                    list: None,
                    cells,
                    flip,
                };
                geometry_layer(surface, k, vertices, out)
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
/// clustering, the listed plain MT triangles ([`PlainList`]) mapped through the output
/// vertices (`vertex_of`), in order, the collapsed ones dropped (in a chunk, only those of the
/// kept cells); otherwise the geometry pass ([`emit_layers`]).
pub(crate) fn emit(
    input: EmitIn<'_>,
    buf: &mut EmitBuffers,
    mesh: &mut Mesh,
    pool: &rayon::ThreadPool,
    stats: &mut Stats,
) {
    let EmitIn {
        surface,
        clustering,
        record,
        clustered,
        flip,
    } = input;
    let keep = surface.keep;
    let listed = clustered.filter(|c| !c.plain.tris.is_empty());
    if let Some(clustered) = listed {
        // The plain triangles are at hand (the quotient test read them): map them through the
        // groups, in order, dropping the collapsed ones (and, in a chunk, those of cells not
        // kept: the listing walked every anchor in the order the geometry pass would walk the
        // kept ones).
        let (plain, map) = (&clustered.plain.tris[..], clustered.vertex_of);
        let kept = (keep.is_some()).then_some(&clustered.plain.kept[..]);
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
        let parts = &mut buf.parts;
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
                    if kept.is_some() {
                        for (i, t) in ts.chunks_exact(3).enumerate() {
                            if let Some(q) = mapped(t, first + i) {
                                out.extend_from_slice(&q);
                            }
                        }
                        return;
                    }
                    // The whole box: every listed triangle, the collapsed ones dropped (the
                    // test without branches: collapsing is data).
                    for t in ts.chunks_exact(3) {
                        let q = [t[0], t[1], t[2]].map(|i| map[i as usize]);
                        if !((q[0] == q[1]) | (q[1] == q[2]) | (q[0] == q[2])) {
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
        // The parts joined in order, each copied into place in parallel.
        let indices = &mut mesh.indices;
        overwritten(indices, parts[..runs].iter().map(Vec::len).sum(), 0, pool);
        let mut places = Vec::with_capacity(runs);
        let mut rest = &mut indices[..];
        for part in &parts[..runs] {
            let (head, tail) = rest.split_at_mut(part.len());
            places.push(head);
            rest = tail;
        }
        pool.install(|| {
            places
                .into_par_iter()
                .zip(parts[..runs].par_iter())
                .for_each(|(place, part)| place.copy_from_slice(part))
        });
        let emitted = indices.len() / 3;
        stats.tetrahedra_processed += clustered.processed;
        stats.discarded += listed - emitted;
        if record {
            // The anchor cells of the emitted triangles, in their order.
            let cells = &clustered.plain.cells;
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
        let record = record
            && matches!(
                clustering,
                Clustering::None | Clustering::Integrated | Clustering::IntegratedUnchecked
            );
        let mut cells = std::mem::take(&mut buf.tri_cells);
        let out = record.then_some(&mut cells);
        let vertices = clustered.map(|c| Vertices {
            positions: c.cpos,
            map: Some(c.vertex_of),
        });
        emit_layers(
            &surface,
            vertices,
            mesh,
            out,
            flip && vertices.is_none(),
            pool,
            stats,
        );
        buf.tri_cells = cells;
    }
    let [nx, ny, nz] = surface.l.s.cells;
    stats.tetrahedra_total = match surface.l.lattice {
        Lattice::BodyCentred => 4 * ((nx + 1) * ny * nz + nx * (ny + 1) * nz + nx * ny * (nz + 1)),
        Lattice::Simple => 6 * nx * ny * nz,
    };
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::mt::layout::Layout;
    use crate::mt::testing::{extracted, settings_on, test_pool, wavy};
    use crate::{CellRange, Lattice};

    #[test]
    fn a_chunk_maps_its_triangles_from_the_list_as_the_geometry_pass_walks_its_cells() {
        // Integrated clustering in a chunk emits the kept cells' triangles from plain MT's
        // list; the geometry pass over the kept cells, through the same vertex map, is the
        // reference (triangles, their order, and the counters).
        let field = wavy();
        let pool = test_pool(2);
        let mut compared = 0;
        for lattice in [Lattice::BodyCentred, Lattice::Simple] {
            for (cells, lo, hi) in [
                ([12, 10, 14], [1, 1, 1], [11, 9, 13]),
                ([16, 16, 16], [0, 3, 5], [9, 16, 12]),
                ([9, 13, 11], [2, 0, 0], [9, 7, 6]),
            ] {
                let mut settings = settings_on(cells, lattice, crate::Clustering::Integrated);
                settings.keep_cells = Some(CellRange { lo, hi });
                let (samples, buf, mesh, listed) = extracted(&field, &settings, &pool);
                let l = Layout::new(&samples, lattice);
                let mut walked = Mesh::default();
                let mut reference = Stats::default();
                let surface = Surface {
                    l: &l,
                    iso: settings.iso,
                    keep: settings.keep_cells,
                    crossed: &buf.vertices.crossed,
                };
                let vertices = Vertices {
                    positions: &buf.clustering.cpos,
                    map: Some(&buf.clustering.vertex_of),
                };
                emit_layers(
                    &surface,
                    Some(vertices),
                    &mut walked,
                    None,
                    false,
                    &pool,
                    &mut reference,
                );
                let what = format!("{lattice:?} {cells:?} {lo:?}..{hi:?}");
                assert_eq!(mesh.indices, walked.indices, "{what}");
                assert_eq!(
                    listed.tetrahedra_processed, reference.tetrahedra_processed,
                    "{what}"
                );
                assert_eq!(listed.discarded, reference.discarded, "{what}");
                compared += mesh.indices.len() / 3;
            }
        }
        assert!(compared > 500, "only {compared} triangles compared");
    }
}
