//! Measures the rendering cost ([`rmt_render::cost`]) of meshes and how long it takes: UV spheres
//! of about 20k, 100k and 400k triangles (the range of the paper manifest's meshes), the bunny,
//! and any mesh files given on the command line (`.ply`, `.obj`, `.glb`).
//!
//! `cargo run --release -p rmt-render --example occupancy_cost [MESH...]`
//!
//! Prints, per mesh, the wall time of each part (quad occupancy at the four sizes over eight
//! views, meshoptimizer's analyzers, buffer sizes) and the whole [`RenderCost`] measure, best of
//! three runs, single-threaded.

use rmt_mesh::Mesh;
use rmt_render::cost::occupancy::{OccupancyMeter, OccupancySettings};
use rmt_render::cost::{analyzers, buffers, RenderCost, RenderCostMeter, CACHE_SIZES};
use rmt_render::shapes::uv_sphere;
use std::error::Error;
use std::path::Path;
use std::time::Instant;

/// Best wall time of three runs, in milliseconds, and the last result.
fn best_of_3<T>(mut f: impl FnMut() -> T) -> (f64, T) {
    let mut best = f64::INFINITY;
    let mut out = None;
    for _ in 0..3 {
        let t = Instant::now();
        let r = f();
        best = best.min(t.elapsed().as_secs_f64() * 1e3);
        out = Some(r);
    }
    (best, out.expect("three runs"))
}

/// Measures and prints one mesh; returns the best wall time of the whole measure, ms.
fn report(name: &str, mesh: &Mesh) -> Result<f64, Box<dyn Error>> {
    let mut meter = RenderCostMeter::new();
    let (total, cost) = best_of_3(|| meter.measure(mesh));
    let cost: RenderCost = cost?;
    let mut occupancy = OccupancyMeter::new(OccupancySettings::default())?;
    let (occ_ms, _) = best_of_3(|| occupancy.measure(mesh));
    let mut per_size = Vec::new();
    for size in OccupancySettings::default().sizes {
        let mut one = OccupancyMeter::new(OccupancySettings {
            sizes: vec![size],
            ..Default::default()
        })?;
        let (ms, _) = best_of_3(|| one.measure(mesh));
        per_size.push(format!("{size}: {ms:.0}"));
    }
    let (cache_ms, _) = best_of_3(|| analyzers::vertex_cache_before_after(mesh, &CACHE_SIZES));
    let (overdraw_ms, _) = best_of_3(|| analyzers::overdraw(mesh));
    let (fetch_ms, _) = best_of_3(|| analyzers::overfetch(mesh, analyzers::VERTEX_SIZE));
    let (buffer_ms, _) = best_of_3(|| buffers::buffer_sizes(mesh));
    println!(
        "{name}: {} triangles, {} vertices\n  total {total:.0} ms = occupancy {occ_ms:.0} ms \
         (per size alone, ms: {}) + vertex cache {cache_ms:.0} + overdraw {overdraw_ms:.0} + \
         fetch {fetch_ms:.1} + buffers/glb {buffer_ms:.0}",
        mesh.triangle_count(),
        mesh.vertex_count(),
        per_size.join(", "),
    );
    println!(
        "  occupancy 1080/540/270/135: {:.3} {:.3} {:.3} {:.3} (merged {:.3} {:.3} {:.3} {:.3}); \
         below 1 px: {:.3} {:.3} {:.3} {:.3}; below 1 quad: {:.3} {:.3} {:.3} {:.3}",
        cost.quad_occupancy_1080,
        cost.quad_occupancy_540,
        cost.quad_occupancy_270,
        cost.quad_occupancy_135,
        cost.quad_occupancy_merged_1080,
        cost.quad_occupancy_merged_540,
        cost.quad_occupancy_merged_270,
        cost.quad_occupancy_merged_135,
        cost.tris_below_pixel_1080,
        cost.tris_below_pixel_540,
        cost.tris_below_pixel_270,
        cost.tris_below_pixel_135,
        cost.tris_below_quad_1080,
        cost.tris_below_quad_540,
        cost.tris_below_quad_270,
        cost.tris_below_quad_135,
    );
    println!(
        "  ACMR 16/32 {:.3}/{:.3} -> optimised {:.3}/{:.3}; ATVR 16 {:.3} -> {:.3}; overdraw \
         {:.3}; overfetch {:.3}; index {} B, vertex {} B, glb {} B",
        cost.acmr_16,
        cost.acmr_32,
        cost.acmr_16_optimized,
        cost.acmr_32_optimized,
        cost.atvr_16,
        cost.atvr_16_optimized,
        cost.overdraw,
        cost.overfetch,
        cost.index_bytes,
        cost.vertex_bytes,
        cost.glb_bytes,
    );
    Ok(total)
}

fn main() -> Result<(), Box<dyn Error>> {
    let paths: Vec<String> = std::env::args().skip(1).collect();
    let (mut sum, mut meshes, mut triangles) = (0.0, 0, 0);
    let mut one = |name: &str, mesh: &Mesh| -> Result<(), Box<dyn Error>> {
        sum += report(name, mesh)?;
        meshes += 1;
        triangles += mesh.triangle_count();
        Ok(())
    };
    if paths.is_empty() {
        // 2 s (r - 1) triangles: about 20k, 100k and 400k.
        for (segments, rings) in [(100, 100), (224, 224), (448, 448)] {
            one(
                &format!("uv sphere {segments}x{rings}"),
                &uv_sphere(1.0, segments, rings),
            )?;
        }
        let bunny = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../data/bunny.obj");
        one("bunny", &rmt_mesh::io::read_obj(bunny)?)?;
    }
    for p in paths {
        let mesh = rmt_mesh::io::read_mesh(&p)?;
        one(&p, &mesh)?;
    }
    println!("all {meshes} meshes ({triangles} triangles): {sum:.0} ms for the whole measure");
    Ok(())
}
