//! The pyramids of the body-centred lattice without ghosts ([`crate::Boundary::Pyramids`]).
//!
//! Between each cube face on the box and the centre `C` of the cube inside lies half an
//! octahedron: a pyramid with the face as its base. With ghosts, the centre of the cube outside
//! (sampled on the face) closes it with four tetrahedra; without, this pass splits it into two
//! tetrahedra along the face diagonal through the face's lowest corner `q00`:
//!
//! ```text
//!   q01 ------ q11        (C, q00, q10, q11) and (C, q00, q11, q01), C above the face
//!    |      /   |
//!    |    /     |         edges C-q and q-q' are lattice edges: their crossings are the
//!    |  /       |         vertex pass's (same ids); the diagonal q00-q11 is no lattice edge:
//!   q00 ------ q10        its crossing is a vertex of this pass, appended after the others
//! ```
//!
//! The geometry walk leaves these faces out (their anchor, or the centre above it, is a ghost,
//! which does not exist), so every tetrahedron of the box is emitted once, and every triangle
//! side of a pyramid (C, q, q') is shared with the one tetrahedron of the walk on the other side
//! (C, C', q, q'): the mesh stays closed wherever the surface stays inside the box. The
//! triangles come from the case table of a positively oriented tetrahedron, as the walk's do.
//! Integrated clustering never groups a crossing of a pyramid (see
//! [`super::layout::Layout::near_pyramid`]), so their ids map to themselves.

use super::crossings::CrossedIndex;
use super::layout::{case_triangles_of, owns, Layout, TET_EDGES};
use crate::lattice::Offset;
use crate::Stats;

/// What the pyramid pass reads.
pub(crate) struct PyramidIn<'a> {
    pub(crate) l: &'a Layout<'a>,
    pub(crate) iso: f32,
    pub(crate) crossed: &'a CrossedIndex,
    /// The crossings' positions (plain MT's vertices), by crossing id.
    pub(crate) cpos: &'a [[f32; 3]],
    /// With clustering, every crossing's output vertex (else crossing ids are vertex ids).
    pub(crate) vertex_of: Option<&'a [u32]>,
    /// The output vertex id of the first diagonal crossing (the mesh's vertices so far).
    pub(crate) first_new: u32,
}

/// What the pyramid pass makes, to append to the mesh.
#[derive(Default)]
pub(crate) struct PyramidOut {
    /// Three output vertex ids per triangle.
    pub(crate) indices: Vec<u32>,
    /// The diagonals' crossings, output vertices `first_new` on.
    pub(crate) positions: Vec<[f32; 3]>,
    /// Each triangle's cube (linear index `x + nx * (y + ny * z)`).
    pub(crate) cells: Vec<u32>,
}

/// The triangles of every pyramid on the box faces (box faces in the order x, y, z, lower then
/// upper, cells in row order), the diagonals' crossings as new vertices. Counts the diagonals'
/// crossings into `stats.crossings`, the tetrahedra with a triangle into
/// `stats.tetrahedra_processed`, and triangles left out because clustering made two of their
/// corners one into `stats.discarded`.
pub(crate) fn pyramids(input: &PyramidIn<'_>, stats: &mut Stats) -> PyramidOut {
    let PyramidIn {
        l,
        iso,
        crossed,
        cpos,
        vertex_of,
        first_new,
    } = *input;
    let mut out = PyramidOut::default();
    let s = l.s;
    let n = s.cells;
    let value = |p: Offset| s.values[s.bcdl_index(p)];
    for a in 0..3 {
        let (b, c) = ((a + 1) % 3, (a + 2) % 3);
        for upper in [false, true] {
            let face = if upper { 2 * n[a] as i32 } else { 0 };
            let centre = if upper { face - 1 } else { 1 };
            for j in 0..n[c] as i32 {
                for i in 0..n[b] as i32 {
                    let point = |fa: i32, fb: i32, fc: i32| {
                        let mut p = [0; 3];
                        (p[a], p[b], p[c]) = (fa, fb, fc);
                        p
                    };
                    let q00 = point(face, 2 * i, 2 * j);
                    let q10 = point(face, 2 * i + 2, 2 * j);
                    let q11 = point(face, 2 * i + 2, 2 * j + 2);
                    let q01 = point(face, 2 * i, 2 * j + 2);
                    let apex = point(centre, 2 * i + 1, 2 * j + 1);
                    let cube = apex.map(|x| (x - 1) as u32 / 2);
                    let cell = cube[0] + n[0] as u32 * (cube[1] + n[1] as u32 * cube[2]);
                    // The diagonal's crossing, made when a tetrahedron first needs it.
                    let mut diagonal: Option<(u32, u32)> = None;
                    for tet in [[apex, q00, q10, q11], [apex, q00, q11, q01]] {
                        let tet = positive(tet);
                        let f = tet.map(value);
                        let case = (0..4).fold(0, |m, k| m | (usize::from(f[k] < iso) << k));
                        if case == 0 || case == 15 {
                            continue;
                        }
                        stats.tetrahedra_processed += 1;
                        // Per tetrahedron edge: (crossing id, output vertex, position).
                        let mut at = [(0u32, 0u32, [0f32; 3]); 6];
                        for (e, &(u, v)) in TET_EDGES.iter().enumerate() {
                            if (f[u] < iso) == (f[v] < iso) {
                                continue;
                            }
                            let (o, t) = if owns(f[u], f[v], iso) {
                                (u, v)
                            } else {
                                (v, u)
                            };
                            let off = [0, 1, 2].map(|k| tet[t][k] - tet[o][k]);
                            at[e] = match l.t.direction(off) {
                                Some(d) => {
                                    let id = crossed.get(s.bcdl_index(tet[o])).id(d as u8);
                                    let vertex = vertex_of.map_or(id, |m| m[id as usize]);
                                    (id, vertex, cpos[id as usize])
                                }
                                None => {
                                    // The diagonal, from its owner as the vertex pass places
                                    // crossings.
                                    let tt = (iso - f[o]) / (f[t] - f[o]);
                                    let p = l.position(tet[o]).lerp(l.position(tet[t]), tt);
                                    let (id, vertex) = *diagonal.get_or_insert_with(|| {
                                        stats.crossings += 1;
                                        out.positions.push(p.to_array());
                                        (u32::MAX, first_new + out.positions.len() as u32 - 1)
                                    });
                                    (id, vertex, p.to_array())
                                }
                            };
                        }
                        let positions = at.map(|x| x.2);
                        let mut tris = [[0u32; 3]; 2];
                        let count = case_triangles_of(
                            case,
                            |u, v| {
                                TET_EDGES
                                    .iter()
                                    .position(|&e| e == (u, v) || e == (v, u))
                                    .map_or(0, |e| e as u32)
                            },
                            &positions,
                            &mut tris,
                        );
                        for tri in &tris[..count] {
                            let q = tri.map(|e| at[e as usize].1);
                            if q[0] == q[1] || q[1] == q[2] || q[0] == q[2] {
                                stats.discarded += 1;
                                continue;
                            }
                            out.indices.extend_from_slice(&q);
                            out.cells.push(cell);
                        }
                    }
                }
            }
        }
    }
    out
}

/// `tet` with its last two corners swapped when it is negatively oriented (the case table
/// orients the triangles of positively oriented tetrahedra).
fn positive(tet: [Offset; 4]) -> [Offset; 4] {
    let d = [1, 2, 3].map(|k| [0, 1, 2].map(|a| i64::from(tet[k][a] - tet[0][a])));
    let det = d[0][0] * (d[1][1] * d[2][2] - d[1][2] * d[2][1])
        - d[0][1] * (d[1][0] * d[2][2] - d[1][2] * d[2][0])
        + d[0][2] * (d[1][0] * d[2][1] - d[1][1] * d[2][0]);
    if det < 0 {
        [tet[0], tet[1], tet[3], tet[2]]
    } else {
        tet
    }
}

/// The pyramid tetrahedra of a box of `cells` (two per cube face on the box).
pub(crate) fn pyramid_tetrahedra(cells: [usize; 3]) -> usize {
    let [nx, ny, nz] = cells;
    2 * 2 * (ny * nz + nx * nz + nx * ny)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::measure::on_box_boundary;
    use crate::mt::testing::{extracted, lcg, settings_on, test_pool};
    use crate::{Boundary, Clustering, Lattice};
    use glam::Vec3;
    use rmt_mesh::{validate, Mesh};

    /// A random smooth field: a few bumps and waves, crossing the box faces.
    fn random_field(seed: u64) -> rmt_fields::FnField<impl Fn(Vec3) -> f32> {
        let mut s = seed.wrapping_mul(0x9e37_79b9_7f4a_7c15) | 1;
        let bumps: Vec<(Vec3, f32, f32)> = (0..5)
            .map(|_| {
                let c = Vec3::new(lcg(&mut s), lcg(&mut s), lcg(&mut s)) * 1.1;
                (c, 0.3 + 0.3 * lcg(&mut s).abs(), lcg(&mut s) + 0.4)
            })
            .collect();
        let freq = Vec3::new(lcg(&mut s), lcg(&mut s), lcg(&mut s)) * 6.0;
        let amp = 0.3 * lcg(&mut s).abs();
        rmt_fields::FnField(move |p: Vec3| {
            let g: f32 = bumps
                .iter()
                .map(|(c, r, a)| a * (-(p - *c).length_squared() / (r * r)).exp())
                .sum();
            0.25 - g
                + amp * (p.x * freq.x).sin() * (p.y * freq.y + 0.2).cos() * (p.z * freq.z).sin()
        })
    }

    fn pyramid_settings(cells: [usize; 3], clustering: Clustering) -> crate::ExtractSettings {
        let mut s = settings_on(cells, Lattice::BodyCentred, clustering);
        s.boundary = Boundary::Pyramids;
        s
    }

    /// Each triangle as its three positions, rotated to start at the smallest (orientation
    /// kept), sorted: a mesh compared without its vertex numbering.
    fn triangles(mesh: &Mesh, keep: impl Fn([f32; 3]) -> bool) -> Vec<[[u32; 3]; 3]> {
        let mut out: Vec<[[u32; 3]; 3]> = mesh
            .triangles()
            .map(|t| t.map(|i| mesh.positions[i as usize]))
            .filter(|t| t.iter().all(|p| keep(*p)))
            .map(|t| {
                let t = t.map(|p| p.map(f32::to_bits));
                let k = (0..3).min_by_key(|&k| t[k]).unwrap_or(0);
                [t[k], t[(k + 1) % 3], t[(k + 2) % 3]]
            })
            .collect();
        out.sort_unstable();
        out
    }

    #[test]
    fn pyramids_close_the_box_without_ghosts_manifold_and_oriented() {
        // Random fields that cross the box faces, plain MT and integrated clustering, 1 and 2
        // threads: no open edge but on the box, no non-manifold edge or vertex, no
        // misoriented edge; the same bytes for both thread counts; the surface does meet the
        // faces (pyramid triangles and diagonal crossings are made).
        let mut diagonals = 0;
        let mut on_box = 0;
        for seed in 0..24u64 {
            let field = random_field(seed);
            let cells = [
                6 + seed as usize % 5,
                7 + seed as usize % 3,
                5 + seed as usize % 4,
            ];
            for clustering in [Clustering::None, Clustering::Integrated] {
                let settings = pyramid_settings(cells, clustering);
                let mut meshes = Vec::new();
                for threads in [1, 2] {
                    let pool = test_pool(threads);
                    let (samples, _, mesh, stats) = extracted(&field, &settings, &pool);
                    // No ghost was sampled: their slots stay NaN.
                    assert!(samples.values[samples.bcdl_index([1, 1, -1])].is_nan());
                    let grid = settings.grid;
                    let r = validate(&mesh, &|p| on_box_boundary(&grid, p));
                    let what = format!("seed {seed} {clustering:?} {threads} threads: {r:?}");
                    assert_eq!(r.boundary_edges_interior, 0, "{what}");
                    assert_eq!(r.non_manifold_edges, 0, "{what}");
                    assert_eq!(r.non_manifold_vertices, 0, "{what}");
                    assert_eq!(r.orientation_errors, 0, "{what}");
                    assert_eq!(r.out_of_range_triangles, 0, "{what}");
                    on_box += r.boundary_edges_on_box;
                    diagonals += stats.crossings;
                    meshes.push(mesh);
                }
                assert_eq!(meshes[0].positions, meshes[1].positions, "seed {seed}");
                assert_eq!(meshes[0].indices, meshes[1].indices, "seed {seed}");
            }
        }
        assert!(
            on_box > 1000,
            "the fields hardly meet the box: {on_box} edges on it"
        );
        assert!(diagonals > 0);
    }

    #[test]
    fn away_from_the_box_faces_the_mesh_is_the_ghosts_one() {
        // Plain MT: every triangle with all corners more than a cell inside the box is the
        // ghost version's, and the other way round (the pyramids and the ghosts' tetrahedra
        // lie within half a cell of the faces). A surface that stays away from the faces gives
        // the same bytes, with integrated clustering too.
        let pool = test_pool(2);
        let (mut compared, mut differing) = (0, 0);
        for seed in 0..12u64 {
            let field = random_field(seed);
            let cells = [9, 8 + seed as usize % 3, 10];
            let pyr = pyramid_settings(cells, Clustering::None);
            let ghosts = settings_on(cells, Lattice::BodyCentred, Clustering::None);
            let (_, _, a, _) = extracted(&field, &pyr, &pool);
            let (_, _, b, _) = extracted(&field, &ghosts, &pool);
            let grid = pyr.grid;
            let h = grid.spacing();
            let inner = |p: [f32; 3]| {
                let p = Vec3::from(p);
                (p - grid.min).cmpgt(h).all() && (grid.max - p).cmpgt(h).all()
            };
            let (ta, tb) = (triangles(&a, inner), triangles(&b, inner));
            assert_eq!(ta, tb, "seed {seed}");
            compared += ta.len();
            // Near the faces they differ (else the test would not test the pyramids).
            differing += usize::from(triangles(&a, |_| true) != triangles(&b, |_| true));
        }
        assert!(compared > 2000, "{compared} inner triangles compared");
        assert!(
            differing >= 6,
            "only {differing} of 12 fields differ near the faces"
        );
        let sphere = rmt_fields::Sphere::new(Vec3::new(0.05, -0.02, 0.03), 0.6);
        for clustering in [Clustering::None, Clustering::Integrated] {
            let pyr = pyramid_settings([14, 12, 13], clustering);
            let mut ghosts = pyr;
            ghosts.boundary = Boundary::Ghosts;
            let (_, _, a, _) = extracted(&sphere, &pyr, &pool);
            let (_, _, b, _) = extracted(&sphere, &ghosts, &pool);
            assert_eq!(a.positions, b.positions, "{clustering:?}");
            assert_eq!(a.indices, b.indices, "{clustering:?}");
            assert!(!a.indices.is_empty());
        }
    }

    #[test]
    fn pyramid_tetrahedra_are_positive_and_fill_the_half_octahedron() {
        // Both tetrahedra of a pyramid positive after `positive`, and their volumes add up to
        // the pyramid's (a third of base times height: 4 * 1 / 3 in lattice units, times 6
        // for the determinant).
        for (apex, base) in [
            ([1, 1, 1], [[0, 0, 0], [2, 0, 0], [2, 2, 0], [0, 2, 0]]),
            ([1, 1, 7], [[0, 0, 8], [2, 0, 8], [2, 2, 8], [0, 2, 8]]),
            ([1, 3, 5], [[0, 2, 4], [0, 4, 4], [0, 4, 6], [0, 2, 6]]),
        ] {
            let [q00, q10, q11, q01] = base;
            let mut total = 0;
            for tet in [[apex, q00, q10, q11], [apex, q00, q11, q01]] {
                let t = positive(tet);
                let d = [1, 2, 3].map(|k| [0, 1, 2].map(|a| i64::from(t[k][a] - t[0][a])));
                let det = d[0][0] * (d[1][1] * d[2][2] - d[1][2] * d[2][1])
                    - d[0][1] * (d[1][0] * d[2][2] - d[1][2] * d[2][0])
                    + d[0][2] * (d[1][0] * d[2][1] - d[1][1] * d[2][0]);
                assert!(det > 0, "{t:?}");
                total += det;
            }
            assert_eq!(total, 8);
        }
    }
}
