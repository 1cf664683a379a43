//! Small closed solids with outward triangles, for tests of anything that reads meshes.

use crate::Mesh;

/// The tetrahedron on the origin and the three unit points, outward.
pub fn tetrahedron() -> Mesh {
    Mesh::from_triangles(
        vec![
            [0.0, 0.0, 0.0],
            [1.0, 0.0, 0.0],
            [0.0, 1.0, 0.0],
            [0.0, 0.0, 1.0],
        ],
        vec![0, 2, 1, 0, 1, 3, 0, 3, 2, 1, 2, 3],
    )
}

/// The octahedron with vertices on the axes (`+x, -x, +y, -y, +z, -z`, numbered 0..6), outward.
pub fn octahedron() -> Mesh {
    let positions = vec![
        [1.0, 0.0, 0.0],
        [-1.0, 0.0, 0.0],
        [0.0, 1.0, 0.0],
        [0.0, -1.0, 0.0],
        [0.0, 0.0, 1.0],
        [0.0, 0.0, -1.0],
    ];
    let mut indices = Vec::new();
    for (x, sx) in [(0u32, 1.0f32), (1, -1.0)] {
        for (y, sy) in [(2u32, 1.0f32), (3, -1.0)] {
            for (z, sz) in [(4u32, 1.0f32), (5, -1.0)] {
                // (x, y, z) is counter-clockwise from outside when the octant has an even number
                // of negative signs.
                if sx * sy * sz > 0.0 {
                    indices.extend([x, y, z]);
                } else {
                    indices.extend([x, z, y]);
                }
            }
        }
    }
    Mesh::from_triangles(positions, indices)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::validate::validate;

    #[test]
    fn both_are_closed_oriented_spheres() {
        for m in [tetrahedron(), octahedron()] {
            let r = validate(&m, &|_| false);
            assert_eq!(r.boundary_edges_interior, 0);
            assert_eq!(r.orientation_errors, 0);
            assert_eq!((r.euler, r.components), (2, 1));
            // Outward: the signed volume is positive.
            let v: f32 = m
                .indices
                .chunks_exact(3)
                .map(|t| {
                    let [a, b, c] = [0, 1, 2].map(|k| glam::Vec3::from(m.positions[t[k] as usize]));
                    a.dot(b.cross(c))
                })
                .sum();
            assert!(v > 0.0);
        }
    }
}
