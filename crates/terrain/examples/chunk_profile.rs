//! Stage times of one chunk's extraction on the Svoboda terrain (what an edit costs per chunk),
//! median over repetitions with a warm extractor, for the chunks the surface crosses:
//!
//! ```text
//! cargo run --release -p rmt-terrain --example chunk_profile -- [clustering] [reps] [chunks]
//! ```
//!
//! `clustering` is none / integrated / integrated-unchecked / postprocessed (default
//! integrated), on the body-centred lattice, 256 x 64 x 256 cells in chunks of 32; `chunks` is
//! how many surface chunks to time (default 8). Each chunk is extracted on its own
//! (`World::extract_chunk`) under the mode's seams: the tile rule for every mode but integrated
//! clustering (what a tile-seam edit costs per chunk), and for integrated clustering, which has
//! exact seams only, the chunk and its halo with the global rule.
use anyhow::{bail, Context, Result};
use glam::Vec3;
use rmt_extract::{Clustering, Extractor, Lattice};
use rmt_fields::{SvobodaParams, SvobodaTerrain};
use rmt_mesh::Mesh;
use rmt_terrain::{World, WorldSettings};

fn median(mut v: Vec<f64>) -> f64 {
    v.sort_by(f64::total_cmp);
    v[v.len() / 2]
}

fn main() -> Result<()> {
    let args: Vec<String> = std::env::args().collect();
    let clustering = match args.get(1).map_or("integrated", String::as_str) {
        "none" => Clustering::None,
        "integrated" => Clustering::Integrated,
        "integrated-unchecked" => Clustering::IntegratedUnchecked,
        "postprocessed" => Clustering::Postprocessed,
        c => bail!("unknown clustering {c:?}"),
    };
    let reps: usize = args.get(2).map_or(Ok(20), |s| s.parse()).context("reps")?;
    let count: usize = args.get(3).map_or(Ok(8), |s| s.parse()).context("chunks")?;
    let cells = [256, 64, 256];
    let h = 8.0 / 256.0;
    let origin = Vec3::new(0.0, -32.0 * h, 0.0);
    let settings = WorldSettings::new(cells, origin, h, Lattice::BodyCentred, clustering);
    let world = World::new(&SvobodaTerrain::new(SvobodaParams::default()), settings)?;
    // The chunks are extracted on a one-thread pool, from inside it, as `World::remesh_dirty`
    // does: the extractor's parallel passes then run inline, with no hand-off between threads.
    let pool = std::sync::Arc::new(rayon::ThreadPoolBuilder::new().num_threads(1).build()?);
    let mut ex = Extractor::new();
    ex.set_pool(pool.clone());
    pool.install(|| profile(&world, &mut ex, clustering, reps, count))
}

/// Times `count` surface chunks of `world`, `reps` times each, and prints their stage times.
fn profile(
    world: &World,
    ex: &mut Extractor,
    clustering: Clustering,
    reps: usize,
    count: usize,
) -> Result<()> {
    let mut mesh = Mesh::default();
    let mut shown = 0;
    let (mut all_v, mut all_g, mut all_t) = (0.0, 0.0, 0.0);
    // The merging steps of the vertex pass (see `Stats`), summed over the chunks.
    let mut all_steps = [0.0; 4];
    for i in 0..world.chunk_count() {
        if shown == count {
            break;
        }
        let first = world
            .extract_chunk(i, ex, &mut mesh)
            .with_context(|| format!("chunk {i}"))?;
        if first.triangles == 0 {
            continue;
        }
        shown += 1;
        let (mut v, mut g, mut t) = (Vec::new(), Vec::new(), Vec::new());
        let mut steps: [Vec<f64>; 4] = Default::default();
        for _ in 0..reps {
            let st = world
                .extract_chunk(i, ex, &mut mesh)
                .with_context(|| format!("chunk {i}"))?;
            v.push(st.t_vertex_s);
            g.push(st.t_geometry_s);
            t.push(st.t_total_s);
            for (acc, x) in steps.iter_mut().zip(st.merge_steps()) {
                acc.push(x);
            }
        }
        for (sum, s) in all_steps.iter_mut().zip(steps) {
            *sum += median(s);
        }
        let (v, g, t) = (median(v), median(g), median(t));
        all_v += v;
        all_g += g;
        all_t += t;
        println!(
            "chunk {i:3}: vertex {:.3} ms  geometry {:.3} ms  total {:.3} ms  ({} points, {} crossings, {} triangles, {} clusters committed of {} proposed, {} prefilter-rejected, {} check-rejected, {} repair rounds, {} welds)",
            v * 1e3,
            g * 1e3,
            t * 1e3,
            first.sample_points,
            first.crossings,
            mesh.triangle_count(),
            first.clusters_committed,
            first.clusters_proposed,
            first.clusters_rejected_prefilter,
            first.clusters_rejected_check,
            first.repair_rounds,
            first.collapses
        );
    }
    let n = shown.max(1) as f64;
    println!(
        "mean over {shown} chunks: vertex {:.3} ms  geometry {:.3} ms  total {:.3} ms",
        all_v / n * 1e3,
        all_g / n * 1e3,
        all_t / n * 1e3
    );
    if clustering != Clustering::None && clustering != Clustering::Postprocessed {
        println!(
            "  of the vertex pass: {} ms",
            rmt_extract::Stats::merge_steps_text(all_steps.map(|s| s / n * 1e3), 3)
        );
    }
    Ok(())
}
