//! Checks of a tetrahedral mesh: volume, face sharing and orientation, hanging vertices, and
//! boundary faces on the domain's boundary. Used by the tests and the measuring example.

use foldhash::{HashMap, HashSet};

use super::lattice::{mid, vol6, Point, Tet, EDGES};

/// What [`check_tets`] found.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct TetCheck {
    /// Tetrahedra.
    pub tets: usize,
    /// Six times the total volume.
    pub volume6: i64,
    /// Tetrahedra of zero or negative volume.
    pub non_positive: usize,
    /// Faces shared by exactly two tetrahedra.
    pub inner_faces: usize,
    /// Faces of one tetrahedron.
    pub boundary_faces: usize,
    /// Faces of more than two tetrahedra.
    pub faces_over_two: usize,
    /// Inner faces whose two tetrahedra give them the same orientation.
    pub same_orientation: usize,
    /// Edges whose midpoint is a vertex of the mesh (a hanging vertex).
    pub hanging: usize,
}

/// The outward faces of a positively oriented tetrahedron, each in cyclic order.
pub fn outward_faces(t: &Tet) -> [[Point; 3]; 4] {
    [
        [t[1], t[2], t[3]],
        [t[0], t[3], t[2]],
        [t[0], t[1], t[3]],
        [t[0], t[2], t[1]],
    ]
}

/// The face sorted, and whether its cyclic order was an even permutation of the sorted one.
pub fn face_key(f: [Point; 3]) -> ([Point; 3], bool) {
    let mut s = f;
    s.sort_unstable();
    let pos = f.map(|p| s.iter().position(|q| *q == p).unwrap_or(0));
    let inv = (pos[0] > pos[1]) as u8 + (pos[0] > pos[2]) as u8 + (pos[1] > pos[2]) as u8;
    (s, inv.is_multiple_of(2))
}

/// Checks the tetrahedra; returns the findings and the boundary faces (sorted vertices, with
/// their outward cyclic order).
pub fn check_tets<'a>(
    tets: impl IntoIterator<Item = &'a Tet>,
) -> (TetCheck, HashMap<[Point; 3], [Point; 3]>) {
    let mut c = TetCheck::default();
    let mut faces: HashMap<[Point; 3], (u32, i32, [Point; 3])> = HashMap::default();
    let mut verts: HashSet<Point> = HashSet::default();
    let mut edges: HashSet<(Point, Point)> = HashSet::default();
    for t in tets {
        c.tets += 1;
        let v = vol6(t);
        c.volume6 += v;
        if v <= 0 {
            c.non_positive += 1;
        }
        for f in outward_faces(t) {
            let (k, even) = face_key(f);
            let e = faces.entry(k).or_insert((0, 0, f));
            e.0 += 1;
            e.1 += if even { 1 } else { -1 };
        }
        verts.extend(t);
        for (a, b) in EDGES {
            let (p, q) = (t[a].min(t[b]), t[a].max(t[b]));
            edges.insert((p, q));
        }
    }
    let mut boundary = HashMap::default();
    for (k, (n, sum, f)) in faces {
        match n {
            1 => {
                c.boundary_faces += 1;
                boundary.insert(k, f);
            }
            2 => {
                c.inner_faces += 1;
                if sum != 0 {
                    c.same_orientation += 1;
                }
            }
            _ => c.faces_over_two += 1,
        }
    }
    c.hanging = edges
        .iter()
        .filter(|(p, q)| mid(*p, *q).is_some_and(|m| verts.contains(&m)))
        .count();
    (c, boundary)
}

fn sub(a: Point, b: Point) -> [i64; 3] {
    std::array::from_fn(|i| i64::from(a[i]) - i64::from(b[i]))
}

fn cross(u: [i64; 3], v: [i64; 3]) -> [i64; 3] {
    [
        u[1] * v[2] - u[2] * v[1],
        u[2] * v[0] - u[0] * v[2],
        u[0] * v[1] - u[1] * v[0],
    ]
}

fn dot(u: [i64; 3], v: [i64; 3]) -> i64 {
    u[0] * v[0] + u[1] * v[1] + u[2] * v[2]
}

/// How many of `faces` (oriented) do not lie inside one of `reference` (oriented), facing the
/// same way: the boundary of a refined mesh must be its domain's boundary, subdivided.
pub fn faces_off(faces: &[[Point; 3]], reference: &[[Point; 3]]) -> usize {
    let refs: Vec<([Point; 3], [i64; 3])> = reference
        .iter()
        .map(|r| (*r, cross(sub(r[1], r[0]), sub(r[2], r[0]))))
        .collect();
    faces
        .iter()
        .filter(|f| {
            let n = cross(sub(f[1], f[0]), sub(f[2], f[0]));
            !refs.iter().any(|(r, rn)| {
                dot(*rn, n) > 0
                    && f.iter().all(|p| {
                        dot(*rn, sub(*p, r[0])) == 0
                            && (0..3).all(|e| {
                                let (a, b) = (r[e], r[(e + 1) % 3]);
                                dot(cross(sub(b, a), sub(*p, a)), *rn) >= 0
                            })
                    })
            })
        })
        .count()
}

/// What [`check_surface`] found on a welded surface.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct SurfaceCheck {
    /// Triangles.
    pub triangles: usize,
    /// Edges of one triangle that do not lie in a boundary face of the tetrahedral mesh.
    pub open_inside: usize,
    /// Edges of one triangle on the domain's boundary (expected where the surface leaves it).
    pub open_on_boundary: usize,
    /// Edges of more than two triangles.
    pub non_manifold: usize,
    /// Edges of two triangles that run the same way in both.
    pub misoriented: usize,
}

/// Checks a surface whose vertices are crossings (`keys[v]`, the tet edge it lies on):
/// every edge in two triangles with opposite directions, except edges in a boundary face of
/// the tetrahedral mesh (`boundary`, from [`check_tets`]).
pub fn check_surface(
    keys: &[[Point; 2]],
    indices: &[u32],
    boundary: &HashMap<[Point; 3], [Point; 3]>,
) -> SurfaceCheck {
    let mut edges: HashMap<(u32, u32), (u32, i32)> = HashMap::default();
    for tri in indices.chunks_exact(3) {
        for k in 0..3 {
            let (a, b) = (tri[k], tri[(k + 1) % 3]);
            let e = edges.entry((a.min(b), a.max(b))).or_insert((0, 0));
            e.0 += 1;
            e.1 += if a < b { 1 } else { -1 };
        }
    }
    let mut c = SurfaceCheck {
        triangles: indices.len() / 3,
        ..SurfaceCheck::default()
    };
    for ((a, b), (n, dir)) in edges {
        match n {
            1 => {
                let mut pts: Vec<Point> = keys[a as usize]
                    .iter()
                    .chain(&keys[b as usize])
                    .copied()
                    .collect();
                pts.sort_unstable();
                pts.dedup();
                let on = pts.len() == 3 && boundary.contains_key(&[pts[0], pts[1], pts[2]]);
                if on {
                    c.open_on_boundary += 1;
                } else {
                    c.open_inside += 1;
                }
            }
            2 => {
                if dir != 0 {
                    c.misoriented += 1;
                }
            }
            _ => c.non_manifold += 1,
        }
    }
    c
}
