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

/// Plain MT's triangles over the whole box, in the order of the geometry pass (layer by
/// layer), into `tris` (three crossing ids each), with each triangle's source tetrahedron
/// gradient (of the linear interpolant on its source tetrahedron, up to a positive factor) in
/// `grad`; then every crossing's triangles as a CSR
/// table (`inc[inc_start[x]..inc_start[x + 1]]`, in triangle order, built in parallel by
/// [`crate::incidence::incidence_parallel`]; `inc_cursor` and `inc_parts` are its working memory). The quotient test reads a group's star from these instead of from the lattice.
/// With `keep` (a chunk) also, per triangle, whether its anchor's cell is kept (`kept`), so
/// that the emission maps the chunk's own triangles from the list too; returns the tetrahedra
/// with a triangle (of the kept cells, with `keep`).
#[allow(clippy::too_many_arguments)]
pub(crate) fn plain_triangles(
    layout: &Layout,
    iso: f32,
    crossed: &CrossedIndex,
    cpos: &[[f32; 3]],
    pool: &rayon::ThreadPool,
    keep: Option<CellRange>,
    tris: &mut Vec<u32>,
    grad: &mut Vec<[f32; 3]>,
    kept: &mut Vec<u8>,
    cells: Option<&mut Vec<u32>>,
    inc_start: &mut Vec<u32>,
    inc: &mut Vec<u32>,
    inc_cursor: &mut Vec<u32>,
    inc_parts: &mut Vec<Vec<u32>>,
) -> usize {
    let counts = layer_counts(layout, None, crossed, pool);
    let layers = counts.len();
    let total: usize = counts.iter().sum();
    overwritten(tris, 3 * total, 0, pool);
    overwritten(grad, total, [0.0; 3], pool);
    overwritten(kept, if keep.is_some() { total } else { 0 }, 0, pool);
    let record = cells.is_some();
    let mut no_cells = Vec::new();
    let cells = cells.unwrap_or(&mut no_cells);
    overwritten(cells, if record { total } else { 0 }, 0, pool);
    let mut parts = Vec::with_capacity(layers);
    let (mut rest, mut rest_src, mut rest_kept) = (&mut tris[..], &mut grad[..], &mut kept[..]);
    let mut rest_cells = &mut cells[..];
    for &n in &counts {
        let (head, tail) = rest.split_at_mut(3 * n);
        let (head_src, tail_src) = rest_src.split_at_mut(n);
        let (head_kept, tail_kept) = rest_kept.split_at_mut(if keep.is_some() { n } else { 0 });
        let (head_cells, tail_cells) = rest_cells.split_at_mut(if record { n } else { 0 });
        parts.push((head, head_src, head_kept, head_cells));
        rest = tail;
        rest_src = tail_src;
        rest_kept = tail_kept;
        rest_cells = tail_cells;
    }
    let processed: usize = pool.install(|| {
        parts
            .into_par_iter()
            .enumerate()
            .map(|(k, (out, grad, kept, cells))| {
                let list = ListOut {
                    grad,
                    kept: keep.map(|range| (range, kept)),
                };
                let cells = record.then_some(cells);
                geometry_layer(
                    layout,
                    k,
                    iso,
                    None,
                    crossed,
                    cpos,
                    None,
                    out,
                    Some(list),
                    cells,
                )
                .0
            })
            .sum()
    });
    // Incidence in triangle order, so the table is deterministic.
    crate::incidence::incidence_parallel(
        cpos.len(),
        tris,
        inc_start,
        inc,
        inc_cursor,
        inc_parts,
        pool,
    );
    processed
}

/// Calls `visit(anchor, rank, group, p)` for each body-centred face (group: its axis) or cube
/// (group 0) of geometry layer `k` that can hold surface: its anchor point (a storage slot, at
/// lattice coordinates `p`) has a crossed edge and, in a chunk, its cell
/// ([`Layout::anchor_cell`]) is kept. The anchor's entry is `crossed.points[rank]`. The count and
/// the geometry pass both walk the layer with it, so they see the same groups.
pub(crate) fn for_each_group(
    l: &Layout,
    k: usize,
    keep: Option<CellRange>,
    crossed: &CrossedIndex,
    mut visit: impl FnMut(usize, usize, usize, Offset),
) {
    let [nx, ny, nz] = l.s.cells;
    let plane = l.s.dims[0] * l.s.dims[1];
    // The anchors of one row are consecutive storage slots, at lattice points `first + (step n,
    // 0, 0)`: scan their bits, visit only the crossed ones.
    let mut row = |start: usize, z: usize, len: usize, g: usize, first: Offset, step: i32| {
        let local = start - z * plane;
        let mut rank = crossed.rank_in(z, local);
        for_each_bit(crossed.plane_bits(z), local, len, |n| {
            let r = rank;
            rank += 1;
            let p = [first[0] + step * n as i32, first[1], first[2]];
            if keep.is_some_and(|range| !range.contains(l.anchor_cell(p, g))) {
                return;
            }
            visit(start + n, r, g, p);
        });
    };
    match l.lattice {
        Lattice::Simple => {
            // Cubes by corner 0, a neighbour of the other 7: no crossed edge there, no surface
            // in the cube.
            for j in 0..ny {
                row(
                    l.s.simple_index(0, j, k),
                    k,
                    nx,
                    0,
                    [0, j as i32, k as i32],
                    1,
                );
            }
        }
        Lattice::BodyCentred => {
            // Faces perpendicular to z at plane k, then (inside layer k) to x and to y, by their
            // anchor A, the centre below (B and the 4 face corners are neighbours of A: without
            // a crossed edge at A, no surface in the face's 4 tetrahedra). Along x a face anchor
            // moves by one storage slot (two lattice units).
            let ki = k as i32;
            let mut faces = |first: Offset, len: usize, axis: usize| {
                // Storage plane (see `Samples::bcdl_index`).
                let z = (first[2] + 1) as usize;
                row(l.s.bcdl_index(first), z, len, axis, first, 2);
            };
            for j in 0..ny as i32 {
                faces([1, 2 * j + 1, 2 * ki - 1], nx, 2);
            }
            if k < nz {
                for j in 0..ny as i32 {
                    faces([-1, 2 * j + 1, 2 * ki + 1], nx + 1, 0);
                }
                for f in 0..=ny as i32 {
                    faces([1, 2 * f - 1, 2 * ki + 1], nx, 1);
                }
            }
        }
    }
}

/// Triangles of every geometry layer (those of the cells `keep`), in layer order.
pub(crate) fn layer_counts(
    l: &Layout,
    keep: Option<CellRange>,
    crossed: &CrossedIndex,
    pool: &rayon::ThreadPool,
) -> Vec<usize> {
    let layers = match l.lattice {
        Lattice::BodyCentred => l.s.cells[2] + 1,
        Lattice::Simple => l.s.cells[2],
    };
    pool.install(|| {
        (0..layers)
            .into_par_iter()
            .map(|k| count_layer(l, k, keep, crossed))
            .collect()
    })
}

/// Triangles geometry layer `k` will give: per group, a table lookup by the anchor's crossed
/// edges.
pub(crate) fn count_layer(
    l: &Layout,
    k: usize,
    keep: Option<CellRange>,
    crossed: &CrossedIndex,
) -> usize {
    let mut n = 0;
    for_each_group(l, k, keep, crossed, |_, rank, g, _| {
        let group = &l.groups[g];
        let mask = usize::from(crossed.points[rank].crossed);
        let mut code = 0;
        for (i, &d) in group.dirs[1..group.len].iter().enumerate() {
            code |= ((mask >> d) & 1) << (i + 1);
        }
        n += usize::from(group.triangles[code]);
    });
    n
}

/// Emission over one z-layer: writes its triangles into `out`, sized by [`count_layer`] (the
/// triangles of plain MT); with `map` (crossing id to output vertex, clustering) the triangles
/// are written with the clustered vertices and those that collapsed are left out. Returns the
/// tetrahedra processed and the triangles written.
#[allow(clippy::too_many_arguments)]
pub(crate) fn geometry_layer(
    l: &Layout,
    k: usize,
    iso: f32,
    keep: Option<CellRange>,
    crossed: &CrossedIndex,
    positions: &[[f32; 3]],
    map: Option<&[u32]>,
    out: &mut [u32],
    list: Option<ListOut<'_>>,
    cells: Option<&mut [u32]>,
) -> (usize, usize) {
    let plane = l.s.dims[0] * l.s.dims[1];
    // The crossed points of the storage planes this layer reads, copied into a dense window (one
    // entry per slot) of this thread: a crossing's id is then one load away, where the rank
    // directory needs two dependent ones. A few planes per thread, not a table per slot.
    let (z0, z1) = l.layer_planes(k);
    LAYER_WINDOW.with_borrow_mut(|window| {
        if window.len() < (z1 + 1 - z0) * plane {
            window.resize((z1 + 1 - z0) * plane, CrossedPoint::default());
        }
        for z in z0..=z1 {
            let base = (z - z0) * plane;
            let mut r = crossed.rank_in(z, 0);
            for_each_bit(crossed.plane_bits(z), 0, plane, |local| {
                window[base + local] = crossed.points[r];
                r += 1;
            });
        }
        geometry_in_window(
            l,
            k,
            iso,
            keep,
            crossed,
            positions,
            map,
            &window[..],
            z0,
            out,
            list,
            cells,
        )
    })
}

thread_local! {
    /// The dense window of [`geometry_layer`], kept per thread between layers and extractions
    /// (entries of slots without a crossed edge are stale and never read).
    pub(crate) static LAYER_WINDOW: std::cell::RefCell<Vec<CrossedPoint>> =
        const { std::cell::RefCell::new(Vec::new()) };
}

/// What the listing of plain MT's triangles ([`plain_triangles`]) writes beside them, per
/// triangle of a layer.
pub(crate) struct ListOut<'s> {
    /// The gradient of its tetrahedron.
    pub(crate) grad: &'s mut [[f32; 3]],
    /// In a chunk: the kept cells, and per triangle 1 when its anchor's cell is one of them
    /// (the triangles the chunk emits), else 0.
    pub(crate) kept: Option<(CellRange, &'s mut [u8])>,
}

/// [`geometry_layer`] once the crossed points of storage planes `z0..` are in `window`; with
/// `cells`, each triangle written gets its anchor cell there (linear index, x fastest).
/// Returns the tetrahedra with a triangle (when listing in a chunk, those of kept cells) and
/// the triangles written.
#[allow(clippy::too_many_arguments)]
pub(crate) fn geometry_in_window(
    l: &Layout,
    k: usize,
    iso: f32,
    keep: Option<CellRange>,
    crossed: &CrossedIndex,
    positions: &[[f32; 3]],
    map: Option<&[u32]>,
    window: &[CrossedPoint],
    z0: usize,
    out: &mut [u32],
    mut list: Option<ListOut<'_>>,
    mut cells: Option<&mut [u32]>,
) -> (usize, usize) {
    let v = &l.s.values;
    let plane = l.s.dims[0] * l.s.dims[1];
    let mut processed = 0;
    let mut w = 0;
    // Listing in a chunk: every anchor is walked, and the kept cells' ones are marked.
    let listing = list.is_some();
    let mark = list
        .as_ref()
        .and_then(|list| list.kept.as_ref().map(|k| k.0));
    let cells_wanted = cells.is_some();
    let [nx, ny, _] = l.s.cells;
    let mut tet =
        |anchor: usize, ti: usize, tpl: &TetTemplate, inner: bool, kept: bool, cell: u32| {
            let idx = tpl.delta.map(|d| (anchor as isize + d) as usize);
            let val = idx.map(|i| v[i]);
            let mut tris = [[0u32; 3]; 2];
            // The window starts at slot 0 of plane z0.
            let id = |o: usize, d: u8| {
                let entry = window[idx[o] - z0 * plane];
                debug_assert_eq!(entry, crossed.get(idx[o]));
                entry.id(d)
            };
            let n = tet_triangles(val, iso, &tpl.dir, id, positions, &mut tris);
            processed += usize::from(n > 0 && kept);
            match map {
                None => {
                    // The gradient of the tetrahedron, for the quotient test's (c).
                    let g = if n > 0 && list.is_some() {
                        l.gradient(anchor, ti, inner)
                    } else {
                        [0.0; 3]
                    };
                    for t in &tris[..n] {
                        if let Some(list) = list.as_mut() {
                            list.grad[w / 3] = g;
                            if let Some((_, flags)) = list.kept.as_mut() {
                                flags[w / 3] = u8::from(kept);
                            }
                        }
                        if let Some(cells) = cells.as_deref_mut() {
                            cells[w / 3] = cell;
                        }
                        out[w..w + 3].copy_from_slice(t);
                        w += 3;
                    }
                }
                Some(map) => {
                    // Clustered: the vertices of the groups' quotient; a triangle with two corners
                    // in one group collapsed and is dropped.
                    for t in &tris[..n] {
                        let q = t.map(|i| map[i as usize]);
                        if q[0] != q[1] && q[1] != q[2] && q[0] != q[2] {
                            if let Some(cells) = cells.as_deref_mut() {
                                cells[w / 3] = cell;
                            }
                            out[w..w + 3].copy_from_slice(&q);
                            w += 3;
                        }
                    }
                }
            }
        };
    for_each_group(l, k, keep, crossed, |anchor, _, g, p| {
        // Only the listing reads these: whether no corner is a ghost (for the gradient), and in
        // a chunk whether the anchor's cell is kept.
        let inner = listing && l.inner_anchor(p);
        let kept = mark.is_none_or(|range| range.contains(l.anchor_cell(p, g)));
        let cell = if cells_wanted {
            let c = l.anchor_cell(p, g);
            (c[0] + nx * (c[1] + ny * c[2])) as u32
        } else {
            0
        };
        let first = match l.lattice {
            Lattice::BodyCentred => 4 * g,
            Lattice::Simple => 0,
        };
        let count = match l.lattice {
            Lattice::BodyCentred => 4,
            Lattice::Simple => l.tets.len(),
        };
        for ti in first..first + count {
            tet(anchor, ti, &l.tets[ti], inner, kept, cell);
        }
    });
    debug_assert!(
        w == out.len() || (map.is_some() && w <= out.len()),
        "layer {k}: triangles counted and written differ"
    );
    (processed, w / 3)
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
