//! The walk over the tetrahedra of one geometry layer, shared by the emission and by the
//! listing of plain MT's triangles (integrated clustering): the anchors of a layer's faces or
//! cubes that can hold surface ([`for_each_group`]), the count of a layer's triangles from the
//! anchors' crossed edges alone ([`layer_counts`]: over the whole box from the per-plane counts
//! of the vertex pass's numbering, in a chunk by [`count_layer`]'s walk), and the writing of
//! its triangles from the case table ([`geometry_layer`]).
//!
//! ```text
//!   layer k:  count (anchors' crossed edges -> triangles)  ->  slice k of the output
//!             write (tetrahedra of each anchor, case table) ->  [ layer 0 | layer 1 | ... ]
//! ```
//!
//! The writing reads no sample value beyond the anchor's own: a group whose table gives no
//! triangle is skipped, the crossing on each of the group's crossed edges is found once (it
//! belongs to the end whose owned bit the vertex pass set: it decided that from the same two
//! values), and the triangles are read off the group's cycle table by the anchor's side and
//! crossed edges (`TetGroup::cycles`: each tetrahedron's case table cycle, in template order,
//! naming group edges). Plain MT writes each id straight into place, in its own instance of
//! the walk (`PLAIN`: no vertex map, listing or cells, so none of their flags is tested per
//! anchor), and so does the listing over the whole box (`LIST`: each triangle's source
//! tetrahedron written beside it, no flag tested per triangle); each edge's ends are read by
//! their deltas from the anchor (`TetGroup::edge_reads`).

use rayon::prelude::*;

use super::crossings::{CrossedIndex, CrossedPoint};
use super::layout::{case_triangles_of, split_quad, Layout, EDGE_SLOTS};
use crate::lattice::Offset;
use crate::util::for_each_bit;
use crate::{Boundary, CellRange, Lattice};

/// What a walk over the geometry layers reads: the lattice, the isovalue, the cells kept (a
/// chunk: only their anchors are walked) and the crossed points of the vertex pass.
#[derive(Clone, Copy)]
pub(crate) struct Surface<'a> {
    pub(crate) l: &'a Layout<'a>,
    pub(crate) iso: f32,
    pub(crate) keep: Option<CellRange>,
    pub(crate) crossed: &'a CrossedIndex,
}

/// The vertices a layer's triangles are written with: the crossings' positions (plain MT's
/// vertices, which choose the diagonal of a quad) and, with clustering, the output vertex of
/// every crossing.
#[derive(Clone, Copy)]
pub(crate) struct Vertices<'a> {
    pub(crate) positions: &'a [[f32; 3]],
    pub(crate) map: Option<&'a [u32]>,
}

/// Where one layer's triangles go: `out` (three ids each, sized by [`count_layer`]), with
/// `list` what the listing of plain MT's triangles writes beside them, with `cells` each
/// triangle's anchor cell.
pub(crate) struct LayerOut<'s> {
    pub(crate) out: &'s mut [u32],
    pub(crate) list: Option<ListOut<'s>>,
    pub(crate) cells: Option<&'s mut [u32]>,
    /// Plain MT only (no vertex map, no listing): write each triangle with its last two
    /// corners swapped, the winding of the mesh in array order
    /// ([`crate::Extractor::set_array_order`]).
    pub(crate) flip: bool,
}

/// Calls `visit(anchor, rank, group, p)` for each body-centred face (group: its axis) or cube
/// (group 0) of geometry layer `k` that can hold surface: its anchor point (a storage slot, at
/// lattice coordinates `p`) has a crossed edge and, in a chunk, its cell
/// ([`Layout::anchor_cell`]) is kept. The anchor's entry is `crossed.points[rank]` when `RANK`
/// (else `rank` is 0: the geometry pass reads its window, not the ranks). The count and the
/// geometry pass both walk the layer with it, so they see the same groups.
pub(crate) fn for_each_group<const RANK: bool>(
    l: &Layout,
    k: usize,
    keep: Option<CellRange>,
    crossed: &CrossedIndex,
    mut visit: impl FnMut(usize, usize, usize, Offset),
) {
    let [nx, ny, nz] = l.s.cells;
    let plane = l.s.dims[0] * l.s.dims[1];
    // The layer's runs of rows, in walk order: (rows, group, row length, the first anchor's
    // x and y, the row step of y, its z), walked by one loop (the row walk compiled into it,
    // not called per row).
    let none = (0, 0, 0, 0, 0, 0, 0);
    let runs: [(usize, usize, usize, i32, i32, i32, i32); 3] = match l.lattice {
        // Cubes by corner 0, a neighbour of the other 7: no crossed edge there, no surface in
        // the cube.
        Lattice::Simple => [(ny, 0, nx, 0, 0, 1, k as i32), none, none],
        Lattice::BodyCentred => {
            // Faces perpendicular to z at plane k, then (inside layer k) to x and to y, by
            // their anchor A, the centre below (B and the 4 face corners are neighbours of A:
            // without a crossed edge at A, no surface in the face's 4 tetrahedra). Along x a
            // face anchor moves by one storage slot (two lattice units). Without ghosts, the
            // faces on the box's upper faces (whose centre above is a ghost) are not walked:
            // their pyramids are `pyramids`' (those on the lower faces have a ghost anchor,
            // which has no crossed edge).
            let ki = k as i32;
            let upper = usize::from(l.s.boundary == Boundary::Pyramids);
            let rows = |walked: bool, n: usize| if walked { n } else { 0 };
            [
                (rows(k + upper <= nz, ny), 2, nx, 1, 1, 2, 2 * ki - 1),
                (rows(k < nz, ny), 0, nx + 1 - upper, -1, 1, 2, 2 * ki + 1),
                (rows(k < nz, ny + 1 - upper), 1, nx, 1, -1, 2, 2 * ki + 1),
            ]
        }
    };
    let row_slots = l.s.dims[0];
    for (rows, g, len, x, y, dy, z) in runs {
        if rows == 0 {
            continue;
        }
        // The run's storage plane, its first row's first anchor, and the lattice step
        // between anchors along a row; each next row starts one storage row further.
        let (start0, plane_z, step) = match l.lattice {
            Lattice::Simple => (l.s.simple_index(0, 0, k), k, 1),
            // Storage plane (see `Samples::bcdl_index`).
            Lattice::BodyCentred => (l.s.bcdl_index([x, y, z]), (z + 1) as usize, 2),
        };
        let bits = crossed.plane_bits(plane_z);
        for j in 0..rows {
            let first = [x, y + dy * j as i32, z];
            let start = start0 + j * row_slots;
            debug_assert_eq!(
                start,
                match l.lattice {
                    Lattice::Simple => l.s.simple_index(0, j, k),
                    Lattice::BodyCentred => l.s.bcdl_index(first),
                }
            );
            // The anchors of one row are consecutive storage slots, at lattice points
            // `first + (step n, 0, 0)`: scan their bits, visit only the crossed ones.
            let local = start - plane_z * plane;
            let mut rank = if RANK {
                crossed.rank_in(plane_z, local)
            } else {
                0
            };
            for_each_bit(bits, local, len, |n| {
                let r = rank;
                rank += 1;
                let p = [first[0] + step * n as i32, first[1], first[2]];
                if keep.is_some_and(|range| !range.contains(l.anchor_cell(p, g))) {
                    return;
                }
                visit(start + n, r, g, p);
            });
        }
    }
}

/// Triangles of every geometry layer (those of the cells `keep`), in layer order: over the
/// whole box from the counts the numbering kept per storage plane
/// ([`CrossedIndex::plane_triangles`]: a body-centred layer k holds the faces perpendicular
/// to z of plane 2k and the others of plane 2k + 2, a simple one the cubes of plane k), in a
/// chunk by a walk over the kept anchors ([`count_layer`]).
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
    let planes = &crossed.plane_triangles;
    if keep.is_none() && planes.len() == l.s.dims[2] {
        let counts: Vec<usize> = (0..layers)
            .map(|k| match l.lattice {
                Lattice::BodyCentred => {
                    let others = planes.get(2 * k + 2).filter(|_| k + 1 < layers);
                    (planes[2 * k][2] + others.map_or(0, |p| p[0] + p[1])) as usize
                }
                Lattice::Simple => planes[k][0] as usize,
            })
            .collect();
        debug_assert_eq!(
            counts,
            (0..layers)
                .map(|k| count_layer(l, k, None, crossed))
                .collect::<Vec<_>>(),
            "the numbering's counts and the walk's differ"
        );
        return counts;
    }
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
    for_each_group::<true>(l, k, keep, crossed, |_, rank, g, _| {
        let group = &l.groups[g];
        n += usize::from(group.triangles[group.code(crossed.points[rank].crossed)]);
    });
    n
}

/// Emission over z-layer `k` (its anchors walked as `surface` says): writes its triangles into
/// `out.out`, sized by [`count_layer`] (the triangles of plain MT); with `vertices.map`
/// (crossing id to output vertex, clustering) the triangles are written with the clustered
/// vertices and those that collapsed are left out. Returns the tetrahedra processed and the
/// triangles written.
pub(crate) fn geometry_layer(
    surface: &Surface,
    k: usize,
    vertices: Vertices,
    out: LayerOut<'_>,
) -> (usize, usize) {
    let (l, crossed) = (surface.l, surface.crossed);
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
            // The plane's crossed points in rank order, beside its bits in slot order.
            let mut points = crossed.points[crossed.rank_in(z, 0)..].iter();
            let dense = &mut window[base..base + plane];
            for_each_bit(crossed.plane_bits(z), 0, plane, |local| {
                if let (Some(slot), Some(&p)) = (dense.get_mut(local), points.next()) {
                    *slot = p;
                }
            });
        }
        // Plain MT (no vertex map, no listing, no cells) walks without the other modes' flags,
        // and so does the listing over the whole box (no kept cells marked, no cells).
        let plain = vertices.map.is_none() && out.list.is_none() && out.cells.is_none();
        let list_only = vertices.map.is_none()
            && out.cells.is_none()
            && out.list.as_ref().is_some_and(|list| list.kept.is_none());
        match (out.flip, plain, list_only) {
            (true, _, _) => {
                geometry_in_window::<true, true, false>(surface, k, vertices, window, z0, out)
            }
            (false, true, _) => {
                geometry_in_window::<false, true, false>(surface, k, vertices, window, z0, out)
            }
            (false, false, true) => {
                geometry_in_window::<false, false, true>(surface, k, vertices, window, z0, out)
            }
            (false, false, false) => {
                geometry_in_window::<false, false, false>(surface, k, vertices, window, z0, out)
            }
        }
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
    /// Its source tetrahedron: the anchor slot, and the template index (bits 0-6) with bit 7
    /// set when no corner is a ghost ([`crate::mt::clustering::plain::PlainList::source`]).
    pub(crate) source: &'s mut [(u32, u8)],
    /// In a chunk: the kept cells, and per triangle 1 when its anchor's cell is one of them
    /// (the triangles the chunk emits), else 0.
    pub(crate) kept: Option<(CellRange, &'s mut [u8])>,
}

/// [`geometry_layer`] once the crossed points of storage planes `z0..` are in `window`; with
/// `out.cells`, each triangle written gets its anchor cell there (linear index, x fastest).
/// Returns the tetrahedra with a triangle (when listing in a chunk, those of kept cells) and
/// the triangles written. `PLAIN`: plain MT's walk (no vertex map, no listing, no cells), its
/// flags known at compile time; `LIST`: the listing over the whole box (no vertex map, no
/// kept cells marked, no cells), each triangle's source written straight into place.
pub(crate) fn geometry_in_window<const FLIP: bool, const PLAIN: bool, const LIST: bool>(
    surface: &Surface,
    k: usize,
    vertices: Vertices,
    window: &[CrossedPoint],
    z0: usize,
    out: LayerOut<'_>,
) -> (usize, usize) {
    let Surface {
        l,
        iso,
        keep,
        crossed,
    } = *surface;
    let Vertices { positions, map } = vertices;
    let LayerOut {
        out,
        list,
        mut cells,
        flip,
    } = out;
    debug_assert_eq!(flip, FLIP);
    debug_assert!(
        !FLIP || (map.is_none() && list.is_none()),
        "flip is plain MT's only"
    );
    debug_assert!(
        !PLAIN || (map.is_none() && list.is_none() && cells.is_none()),
        "the plain walk writes only triangles"
    );
    debug_assert!(
        !LIST || (!PLAIN && map.is_none() && cells.is_none()),
        "the listing's walk writes triangles and sources"
    );
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
    let plain = map.is_none() && !listing && !cells_wanted;
    // The listing's own walk: the sources slice taken out of `list`, no flag tested per
    // triangle.
    let (mut list, source) = match list {
        Some(ListOut { source, kept: None }) if LIST => (None, source),
        other => (other, &mut [][..]),
    };
    let [nx, ny, _] = l.s.cells;
    // The window starts at slot 0 of plane z0.
    let base = z0 * plane;
    for_each_group::<false>(l, k, keep, crossed, |anchor, _, g, p| {
        // The group's points on the other side from the anchor, as in [`count_layer`].
        let group = &l.groups[g];
        let at = anchor - base;
        let code = group.code(window[at].crossed);
        if group.triangles[code] == 0 {
            return;
        }
        // The crossing on each crossed edge of the group, once: the end whose owned bit the
        // vertex pass set (it decided that from the same two values the case would read), as
        // `case_triangles_of` would ask for it, edge (a, b) of a tetrahedron with a < b.
        // Indexed by edge masked to 5 bits (`EDGE_SLOTS`): no bounds checks.
        let mut ids = [0u32; EDGE_SLOTS];
        let mut todo = group.crossed_edges[code];
        while todo != 0 {
            let e = todo.trailing_zeros() as usize & (EDGE_SLOTS - 1);
            todo &= todo - 1;
            let read = group.edge_reads[e];
            let a = window[(at as isize + read.deltas[0]) as usize];
            debug_assert_eq!(
                a,
                crossed.get((anchor as isize + read.deltas[0]) as usize),
                "edge {e}"
            );
            debug_assert_ne!(a.crossed >> read.dir[0] & 1, 0, "edge {e} not crossed");
            // The far end read only when the near one does not own the crossing.
            let (owner, d) = if a.owned >> read.dir[0] & 1 != 0 {
                (a, read.dir[0])
            } else {
                (window[(at as isize + read.deltas[1]) as usize], read.dir[1])
            };
            ids[e] = owner.id(d);
        }
        // Each tetrahedron's case (bit i: corner i inside) is known from the anchor's side and
        // its crossed edges: no other sample value is read.
        let side = usize::from(v[anchor] < iso);
        let range = usize::from(group.cycle_start[2 * code + side])
            ..usize::from(group.cycle_start[2 * code + side + 1]);
        // Only the listing reads these: whether no corner is a ghost (for the gradient), and in
        // a chunk whether the anchor's cell is kept.
        let inner = !PLAIN && listing && l.inner_anchor(p);
        let kept = PLAIN || mark.is_none_or(|range| range.contains(l.anchor_cell(p, g)));
        let cell = if !PLAIN && cells_wanted {
            let c = l.anchor_cell(p, g);
            (c[0] + nx * (c[1] + ny * c[2])) as u32
        } else {
            0
        };
        let first = match l.lattice {
            Lattice::BodyCentred if !PLAIN => 4 * g,
            _ => 0,
        };
        processed += if kept { range.len() } else { 0 };
        if PLAIN || map.is_none() {
            // Plain MT's triangles: the ids straight into place, each value stored once (an
            // array of triangles copied over would be read back across its stores), the write
            // position in a register; the listing's gradient, flags and cells beside them.
            let mut at = w;
            // The listing's first triangle of this anchor.
            let mut t = if LIST { w / 3 } else { 0 };
            let tet_flag = u8::from(inner) << 7;
            for cycle in &group.cycles[range] {
                let e = cycle.edges.map(|e| usize::from(e) & (EDGE_SLOTS - 1));
                let q = [ids[e[0]], ids[e[1]], ids[e[2]], 0];
                let n = if cycle.edges[3] == u8::MAX {
                    if FLIP {
                        out[at..at + 3].copy_from_slice(&[q[0], q[2], q[1]]);
                    } else {
                        out[at..at + 3].copy_from_slice(&q[..3]);
                    }
                    1
                } else {
                    let q = [q[0], q[1], q[2], ids[e[3]]];
                    // As [`split_quad`], by an index rather than a branch (the choice is
                    // data-dependent): along 0-2 unless it is the longer diagonal, else the
                    // cycle turned by one.
                    let p = |i: u32| glam::Vec3::from(positions[i as usize]);
                    let short02 =
                        p(q[0]).distance_squared(p(q[2])) <= p(q[1]).distance_squared(p(q[3]));
                    let r = usize::from(!short02);
                    if FLIP {
                        out[at..at + 6].copy_from_slice(&[
                            q[r],
                            q[r + 2],
                            q[r + 1],
                            q[r],
                            q[(r + 3) & 3],
                            q[r + 2],
                        ]);
                    } else {
                        out[at..at + 6].copy_from_slice(&[
                            q[r],
                            q[r + 1],
                            q[r + 2],
                            q[r],
                            q[r + 2],
                            q[(r + 3) & 3],
                        ]);
                    }
                    2
                };
                if LIST {
                    // The tetrahedron, whose gradient the quotient test's (c) reads.
                    let tet = (first + usize::from(cycle.tet)) as u8 | tet_flag;
                    source[t] = (anchor as u32, tet);
                    if n == 2 {
                        source[t + 1] = (anchor as u32, tet);
                    }
                    t += n;
                } else if !PLAIN && !plain {
                    let t = at / 3;
                    if let Some(list) = list.as_mut() {
                        // The tetrahedron, whose gradient the quotient test's (c) reads.
                        let tet = (first + usize::from(cycle.tet)) as u8 | u8::from(inner) << 7;
                        list.source[t..t + n].fill((anchor as u32, tet));
                        if let Some((_, flags)) = list.kept.as_mut() {
                            flags[t..t + n].fill(u8::from(kept));
                        }
                    }
                    if let Some(cells) = cells.as_deref_mut() {
                        cells[t..t + n].fill(cell);
                    }
                }
                at += 3 * n;
            }
            w = at;
            return;
        }
        for cycle in &group.cycles[range] {
            let e = cycle.edges;
            let mut tris = [[0u32; 3]; 2];
            let n = if e[3] == u8::MAX {
                tris[0] = [
                    ids[usize::from(e[0])],
                    ids[usize::from(e[1])],
                    ids[usize::from(e[2])],
                ];
                1
            } else {
                tris = split_quad(e.map(|e| ids[usize::from(e)]), positions);
                2
            };
            debug_assert_eq!(
                {
                    let ti = first + usize::from(cycle.tet);
                    let tpl = &l.tets[ti];
                    let case = (0..4).fold(0, |c, i| {
                        c | usize::from(v[(anchor as isize + tpl.delta[i]) as usize] < iso) << i
                    });
                    let edge = |a: usize, b: usize| {
                        let at = |o: usize| crossed.get((anchor as isize + tpl.delta[o]) as usize);
                        if at(a).owned >> tpl.dir[a][b] & 1 != 0 {
                            at(a).id(tpl.dir[a][b])
                        } else {
                            at(b).id(tpl.dir[b][a])
                        }
                    };
                    let mut reference = [[0u32; 3]; 2];
                    let m = case_triangles_of(case, edge, positions, &mut reference);
                    reference[..m].to_vec()
                },
                tris[..n].to_vec(),
                "tetrahedron {} of anchor {anchor}",
                cycle.tet
            );
            match map {
                None => unreachable!("plain MT's triangles are written above"),
                Some(map) => {
                    // Clustered: the vertices of the groups' quotient; a triangle with two
                    // corners in one group collapsed and is dropped.
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
        }
    });
    debug_assert!(
        w == out.len() || (map.is_some() && w <= out.len()),
        "layer {k}: triangles counted and written differ"
    );
    (processed, w / 3)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::mt::layout::case_triangles;
    use crate::mt::testing::{plain_mt, test_pool, wavy};

    #[test]
    fn layer_triangle_counts_match_the_tetrahedra_of_every_group() {
        // The count reads only the anchor's crossed edges through the group tables; here each
        // group's tetrahedra are evaluated from the sample values instead, with and without
        // kept cells.
        let field = wavy();
        let pool = test_pool(1);
        let mut triangles = 0;
        // Anchors visited as not inner / inner.
        let mut flags = [0usize; 2];
        for lattice in [Lattice::BodyCentred, Lattice::Simple] {
            for cells in [[3, 2, 4], [9, 8, 6], [13, 11, 12]] {
                let (settings, samples, buf, mesh) = plain_mt(&field, lattice, cells, &pool);
                let l = Layout::new(&samples, lattice);
                let (expected_len, dirs_from) = match lattice {
                    Lattice::BodyCentred => (6, 1),
                    Lattice::Simple => (8, 0),
                };
                for g in &l.groups {
                    assert_eq!(g.len, expected_len, "{lattice:?}");
                    assert_eq!(g.points[0], 0, "the anchor comes first");
                    for i in 1..g.len {
                        let d = l.delta[dirs_from][g.dirs[i] as usize];
                        assert_eq!(d, g.points[i], "{lattice:?} point {i}");
                    }
                    for code in 0..1usize << g.len {
                        let swapped = !code & ((1 << g.len) - 1);
                        assert_eq!(g.triangles[code], g.triangles[swapped], "side swap");
                    }
                }
                let layers = match lattice {
                    Lattice::BodyCentred => cells[2] + 1,
                    Lattice::Simple => cells[2],
                };
                let keeps = [
                    None,
                    Some(CellRange {
                        lo: [1, 0, 1],
                        hi: [cells[0] - 1, cells[1], cells[2] - 1],
                    }),
                ];
                for keep in keeps {
                    let mut total = 0;
                    let mut per_layer = Vec::new();
                    for k in 0..layers {
                        let mut direct = 0;
                        for_each_group::<false>(
                            &l,
                            k,
                            keep,
                            &buf.vertices.crossed,
                            |anchor, _, g, q| {
                                let tets = match lattice {
                                    Lattice::BodyCentred => &l.tets[4 * g..4 * g + 4],
                                    Lattice::Simple => &l.tets[..],
                                };
                                // The walk's coordinates are the anchor's, and `inner_anchor`
                                // promises every corner in the box (no ghost).
                                let p = l.coords_of(anchor);
                                assert_eq!(q, p, "{lattice:?} {cells:?}");
                                let inner = l.inner_anchor(p);
                                let in_box = tets.iter().all(|tpl| {
                                    tpl.off.iter().all(|o| {
                                        (0..3).all(|a| {
                                            p[a] + o[a] >= 0 && p[a] + o[a] <= l.max_coord(a)
                                        })
                                    })
                                });
                                assert!(!inner || in_box, "{lattice:?} {cells:?} anchor {p:?}");
                                flags[usize::from(inner)] += 1;
                                for tpl in tets {
                                    let case = (0..4).fold(0, |case, i| {
                                        let slot = (anchor as isize + tpl.delta[i]) as usize;
                                        case | usize::from(samples.values[slot] < settings.iso) << i
                                    });
                                    direct += usize::from(case_triangles(case));
                                }
                            },
                        );
                        let counted = count_layer(&l, k, keep, &buf.vertices.crossed);
                        assert_eq!(counted, direct, "{lattice:?} {cells:?} layer {k} {keep:?}");
                        total += counted;
                        per_layer.push(counted);
                    }
                    if keep.is_none() {
                        assert_eq!(total * 3, mesh.indices.len(), "{lattice:?} {cells:?}");
                        // The counts the numbering kept per plane give the same layers.
                        let planes = buf.vertices.crossed.plane_triangles.len();
                        assert_eq!(planes, samples.dims[2], "{lattice:?} {cells:?}");
                        let numbered = layer_counts(&l, None, &buf.vertices.crossed, &pool);
                        assert_eq!(numbered, per_layer, "{lattice:?} {cells:?}");
                    }
                    triangles += total;
                }
            }
        }
        assert!(
            triangles > 1000,
            "only {triangles} triangles: the fields miss the grids"
        );
        assert!(
            flags[0] > 50 && flags[1] > 50,
            "anchors by inner: {flags:?}"
        );
    }
}
