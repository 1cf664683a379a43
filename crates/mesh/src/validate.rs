//! Topological checks: is a mesh closed, manifold and consistently oriented?
//!
//! The whole check is one walk over the vertices. First each vertex gets the list of triangles
//! around it (a compressed incidence list: two flat arrays, no allocation per vertex or
//! triangle). Then, for vertex `v`, every incident triangle, rotated so that `v` comes first,
//! `(v, u, w)`, contributes one edge `u - w` to the *link* of `v`:
//!
//! ```text
//!        w3 ---- w2            link of v: the polygon u1 - w1=u2 - w2=u3 - w3 ...
//!       /  \    /  \           closed cycle  -> v is inside a disk (interior vertex)
//!     u1 -- v ----- w1=u2      open path     -> v is on a half-disk (boundary vertex)
//!       \  /                   anything else -> non-manifold vertex
//!        ..
//! ```
//!
//! The number of times a link vertex `x` appears is the number of triangles on the edge `v - x`,
//! and whether it appears as a `u` (the triangle runs `v -> x`) or as a `w` (it runs `x -> v`)
//! gives the edge's directions. So the link also yields every edge incident to `v`; each edge is
//! counted once, at its smaller endpoint. A link whose vertices all appear at most twice (every
//! incident edge manifold) and which is connected is a single path or cycle: a disk or half-disk.
//! Two triangles with the same three vertices have the same link edge at their smallest vertex,
//! which finds duplicates (in any order or orientation).
//!
//! Cost: `O(F log k)` for `F` triangles and vertex valence `k`; memory about 12 bytes per
//! triangle and 25 per vertex. Reproduce the timing with
//! `cargo run --release -p rmt-mesh --example validate_speed -- 3` (3 million triangles).
//!
//! **Conventions.** Triangles with an index out of range are counted in
//! [`ValidationReport::out_of_range_triangles`] and otherwise ignored. Triangles with a repeated
//! index are zero-area triangles (see [`crate::quality::ZERO_AREA_REL_TOL`] for the geometric
//! tolerance, shared with [`crate::quality()`]); they have no well-defined edges, so they are
//! left out of the edges, the vertex fans, the Euler characteristic and the components, but they
//! do reference their vertices and take part in the duplicate check. Geometrically zero-area
//! triangles with three distinct indices take part in everything.

use crate::quality::{triangle_shape, TriangleShape};
use crate::Mesh;
use serde::{Deserialize, Serialize};

/// What [`validate`] found.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct ValidationReport {
    /// Distinct undirected edges of the mesh.
    pub mesh_edges: usize,
    /// Edges with one triangle lying on the sampled domain's boundary (expected where the surface
    /// leaves the box).
    pub boundary_edges_on_box: usize,
    /// Edges with one triangle inside the domain: holes (defects).
    pub boundary_edges_interior: usize,
    /// Edges with more than two triangles.
    pub non_manifold_edges: usize,
    /// Vertices whose triangle fan is not a single disk or half-disk.
    pub non_manifold_vertices: usize,
    /// Edges whose two triangles traverse it in the same direction.
    pub orientation_errors: usize,
    /// Triangles with the same three vertices as an earlier one (any order).
    pub duplicate_triangles: usize,
    /// Triangles with (near) zero area.
    pub zero_area_triangles: usize,
    /// Vertices with a NaN or infinite coordinate.
    pub non_finite_vertices: usize,
    /// Vertices referenced by no triangle.
    pub unreferenced_vertices: usize,
    /// V - E + F over referenced vertices.
    pub euler: i64,
    /// Connected components (through shared vertices).
    pub components: usize,
    /// Triangles with an index not below the vertex count (ignored by every other check).
    #[serde(default)]
    pub out_of_range_triangles: usize,
}

impl ValidationReport {
    /// Closed inside the domain, manifold, consistently oriented, no duplicates, finite.
    pub fn is_watertight_manifold(&self) -> bool {
        self.boundary_edges_interior == 0
            && self.non_manifold_edges == 0
            && self.non_manifold_vertices == 0
            && self.orientation_errors == 0
            && self.duplicate_triangles == 0
            && self.non_finite_vertices == 0
            && self.out_of_range_triangles == 0
    }
}

/// Checks `mesh`; `on_domain_boundary(p)` says whether a point lies on the sampled domain's outer
/// boundary (a boundary edge is "on box" when both ends and its midpoint are).
///
/// The Euler characteristic is `V - E + F` where `V` counts the vertices of triangles with three
/// distinct indices, `E` is [`ValidationReport::mesh_edges`] and `F` counts those triangles;
/// components are the connected components of those triangles through shared vertices. See the
/// [module documentation](self) for the method and the treatment of degenerate input.
///
/// ```
/// use rmt_mesh::{validate, Mesh};
/// let tetrahedron = Mesh::from_triangles(
///     vec![[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]],
///     vec![0, 2, 1, 0, 1, 3, 0, 3, 2, 1, 2, 3],
/// );
/// let report = validate(&tetrahedron, &|_| false);
/// assert!(report.is_watertight_manifold());
/// assert_eq!((report.euler, report.components, report.mesh_edges), (2, 1, 6));
/// ```
pub fn validate(mesh: &Mesh, on_domain_boundary: &dyn Fn([f32; 3]) -> bool) -> ValidationReport {
    let positions = &mesh.positions;
    let vertex_count = positions.len();
    let mut report = ValidationReport {
        non_finite_vertices: positions
            .iter()
            .filter(|p| !p.iter().all(|c| c.is_finite()))
            .count(),
        ..ValidationReport::default()
    };

    // Pass over the triangles: classify, count incidences, join components. Duplicates among
    // proper triangles are found in the vertex walk below; triangles with a repeated index are
    // rare and compared here, as sorted index triples.
    let mut referenced = vec![false; vertex_count];
    let mut degenerate_triples: Vec<[u32; 3]> = Vec::new();
    // incidence_start[v + 1] counts v's proper triangles for now; prefix sums come later.
    let mut incidence_start = vec![0usize; vertex_count + 1];
    let mut components = UnionFind::new(vertex_count);
    let mut proper_triangles = 0usize;
    for t in mesh.triangles() {
        match triangle_shape(positions, t) {
            TriangleShape::OutOfRange => {
                report.out_of_range_triangles += 1;
                continue;
            }
            TriangleShape::ZeroArea { .. } => report.zero_area_triangles += 1,
            TriangleShape::NonFinite | TriangleShape::Proper { .. } => {}
        }
        for i in t {
            referenced[i as usize] = true;
        }
        if is_proper(t) {
            proper_triangles += 1;
            for i in t {
                incidence_start[i as usize + 1] += 1;
            }
            components.union(t[0], t[1]);
            components.union(t[0], t[2]);
        } else {
            let mut key = t;
            key.sort_unstable();
            degenerate_triples.push(key);
        }
    }
    report.unreferenced_vertices = referenced.iter().filter(|&&r| !r).count();
    drop(referenced);

    // A triple equal to its predecessor in sorted order repeats an earlier triangle.
    degenerate_triples.sort_unstable();
    report.duplicate_triangles = degenerate_triples
        .windows(2)
        .filter(|w| w[0] == w[1])
        .count();
    drop(degenerate_triples);

    // Incidence lists: the proper triangles around v are incident[start[v]..start[v + 1]].
    for v in 0..vertex_count {
        incidence_start[v + 1] += incidence_start[v];
    }
    let mut incident = vec![0u32; incidence_start[vertex_count]];
    let mut fill = incidence_start.clone();
    for (ti, t) in mesh.triangles().enumerate() {
        if t.iter().all(|&i| (i as usize) < vertex_count) && is_proper(t) {
            for i in t {
                incident[fill[i as usize]] = ti as u32;
                fill[i as usize] += 1;
            }
        }
    }
    drop(fill);

    // Walk the vertices and their links, with scratch buffers reused from vertex to vertex.
    let mut link = VertexLink::default();
    let mut used_vertices = 0usize;
    for v in 0..vertex_count {
        let around = &incident[incidence_start[v]..incidence_start[v + 1]];
        if around.is_empty() {
            continue;
        }
        used_vertices += 1;
        link.build(v as u32, around, &mesh.indices);
        let mut manifold = true;
        for &LinkVertex {
            vertex: x,
            triangles,
            outgoing,
        } in &link.vertices
        {
            if triangles > 2 {
                manifold = false;
            }
            // Count each edge once, at its smaller endpoint.
            if x < v as u32 {
                continue;
            }
            report.mesh_edges += 1;
            match triangles {
                1 => {
                    let (a, b) = (positions[v], positions[x as usize]);
                    let mid = [0, 1, 2].map(|k| ((f64::from(a[k]) + f64::from(b[k])) * 0.5) as f32);
                    if on_domain_boundary(a) && on_domain_boundary(b) && on_domain_boundary(mid) {
                        report.boundary_edges_on_box += 1;
                    } else {
                        report.boundary_edges_interior += 1;
                    }
                }
                2 => {
                    if outgoing != 1 {
                        report.orientation_errors += 1;
                    }
                }
                _ => report.non_manifold_edges += 1,
            }
        }
        report.duplicate_triangles += link.duplicates_with_smallest_vertex();
        if !manifold || link.fan_count() != 1 {
            report.non_manifold_vertices += 1;
        }
    }

    report.euler = used_vertices as i64 - report.mesh_edges as i64 + proper_triangles as i64;
    report.components = (0..vertex_count)
        .filter(|&v| {
            incidence_start[v + 1] > incidence_start[v] && components.find(v as u32) == v as u32
        })
        .count();
    report
}

/// Three distinct indices (the caller has checked they are in range).
fn is_proper(t: [u32; 3]) -> bool {
    t[0] != t[1] && t[1] != t[2] && t[0] != t[2]
}

/// One vertex `x` of the link of `v`, i.e. one edge `v - x`.
#[derive(Clone, Copy, Debug)]
struct LinkVertex {
    vertex: u32,
    /// Triangles on the edge `v - x`.
    triangles: u32,
    /// How many of them run `v -> x` (the others run `x -> v`).
    outgoing: u32,
}

/// The link of one vertex: its link vertices (= incident edges) and link edges (one per incident
/// triangle). Buffers are kept between vertices.
#[derive(Default)]
struct VertexLink {
    /// `x << 1 | 1` for a triangle `(v, x, _)`, `x << 1` for `(v, _, x)`.
    ends: Vec<u64>,
    /// Link edges `(u, w)` of triangles `(v, u, w)`.
    edges: Vec<[u32; 2]>,
    /// Link edges `(min(u, w), max(u, w))` packed in a `u64`, of the triangles whose smallest
    /// vertex is `v`: each proper triangle appears in exactly one vertex's list.
    smallest_at_v: Vec<u64>,
    /// Distinct link vertices, ascending.
    vertices: Vec<LinkVertex>,
    /// Union-find parents over indices into `vertices`.
    parent: Vec<u32>,
}

impl VertexLink {
    fn build(&mut self, v: u32, around: &[u32], indices: &[u32]) {
        self.ends.clear();
        self.edges.clear();
        self.smallest_at_v.clear();
        self.vertices.clear();
        for &t in around {
            let t = t as usize;
            let [a, b, c] = [indices[3 * t], indices[3 * t + 1], indices[3 * t + 2]];
            // Rotate (a, b, c) so that v comes first; rotation keeps the orientation.
            let [u, w] = if a == v {
                [b, c]
            } else if b == v {
                [c, a]
            } else {
                [a, b]
            };
            self.ends.push((u64::from(u) << 1) | 1);
            self.ends.push(u64::from(w) << 1);
            self.edges.push([u, w]);
            if u > v && w > v {
                self.smallest_at_v
                    .push((u64::from(u.min(w)) << 32) | u64::from(u.max(w)));
            }
        }
        self.ends.sort_unstable();
        for &e in &self.ends {
            let x = (e >> 1) as u32;
            let out = (e & 1) as u32;
            match self.vertices.last_mut() {
                Some(last) if last.vertex == x => {
                    last.triangles += 1;
                    last.outgoing += out;
                }
                _ => self.vertices.push(LinkVertex {
                    vertex: x,
                    triangles: 1,
                    outgoing: out,
                }),
            }
        }
    }

    /// Triangles around `v`, with `v` as their smallest vertex, that repeat the vertex set of
    /// another such triangle (all copies but one are counted).
    fn duplicates_with_smallest_vertex(&mut self) -> usize {
        self.smallest_at_v.sort_unstable();
        self.smallest_at_v
            .windows(2)
            .filter(|w| w[0] == w[1])
            .count()
    }

    /// Connected components of the link graph: the number of separate triangle fans around `v`.
    fn fan_count(&mut self) -> usize {
        let n = self.vertices.len();
        self.parent.clear();
        self.parent.extend(0..n as u32);
        let mut fans = n;
        for &[u, w] in &self.edges {
            let (Ok(iu), Ok(iw)) = (self.local(u), self.local(w)) else {
                // Cannot happen: every link edge end was inserted into `vertices`.
                continue;
            };
            let (ru, rw) = (
                find(&mut self.parent, iu as u32),
                find(&mut self.parent, iw as u32),
            );
            if ru != rw {
                self.parent[ru as usize] = rw;
                fans -= 1;
            }
        }
        fans
    }

    fn local(&self, x: u32) -> Result<usize, usize> {
        self.vertices.binary_search_by_key(&x, |lv| lv.vertex)
    }
}

/// Root of `i` with path halving.
fn find(parent: &mut [u32], mut i: u32) -> u32 {
    while parent[i as usize] != i {
        let grand = parent[parent[i as usize] as usize];
        parent[i as usize] = grand;
        i = grand;
    }
    i
}

/// Union-find over vertices (union by size, path halving).
struct UnionFind {
    parent: Vec<u32>,
    size: Vec<u32>,
}

impl UnionFind {
    fn new(n: usize) -> Self {
        Self {
            parent: (0..n as u32).collect(),
            size: vec![1; n],
        }
    }

    fn find(&mut self, i: u32) -> u32 {
        find(&mut self.parent, i)
    }

    fn union(&mut self, a: u32, b: u32) {
        let (mut ra, mut rb) = (self.find(a), self.find(b));
        if ra == rb {
            return;
        }
        if self.size[ra as usize] < self.size[rb as usize] {
            std::mem::swap(&mut ra, &mut rb);
        }
        self.parent[rb as usize] = ra;
        self.size[ra as usize] += self.size[rb as usize];
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::solids::{octahedron, tetrahedron};
    use proptest::prelude::*;

    fn never(_: [f32; 3]) -> bool {
        false
    }

    fn always(_: [f32; 3]) -> bool {
        true
    }

    /// The surface of the cube [0, n]^3, each face an n x n grid of split squares, outward.
    fn cube(n: u32) -> Mesh {
        let mut mesh = Mesh::default();
        let mut lookup = std::collections::HashMap::new();
        let mut vertex = |p: [u32; 3], mesh: &mut Mesh| -> u32 {
            *lookup.entry(p).or_insert_with(|| {
                mesh.positions.push(p.map(|c| c as f32));
                mesh.positions.len() as u32 - 1
            })
        };
        for axis in 0..3 {
            for side in [0, n] {
                let (ua, va) = ((axis + 1) % 3, (axis + 2) % 3);
                for i in 0..n {
                    for j in 0..n {
                        let corner = |di: u32, dj: u32| {
                            let mut p = [0; 3];
                            p[axis] = side;
                            p[ua] = i + di;
                            p[va] = j + dj;
                            p
                        };
                        let q = [corner(0, 0), corner(1, 0), corner(1, 1), corner(0, 1)]
                            .map(|p| vertex(p, &mut mesh));
                        // (ua, va, axis) is right-handed, so (q0, q1, q2) faces +axis.
                        let tris = if side == n {
                            [q[0], q[1], q[2], q[0], q[2], q[3]]
                        } else {
                            [q[0], q[2], q[1], q[0], q[3], q[2]]
                        };
                        mesh.indices.extend(tris);
                    }
                }
            }
        }
        mesh
    }

    /// A torus as an m x n grid with wrap-around, consistently oriented.
    fn torus(m: u32, n: u32) -> Mesh {
        let mut positions = Vec::new();
        for i in 0..m {
            for j in 0..n {
                let (a, b) = (
                    i as f32 / m as f32 * std::f32::consts::TAU,
                    j as f32 / n as f32 * std::f32::consts::TAU,
                );
                let r = 2.0 + b.cos();
                positions.push([r * a.cos(), r * a.sin(), b.sin()]);
            }
        }
        let id = |i: u32, j: u32| (i % m) * n + (j % n);
        let mut indices = Vec::new();
        for i in 0..m {
            for j in 0..n {
                let q = [id(i, j), id(i + 1, j), id(i + 1, j + 1), id(i, j + 1)];
                indices.extend([q[0], q[1], q[2], q[0], q[2], q[3]]);
            }
        }
        Mesh::from_triangles(positions, indices)
    }

    fn assert_closed_sphere(mesh: &Mesh) {
        let r = validate(mesh, &never);
        assert!(r.is_watertight_manifold(), "{r:?}");
        assert_eq!(r.euler, 2, "{r:?}");
        assert_eq!(r.components, 1);
        assert_eq!(r.boundary_edges_on_box + r.boundary_edges_interior, 0);
        assert_eq!(
            r.mesh_edges * 2,
            mesh.triangle_count() * 3,
            "closed: E = 3F/2"
        );
        assert_eq!(r.zero_area_triangles, 0);
        assert_eq!(r.unreferenced_vertices, 0);
    }

    #[test]
    fn closed_polyhedra_are_watertight_spheres() {
        assert_closed_sphere(&tetrahedron());
        assert_closed_sphere(&octahedron());
        assert_closed_sphere(&cube(1));
        assert_closed_sphere(&cube(4));
    }

    #[test]
    fn torus_has_euler_characteristic_zero() {
        let r = validate(&torus(6, 5), &never);
        assert!(r.is_watertight_manifold(), "{r:?}");
        assert_eq!(r.euler, 0);
        assert_eq!(r.components, 1);
    }

    #[test]
    fn removing_a_triangle_opens_three_boundary_edges() {
        for mut mesh in [tetrahedron(), octahedron(), cube(2)] {
            mesh.indices.truncate(mesh.indices.len() - 3);
            let r = validate(&mesh, &never);
            assert_eq!(r.boundary_edges_interior, 3, "{r:?}");
            assert_eq!(r.boundary_edges_on_box, 0);
            assert!(!r.is_watertight_manifold());
            // A disk: Euler characteristic 1, and every vertex still a (half-)disk.
            assert_eq!(r.euler, 1);
            assert_eq!(r.non_manifold_vertices, 0);
            assert_eq!(r.orientation_errors, 0);

            let r = validate(&mesh, &always);
            assert_eq!((r.boundary_edges_on_box, r.boundary_edges_interior), (3, 0));
            assert!(
                r.is_watertight_manifold(),
                "open only on the domain boundary: {r:?}"
            );
        }
    }

    #[test]
    fn on_box_needs_both_ends_and_the_midpoint() {
        // An open square in the plane z = 0 split into two triangles; the closure accepts only
        // points with x = 0, so exactly the left edge (0,0)-(0,1) is on the box.
        let mesh = Mesh::from_triangles(
            vec![
                [0.0, 0.0, 0.0],
                [1.0, 0.0, 0.0],
                [1.0, 1.0, 0.0],
                [0.0, 1.0, 0.0],
            ],
            vec![0, 1, 2, 0, 2, 3],
        );
        let r = validate(&mesh, &|p| p[0] == 0.0);
        assert_eq!(
            (r.boundary_edges_on_box, r.boundary_edges_interior),
            (1, 3),
            "{r:?}"
        );
        // A closure true at every vertex but at no midpoint: no edge is on the box.
        let r = validate(&mesh, &|p| p[0] == p[0].round() && p[1] == p[1].round());
        assert_eq!(
            (r.boundary_edges_on_box, r.boundary_edges_interior),
            (0, 4),
            "{r:?}"
        );
        assert_eq!(r.mesh_edges, 5);
        assert_eq!(r.euler, 1);
    }

    #[test]
    fn flipping_one_triangle_gives_orientation_errors() {
        let mut mesh = octahedron();
        mesh.indices.swap(0, 1);
        let r = validate(&mesh, &never);
        assert_eq!(r.orientation_errors, 3, "{r:?}");
        assert!(!r.is_watertight_manifold());
        assert_eq!(r.non_manifold_vertices, 0);
        assert_eq!(r.euler, 2);
    }

    #[test]
    fn two_tetrahedra_sharing_a_vertex_make_one_non_manifold_vertex() {
        let mut mesh = tetrahedron();
        let other = tetrahedron();
        // Mirror the second tetrahedron through the origin (vertex 0), keeping orientation by
        // swapping two indices per triangle; vertex 0 is shared.
        mesh.positions
            .extend(other.positions[1..].iter().map(|p| p.map(|c| -c)));
        for t in other.triangles() {
            let m = t.map(|i| if i == 0 { 0 } else { i + 3 });
            mesh.indices.extend([m[0], m[2], m[1]]);
        }
        let r = validate(&mesh, &never);
        assert_eq!(r.non_manifold_vertices, 1, "{r:?}");
        assert_eq!(r.non_manifold_edges, 0);
        assert_eq!(r.orientation_errors, 0);
        // V = 7, E = 12, F = 8: 7 - 12 + 8 = 3 (two spheres, 2 + 2, glued at a point: minus 1).
        assert_eq!(r.euler, 3);
        // Triangles connect through the shared vertex.
        assert_eq!(r.components, 1);
        assert!(!r.is_watertight_manifold());
    }

    #[test]
    fn separate_pieces_are_separate_components() {
        let mut mesh = tetrahedron();
        let offset = mesh.positions.len() as u32;
        let other = octahedron();
        mesh.positions
            .extend(other.positions.iter().map(|p| p.map(|c| c + 5.0)));
        mesh.indices
            .extend(other.indices.iter().map(|i| i + offset));
        let r = validate(&mesh, &never);
        assert_eq!(r.components, 2);
        assert_eq!(r.euler, 4);
        assert!(r.is_watertight_manifold());
    }

    #[test]
    fn three_triangles_on_one_edge_make_it_non_manifold() {
        let mesh = Mesh::from_triangles(
            vec![
                [0.0, 0.0, 0.0],
                [1.0, 0.0, 0.0],
                [0.5, 1.0, 0.0],
                [0.5, -1.0, 0.0],
                [0.5, 0.0, 1.0],
            ],
            vec![0, 1, 2, 1, 0, 3, 0, 1, 4],
        );
        let r = validate(&mesh, &never);
        assert_eq!(r.non_manifold_edges, 1, "{r:?}");
        // Both ends of the shared edge have a link vertex of degree 3.
        assert_eq!(r.non_manifold_vertices, 2);
        assert_eq!(r.boundary_edges_interior, 6);
        assert_eq!(r.mesh_edges, 7);
    }

    #[test]
    fn duplicates_are_found_in_any_order() {
        let mut mesh = tetrahedron();
        mesh.indices.extend([2, 1, 0]); // reversed copy of (0, 2, 1)
        mesh.indices.extend([1, 3, 0]); // rotated copy of (0, 1, 3)
        mesh.indices.extend([3, 1, 0]); // a third copy of it
        let r = validate(&mesh, &never);
        assert_eq!(r.duplicate_triangles, 3, "{r:?}");
        assert!(!r.is_watertight_manifold());
    }

    #[test]
    fn zero_area_and_degenerate_triangles_are_counted() {
        let mut mesh = tetrahedron();
        mesh.positions
            .extend([[2.0, 0.0, 0.0], [3.0, 0.0, 0.0], [4.0, 0.0, 0.0], [9.0; 3]]);
        // Collinear corners (distinct indices), then a repeated index.
        mesh.indices.extend([4, 5, 6, 0, 0, 1]);
        let r = validate(&mesh, &never);
        assert_eq!(r.zero_area_triangles, 2, "{r:?}");
        assert_eq!(r.unreferenced_vertices, 1);
        // The collinear triangle is a separate open piece: 3 interior boundary edges.
        assert_eq!(r.boundary_edges_interior, 3);
        assert_eq!(r.components, 2);
        assert_eq!(r.euler, 3);
    }

    #[test]
    fn non_finite_and_out_of_range_input_is_reported_not_panicked_on() {
        let mut mesh = tetrahedron();
        mesh.positions[3] = [f32::NAN, 0.0, f32::INFINITY];
        mesh.indices.extend([0, 1, 100]);
        let r = validate(&mesh, &never);
        assert_eq!(r.non_finite_vertices, 1);
        assert_eq!(r.out_of_range_triangles, 1);
        assert_eq!(r.euler, 2);
        assert!(!r.is_watertight_manifold());
        assert_eq!(
            validate(&Mesh::default(), &never),
            ValidationReport::default()
        );
    }

    #[test]
    fn bunny_from_data_is_a_closed_sphere() {
        let path = concat!(env!("CARGO_MANIFEST_DIR"), "/../../data/bunny.obj");
        let Ok(text) = std::fs::read_to_string(path) else {
            panic!("cannot read {path}");
        };
        let faces = text.lines().filter(|l| l.starts_with("f ")).count();
        match crate::io::read_obj(path) {
            Ok(mesh) => {
                assert_eq!(mesh.triangle_count(), faces);
                let r = validate(&mesh, &never);
                assert!(r.is_watertight_manifold(), "{r:?}");
                assert_eq!((r.euler, r.components), (2, 1));
            }
            Err(e) => panic!("{e}"),
        }
    }

    /// A deterministic shuffle (for relabelling tests) driven by a seed.
    fn permutation(n: usize, seed: u64) -> Vec<u32> {
        let mut p: Vec<u32> = (0..n as u32).collect();
        let mut s = seed | 1;
        for i in (1..n).rev() {
            s ^= s << 13;
            s ^= s >> 7;
            s ^= s << 17;
            p.swap(i, (s % (i as u64 + 1)) as usize);
        }
        p
    }

    proptest! {
        #[test]
        fn report_does_not_depend_on_labels_or_triangle_order(
            removed in prop::collection::vec(0usize..48, 0..6),
            flipped in prop::collection::vec(0usize..48, 0..4),
            seed in any::<u64>(),
            rotate in 0usize..3,
        ) {
            let mut mesh = cube(2);
            for &f in &flipped {
                mesh.indices.swap(3 * f, 3 * f + 1);
            }
            let mut removed = removed;
            removed.sort_unstable();
            removed.dedup();
            for &t in removed.iter().rev() {
                mesh.indices.drain(3 * t..3 * t + 3);
            }
            let base = validate(&mesh, &never);
            // Relabel vertices, shuffle triangles, rotate corners.
            let vp = permutation(mesh.vertex_count(), seed);
            let tp = permutation(mesh.triangle_count(), seed.rotate_left(17));
            let mut positions = vec![[0.0; 3]; mesh.vertex_count()];
            for (old, &new) in vp.iter().enumerate() {
                positions[new as usize] = mesh.positions[old];
            }
            let tris: Vec<[u32; 3]> = mesh.triangles().collect();
            let mut indices = Vec::new();
            for &t in &tp {
                let mut tri = tris[t as usize].map(|i| vp[i as usize]);
                tri.rotate_left(rotate);
                indices.extend(tri);
            }
            let other = validate(&Mesh::from_triangles(positions, indices), &never);
            prop_assert_eq!(&base, &other);
            // Every triangle side lies on an edge: 3F = 2 (interior edges) + (boundary edges).
            let boundary = base.boundary_edges_interior + base.boundary_edges_on_box;
            if base.non_manifold_edges == 0 {
                let sides = 2 * (base.mesh_edges - boundary) + boundary;
                prop_assert_eq!(3 * mesh.triangle_count(), sides);
            }
        }

        #[test]
        fn arbitrary_index_soup_never_panics(
            indices in prop::collection::vec(0u32..12, 0..60),
            extra in 0usize..4,
        ) {
            let positions: Vec<[f32; 3]> =
                (0..8 + extra).map(|i| [i as f32, (i * i % 7) as f32, (i % 3) as f32]).collect();
            let mesh = Mesh::from_triangles(positions, indices);
            let r = validate(&mesh, &|p| p[2] == 0.0);
            prop_assert!(r.components <= mesh.vertex_count());
            prop_assert!(r.duplicate_triangles + r.out_of_range_triangles <= mesh.triangle_count());
            // Duplicates, counted the slow way: in-range sorted triples seen before.
            let mut seen = std::collections::HashSet::new();
            let brute_force = mesh
                .triangles()
                .filter(|t| t.iter().all(|&i| (i as usize) < mesh.vertex_count()))
                .filter(|t| {
                    let mut key = *t;
                    key.sort_unstable();
                    !seen.insert(key)
                })
                .count();
            prop_assert_eq!(r.duplicate_triangles, brute_force);
            let q = crate::quality(&mesh);
            prop_assert_eq!(q.zero_area_triangles, r.zero_area_triangles);
            prop_assert!(q.ar_mean.is_finite() && q.area_total.is_finite());
        }
    }
}
