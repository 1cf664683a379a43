//! Watertight triangle rasterisation into a G-buffer with a `1/w` depth test.
//!
//! Vertices are projected to screen space (sample units, y down) and snapped to 1/256 of a
//! sample, so every edge function below is an exact 64-bit integer: two triangles that share an
//! edge agree exactly on which samples lie on which side, and the top-left rule gives a sample on
//! the shared edge to exactly one of them. No cracks, no double hits.
//!
//! ```text
//!   sample (i, j) is the point (i + 1/2, j + 1/2) of the sample grid
//!
//!        q0                  w_k(p) = edge(q_{k+1}, q_{k+2}, p), twice the signed area of the
//!        /\                  triangle (q_{k+1}, q_{k+2}, p): positive inside when the triangle's
//!       /  \   p inside:     area is positive, equal to `area` at q_k, zero on the opposite edge.
//!      / p  \  w0, w1, w2    Barycentric weight of q_k: w_k / area.
//!   q2 ------ q1  >= 0
//! ```
//!
//! Front faces (counter-clockwise seen from outside, so they also look counter-clockwise in the
//! image) have negative signed area in y-down screen coordinates; back faces and degenerate
//! triangles are skipped. Depth is `1/w` (w = distance along the view axis), which is affine in
//! screen space: larger is nearer, and the buffer starts at 0 (infinitely far). A sample keeps the
//! first triangle that is strictly nearer, so equal depths resolve by submission order and
//! nothing else. The G-buffer keeps, per sample, the triangle and the perspective-correct
//! barycentric weights of its second and third vertex: shading happens later, once per sample.

use glam::{Mat4, Vec3};
use rmt_mesh::Mesh;

use crate::{RenderError, Result};

/// Fixed-point steps per sample.
pub(crate) const SUBSAMPLE: i64 = 256;
/// Vertices farther than this many samples off-frame are not rasterised (the fitted framing keeps
/// every vertex inside the frame, so this only guards against overflow).
const GUARD_BAND: f32 = 1.0e6;

/// Marks a sample that no triangle covers.
pub const NO_TRIANGLE: u32 = u32::MAX;

/// A vertex after projection.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct ScreenVertex {
    /// Horizontal position in samples, 0 at the left edge of the frame.
    pub x: f32,
    /// Vertical position in samples, 0 at the top edge, growing downwards.
    pub y: f32,
    /// 1 / w: the reciprocal of the distance along the view axis.
    pub inv_w: f32,
    /// False when the vertex is behind the eye or outside the guard band.
    pub valid: bool,
}

/// Projects model-space positions with `model_view_projection` onto a `width` x `height` sample
/// grid.
pub fn project(
    positions: &[Vec3],
    model_view_projection: Mat4,
    width: u32,
    height: u32,
    out: &mut Vec<ScreenVertex>,
) {
    out.clear();
    out.extend(positions.iter().map(|&p| {
        let clip = model_view_projection * p.extend(1.0);
        if clip.w <= f32::EPSILON {
            return ScreenVertex::default();
        }
        let inv_w = 1.0 / clip.w;
        let x = (clip.x * inv_w * 0.5 + 0.5) * width as f32;
        let y = (0.5 - clip.y * inv_w * 0.5) * height as f32;
        let valid = x.abs() < GUARD_BAND && y.abs() < GUARD_BAND;
        ScreenVertex { x, y, inv_w, valid }
    }));
}

/// Per-sample visibility: which triangle, where on it, how far.
#[derive(Clone, Debug)]
pub struct GBuffer {
    /// Samples per row.
    pub width: u32,
    /// Rows.
    pub height: u32,
    /// 1/w of the nearest surface, 0 where nothing was drawn.
    pub inv_w: Vec<f32>,
    /// Index of the nearest triangle (position in the index buffer / 3), or [`NO_TRIANGLE`].
    pub triangle: Vec<u32>,
    /// Perspective-correct barycentric weights of the triangle's second and third vertex (the
    /// first vertex has weight `1 - b1 - b2`).
    pub barycentric: Vec<[f32; 2]>,
}

impl GBuffer {
    /// An empty buffer of `width` x `height` samples.
    pub fn new(width: u32, height: u32) -> Self {
        let n = width as usize * height as usize;
        Self {
            width,
            height,
            inv_w: vec![0.0; n],
            triangle: vec![NO_TRIANGLE; n],
            barycentric: vec![[0.0; 2]; n],
        }
    }

    /// Forgets every triangle.
    pub fn clear(&mut self) {
        self.inv_w.fill(0.0);
        self.triangle.fill(NO_TRIANGLE);
        self.barycentric.fill([0.0; 2]);
    }

    /// The triangle covering sample (x, y), if any.
    pub fn triangle_at(&self, x: u32, y: u32) -> Option<u32> {
        let t = self.triangle[(y * self.width + x) as usize];
        (t != NO_TRIANGLE).then_some(t)
    }
}

/// Twice the signed area of (u, v, p), exact.
fn edge(u: [i64; 2], v: [i64; 2], p: [i64; 2]) -> i64 {
    (v[0] - u[0]) * (p[1] - u[1]) - (v[1] - u[1]) * (p[0] - u[0])
}

/// Top-left rule for positive-area triangles in y-down coordinates: of the two directions of a
/// shared edge exactly one is inclusive, so a sample on it belongs to exactly one triangle.
fn inclusive(u: [i64; 2], v: [i64; 2]) -> bool {
    let (dx, dy) = (v[0] - u[0], v[1] - u[1]);
    dy > 0 || (dy == 0 && dx < 0)
}

/// Which original vertex each of [`TriangleSetup`]'s positive-area corners is: the last two
/// vertices are swapped, so corner `k` is vertex `CORNER_VERTEX[k]` of the triangle.
const CORNER_VERTEX: [usize; 3] = [0, 2, 1];

/// A front-facing triangle ready for scan conversion: vertices snapped to 1/256 of a sample and
/// wound to positive area, and its sample bounding box clipped to the frame. The one
/// implementation of the edge functions, the top-left rule and the `1/w` interpolation, shared by
/// [`rasterize`] and the quad-occupancy pass ([`crate::cost::occupancy`]), so both see exactly the
/// same samples with exactly the same depths.
#[derive(Clone, Copy, Debug)]
pub(crate) struct TriangleSetup {
    /// Snapped corners in positive-area order (corner `k` is vertex `CORNER_VERTEX[k]`).
    q: [[i64; 2]; 3],
    /// 1/w of each corner.
    iw: [f32; 3],
    /// Twice the area in (1/256 sample)^2; positive.
    area: i64,
    /// Inclusive sample bounding box clipped to the frame; empty when `x0 > x1` or `y0 > y1`.
    x0: i64,
    x1: i64,
    y0: i64,
    y1: i64,
}

impl TriangleSetup {
    /// Sets up the triangle `v` (its three vertices in index order) for a `width` x `height`
    /// sample grid. `None` for a triangle with an invalid vertex, a back face, or a triangle whose
    /// snapped area is zero; a front face outside the frame gives an empty box.
    #[inline]
    pub(crate) fn new(v: [ScreenVertex; 3], width: i64, height: i64) -> Option<Self> {
        if !(v[0].valid && v[1].valid && v[2].valid) {
            return None;
        }
        let snap = |s: &ScreenVertex| {
            [
                (s.x * SUBSAMPLE as f32).round() as i64,
                (s.y * SUBSAMPLE as f32).round() as i64,
            ]
        };
        let p = [snap(&v[0]), snap(&v[1]), snap(&v[2])];
        let area = edge(p[0], p[1], p[2]);
        if area >= 0 {
            return None; // back face or degenerate
        }
        // Swap the last two vertices so the area is positive.
        let q = CORNER_VERTEX.map(|k| p[k]);
        let iw = CORNER_VERTEX.map(|k| v[k].inv_w);
        // Samples whose centres 256 i + 128 lie in the bounding box.
        let lo = |c: i64| (c - SUBSAMPLE / 2 + SUBSAMPLE - 1).div_euclid(SUBSAMPLE);
        let hi = |c: i64| (c - SUBSAMPLE / 2).div_euclid(SUBSAMPLE);
        Some(Self {
            q,
            iw,
            area: -area,
            x0: lo(q[0][0].min(q[1][0]).min(q[2][0])).max(0),
            x1: hi(q[0][0].max(q[1][0]).max(q[2][0])).min(width - 1),
            y0: lo(q[0][1].min(q[1][1]).min(q[2][1])).max(0),
            y1: hi(q[0][1].max(q[1][1]).max(q[2][1])).min(height - 1),
        })
    }

    /// The inclusive sample box `[x0, x1, y0, y1]` clipped to the frame, `None` when empty.
    #[inline]
    pub(crate) fn sample_box(&self) -> Option<[i64; 4]> {
        (self.x0 <= self.x1 && self.y0 <= self.y1).then_some([self.x0, self.x1, self.y0, self.y1])
    }

    /// Twice the triangle's area in units of (1/[`SUBSAMPLE`] sample)^2, exact; positive.
    #[inline]
    pub(crate) fn twice_area_fixed(&self) -> i64 {
        self.area
    }

    /// Calls `covered(s, l, z)` for every sample the triangle covers (top-left rule), in row
    /// order: `s` is the sample's index `y * width + x`, `l` the screen-space barycentric weights
    /// of the corners and `z` the interpolated `1/w`.
    #[inline]
    pub(crate) fn for_each_sample(
        &self,
        width: i64,
        mut covered: impl FnMut(usize, [f32; 3], f32),
    ) {
        let (x0, x1, y0, y1) = (self.x0, self.x1, self.y0, self.y1);
        if x0 > x1 || y0 > y1 {
            return;
        }
        let q = self.q;
        let edges = [(q[1], q[2]), (q[2], q[0]), (q[0], q[1])];
        let bias = edges.map(|(u, v)| if inclusive(u, v) { 0 } else { -1 });
        let step_x = edges.map(|(u, v)| -(v[1] - u[1]) * SUBSAMPLE);
        let step_y = edges.map(|(u, v)| (v[0] - u[0]) * SUBSAMPLE);
        let start = [
            x0 * SUBSAMPLE + SUBSAMPLE / 2,
            y0 * SUBSAMPLE + SUBSAMPLE / 2,
        ];
        let mut w_row = edges.map(|(u, v)| edge(u, v, start));
        let inv_area = 1.0 / self.area as f32;
        let iw = self.iw;
        for y in y0..=y1 {
            let mut w = w_row;
            let row = (y * width) as usize;
            for x in x0..=x1 {
                if w[0] + bias[0] >= 0 && w[1] + bias[1] >= 0 && w[2] + bias[2] >= 0 {
                    let l = w.map(|w| w as f32 * inv_area);
                    let z = l[0] * iw[0] + l[1] * iw[1] + l[2] * iw[2];
                    covered(row + x as usize, l, z);
                }
                for k in 0..3 {
                    w[k] += step_x[k];
                }
            }
            for k in 0..3 {
                w_row[k] += step_y[k];
            }
        }
    }

    /// Perspective-correct barycentric weights of the triangle's second and third vertex (index
    /// order) at a sample with screen-space weights `l` and depth `z`.
    #[inline]
    fn perspective_weights(&self, l: [f32; 3], z: f32) -> [f32; 2] {
        // Weight of corner k: (l_k / w_k) / (sum l_j / w_j).
        let mut b = [0.0f32; 3];
        for k in 0..3 {
            b[CORNER_VERTEX[k]] = l[k] * self.iw[k] / z;
        }
        [b[1], b[2]]
    }
}

/// Draws the front-facing triangles of `indices` (three per triangle, into `vertices`) into
/// `gbuffer`. Returns the number of front-facing triangles.
pub fn rasterize(vertices: &[ScreenVertex], indices: &[u32], gbuffer: &mut GBuffer) -> usize {
    let (width, height) = (gbuffer.width as i64, gbuffer.height as i64);
    let mut front = 0;
    for (t, tri) in indices.chunks_exact(3).enumerate() {
        let v = [tri[0], tri[1], tri[2]].map(|i| vertices[i as usize]);
        let Some(setup) = TriangleSetup::new(v, width, height) else {
            continue;
        };
        front += 1;
        setup.for_each_sample(width, |s, l, z| {
            if z > gbuffer.inv_w[s] {
                gbuffer.inv_w[s] = z;
                gbuffer.triangle[s] = t as u32;
                gbuffer.barycentric[s] = setup.perspective_weights(l, z);
            }
        });
    }
    front
}

/// Checks that `mesh` is whole triangles whose indices are in range.
pub(crate) fn check_indices(mesh: &Mesh) -> Result<()> {
    if !mesh.indices.chunks_exact(3).remainder().is_empty() {
        return Err(RenderError::InvalidMesh(format!(
            "{} indices is not a multiple of 3",
            mesh.indices.len()
        )));
    }
    if let Some(pos) = mesh
        .indices
        .iter()
        .position(|&i| i as usize >= mesh.positions.len())
    {
        return Err(RenderError::InvalidMesh(format!(
            "triangle {} refers to vertex {} but the mesh has {} vertices",
            pos / 3,
            mesh.indices[pos],
            mesh.positions.len()
        )));
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    fn vertex(x: f32, y: f32, inv_w: f32) -> ScreenVertex {
        ScreenVertex {
            x,
            y,
            inv_w,
            valid: true,
        }
    }

    /// Front faces look counter-clockwise on screen (their y-down signed area is negative).
    #[test]
    fn nearer_triangle_hides_farther_one_in_either_submission_order() {
        // Two overlapping front-facing triangles; `near` at distance 2, `far` at distance 5.
        let near = [
            vertex(2.0, 2.0, 0.5),
            vertex(2.0, 14.0, 0.5),
            vertex(14.0, 8.0, 0.5),
        ];
        let far = [
            vertex(1.0, 1.0, 0.2),
            vertex(1.0, 15.0, 0.2),
            vertex(15.0, 8.0, 0.2),
        ];
        for near_first in [true, false] {
            let vertices: Vec<ScreenVertex> = if near_first {
                [near, far].concat()
            } else {
                [far, near].concat()
            };
            let near_id = if near_first { 0 } else { 1 };
            let mut g = GBuffer::new(16, 16);
            let front = rasterize(&vertices, &[0, 1, 2, 3, 4, 5], &mut g);
            assert_eq!(front, 2, "both triangles face the camera");
            assert_eq!(
                g.triangle_at(6, 8),
                Some(near_id),
                "near_first = {near_first}"
            );
            assert!((g.inv_w[8 * 16 + 6] - 0.5).abs() < 1e-6);
            // Where only the far triangle is, the far triangle shows.
            assert_eq!(g.triangle_at(1, 8), Some(1 - near_id));
        }
    }

    #[test]
    fn back_faces_are_culled() {
        let v = [
            vertex(2.0, 2.0, 0.5),
            vertex(2.0, 14.0, 0.5),
            vertex(14.0, 8.0, 0.5),
        ];
        let mut g = GBuffer::new(16, 16);
        // (0, 2, 1) looks clockwise on screen: a back face.
        assert_eq!(rasterize(&v, &[0, 2, 1], &mut g), 0);
        assert!(g.triangle.iter().all(|&t| t == NO_TRIANGLE));
    }

    #[test]
    fn a_fan_of_triangles_covers_every_sample_exactly_once() {
        // A square split into 8 triangles around an off-grid centre; vertices on sample centres
        // and edges through sample centres exercise the tie rule.
        let c = vertex(7.5, 6.5, 1.0);
        let ring = [
            (0.5, 0.5),
            (8.0, 0.5),
            (15.5, 0.5),
            (15.5, 8.0),
            (15.5, 15.5),
            (8.0, 15.5),
            (0.5, 15.5),
            (0.5, 8.0),
        ];
        let mut vertices = vec![c];
        vertices.extend(ring.iter().map(|&(x, y)| vertex(x, y, 1.0)));
        let mut indices = Vec::new();
        for k in 0..8u32 {
            // The ring looks clockwise on screen (right, then down), so (c, r_{k+1}, r_k) looks
            // counter-clockwise: a front face.
            indices.extend([0, 1 + (k + 1) % 8, 1 + k]);
        }
        let mut counts = vec![0u32; 16 * 16];
        for t in 0..8 {
            let mut g = GBuffer::new(16, 16);
            rasterize(&vertices, &indices[3 * t..3 * t + 3], &mut g);
            for (c, &tri) in counts.iter_mut().zip(&g.triangle) {
                *c += u32::from(tri != NO_TRIANGLE);
            }
        }
        // Samples (0..=15) + 0.5 inside the closed square [0.5, 15.5]^2: the boundary belongs
        // partly to the square (top-left rule), the interior exactly once.
        for y in 1..15 {
            for x in 1..15 {
                assert_eq!(counts[y * 16 + x], 1, "sample ({x}, {y})");
            }
        }
    }

    #[test]
    fn barycentrics_are_perspective_correct() {
        // A triangle whose vertices have different depths: the screen-space midpoint of an edge
        // is not the edge's midpoint in 3D; the weights must follow 1/w.
        let v = [
            vertex(0.0, 0.0, 1.0),
            vertex(32.0, 0.0, 0.25),
            vertex(0.0, 32.0, 1.0),
        ];
        let mut g = GBuffer::new(32, 32);
        // Triangle (v0, v2, v1): its second vertex is v2, its third v1.
        assert_eq!(rasterize(&v, &[0, 2, 1], &mut g), 1);
        // Sample (16, 0), centre (16.5, 0.5): screen-space weight of v1 is l = 16.5 / 32, and the
        // perspective-correct weight is (l / 4) / ((1 - l) + l / 4).
        let [_, b1] = g.barycentric[16];
        let l = 16.5 / 32.0;
        let expected = (l * 0.25) / ((1.0 - l) + l * 0.25);
        assert!((b1 - expected).abs() < 1e-3, "{b1} vs {expected}");
    }
}
