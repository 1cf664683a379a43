//! A lower bound on a viewer step's re-mesh time on the `lod.toml` world (caves 4096 x 256 x
//! 4096, chunks 16^3, levels 0-4, the 400-step path), whatever the mesher: the field samples
//! that no earlier step could have taken.
//!
//! Per step, a chunk that is a leaf of the new map and not of the old one (a level change)
//! needs the field at the lattice points of its level in its closed box, unless the field's
//! bound ([`ScalarField::side`]) puts the box on one side of 0. A point sampled at any earlier
//! step (at any level: a coarse sample is a fine sample) is taken as known, as a mesher that
//! kept every sample it ever took would have it. The rest are new samples; a step needs at
//! least `new samples x the field's cost per sample / threads`. (The chunks that are re-meshed
//! because a neighbour changed level need no new sample at all under that assumption.)
//!
//! `cargo run --release -p rmt-terrain --example lod_bound -- [STEPS] [THREADS] [BLOCK]`:
//! STEPS of the path (default 400), the thread count the bound divides by (default 2), and the
//! edge in cells of the blocks the bound is asked about (default 16, the chunk; a smaller
//! block skips more of a chunk, as a sparse sampler would); `walk` as a fourth argument flies
//! `lod-walk.toml`'s path instead (a tenth of the distance, 0.45 finest cells a step). Prints the
//! field's cost per sample (sampled in rows of 17 points, as chunks are, one thread), then the
//! new samples per step (mean, p50, p99, max) and the bound in ms, and the samples of the
//! chunks a step changes when nothing is kept (every new leaf sampled whole).

use std::collections::HashSet;
use std::time::Instant;

use glam::Vec3;
use rmt_fields::{CaveParams, CaveTerrain, ScalarField};
use rmt_terrain::lod::lattice::cell_size;
use rmt_terrain::lod::{ChunkKey, LevelMap, LodFrame, LodGeometry};

fn main() -> anyhow::Result<()> {
    let args: Vec<String> = std::env::args().collect();
    let arg = |i: usize, d: usize| -> anyhow::Result<usize> {
        Ok(args.get(i).map(|a| a.parse()).transpose()?.unwrap_or(d))
    };
    let (steps, threads, block) = (arg(1, 400)?, arg(2, 2)?.max(1), arg(3, 16)?.max(1));
    let g = LodGeometry::new(4, 16, [16, 1, 16])?;
    let frame = LodFrame {
        origin: Vec3::new(-64.0, -4.0, -64.0),
        h: 1.0 / 32.0,
    };
    let field = CaveTerrain::new(CaveParams::default());
    let ns = ns_per_sample(&field, &frame);
    println!("caves: {ns:.1} ns a sample (rows of 17 points, one thread)");
    let end = if args.get(4).map(String::as_str) == Some("walk") {
        -16.0
    } else {
        20.0
    };
    let (a, b) = (Vec3::new(-20.0, 1.0, -20.0), Vec3::new(end, 1.0, end));
    let map_at = |k: usize| {
        let p = a.lerp(b, k as f32 / 400.0);
        let u = f64::from(frame.h) * 0.5;
        let q = (p.as_dvec3() - frame.origin.as_dvec3()) / u;
        LevelMap::from_viewer(g, q.to_array(), 1.5)
    };
    let mut known: HashSet<[i32; 3]> = HashSet::new();
    let mut old = map_at(0);
    // Step 0 meshes the whole map: its samples are known from then on.
    for k in old.chunks() {
        for_points(&field, &frame, &g, k, block, |p| {
            known.insert(p);
        });
    }
    let (mut new_per_step, mut whole_per_step) = (Vec::new(), Vec::new());
    println!("step changed_leaves sampled_leaves new_samples whole_samples bound_ms");
    for step in 1..=steps {
        let new = map_at(step);
        let (mut changed, mut sampled, mut fresh, mut whole) = (0, 0, 0usize, 0usize);
        for k in new.chunks() {
            if old.contains(k) {
                continue;
            }
            changed += 1;
            let before = whole;
            for_points(&field, &frame, &g, k, block, |p| {
                whole += 1;
                if known.insert(p) {
                    fresh += 1;
                }
            });
            sampled += usize::from(whole > before);
        }
        let bound = fresh as f64 * ns / threads as f64 * 1e-6;
        println!("{step:4} {changed:5} {sampled:5} {fresh:9} {whole:9} {bound:9.3}");
        new_per_step.push(fresh as f64);
        whole_per_step.push(whole as f64);
        old = new;
    }
    for (what, v) in [
        ("new samples", &mut new_per_step),
        (
            "samples of the new leaves, nothing kept",
            &mut whole_per_step,
        ),
    ] {
        v.sort_by(f64::total_cmp);
        let n = v.len().max(1);
        let mean = v.iter().sum::<f64>() / n as f64;
        let at = |q: f64| {
            v.get(((n as f64 * q).ceil() as usize).clamp(1, n) - 1)
                .copied()
        };
        let ms = |s: f64| s * ns / threads as f64 * 1e-6;
        let (p50, p99, max) = (
            at(0.5).unwrap_or(0.0),
            at(0.99).unwrap_or(0.0),
            v.last().copied().unwrap_or(0.0),
        );
        println!(
            "{what} per step, {threads} threads: mean {mean:.0} ({:.3} ms), p50 {p50:.0} ({:.3} ms), \
             p99 {p99:.0} ({:.3} ms), max {max:.0} ({:.3} ms)",
            ms(mean),
            ms(p50),
            ms(p99),
            ms(max)
        );
    }
    Ok(())
}

/// The lattice points of chunk `k`'s level in the closed boxes of its blocks of `block` cells
/// (cube corners and centres) that the field's bound does not put on one side of 0; a point
/// shared by blocks is visited once per block (the caller's set counts it once).
fn for_points(
    field: &CaveTerrain,
    frame: &LodFrame,
    g: &LodGeometry,
    k: &ChunkKey,
    block: usize,
    mut f: impl FnMut([i32; 3]),
) {
    let (lo, hi) = k.bounds(g);
    let s = cell_size(k.level);
    let step = s * block as i64;
    let mut seen: HashSet<[i32; 3]> = HashSet::new();
    let mut bx = lo[0];
    while bx < hi[0] {
        let mut by = lo[1];
        while by < hi[1] {
            let mut bz = lo[2];
            while bz < hi[2] {
                let blo = [bx, by, bz];
                let bhi = [
                    (bx + step).min(hi[0]),
                    (by + step).min(hi[1]),
                    (bz + step).min(hi[2]),
                ];
                let p = |v: [i64; 3]| v.map(|c| c as i32);
                if field
                    .side(frame.world(p(blo)), frame.world(p(bhi)), 0.0)
                    .is_none()
                {
                    for half in [0, s / 2] {
                        let mut x = blo[0] + half;
                        while x <= bhi[0] {
                            let mut y = blo[1] + half;
                            while y <= bhi[1] {
                                let mut z = blo[2] + half;
                                while z <= bhi[2] {
                                    let q = [x as i32, y as i32, z as i32];
                                    if seen.insert(q) {
                                        f(q);
                                    }
                                    z += s;
                                }
                                y += s;
                            }
                            x += s;
                        }
                    }
                }
                bz += step;
            }
            by += step;
        }
        bx += step;
    }
}

/// The field's cost per sample in rows of 17 points (a 17^3 block at the ground, repeated).
fn ns_per_sample(field: &CaveTerrain, frame: &LodFrame) -> f64 {
    let n = 17usize;
    let h = frame.h;
    let xs: Vec<f32> = (0..n).map(|i| i as f32 * h).collect();
    let ys: Vec<f32> = (0..n).map(|i| -0.25 + i as f32 * h).collect();
    let mut out = vec![0.0f32; n * n];
    let mut best = f64::INFINITY;
    for _ in 0..7 {
        let t = Instant::now();
        for rep in 0..20 {
            for z in 0..n {
                let zz = z as f32 * h + rep as f32 * 0.53;
                field.sample_rows(&xs, &ys, zz, &mut out, n);
            }
        }
        let per = t.elapsed().as_secs_f64() * 1e9 / (20 * n * n * n) as f64;
        best = best.min(per);
        std::hint::black_box(&out);
    }
    best
}
