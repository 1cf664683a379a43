//! Gradient normals of a volume: central differences of the corner values (one-sided at the
//! box faces), interpolated trilinearly at each vertex and normalised; they point toward
//! increasing values, like the library's normals (outward for a signed distance field).

use glam::Vec3;
use rmt_extract::Grid;
use rmt_mesh::Mesh;

use crate::volume::Input;

/// Sets `mesh.normals` from the gradient of `input`'s corner values on `grid`; with
/// `array_order`, the mesh's positions are `[z, y, x]` and the normals are written so.
pub fn from_volume(input: &Input<'_>, grid: &Grid, array_order: bool, mesh: &mut Mesh) {
    let [nx, ny, nz] = grid.cells;
    let n = [nx, ny, nz];
    let s = grid.spacing();
    let v = |x: usize, y: usize, z: usize| input.values[(z * (ny + 1) + y) * (nx + 1) + x];
    // The gradient at corner c along axis a.
    let grad = |c: [usize; 3]| -> Vec3 {
        let mut g = [0.0f32; 3];
        for a in 0..3 {
            let (lo, hi) = (c[a].saturating_sub(1), (c[a] + 1).min(n[a]));
            let (mut p, mut q) = (c, c);
            p[a] = lo;
            q[a] = hi;
            g[a] = (v(q[0], q[1], q[2]) - v(p[0], p[1], p[2])) / ((hi - lo) as f32 * s[a]);
        }
        Vec3::from(g)
    };
    mesh.normals.clear();
    mesh.normals.reserve(mesh.positions.len());
    for p in &mesh.positions {
        let p = if array_order { [p[2], p[1], p[0]] } else { *p };
        let u = (Vec3::from(p) - grid.min) / s;
        let mut c0 = [0usize; 3];
        let mut t = [0.0f32; 3];
        for a in 0..3 {
            let ua = u[a].clamp(0.0, n[a] as f32);
            c0[a] = (ua.floor() as usize).min(n[a] - 1);
            t[a] = ua - c0[a] as f32;
        }
        let mut g = Vec3::ZERO;
        for corner in 0..8 {
            let mut c = c0;
            let mut w = 1.0;
            for a in 0..3 {
                if corner >> a & 1 == 1 {
                    c[a] += 1;
                    w *= t[a];
                } else {
                    w *= 1.0 - t[a];
                }
            }
            if w != 0.0 {
                g += grad(c) * w;
            }
        }
        let n = g.normalize_or_zero().to_array();
        mesh.normals
            .push(if array_order { [n[2], n[1], n[0]] } else { n });
    }
}
