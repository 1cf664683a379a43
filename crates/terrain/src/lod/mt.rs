//! Marching tetrahedra on the multiresolution mesh, with globally keyed crossings.
//!
//! ```text
//!   inside: f < 0.  Per tet (canonical vertex order, positive volume), by inside set:
//!     {i}         (i,j,k,l) even permutation of (0,1,2,3): triangle (ij, ik, il)
//!     {o} outside (o,j,k,l) even:                           triangle (oj, ol, ok)
//!     {i,j}       (i,j,k,l) even:                           (ik, jl, jk) + (ik, il, jl)
//!   every triangle faces the outside (f >= 0)
//!   crossing key = its edge's two lattice points (lo, hi) sorted;  position from (lo, hi,
//!   f(lo), f(hi)) alone:  t = f(lo) / (f(lo) - f(hi)),  p = lo + t (hi - lo)   (f64)
//!   normal = the field's gradient at p by central differences (step h / 4), normalised
//!            (where those differences vanish: the edge's direction lo -> hi towards f >= 0)
//! ```
//!
//! A crossing's position and normal are functions of its key and the field only, so any
//! chunk that computes it gets the same bits; welding chunk meshes by key ([`weld`]) is exact
//! and the shading has no seam where the level changes (the two sides share the vertex).
//! Samples are taken at the level a tet is meshed at: a coarse sample is a fine sample.

use foldhash::HashMap;

use glam::{DVec3, Vec3};
use rmt_fields::ScalarField;
use rmt_mesh::Mesh;

use super::lattice::Point;
use super::mesh::MeshTet;

/// Where the lattice sits in the world: lattice point `p` (in `u`) is at `origin + p h / 2`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LodFrame {
    /// World position of lattice point 0.
    pub origin: Vec3,
    /// The finest cell edge `h` (world units).
    pub h: f32,
}

impl LodFrame {
    /// World position of a lattice point (f64 arithmetic, rounded once).
    pub fn world(&self, p: Point) -> Vec3 {
        self.world_f64(DVec3::new(
            f64::from(p[0]),
            f64::from(p[1]),
            f64::from(p[2]),
        ))
    }

    fn world_f64(&self, p: DVec3) -> Vec3 {
        (self.origin.as_dvec3() + p * (f64::from(self.h) * 0.5)).as_vec3()
    }
}

/// The surface of some tets: vertices named by their crossing keys.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct ChunkMesh {
    /// Per vertex, its crossing's edge `(lo, hi)` in lattice points.
    pub keys: Vec<[Point; 2]>,
    /// Per vertex, its world position.
    pub positions: Vec<[f32; 3]>,
    /// Per vertex, the unit normal (the field's gradient, or the crossed edge's direction
    /// where the central differences vanish).
    pub normals: Vec<[f32; 3]>,
    /// Three vertex indices per triangle, facing the outside (`f >= 0`).
    pub indices: Vec<u32>,
    /// Field samples taken (lattice points; normals take six more per vertex).
    pub samples: usize,
}

impl ChunkMesh {
    /// Bytes held by the vectors.
    pub fn bytes(&self) -> usize {
        self.keys.capacity() * std::mem::size_of::<[Point; 2]>()
            + (self.positions.capacity() + self.normals.capacity()) * 12
            + self.indices.capacity() * 4
    }

    /// Triangles.
    pub fn triangles(&self) -> usize {
        self.indices.len() / 3
    }
}

/// The even permutation of `(0, 1, 2, 3)` that starts with each vertex.
const EVEN: [[usize; 4]; 4] = [[0, 1, 2, 3], [1, 0, 3, 2], [2, 3, 0, 1], [3, 2, 1, 0]];

/// The triangles of one tet with inside mask `mask` (bit `i` for vertex `i`), as triples of
/// tet edges `(a, b)`; returns how many (0 to 2).
pub fn case_triangles(mask: u8, out: &mut [[(usize, usize); 3]; 2]) -> usize {
    let n = mask.count_ones();
    match n {
        1 | 3 => {
            let lone = (0..4)
                .find(|&v| (mask >> v & 1 == 1) == (n == 1))
                .unwrap_or(0);
            let [x, j, k, l] = EVEN[lone];
            out[0] = if n == 1 {
                [(x, j), (x, k), (x, l)]
            } else {
                [(x, j), (x, l), (x, k)]
            };
            1
        }
        2 => {
            let ins: Vec<usize> = (0..4).filter(|&v| mask >> v & 1 == 1).collect();
            let outs: Vec<usize> = (0..4).filter(|&v| mask >> v & 1 == 0).collect();
            let (i, j) = (ins[0], ins[1]);
            let (mut k, mut l) = (outs[0], outs[1]);
            let p = [i, j, k, l];
            let inversions = (0..4)
                .flat_map(|a| (a + 1..4).map(move |b| (a, b)))
                .filter(|&(a, b)| p[a] > p[b])
                .count();
            if inversions % 2 == 1 {
                std::mem::swap(&mut k, &mut l);
            }
            out[0] = [(i, k), (j, l), (j, k)];
            out[1] = [(i, k), (i, l), (j, l)];
            2
        }
        _ => 0,
    }
}

/// Marching tetrahedra over `tets`. Deterministic: vertices in order of first use, tets in
/// the given order.
pub fn march(tets: &[MeshTet], field: &dyn ScalarField, frame: &LodFrame) -> ChunkMesh {
    // Sample every distinct lattice point once, in order of first use.
    let mut point_index: HashMap<Point, u32> =
        HashMap::with_capacity_and_hasher(tets.len(), Default::default());
    let mut points: Vec<Vec3> = Vec::with_capacity(tets.len());
    let mut corner: Vec<u32> = Vec::with_capacity(tets.len() * 4);
    for t in tets {
        for p in t.tet {
            let next = points.len() as u32;
            let i = *point_index.entry(p).or_insert_with(|| {
                points.push(frame.world(p));
                next
            });
            corner.push(i);
        }
    }
    let mut values = vec![0f32; points.len()];
    field.sample_batch(&points, &mut values);
    let mut mesh = ChunkMesh {
        samples: points.len(),
        ..ChunkMesh::default()
    };
    let mut crossing: HashMap<[Point; 2], u32> = HashMap::default();
    let mut tris = [[(0usize, 0usize); 3]; 2];
    let eps = frame.h * 0.25;
    let mut probe = [Vec3::ZERO; 6];
    let mut probe_values = [0f32; 6];
    for (ti, t) in tets.iter().enumerate() {
        let ids = &corner[4 * ti..4 * ti + 4];
        let f: [f32; 4] = std::array::from_fn(|v| values[ids[v] as usize]);
        let mask = (0..4).fold(0u8, |m, v| m | u8::from(f[v] < 0.0) << v);
        let n = case_triangles(mask, &mut tris);
        for tri in &tris[..n] {
            for &(a, b) in tri {
                let (pa, pb) = (t.tet[a], t.tet[b]);
                let (lo, hi, flo, fhi) = if pa < pb {
                    (pa, pb, f[a], f[b])
                } else {
                    (pb, pa, f[b], f[a])
                };
                let key = [lo, hi];
                let next = mesh.keys.len() as u32;
                let v = *crossing.entry(key).or_insert_with(|| {
                    let s = f64::from(flo) / (f64::from(flo) - f64::from(fhi));
                    let dl = DVec3::new(f64::from(lo[0]), f64::from(lo[1]), f64::from(lo[2]));
                    let dh = DVec3::new(f64::from(hi[0]), f64::from(hi[1]), f64::from(hi[2]));
                    let p = frame.world_f64(dl + (dh - dl) * s);
                    for (axis, pair) in probe.chunks_exact_mut(2).enumerate() {
                        let mut d = Vec3::ZERO;
                        d[axis] = eps;
                        pair[0] = p + d;
                        pair[1] = p - d;
                    }
                    field.sample_batch(&probe, &mut probe_values);
                    let g = Vec3::new(
                        probe_values[0] - probe_values[1],
                        probe_values[2] - probe_values[3],
                        probe_values[4] - probe_values[5],
                    );
                    // Where the differences vanish (flat, quantised fields), the edge's own
                    // direction towards the outside: still a function of the key alone.
                    let g = if g.length_squared() > 0.0 && g.is_finite() {
                        g
                    } else {
                        (dh - dl).as_vec3() * (fhi - flo).signum()
                    };
                    mesh.keys.push(key);
                    mesh.positions.push(p.to_array());
                    mesh.normals.push(g.normalize_or_zero().to_array());
                    next
                });
                mesh.indices.push(v);
            }
        }
    }
    mesh
}

/// Welds chunk meshes (in the given order) into one mesh by crossing key: vertices in order
/// of first appearance. Returns the mesh and each vertex's key.
pub fn weld<'a>(chunks: impl IntoIterator<Item = &'a ChunkMesh>) -> (Mesh, Vec<[Point; 2]>) {
    let mut index: HashMap<[Point; 2], u32> = HashMap::default();
    let mut mesh = Mesh::default();
    let mut keys = Vec::new();
    let mut local = Vec::new();
    for c in chunks {
        local.clear();
        for (v, key) in c.keys.iter().enumerate() {
            let next = keys.len() as u32;
            let id = *index.entry(*key).or_insert_with(|| {
                keys.push(*key);
                mesh.positions.push(c.positions[v]);
                mesh.normals.push(c.normals[v]);
                next
            });
            local.push(id);
        }
        mesh.indices
            .extend(c.indices.iter().map(|&i| local[i as usize]));
    }
    (mesh, keys)
}

#[cfg(test)]
mod tests {
    use super::super::lattice::EDGES;
    use super::*;

    #[test]
    fn cases_face_the_outside_and_use_crossed_edges_only() {
        // The unit corner tet, positively oriented; crossings at edge midpoints.
        let t: [DVec3; 4] = [DVec3::ZERO, DVec3::X, DVec3::Y, DVec3::Z];
        let mut tris = [[(0usize, 0usize); 3]; 2];
        for mask in 0u8..16 {
            let n = case_triangles(mask, &mut tris);
            let expect = match mask.count_ones() {
                0 | 4 => 0,
                2 => 2,
                _ => 1,
            };
            assert_eq!(n, expect);
            let ins = |v: usize| mask >> v & 1 == 1;
            let inside_mean = (0..4).filter(|&v| ins(v)).map(|v| t[v]).sum::<DVec3>();
            let outside_mean = (0..4).filter(|&v| !ins(v)).map(|v| t[v]).sum::<DVec3>();
            let dir = outside_mean / (4 - mask.count_ones()).max(1) as f64
                - inside_mean / mask.count_ones().max(1) as f64;
            for tri in &tris[..n] {
                for &(a, b) in tri {
                    assert_ne!(ins(a), ins(b), "edge {a}{b} is not crossed");
                    assert!(EDGES.contains(&(a.min(b), a.max(b))));
                }
                let p = tri.map(|(a, b)| (t[a] + t[b]) * 0.5);
                let nrm = (p[1] - p[0]).cross(p[2] - p[0]);
                assert!(nrm.dot(dir) > 0.0, "mask {mask:04b} faces inwards");
            }
        }
    }
}
