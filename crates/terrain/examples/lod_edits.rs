//! Edits on the multiresolution world, measured: strokes on the surface of lod-ci's cave world
//! (64 x 32 x 64 cells of 1/32, chunks 8^3, levels 0-2, ratio 1.5, viewer at the flight's
//! start), alternating add and remove, each centred on a surface vertex picked at random (so
//! at every level). Per stroke: the level of the chunk under it, chunks marked, chunks whose
//! surface changed, the re-mesh time, the overlay's bytes.
//!
//! ```text
//! cargo run --release -p rmt-terrain --example lod_edits -- [STROKES] [SEED]
//! ```

use glam::Vec3;
use rmt_fields::{CaveParams, CaveTerrain};
use rmt_terrain::lod::{LodFrame, LodGeometry, LodSettings, LodWorld};
use rmt_terrain::Brush;

fn main() -> anyhow::Result<()> {
    let args: Vec<String> = std::env::args().collect();
    let strokes: usize = args.get(1).map_or(Ok(20), |s| s.parse())?;
    let mut seed: u64 = args.get(2).map_or(Ok(1), |s| s.parse())?;
    let h = 1.0f32 / 32.0;
    let origin = Vec3::new(-1.0, -0.5, -1.0);
    let settings = LodSettings {
        geometry: LodGeometry::new(2, 8, [2, 1, 2])?,
        frame: LodFrame { origin, h },
        ratio: 1.5,
        threads: 2,
        morph: None,
        cluster: false,
    };
    let mut world = LodWorld::new(CaveTerrain::new(CaveParams::default()), settings)?;
    world.set_viewer(Vec3::new(-0.9, 0.3, -0.9));
    world.remesh()?;
    let chunks = world.level_map().map_or(0, |m| m.chunks().len());
    println!("stroke,level,marked,changed,chunks,remesh_ms,overlay_bytes");
    let mut next = move || {
        seed = seed.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = seed;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        z ^ (z >> 31)
    };
    for i in 0..strokes {
        let (mesh, _) = world.mesh_welded();
        if mesh.positions.is_empty() {
            anyhow::bail!("no surface");
        }
        let c = Vec3::from(mesh.positions[(next() % mesh.positions.len() as u64) as usize]);
        let map = world
            .level_map()
            .cloned()
            .ok_or_else(|| anyhow::anyhow!("no map"))?;
        let u = (c - origin) / (h * 0.5);
        let p4 = [u.x, u.y, u.z].map(|v| (4.0 * v).floor() as i64);
        let level = map.chunk_of4(p4).map_or(-1, |k| i32::from(k.level));
        let brush = if i % 2 == 0 {
            Brush::subtract(c, 4.0 * h, 30.0 * h)
        } else {
            Brush::add(c, 4.0 * h, 30.0 * h)
        };
        let before: Vec<_> = map
            .chunks()
            .iter()
            .map(|k| world.chunk_mesh(k).cloned())
            .collect();
        let marked = world.edit(&brush, 1.0 / 60.0)?;
        let start = std::time::Instant::now();
        let r = world.remesh()?;
        let ms = start.elapsed().as_secs_f64() * 1e3;
        let changed = map
            .chunks()
            .iter()
            .zip(&before)
            .filter(|(k, b)| world.chunk_mesh(k) != b.as_ref())
            .count();
        debug_assert_eq!(r.remeshed.len(), marked);
        println!(
            "{i},{level},{marked},{changed},{chunks},{ms:.1},{}",
            world.edits().bytes()
        );
    }
    Ok(())
}
