//! Times `validate` and `quality` on a large closed mesh (a torus grid).
//!
//! `cargo run --release -p rmt-mesh --example validate_speed -- [triangles in millions]`

use rmt_mesh::{quality, validate, Mesh};
use std::time::Instant;

/// A torus as an m x n grid with wrap-around: 2 m n triangles.
fn torus(m: u32, n: u32) -> Mesh {
    let mut positions = Vec::with_capacity((m * n) as usize);
    for i in 0..m {
        for j in 0..n {
            let a = i as f32 / m as f32 * std::f32::consts::TAU;
            let b = j as f32 / n as f32 * std::f32::consts::TAU;
            let r = 2.0 + b.cos();
            positions.push([r * a.cos(), r * a.sin(), b.sin()]);
        }
    }
    let id = |i: u32, j: u32| (i % m) * n + (j % n);
    let mut indices = Vec::with_capacity(6 * (m * n) as usize);
    for i in 0..m {
        for j in 0..n {
            let q = [id(i, j), id(i + 1, j), id(i + 1, j + 1), id(i, j + 1)];
            indices.extend([q[0], q[1], q[2], q[0], q[2], q[3]]);
        }
    }
    Mesh::from_triangles(positions, indices)
}

fn main() {
    let millions: f64 = std::env::args()
        .nth(1)
        .and_then(|s| s.parse().ok())
        .unwrap_or(3.0);
    let side = ((millions * 1e6 / 2.0).sqrt()).max(3.0) as u32;
    let mesh = torus(side, side);
    let start = Instant::now();
    let report = validate(&mesh, &|_| false);
    let validate_time = start.elapsed();
    let start = Instant::now();
    let q = quality(&mesh);
    let quality_time = start.elapsed();
    println!(
        "{} triangles: validate {:.3} s (watertight {}, euler {}), quality {:.3} s \
         (ratio mean {:.4})",
        mesh.triangle_count(),
        validate_time.as_secs_f64(),
        report.is_watertight_manifold(),
        report.euler,
        quality_time.as_secs_f64(),
        q.ar_mean
    );
}
