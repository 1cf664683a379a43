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
//!   normal = the field's gradient at p from 4 probes at the corners of a regular tet,
//!            p + (h / 4) k for k in PROBE_DIRECTIONS: g = sum_k k f(p + (h / 4) k), second
//!            order like central differences (6 probes); normalised (where g vanishes: the
//!            edge's direction lo -> hi towards f >= 0)
//! ```
//!
//! Speed without changing a bit: lattice points are numbered on a flat grid over the tets'
//! box and sampled in rows, the triangles of each inside mask come from a table, all normal
//! probes of a chunk go to the field in one batch (a batch gives every point the bits a single
//! sample gives), a re-meshed chunk takes the normals of the crossings it keeps from its last
//! surface ([`march_reusing`]), and
//! a chunk whose box the field's bound ([`ScalarField::side`]) puts on one side of 0 is not
//! sampled at all (its surface is empty either way).
//!
//! A crossing's position and normal are functions of its key and the field only, so any
//! chunk that computes it gets the same bits; welding chunk meshes by key ([`weld`]) is exact
//! and the shading has no seam where the level changes (the two sides share the vertex).
//! Samples are taken at the level a tet is meshed at: a coarse sample is a fine sample.

use foldhash::HashMap;

use glam::{DVec3, Vec3};
use rmt_fields::ScalarField;
use rmt_mesh::Mesh;

use super::error::LodError;
use super::lattice::{cell_size, Point};
use super::level_map::{ChunkKey, LevelMap};
use super::mesh::{chunk_tets, MeshTet};
use super::morph::Morph;
use super::tet_cache::{EncodedTets, TetCache};

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
    /// where the probes' differences vanish).
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

/// One inside mask's triangles (as tet edges) and how many there are.
type Case = ([[(usize, usize); 3]; 2], usize);

/// The triangles of every inside mask ([`case_triangles`]), computed once.
fn case_table() -> &'static [Case; 16] {
    static TABLE: std::sync::OnceLock<[Case; 16]> = std::sync::OnceLock::new();
    TABLE.get_or_init(|| {
        std::array::from_fn(|mask| {
            let mut tris = [[(0usize, 0usize); 3]; 2];
            let n = case_triangles(mask as u8, &mut tris);
            (tris, n)
        })
    })
}

/// The distinct lattice points of some tets, numbered in order of first use, on a flat grid
/// over their bounding box (at the largest power-of-two step dividing every offset), `x`
/// fastest: the grid's order is rows of equal `y` and `z`.
struct PointGrid {
    lo: Point,
    shift: u32,
    n: [usize; 3],
    slot: Vec<u32>,
}

impl PointGrid {
    fn new(tets: &[MeshTet]) -> Option<Self> {
        let first = tets.first()?.tet[0];
        let (mut lo, mut hi) = (first, first);
        for p in tets.iter().flat_map(|t| &t.tet) {
            for i in 0..3 {
                lo[i] = lo[i].min(p[i]);
                hi[i] = hi[i].max(p[i]);
            }
        }
        let mut bits = 0u32;
        for p in tets.iter().flat_map(|t| &t.tet) {
            for i in 0..3 {
                bits |= (p[i] - lo[i]) as u32;
            }
        }
        let shift = bits.trailing_zeros().min(31);
        let n: [usize; 3] = std::array::from_fn(|i| ((hi[i] - lo[i]) as u32 >> shift) as usize + 1);
        let cells = n[0].checked_mul(n[1])?.checked_mul(n[2])?;
        // A sparse set of points (far apart tets) would make a huge grid: use the hash then.
        if cells > 64 * tets.len() + 4096 {
            return None;
        }
        Some(PointGrid {
            lo,
            shift,
            n,
            slot: vec![u32::MAX; cells],
        })
    }

    fn slot(&mut self, p: Point) -> &mut u32 {
        let c: [usize; 3] =
            std::array::from_fn(|i| ((p[i] - self.lo[i]) as u32 >> self.shift) as usize);
        &mut self.slot[(c[2] * self.n[1] + c[1]) * self.n[0] + c[0]]
    }

    /// The number of `p`, when it is one of the points.
    fn get(&self, p: Point) -> Option<u32> {
        let mut c = [0usize; 3];
        for i in 0..3 {
            let d = p[i].checked_sub(self.lo[i]).filter(|&d| d >= 0)? as u32;
            if d & ((1u32 << self.shift) - 1) != 0 {
                return None;
            }
            c[i] = (d >> self.shift) as usize;
            if c[i] >= self.n[i] {
                return None;
            }
        }
        let i = self.slot[(c[2] * self.n[1] + c[1]) * self.n[0] + c[0]];
        (i != u32::MAX).then_some(i)
    }

    /// The points' numbers in rows: `z`, then `y`, then `x` ascending.
    fn rows(&self) -> Vec<u32> {
        self.slot
            .iter()
            .copied()
            .filter(|&i| i != u32::MAX)
            .collect()
    }
}

/// The numbers of a chunk's lattice points, on a grid or in a hash.
enum PointIndex {
    Grid(PointGrid),
    Map(HashMap<Point, u32>),
}

impl PointIndex {
    fn get(&self, p: Point) -> Option<u32> {
        match self {
            PointIndex::Grid(g) => g.get(p),
            PointIndex::Map(m) => m.get(&p).copied(),
        }
    }
}

/// Where a normal's probes sit around a crossing, in steps of `h / 4`: the corners of a
/// regular tet centred on it. Their sum is 0 and the sum of their outer products is 4 I, so
/// `sum_k k f(p + e k) = 4 e grad f(p) + O(e^3)`: the gradient's direction to second order,
/// from 4 samples.
pub const PROBE_DIRECTIONS: [[f32; 3]; 4] = [
    [1.0, 1.0, 1.0],
    [1.0, -1.0, -1.0],
    [-1.0, 1.0, -1.0],
    [-1.0, -1.0, 1.0],
];

/// Marching tetrahedra over `tets`. Deterministic: vertices in order of first use, tets in
/// the given order. When the field's bound ([`ScalarField::side`]) puts the tets' bounding
/// box on one side of 0, the surface is empty and nothing is sampled.
pub fn march(tets: &[MeshTet], field: &dyn ScalarField, frame: &LodFrame) -> ChunkMesh {
    march_reusing(tets, field, frame, None, None)
}

/// [`march`] on the values `morph` makes of the field's ([`Morph::apply`]; the field's own
/// without one), taking the normal of every crossing that `before` (a surface marched over the
/// same field) also has, at the same position, from it instead of probing the field again: a
/// crossing's normal is a function of its position and the field alone, so the surface is the
/// same, bit for bit.
pub fn march_reusing(
    tets: &[MeshTet],
    field: &dyn ScalarField,
    frame: &LodFrame,
    before: Option<&ChunkMesh>,
    morph: Option<&Morph>,
) -> ChunkMesh {
    if let Some((lo, hi)) =
        tets.iter()
            .map(|t| super::lattice::bbox(&t.tet))
            .reduce(|(a, b), (c, d)| {
                (
                    std::array::from_fn(|i| a[i].min(c[i])),
                    std::array::from_fn(|i| b[i].max(d[i])),
                )
            })
    {
        // World positions round monotonically, so the box holds every sample point (and
        // every parent a morphed value reads, within the morph's reach).
        let r = morph.map_or(0, |m| m.reach(lo.map(i64::from), hi.map(i64::from)) as i32);
        let (lo, hi) = (
            lo.map(|v| v.saturating_sub(r)),
            hi.map(|v| v.saturating_add(r)),
        );
        if field.side(frame.world(lo), frame.world(hi), 0.0).is_some() {
            return ChunkMesh::default();
        }
    }
    // Sample every distinct lattice point once, in order of first use.
    let mut points: Vec<Vec3> = Vec::with_capacity(tets.len());
    let mut corner: Vec<u32> = Vec::with_capacity(tets.len() * 4);
    // The lattice points too, when a morph needs them.
    let mut lattice: Vec<Point> = Vec::new();
    let keep = morph.is_some();
    let (rows, index) = match PointGrid::new(tets) {
        Some(mut grid) => {
            for t in tets {
                for p in t.tet {
                    let slot = grid.slot(p);
                    if *slot == u32::MAX {
                        *slot = points.len() as u32;
                        points.push(frame.world(p));
                        if keep {
                            lattice.push(p);
                        }
                    }
                    corner.push(*slot);
                }
            }
            (grid.rows(), PointIndex::Grid(grid))
        }
        None => {
            let mut point_index: HashMap<Point, u32> =
                HashMap::with_capacity_and_hasher(tets.len(), Default::default());
            for t in tets {
                for p in t.tet {
                    let next = points.len() as u32;
                    let i = *point_index.entry(p).or_insert_with(|| {
                        points.push(frame.world(p));
                        if keep {
                            lattice.push(p);
                        }
                        next
                    });
                    corner.push(i);
                }
            }
            let mut rows: Vec<(Point, u32)> = point_index.iter().map(|(&p, &i)| (p, i)).collect();
            rows.sort_unstable_by_key(|&([x, y, z], _)| [z, y, x]);
            (
                rows.into_iter().map(|(_, i)| i).collect(),
                PointIndex::Map(point_index),
            )
        }
    };
    // Sampled in rows of equal y and z (a field that shares work along rows, as the noises
    // do, pays once per row); a value depends on its point alone, so the bits are the same.
    let in_rows: Vec<Vec3> = rows.iter().map(|&i| points[i as usize]).collect();
    let mut sampled = vec![0f32; points.len()];
    field.sample_batch(&in_rows, &mut sampled);
    let mut values = vec![0f32; points.len()];
    for (&i, &v) in rows.iter().zip(&sampled) {
        values[i as usize] = v;
    }
    if let Some(m) = morph {
        let fields = values.clone();
        let known = |p: Point| index.get(p).map(|i| fields[i as usize]);
        m.apply(&lattice, &mut values, &known, field, &|p| frame.world(p));
    }
    let mut mesh = ChunkMesh {
        samples: points.len(),
        ..ChunkMesh::default()
    };
    // Crossings by their edge's two point numbers; positions now, normals after one batch of
    // probes (a batch gives every point the bits a single sample would).
    // The cases first: the crossed tets bound the crossings (each has 3 or 4 crossed edges,
    // and an edge is shared by 4 to 6 tets), so the table is sized once.
    let masks: Vec<u8> = corner
        .chunks_exact(4)
        .map(|ids| (0..4).fold(0u8, |m, v| m | u8::from(values[ids[v] as usize] < 0.0) << v))
        .collect();
    let crossed = masks.iter().filter(|&&m| m != 0 && m != 15).count();
    let mut crossing: HashMap<u64, u32> =
        HashMap::with_capacity_and_hasher(crossed, Default::default());
    let mut ends: Vec<(Point, Point, f32, f32)> = Vec::with_capacity(crossed);
    let table = case_table();
    for (ti, t) in tets.iter().enumerate() {
        let ids = &corner[4 * ti..4 * ti + 4];
        let f: [f32; 4] = std::array::from_fn(|v| values[ids[v] as usize]);
        let (tris, n) = &table[masks[ti] as usize];
        for tri in &tris[..*n] {
            for &(a, b) in tri {
                let (pa, pb) = (t.tet[a], t.tet[b]);
                let (lo, hi, flo, fhi, ilo, ihi) = if pa < pb {
                    (pa, pb, f[a], f[b], ids[a], ids[b])
                } else {
                    (pb, pa, f[b], f[a], ids[b], ids[a])
                };
                let key = u64::from(ilo) << 32 | u64::from(ihi);
                let next = mesh.keys.len() as u32;
                let v = *crossing.entry(key).or_insert_with(|| {
                    let s = f64::from(flo) / (f64::from(flo) - f64::from(fhi));
                    let dl = DVec3::new(f64::from(lo[0]), f64::from(lo[1]), f64::from(lo[2]));
                    let dh = DVec3::new(f64::from(hi[0]), f64::from(hi[1]), f64::from(hi[2]));
                    let p = frame.world_f64(dl + (dh - dl) * s);
                    mesh.keys.push([lo, hi]);
                    mesh.positions.push(p.to_array());
                    ends.push((lo, hi, flo, fhi));
                    next
                });
                mesh.indices.push(v);
            }
        }
    }
    // Each crossing's normal from `before` (by key, at the same position), else from its
    // probes.
    let known: HashMap<[Point; 2], u32> = before.map_or_else(HashMap::default, |b| {
        b.keys
            .iter()
            .enumerate()
            .map(|(i, k)| (*k, i as u32))
            .collect()
    });
    let from_before: Vec<Option<u32>> = mesh
        .keys
        .iter()
        .zip(&mesh.positions)
        .map(|(k, p)| {
            known.get(k).copied().filter(|&i| {
                before.is_some_and(|b| {
                    b.positions[i as usize].map(f32::to_bits) == p.map(f32::to_bits)
                })
            })
        })
        .collect();
    let eps = frame.h * 0.25;
    let probed = from_before.iter().filter(|b| b.is_none()).count();
    let mut probe = Vec::with_capacity(PROBE_DIRECTIONS.len() * probed);
    for (p, _) in mesh
        .positions
        .iter()
        .zip(&from_before)
        .filter(|(_, b)| b.is_none())
    {
        let p = Vec3::from(*p);
        probe.extend(PROBE_DIRECTIONS.map(|k| p + Vec3::from(k) * eps));
    }
    let mut probe_values = vec![0f32; probe.len()];
    field.sample_batch(&probe, &mut probe_values);
    let mut pv = probe_values.chunks_exact(PROBE_DIRECTIONS.len());
    mesh.normals = from_before
        .iter()
        .zip(&ends)
        .map(|(b, &(lo, hi, flo, fhi))| {
            if let (Some(i), Some(before)) = (b, before) {
                return before.normals[*i as usize];
            }
            let pv = pv.next().unwrap_or(&[0.0; 4]);
            let g = PROBE_DIRECTIONS
                .iter()
                .zip(pv)
                .fold(Vec3::ZERO, |g, (&k, &v)| g + Vec3::from(k) * v);
            // Where the differences vanish (flat, quantised fields), the edge's own direction
            // towards the outside: still a function of the key alone.
            let g = if g.length_squared() > 0.0 && g.is_finite() {
                g
            } else {
                let dl = DVec3::new(f64::from(lo[0]), f64::from(lo[1]), f64::from(lo[2]));
                let dh = DVec3::new(f64::from(hi[0]), f64::from(hi[1]), f64::from(hi[2]));
                (dh - dl).as_vec3() * (fhi - flo).signum()
            };
            g.normalize_or_zero().to_array()
        })
        .collect();
    // The world keeps the surface: hold no spare capacity.
    mesh.keys.shrink_to_fit();
    mesh.positions.shrink_to_fit();
    mesh.indices.shrink_to_fit();
    mesh
}

/// The surface of one chunk of `map`: marching tetrahedra over [`chunk_tets`], or nothing
/// (without building the tets) when the field's bound puts the chunk's box grown by one cell
/// of its level on one side of 0. Every tet a chunk owns lies in that box: its centroid is in
/// the chunk, and it lies in a red-forest leaf of the chunk's level or finer (a coarser tet
/// meeting the chunk is refined), whose extent along each axis is at most one cell.
pub fn mesh_chunk(
    map: &LevelMap,
    chunk: &ChunkKey,
    field: &dyn ScalarField,
    frame: &LodFrame,
) -> Result<ChunkMesh, LodError> {
    mesh_chunk_with(map, chunk, field, frame, None, None)
}

/// [`mesh_chunk`] on the values `morph` makes of the field's, taking the tets from `cache`
/// when one is given (the same tets, so the same surface).
pub fn mesh_chunk_with(
    map: &LevelMap,
    chunk: &ChunkKey,
    field: &dyn ScalarField,
    frame: &LodFrame,
    cache: Option<&TetCache>,
    morph: Option<&Morph>,
) -> Result<ChunkMesh, LodError> {
    if empty_box(map, chunk, field, frame, morph) {
        return Ok(ChunkMesh::default());
    }
    let tets = match cache {
        Some(c) => c.chunk_tets(map, chunk)?,
        None => chunk_tets(map, chunk)?,
    };
    Ok(march_reusing(&tets, field, frame, None, morph))
}

/// What [`remesh_chunk`] did.
#[derive(Debug)]
pub enum Remeshed {
    /// The chunk's tets are those `previous` encodes: its surface is the same (the field
    /// being unchanged), and nothing was marched.
    Same,
    /// The new surface, with its tets' encoding when they have one (none for an empty box).
    Meshed(ChunkMesh, Option<EncodedTets>),
}

/// What a chunk's last meshing left, for [`remesh_chunk`].
#[derive(Clone, Copy, Debug, Default)]
pub struct Last<'a> {
    /// The encoding of the tets its surface was marched from, when the values it was marched
    /// on are the ones it is re-meshed on (none when they can differ).
    pub tets: Option<&'a EncodedTets>,
    /// Its surface, over the same field.
    pub mesh: Option<&'a ChunkMesh>,
}

/// [`mesh_chunk_with`] for a chunk last meshed as `last` says: [`Remeshed::Same`] when its
/// tets under `map` are the ones `last.tets` encodes, else the new surface, with the normals of
/// the crossings it shares with `last.mesh` taken from it ([`march_reusing`]).
pub fn remesh_chunk(
    map: &LevelMap,
    chunk: &ChunkKey,
    field: &dyn ScalarField,
    frame: &LodFrame,
    cache: &TetCache,
    last: Last<'_>,
    morph: Option<&Morph>,
) -> Result<Remeshed, LodError> {
    let (previous, before) = (last.tets, last.mesh);
    if empty_box(map, chunk, field, frame, morph) {
        return Ok(Remeshed::Meshed(ChunkMesh::default(), None));
    }
    let tets = cache.encoded_tets(map, chunk)?;
    if let (Some(p), Some(e)) = (previous, &tets.encoded) {
        if p == e {
            return Ok(Remeshed::Same);
        }
    }
    let encoded = tets.encoded.clone();
    Ok(Remeshed::Meshed(
        march_reusing(&tets.into_tets(), field, frame, before, morph),
        encoded,
    ))
}

/// Whether the field's bound puts `chunk`'s box grown by one cell of its level (and the
/// morph's reach) on one side of 0 (see [`mesh_chunk`]): a morphed value is a mean of values
/// within the reach.
fn empty_box(
    map: &LevelMap,
    chunk: &ChunkKey,
    field: &dyn ScalarField,
    frame: &LodFrame,
    morph: Option<&Morph>,
) -> bool {
    let (lo, hi) = chunk.bounds(map.geometry());
    let s = cell_size(chunk.level);
    let s = s + morph.map_or(0, |m| m.reach(lo.map(|v| v - s), hi.map(|v| v + s)));
    let corner = |v: [i64; 3]| -> Option<Point> {
        let p: [i32; 3] = std::array::from_fn(|i| i32::try_from(v[i]).unwrap_or(i32::MAX));
        p.iter().all(|&c| c != i32::MAX).then_some(p)
    };
    map.contains(chunk)
        && match (corner(lo.map(|v| v - s)), corner(hi.map(|v| v + s))) {
            (Some(a), Some(b)) => field.side(frame.world(a), frame.world(b), 0.0).is_some(),
            _ => false,
        }
}

/// Whether two lists of chunk surfaces are the same, bit for bit: keys, triangles, and every
/// position's and normal's bits (stricter than `==` on floats: it tells `-0.0` from `0.0`).
pub fn same_bits(a: &[ChunkMesh], b: &[ChunkMesh]) -> bool {
    let bits = |v: &[[f32; 3]]| -> Vec<u32> { v.iter().flatten().map(|x| x.to_bits()).collect() };
    a.len() == b.len()
        && a.iter().zip(b).all(|(x, y)| {
            x.keys == y.keys
                && x.indices == y.indices
                && bits(&x.positions) == bits(&y.positions)
                && bits(&x.normals) == bits(&y.normals)
        })
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
    use super::super::level_map::LodGeometry;
    use super::*;
    use std::sync::atomic::{AtomicUsize, Ordering};

    /// A field that counts its samples.
    struct Counted<F>(F, AtomicUsize);

    impl<F: ScalarField> ScalarField for Counted<F> {
        fn sample(&self, p: Vec3) -> f32 {
            self.1.fetch_add(1, Ordering::Relaxed);
            self.0.sample(p)
        }
    }

    /// Reusing a surface's normals gives the surface marched from scratch, bit for bit, and
    /// probes only the crossings the old surface lacks.
    #[test]
    fn reused_normals_equal_probed_ones() {
        let g = LodGeometry::new(2, 4, [2, 1, 2]).unwrap();
        let frame = LodFrame {
            origin: Vec3::splat(-1.0),
            h: 1.0 / 8.0,
        };
        let field = Counted(rmt_fields::RandomField::from_seed(3), AtomicUsize::new(0));
        let bits = |m: &ChunkMesh| {
            let f = |v: &Vec<[f32; 3]>| v.iter().flat_map(|p| p.map(f32::to_bits)).collect();
            (
                m.keys.clone(),
                f(&m.positions),
                f(&m.normals),
                m.indices.clone(),
            )
        };
        type Bits = (Vec<[Point; 2]>, Vec<u32>, Vec<u32>, Vec<u32>);
        let (mut reused, mut saved) = (0, 0);
        // A finer chunk appears beside chunk 0 of level 1 as the maps change.
        let maps = [
            LevelMap::uniform(g, 1),
            LevelMap::build(g, |k| k.level == 2 || k.at[0] > 0),
            LevelMap::random(g, 5, 0.5),
        ];
        for (a, b) in maps.iter().zip(maps.iter().skip(1)) {
            for k in b.chunks().iter().filter(|k| a.contains(k)) {
                let old = march(&chunk_tets(a, k).unwrap(), &field, &frame);
                let tets = chunk_tets(b, k).unwrap();
                field.1.store(0, Ordering::Relaxed);
                let fresh = march(&tets, &field, &frame);
                let n_fresh = field.1.swap(0, Ordering::Relaxed);
                let again = march_reusing(&tets, &field, &frame, Some(&old), None);
                let n_again = field.1.swap(0, Ordering::Relaxed);
                let (x, y): (Bits, Bits) = (bits(&fresh), bits(&again));
                assert!(x == y, "chunk {k:?}");
                let shared = fresh.keys.iter().filter(|q| old.keys.contains(q)).count();
                assert_eq!(
                    n_fresh - n_again,
                    PROBE_DIRECTIONS.len() * shared,
                    "chunk {k:?}"
                );
                reused += usize::from(shared > 0);
                saved += shared;
            }
        }
        assert!(reused > 0 && saved > 0, "nothing was reused");
    }

    /// The probe directions sum to 0 and their outer products to 4 I, so a linear field's
    /// probes give its gradient exactly (up to the factor), in any direction.
    #[test]
    fn probes_give_a_linear_fields_gradient() {
        let sum = PROBE_DIRECTIONS
            .iter()
            .fold(Vec3::ZERO, |s, &k| s + Vec3::from(k));
        assert_eq!(sum, Vec3::ZERO);
        for i in 0..3 {
            for j in 0..3 {
                let m: f32 = PROBE_DIRECTIONS.iter().map(|k| k[i] * k[j]).sum();
                assert_eq!(m, if i == j { 4.0 } else { 0.0 }, "({i}, {j})");
            }
        }
        let a = Vec3::new(0.3, -1.7, 0.9);
        let g = PROBE_DIRECTIONS.iter().fold(Vec3::ZERO, |g, &k| {
            g + Vec3::from(k) * a.dot(Vec3::from(k) * 0.25)
        });
        assert!((g - a).length() < 1e-6, "{g} against {a}");
    }

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
