//! Per-edit latency of brush strokes on a chunked terrain, and whole-volume vs chunked
//! extraction time.
//!
//! ```text
//! cargo run --release -p rmt-terrain --example edit_latency -- \
//!     [--field svoboda|cave] [--cells 256x64x256] [--chunk 32] [--threads 2] \
//!     [--lattice bcdl|simple] [--clustering integrated|none|postprocessed|integrated-unchecked|mc] \
//!     [--strokes 200] [--warmup 20] [--seed 1] [--ground-cell Y] [--placement os|pinned] \
//!     [--pause-ms 0] [--seams exact|tiles]
//! ```
//!
//! `--seams` defaults to the world's default: exact for integrated clustering of marching
//! tetrahedra (its only seams: the chunks are the whole volume's mesh; a stroke re-extracts a
//! box), tiles for the other modes (each marked chunk re-extracted under the tile rule).
//!
//! `--placement pinned` binds the world's workers to their own CPUs (`rmt_extract::threads`);
//! `--pause-ms` idles before each timed stroke, as a player does between strokes (the workers
//! fall asleep meanwhile).
//!
//! The world spans 8 world units along x (h = 8 / cells_x); the terrain's base height (y = 0)
//! sits at cell `Y` of the y axis (default: the middle, which with 32-cell chunks on a 64-cell
//! axis puts a horizontal seam right through the ground, the worst case for the tile rule).

use anyhow::{bail, Context, Result};
use glam::Vec3;
use rmt_extract::{Clustering, Lattice, ThreadPlacement};
use rmt_fields::{CaveParams, CaveTerrain, ScalarField, SvobodaParams, SvobodaTerrain};
use rmt_terrain::{canonical_triangles, run_strokes, Seams, StrokeParams, World, WorldSettings};

struct Args {
    field: String,
    cells: [usize; 3],
    chunk: usize,
    threads: usize,
    lattice: Lattice,
    clustering: String,
    strokes: usize,
    warmup: usize,
    seed: u64,
    ground_cell: Option<usize>,
    placement: ThreadPlacement,
    pause_ms: usize,
    seams: Option<Seams>,
}

/// The flags, as the module documentation lists them (printed for `--help`).
const USAGE: &str = "edit_latency [--field svoboda|cave] [--cells 256x64x256] [--chunk 32] \
[--threads 2] [--lattice bcdl|simple] \
[--clustering integrated|none|postprocessed|integrated-unchecked|mc] [--strokes 200] \
[--warmup 20] [--seed 1] [--ground-cell Y] [--placement os|pinned] [--pause-ms 0] \
[--seams exact|tiles]";

/// The arguments, or `None` when `--help` asked for the usage.
fn parse() -> Result<Option<Args>> {
    let mut a = Args {
        field: "svoboda".into(),
        cells: [256, 64, 256],
        chunk: 32,
        threads: 2,
        lattice: Lattice::BodyCentred,
        clustering: "integrated".into(),
        strokes: 200,
        warmup: 20,
        seed: 1,
        ground_cell: None,
        placement: ThreadPlacement::Os,
        pause_ms: 0,
        seams: None,
    };
    let mut it = std::env::args().skip(1);
    while let Some(flag) = it.next() {
        if flag == "--help" || flag == "-h" {
            return Ok(None);
        }
        let value = it
            .next()
            .with_context(|| format!("{flag} needs a value (usage: {USAGE})"))?;
        let num = |v: &str| -> Result<usize> {
            v.parse()
                .with_context(|| format!("{flag}: not a whole number: {v:?}"))
        };
        match flag.as_str() {
            "--field" => a.field = value,
            "--cells" => {
                let parts: Vec<usize> = value.split('x').map(num).collect::<Result<_>>()?;
                let [x, y, z] = parts[..] else {
                    bail!("--cells wants XxYxZ, got {value:?}");
                };
                a.cells = [x, y, z];
            }
            "--chunk" => a.chunk = num(&value)?,
            "--threads" => a.threads = num(&value)?,
            "--placement" => {
                a.placement = ThreadPlacement::parse(&value)
                    .with_context(|| format!("--placement wants os or pinned, got {value:?}"))?
            }
            "--strokes" => a.strokes = num(&value)?,
            "--pause-ms" => a.pause_ms = num(&value)?,
            "--warmup" => a.warmup = num(&value)?,
            "--seed" => a.seed = num(&value)? as u64,
            "--ground-cell" => a.ground_cell = Some(num(&value)?),
            "--lattice" => {
                a.lattice = match value.as_str() {
                    "bcdl" => Lattice::BodyCentred,
                    "simple" => Lattice::Simple,
                    _ => bail!("--lattice wants bcdl or simple, got {value:?}"),
                }
            }
            "--clustering" => a.clustering = value,
            "--seams" => {
                a.seams = Some(match value.as_str() {
                    "exact" => Seams::Exact,
                    "tiles" => Seams::Tiles,
                    _ => bail!("--seams wants exact or tiles, got {value:?}"),
                })
            }
            _ => bail!("unknown flag {flag:?} (usage: {USAGE})"),
        }
    }
    Ok(Some(a))
}

fn main() -> Result<()> {
    let Some(a) = parse()? else {
        println!("{USAGE}");
        return Ok(());
    };
    let h = 8.0 / a.cells[0] as f32;
    let ground = a.ground_cell.unwrap_or(a.cells[1] / 2);
    let origin = Vec3::new(0.0, -(ground as f32) * h, 0.0);
    let mut settings = match a.clustering.as_str() {
        "mc" => WorldSettings::marching_cubes(a.cells, origin, h),
        c => {
            let clustering = match c {
                "none" => Clustering::None,
                "integrated" => Clustering::Integrated,
                "integrated-unchecked" => Clustering::IntegratedUnchecked,
                "postprocessed" => Clustering::Postprocessed,
                _ => bail!("unknown clustering {c:?}"),
            };
            WorldSettings::new(a.cells, origin, h, a.lattice, clustering)
        }
    };
    settings = settings
        .with_chunk(a.chunk)
        .with_threads(a.threads)
        .with_placement(a.placement);
    if let Some(seams) = a.seams {
        settings = settings.with_seams(seams);
    }
    let field: Box<dyn ScalarField> = match a.field.as_str() {
        "svoboda" => Box::new(SvobodaTerrain::new(SvobodaParams::default())),
        "cave" => Box::new(CaveTerrain::new(CaveParams::default())),
        f => bail!("--field wants svoboda or cave, got {f:?}"),
    };

    let t = std::time::Instant::now();
    let mut world = World::new(&*field, settings).context("building the world")?;
    let sampling = t.elapsed().as_secs_f64();
    let all = world.remesh_dirty().context("meshing the chunks")?;
    // Second full pass with warm extractors (what a re-mesh of everything costs in steady state).
    world.mark_all_dirty();
    let all_warm = world.remesh_dirty().context("meshing the chunks")?;
    let (whole, whole_s) = world.extract_whole().context("whole extraction")?;
    let chunked = world.mesh_welded();
    // The same volume without the tile rule: what the seams cost in triangles.
    let mut untiled = world.settings().unit_settings();
    untiled.tiles = None;
    let mut ex = rmt_extract::Extractor::new();
    *ex.samples_mut() = world.samples().clone();
    let mut free = rmt_mesh::Mesh::default();
    let free_stats = ex
        .extract_presampled(&untiled, &mut free)
        .context("untiled extraction")?;
    let same = canonical_triangles(&chunked) == canonical_triangles(&whole);
    println!(
        "world {:?} cells (ground at y cell {ground}), {} chunks of {}^3, {} threads, field {}, {} {}, {:?} seams",
        a.cells,
        world.chunk_count(),
        a.chunk,
        a.threads,
        a.field,
        a.lattice.name(),
        a.clustering,
        world.settings().seams
    );
    println!("sampling: {:.1} ms", sampling * 1e3);
    println!(
        "whole volume at once: {:.1} ms, {} triangles",
        whole_s * 1e3,
        whole.triangle_count()
    );
    println!(
        "whole volume without the tile rule: {:.1} ms, {} triangles",
        free_stats.t_total_s * 1e3,
        free.triangle_count()
    );
    println!(
        "all chunks: {:.1} ms cold, {:.1} ms warm, {} triangles; welded == whole: {same}",
        all.seconds * 1e3,
        all_warm.seconds * 1e3,
        chunked.triangle_count()
    );

    let params = StrokeParams::for_cells(h, a.warmup, a.seed.wrapping_add(1_000_003));
    run_strokes(&mut world, &params).context("warm-up strokes")?;
    let params = StrokeParams {
        pause_s: a.pause_ms as f32 * 1e-3,
        ..StrokeParams::for_cells(h, a.strokes, a.seed)
    };
    let r = run_strokes(&mut world, &params).context("strokes")?;
    let n = r.chunks.len().max(1) as f64;
    let per_chunk: Vec<f64> = r.triangles_per_chunk();
    println!(
        "{} strokes (radius {:.3}, {} warm-up): latency p50 {:.2} ms, p90 {:.2} ms, p99 {:.2} ms, max {:.2} ms",
        a.strokes,
        params.radius,
        a.warmup,
        r.latency_quantile(0.5) * 1e3,
        r.latency_quantile(0.9) * 1e3,
        r.latency_quantile(0.99) * 1e3,
        r.latency_quantile(1.0) * 1e3
    );
    println!(
        "chunks re-meshed per edit: mean {:.2}, max {}; triangles per re-meshed chunk: mean {:.0}",
        r.chunks.iter().sum::<usize>() as f64 / n,
        r.chunks.iter().max().unwrap_or(&0),
        per_chunk.iter().sum::<f64>() / n
    );
    println!(
        "boxes extracted per edit: mean {:.2}, max {}; cells per edit: mean {:.0} (a chunk: {})",
        r.boxes.iter().sum::<usize>() as f64 / n,
        r.boxes.iter().max().unwrap_or(&0),
        r.box_cells.iter().sum::<usize>() as f64 / n,
        a.chunk.pow(3)
    );
    // The edited world against its whole volume extracted at once.
    let (whole, _) = world.extract_whole().context("whole extraction")?;
    let chunked = world.mesh_welded();
    println!(
        "after the strokes: {} triangles in the chunks, {} in the whole volume; welded == whole: {}",
        chunked.triangle_count(),
        whole.triangle_count(),
        canonical_triangles(&chunked) == canonical_triangles(&whole)
    );
    Ok(())
}
