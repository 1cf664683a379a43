//! Measures the multiresolution mesh (issue 40): open, non-manifold and misoriented edges over
//! random fields and random 2:1-balanced level maps; the pop when a chunk changes level
//! (Hausdorff, max and mean, in cells of the finer level); the normal difference across level
//! seams; and meshing times.
//!
//! `cargo run --release -p rmt-terrain --example lod_measure -- [N] [POPS]`: N fields and maps
//! for the edge counts (default `RMT_CASES`, else 200), POPS chunk level changes for the pop
//! (default 40; 0 stops after the edge counts).

use std::time::Instant;

use glam::Vec3;
use rmt_fields::RandomField;
use rmt_terrain::lod::check::{check_surface, check_tets};
use rmt_terrain::lod::{
    mesh_chunks, thread_pool, weld, world_tets, ChunkKey, ChunkMesh, LevelMap, LodFrame,
    LodGeometry,
};

fn main() -> anyhow::Result<()> {
    let args: Vec<String> = std::env::args().collect();
    let n: u64 = match args.get(1) {
        Some(a) => a.parse()?,
        None => std::env::var("RMT_CASES")
            .ok()
            .and_then(|s| s.parse().ok())
            .unwrap_or(200),
    };
    let pops: u64 = args.get(2).map(|a| a.parse()).transpose()?.unwrap_or(40);
    let pool1 = thread_pool(1)?;
    let pool2 = thread_pool(2)?;

    // 1. Closed, manifold, oriented: random fields on random maps, 3 levels (chunks of 4^3
    //    cells at 8, 16 and 32 cells across), [-1, 1]^3.
    let g = LodGeometry::new(2, 4, [1, 1, 1])?;
    let frame = LodFrame {
        origin: Vec3::splat(-1.0),
        h: 0.125,
    };
    let (mut open, mut nm, mut mis, mut tris, mut boundary_open) = (0, 0, 0, 0usize, 0);
    let t0 = Instant::now();
    for seed in 0..n {
        let field = RandomField::from_seed(seed);
        let map = LevelMap::random(g, seed.wrapping_mul(0x9E37_79B9), 0.5);
        let meshes = mesh_chunks(&map, &field, &frame, &pool2)?;
        let tets: Vec<_> = world_tets(&map)?.into_iter().map(|(_, t)| t.tet).collect();
        let (_, bfaces) = check_tets(&tets);
        let (mesh, keys) = weld(&meshes);
        let c = check_surface(&keys, &mesh.indices, &bfaces);
        open += c.open_inside;
        nm += c.non_manifold;
        mis += c.misoriented;
        boundary_open += c.open_on_boundary;
        tris += c.triangles;
        if (seed + 1) % 500 == 0 {
            eprintln!(
                "  {} fields: open inside {open}, non-manifold {nm}, misoriented {mis} ({tris} triangles; {:.1} s)",
                seed + 1,
                t0.elapsed().as_secs_f64()
            );
        }
    }
    println!(
        "edges over {n} random fields x random 2:1 maps (levels 0..2, 16^3 finest cells): open inside {open}, \
         non-manifold {nm}, misoriented {mis} ({tris} triangles, {boundary_open} open edges on \
         the domain boundary; {:.1} s)",
        t0.elapsed().as_secs_f64()
    );

    if pops == 0 {
        return Ok(());
    }

    // 2. Pop: a chunk of level l >= 1 splits into level l - 1; the surfaces before and after
    //    over its box, both ways, in cells of level l - 1.
    let g = LodGeometry::new(2, 4, [2, 1, 2])?;
    let frame = LodFrame {
        origin: Vec3::splat(-1.0),
        h: 2.0 / 32.0,
    };
    let (mut pop_max, mut pop_sum, mut pop_count) = (0f64, 0f64, 0usize);
    let mut worst_chunk_mean = 0f64;
    let mut measured = 0;
    for seed in 0..pops {
        let field = RandomField::from_seed(10_000 + seed);
        let split = |k: &ChunkKey| {
            // A coarse map: split the chunks near one corner only.
            k.bounds(&g).0.iter().all(|&v| v == 0) && k.level == 2
        };
        let before = LevelMap::build(g, split);
        let coarse: Vec<ChunkKey> = before
            .chunks()
            .iter()
            .copied()
            .filter(|k| k.level >= 1)
            .collect();
        let Some(&target) = coarse.get((seed as usize * 7) % coarse.len().max(1)) else {
            continue;
        };
        let after = LevelMap::build(g, |k| split(k) || *k == target);
        let mb = weld(&mesh_chunks(&before, &field, &frame, &pool2)?).0;
        let ma = weld(&mesh_chunks(&after, &field, &frame, &pool2)?).0;
        let (lo, hi) = target.bounds(&g);
        let u = f64::from(frame.h) * 0.5;
        let to_world = |p: [i64; 3]| {
            Vec3::new(
                (f64::from(frame.origin.x) + p[0] as f64 * u) as f32,
                (f64::from(frame.origin.y) + p[1] as f64 * u) as f32,
                (f64::from(frame.origin.z) + p[2] as f64 * u) as f32,
            )
        };
        let (blo, bhi) = (to_world(lo), to_world(hi));
        let finer_cell = f64::from(frame.h) * f64::from(1u32 << (target.level - 1));
        let ab = one_way(&mb, &ma, blo, bhi, finer_cell as f32);
        let ba = one_way(&ma, &mb, blo, bhi, finer_cell as f32);
        let mut chunk_sum = 0.0;
        let mut chunk_n = 0;
        for d in ab.iter().chain(&ba) {
            let d = f64::from(*d) / finer_cell;
            pop_max = pop_max.max(d);
            pop_sum += d;
            chunk_sum += d;
            chunk_n += 1;
        }
        pop_count += chunk_n;
        if chunk_n > 0 {
            measured += 1;
            worst_chunk_mean = worst_chunk_mean.max(chunk_sum / chunk_n as f64);
        }
    }
    println!(
        "pop over {measured} chunk level changes (level l -> l-1, surfaces over the chunk's box, \
         both ways, 15 samples per triangle): max {pop_max:.3}, mean {:.3} (worst chunk's mean \
         {worst_chunk_mean:.3}) cells of the finer level",
        pop_sum / pop_count.max(1) as f64
    );

    // 3. Normals across level seams: a crossing on a seam between chunks of different levels
    //    is one vertex computed by each chunk from its key; compare the bits.
    let mut seam_max_deg = 0f64;
    let mut seam_vertices = 0;
    let mut seam_bits_differ = 0;
    for seed in 0..n.min(50) {
        let field = RandomField::from_seed(20_000 + seed);
        let map = LevelMap::random(g, seed, 0.5);
        let meshes = mesh_chunks(&map, &field, &frame, &pool1)?;
        let mut first: std::collections::HashMap<[[i32; 3]; 2], (u8, [f32; 3])> =
            std::collections::HashMap::new();
        for (k, m) in map.chunks().iter().zip(&meshes) {
            for (v, key) in m.keys.iter().enumerate() {
                let nrm = m.normals[v];
                match first.get(key) {
                    Some(&(level, other)) if level != k.level => {
                        seam_vertices += 1;
                        seam_bits_differ +=
                            usize::from(other.map(f32::to_bits) != nrm.map(f32::to_bits));
                        if other.map(f32::to_bits) != nrm.map(f32::to_bits) {
                            let dot = Vec3::from(nrm).dot(Vec3::from(other)).clamp(-1.0, 1.0);
                            seam_max_deg = seam_max_deg.max(f64::from(dot.acos().to_degrees()));
                        }
                    }
                    Some(_) => {}
                    None => {
                        first.insert(*key, (k.level, nrm));
                    }
                }
            }
        }
    }
    println!(
        "normals across level seams: {seam_vertices} crossings computed by chunks of two \
         levels, {seam_bits_differ} with different bits, largest difference \
         {seam_max_deg:.4} degrees"
    );

    // 4. Times: whole meshing of a viewer map, 1 and 2 threads.
    let g = LodGeometry::new(3, 8, [2, 1, 2])?;
    let frame = LodFrame {
        origin: Vec3::new(-1.0, -1.0, -1.0),
        h: 2.0 / 128.0,
    };
    let field = RandomField::from_seed(3);
    let map = LevelMap::from_viewer(g, [64.0, 32.0, 64.0], 1.0);
    for (threads, pool) in [(1, &pool1), (2, &pool2)] {
        let t = Instant::now();
        let meshes = mesh_chunks(&map, &field, &frame, pool)?;
        let tri: usize = meshes.iter().map(ChunkMesh::triangles).sum();
        println!(
            "viewer map over 128 x 64 x 128 finest cells, {} chunks (levels 0..3, C = 8), {threads} thread(s): {:.0} ms, {tri} \
             triangles",
            map.chunks().len(),
            t.elapsed().as_secs_f64() * 1e3
        );
    }
    Ok(())
}

/// Distances from sample points of `a`'s triangles inside the box `[lo, hi]` to the nearest
/// triangle of `b` near the box.
fn one_way(a: &rmt_mesh::Mesh, b: &rmt_mesh::Mesh, lo: Vec3, hi: Vec3, cell: f32) -> Vec<f32> {
    let tri = |m: &rmt_mesh::Mesh, t: &[u32]| -> [Vec3; 3] {
        [0, 1, 2].map(|i| Vec3::from(m.positions[t[i] as usize]))
    };
    let grow = Vec3::splat(3.0 * cell);
    let near: Vec<[Vec3; 3]> = b
        .indices
        .chunks_exact(3)
        .map(|t| tri(b, t))
        .filter(|p| {
            p.iter()
                .any(|q| q.cmpge(lo - grow).all() && q.cmple(hi + grow).all())
        })
        .collect();
    let mut out = Vec::new();
    for t in a.indices.chunks_exact(3) {
        let p = tri(a, t);
        let c = (p[0] + p[1] + p[2]) / 3.0;
        if !(c.cmpge(lo).all() && c.cmple(hi).all()) {
            continue;
        }
        for i in 0..=4 {
            for j in 0..=4 - i {
                let k = 4 - i - j;
                let s = (p[0] * i as f32 + p[1] * j as f32 + p[2] * k as f32) / 4.0;
                let d = near
                    .iter()
                    .map(|q| point_triangle(s, q))
                    .fold(f32::INFINITY, f32::min);
                if d.is_finite() {
                    out.push(d);
                }
            }
        }
    }
    out
}

/// Distance from `p` to triangle `t` (closest point by regions, Ericson 5.1.5).
fn point_triangle(p: Vec3, t: &[Vec3; 3]) -> f32 {
    let [a, b, c] = *t;
    let (ab, ac, ap) = (b - a, c - a, p - a);
    let (d1, d2) = (ab.dot(ap), ac.dot(ap));
    if d1 <= 0.0 && d2 <= 0.0 {
        return ap.length();
    }
    let bp = p - b;
    let (d3, d4) = (ab.dot(bp), ac.dot(bp));
    if d3 >= 0.0 && d4 <= d3 {
        return bp.length();
    }
    let vc = d1 * d4 - d3 * d2;
    if vc <= 0.0 && d1 >= 0.0 && d3 <= 0.0 {
        let v = d1 / (d1 - d3);
        return (p - (a + ab * v)).length();
    }
    let cp = p - c;
    let (d5, d6) = (ab.dot(cp), ac.dot(cp));
    if d6 >= 0.0 && d5 <= d6 {
        return cp.length();
    }
    let vb = d5 * d2 - d1 * d6;
    if vb <= 0.0 && d2 >= 0.0 && d6 <= 0.0 {
        let w = d2 / (d2 - d6);
        return (p - (a + ac * w)).length();
    }
    let va = d3 * d6 - d5 * d4;
    if va <= 0.0 && (d4 - d3) >= 0.0 && (d5 - d6) >= 0.0 {
        let w = (d4 - d3) / ((d4 - d3) + (d5 - d6));
        return (p - (b + (c - b) * w)).length();
    }
    let denom = 1.0 / (va + vb + vc);
    let (v, w) = (vb * denom, vc * denom);
    (p - (a + ab * v + ac * w)).length()
}
