//! Where a viewer step's re-mesh time goes on the `lod.toml` world (caves 4096 x 256 x 4096,
//! chunks 16^3, levels 0-4): per step, the chunks the re-mesh rule picks, how many take the
//! fast path (a uniform neighbourhood) and how many the window path, and the time of building
//! their tetrahedra and of marching them, on one thread.
//!
//! `cargo run --release -p rmt-terrain --example lod_profile -- [STEPS] [FIRST] [SAMPLE]`:
//! STEPS viewer steps of the 400-step path (default 12) from step FIRST (default 1); at most
//! SAMPLE chunks of each path are timed per step (default 8; 0 times them all).
//!
//! `... --example lod_profile -- world STEPS THREADS CACHE_MB [cluster]`: the world itself flown
//! over the first STEPS steps on THREADS threads with a chunk-tets cache of CACHE_MB MiB (and
//! clustering at every level with `cluster`)
//! (`LodWorld::set_tet_cache_bytes`): per step the chunks re-meshed and kept unchanged, the
//! re-mesh time and the cache's hits and misses, then the median and the slowest step after step 0.

use std::time::Instant;

use glam::Vec3;
use rmt_fields::{CaveParams, CaveTerrain, ScalarField};
use rmt_terrain::lod::mesh::{chunk_tets, is_fast_path, needs_remesh};
use rmt_terrain::lod::mt::mesh_chunk;
use rmt_terrain::lod::{march, LevelMap, LodFrame, LodGeometry, LodSettings, LodWorld};

fn main() -> anyhow::Result<()> {
    let args: Vec<String> = std::env::args().collect();
    let arg = |i: usize, d: usize| -> anyhow::Result<usize> {
        Ok(args.get(i).map(|a| a.parse()).transpose()?.unwrap_or(d))
    };
    if args.get(1).map(String::as_str) == Some("world") {
        let cluster = args.get(5).map(String::as_str) == Some("cluster");
        return fly(arg(2, 40)?, arg(3, 2)?, arg(4, 1024)?, cluster);
    }
    let (steps, first, sample) = (arg(1, 12)?, arg(2, 1)?, arg(3, 8)?);
    let g = LodGeometry::new(4, 16, [16, 1, 16])?;
    let frame = LodFrame {
        origin: Vec3::new(-64.0, -4.0, -64.0),
        h: 1.0 / 32.0,
    };
    let field = CaveTerrain::new(CaveParams::default());
    let (a, b) = (Vec3::new(-20.0, 1.0, -20.0), Vec3::new(20.0, 1.0, 20.0));
    let map_at = |k: usize| {
        let p = a.lerp(b, k as f32 / 400.0);
        let u = f64::from(frame.h) * 0.5;
        let q = (p.as_dvec3() - frame.origin.as_dvec3()) / u;
        LevelMap::from_viewer(g, q.to_array(), 1.5)
    };
    let mut old = map_at(first - 1);
    println!("step chunks stale fast window | t_map_ms | fast: n tets_ms march_ms chunk_ms tris | window: n tets_ms march_ms chunk_ms tris");
    for k in first..first + steps {
        let t0 = Instant::now();
        let new = map_at(k);
        let t_map = t0.elapsed().as_secs_f64() * 1e3;
        let stale: Vec<_> = new
            .chunks()
            .iter()
            .copied()
            .filter(|c| needs_remesh(&old, &new, c))
            .collect();
        let (fast, window): (Vec<_>, Vec<_>) = stale.iter().partition(|c| is_fast_path(&new, c));
        let mut row = format!(
            "{k:4} {:6} {:5} {:4} {:4} | {t_map:8.2} |",
            new.chunks().len(),
            stale.len(),
            fast.len(),
            window.len()
        );
        for set in [&fast, &window] {
            let n = if sample == 0 {
                set.len()
            } else {
                set.len().min(sample)
            };
            let (mut tt, mut tm, mut tris) = (0.0, 0.0, 0usize);
            for c in &set[..n] {
                let t = Instant::now();
                let tets = chunk_tets(&new, c)?;
                tt += t.elapsed().as_secs_f64() * 1e3;
                let t = Instant::now();
                let m = march(&tets, &field as &dyn ScalarField, &frame);
                tm += t.elapsed().as_secs_f64() * 1e3;
                tris += m.triangles();
            }
            // The whole chunk as the world meshes it (an empty box skips the tets).
            let t = Instant::now();
            for c in &set[..n] {
                mesh_chunk(&new, c, &field, &frame)?;
            }
            let tc = t.elapsed().as_secs_f64() * 1e3;
            row += &format!(" {n:3} {tt:9.2} {tm:9.2} {tc:9.2} {tris:7} |");
        }
        println!("{row}");
        old = new;
    }
    Ok(())
}

/// The world flown over `steps` steps of the path (see the module doc).
fn fly(steps: usize, threads: usize, cache_mb: usize, cluster: bool) -> anyhow::Result<()> {
    let g = LodGeometry::new(4, 16, [16, 1, 16])?;
    let frame = LodFrame {
        origin: Vec3::new(-64.0, -4.0, -64.0),
        h: 1.0 / 32.0,
    };
    let settings = LodSettings {
        geometry: g,
        frame,
        ratio: 1.5,
        threads,
        morph: None,
        cluster,
    };
    let mut world = LodWorld::new(CaveTerrain::new(CaveParams::default()), settings)?;
    world.set_tet_cache_bytes(cache_mb << 20);
    let (a, b) = (Vec3::new(-20.0, 1.0, -20.0), Vec3::new(20.0, 1.0, 20.0));
    let mut times = Vec::new();
    println!("step remeshed unchanged ms hits misses entries MiB");
    for k in 0..=steps {
        world.set_viewer(a.lerp(b, k as f32 / 400.0));
        let t = Instant::now();
        let r = world.remesh()?;
        let ms = t.elapsed().as_secs_f64() * 1e3;
        let s = world.tet_cache_stats();
        println!(
            "{k:4} {:5} {:5} {ms:9.1} {:7} {:7} {:6} {:7.1}",
            r.remeshed.len(),
            r.unchanged.len(),
            s.hits,
            s.misses,
            s.entries,
            s.bytes as f64 / (1 << 20) as f64
        );
        if k > 0 {
            times.push(ms);
        }
    }
    times.sort_by(f64::total_cmp);
    if let (Some(mid), Some(max)) = (times.get(times.len() / 2), times.last()) {
        println!("steps 1-{steps}: median {mid:.1} ms, slowest {max:.1} ms");
    }
    Ok(())
}
