//! Inputs for measuring clustering at every level (issue 40, part 2): for a few viewer maps of
//! a cave world, the plain multiresolution surface's triangles per chunk, each chunk marked
//! uniform (its tets are exactly its level's body-centred lattice, away from the world's x and z
//! faces), transition or boundary, and per level a job listing the uniform chunks, for a tool
//! that extracts each level's lattice with and without clustering and counts triangles per
//! chunk.
//!
//! ```text
//! cargo run --release -p rmt-terrain --example lod_cluster -- OUT_DIR [ci|big|big16]
//!   OUT_DIR/chunks.csv            map,level,x,y,z,class,triangles
//!   OUT_DIR/job-MAP-LEVEL.txt     s nx ny nz ox oy oz h chunk, then one uniform chunk a line
//! ```
//!
//! `ci` is the `lod-ci` workload's world (caves 64 x 32 x 64, chunks 8^3, levels 0-2, ratio
//! 1.5) at the first, middle and last viewer step; `big` is caves 256 x 64 x 256 with levels
//! 0-3 and three viewers, `big16` the same world in chunks of 16^3 with levels 0-2.

use std::fmt::Write as _;

use glam::Vec3;
use rmt_fields::{CaveParams, CaveTerrain};
use rmt_terrain::lod::lattice::cell_size;
use rmt_terrain::lod::{
    chunk_tets, mesh_chunks, thread_pool, ChunkKey, LevelMap, LodFrame, LodGeometry, TetKind,
};

/// Whether the chunk's tets are all body-centred tets of its level and it lies a coarsest cell
/// inside the world along x and z (where the domain holds every tet of its level): its tets are
/// then exactly its level's lattice tets whose centroid it owns, except in the half coarsest
/// cell along the world's bottom and top faces, outside the domain (the tool that counts
/// triangles per chunk compares the plain counts and drops the chunks that differ).
/// `"transition"` when some tet is not, `"boundary"` when the chunk is too near the x or z
/// faces.
fn class(map: &LevelMap, k: &ChunkKey) -> anyhow::Result<&'static str> {
    let g = map.geometry();
    let (lo, hi) = k.bounds(g);
    let s_top = cell_size(g.levels);
    let w = g.world_size();
    let interior = [0, 2]
        .iter()
        .all(|&i| lo[i] >= s_top && hi[i] <= w[i] - s_top);
    let lattice = chunk_tets(map, k)?
        .iter()
        .all(|t| t.kind == TetKind::Bcc && t.level == k.level);
    Ok(match (lattice, interior) {
        (false, _) => "transition",
        (true, false) => "boundary",
        (true, true) => "uniform",
    })
}

fn main() -> anyhow::Result<()> {
    let args: Vec<String> = std::env::args().collect();
    let out = std::path::PathBuf::from(args.get(1).map_or("lod-cluster", String::as_str));
    let which = args.get(2).map_or("ci", String::as_str);
    std::fs::create_dir_all(&out)?;
    let h = 1.0f32 / 32.0;
    let (g, origin, viewers): (LodGeometry, Vec3, Vec<Vec3>) = match which {
        "big16" => (
            LodGeometry::new(2, 16, [4, 1, 4])?,
            Vec3::new(-4.0, -1.0, -4.0),
            vec![
                Vec3::new(0.0, 0.3, 0.0),
                Vec3::new(-2.5, 0.3, 1.5),
                Vec3::new(3.5, 0.3, -3.5),
            ],
        ),
        "big" => (
            LodGeometry::new(3, 8, [4, 1, 4])?,
            Vec3::new(-4.0, -1.0, -4.0),
            vec![
                Vec3::new(0.0, 0.3, 0.0),
                Vec3::new(-2.5, 0.3, 1.5),
                Vec3::new(3.5, 0.3, -3.5),
            ],
        ),
        _ => (
            LodGeometry::new(2, 8, [2, 1, 2])?,
            Vec3::new(-1.0, -0.5, -1.0),
            vec![
                Vec3::new(-0.9, 0.3, -0.9),
                Vec3::new(0.0, 0.3, 0.0),
                Vec3::new(0.9, 0.3, 0.9),
            ],
        ),
    };
    let frame = LodFrame { origin, h };
    let field = CaveTerrain::new(CaveParams::default());
    let pool = thread_pool(2)?;
    let mut csv = String::from("map,level,x,y,z,class,triangles\n");
    for (m, v) in viewers.iter().enumerate() {
        let p = (*v - origin) / (h * 0.5);
        let map = LevelMap::from_viewer(g, [p.x, p.y, p.z].map(f64::from), 1.5);
        let start = std::time::Instant::now();
        let meshes = mesh_chunks(&map, &field, &frame, &pool)?;
        eprintln!(
            "map {m}: {} chunks meshed in {:.1} s",
            map.chunks().len(),
            start.elapsed().as_secs_f64()
        );
        let mut jobs: Vec<String> = (0..=g.levels)
            .map(|l| {
                let s = cell_size(l);
                let n = g.world_size().map(|w| w / s);
                format!(
                    "{s} {} {} {} {} {} {} {} {}\n",
                    n[0],
                    n[1],
                    n[2],
                    f64::from(origin.x),
                    f64::from(origin.y),
                    f64::from(origin.z),
                    f64::from(h),
                    g.chunk
                )
            })
            .collect();
        for (k, mesh) in map.chunks().iter().zip(&meshes) {
            let c = class(&map, k)?;
            writeln!(
                csv,
                "{m},{},{},{},{},{c},{}",
                k.level,
                k.at[0],
                k.at[1],
                k.at[2],
                mesh.triangles()
            )?;
            if c == "uniform" {
                writeln!(
                    jobs[k.level as usize],
                    "{} {} {}",
                    k.at[0], k.at[1], k.at[2]
                )?;
            }
        }
        for (l, job) in jobs.iter().enumerate() {
            if job.lines().count() > 1 {
                std::fs::write(out.join(format!("job-{m}-{l}.txt")), job)?;
            }
        }
    }
    std::fs::write(out.join("chunks.csv"), csv)?;
    Ok(())
}
