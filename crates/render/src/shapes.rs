//! Reference shapes built in code: the sphere that trains the palette, and test meshes.

use rmt_mesh::Mesh;
use std::f32::consts::PI;

/// A closed UV sphere centred at the origin, poles on the y axis, triangles counter-clockwise seen
/// from outside, with exact unit normals.
///
/// `segments` (at least 3) splits the equator, `rings` (at least 2) splits a meridian; the mesh
/// has `segments * (rings - 1) + 2` vertices and `2 * segments * (rings - 1)` triangles.
///
/// ```text
///        N            ring i   a ---- b      a = (i, j),   b = (i, j + 1)
///       /|\                    | \    |      triangles (a, b, d) and (a, d, c):
///      b-+-a  (seen from       |   \  |      counter-clockwise seen from outside
///     ring 1   above: phi      c ---- d      because phi turns clockwise seen from +y
///              runs clockwise)  ring i + 1
/// ```
pub fn uv_sphere(radius: f32, segments: u32, rings: u32) -> Mesh {
    let segments = segments.max(3);
    let rings = rings.max(2);
    let mut positions = vec![[0.0, radius, 0.0]];
    let mut normals = vec![[0.0, 1.0, 0.0]];
    for i in 1..rings {
        let theta = PI * i as f32 / rings as f32;
        for j in 0..segments {
            let phi = 2.0 * PI * j as f32 / segments as f32;
            let n = [
                theta.sin() * phi.cos(),
                theta.cos(),
                theta.sin() * phi.sin(),
            ];
            normals.push(n);
            positions.push(n.map(|c| c * radius));
        }
    }
    positions.push([0.0, -radius, 0.0]);
    normals.push([0.0, -1.0, 0.0]);
    let south = positions.len() as u32 - 1;
    let ring_vertex = |i: u32, j: u32| 1 + (i - 1) * segments + j % segments;
    let mut indices = Vec::with_capacity(6 * (segments * (rings - 1)) as usize);
    for j in 0..segments {
        indices.extend([0, ring_vertex(1, j + 1), ring_vertex(1, j)]);
    }
    for i in 1..rings - 1 {
        for j in 0..segments {
            let (a, b) = (ring_vertex(i, j), ring_vertex(i, j + 1));
            let (c, d) = (ring_vertex(i + 1, j), ring_vertex(i + 1, j + 1));
            indices.extend([a, b, d, a, d, c]);
        }
    }
    for j in 0..segments {
        indices.extend([
            ring_vertex(rings - 1, j),
            ring_vertex(rings - 1, j + 1),
            south,
        ]);
    }
    Mesh {
        positions,
        normals,
        indices,
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::Vec3;

    /// Signed volume by the divergence theorem: positive iff triangles face outwards.
    fn signed_volume(mesh: &Mesh) -> f64 {
        mesh.triangles()
            .map(|t| {
                let [a, b, c] = t.map(|i| Vec3::from(mesh.positions[i as usize]).as_dvec3());
                a.dot(b.cross(c)) / 6.0
            })
            .sum()
    }

    #[test]
    fn uv_sphere_is_outward_and_close_to_the_ball_volume() {
        let mesh = uv_sphere(2.0, 64, 32);
        let ball = 4.0 / 3.0 * std::f64::consts::PI * 8.0;
        let v = signed_volume(&mesh);
        assert!(v > 0.97 * ball && v < ball, "volume {v} vs {ball}");
        assert_eq!(mesh.triangle_count(), 2 * 64 * 31);
        assert_eq!(mesh.vertex_count(), 64 * 31 + 2);
    }

    #[test]
    fn uv_sphere_every_edge_has_two_opposite_triangles() {
        let mesh = uv_sphere(1.0, 7, 5);
        let mut edges: Vec<(u32, u32)> = mesh
            .triangles()
            .flat_map(|[a, b, c]| [(a, b), (b, c), (c, a)])
            .collect();
        edges.sort_unstable();
        for w in edges.windows(2) {
            assert_ne!(w[0], w[1], "directed edge used twice");
        }
        for &(a, b) in &edges {
            assert!(
                edges.binary_search(&(b, a)).is_ok(),
                "edge {a}-{b} has no twin"
            );
        }
    }
}
