//! How wide a halo makes a chunk reproduce the whole volume *without* the tile rule (issue 18's
//! chunk seams): the data for choosing the rule that will replace the tile rule.
//!
//! ```text
//! cargo run --release -p rmt-terrain --example halo_exactness -- [object] [chunk] [halos] [fields]
//! ```
//!
//! `object` is `asteroid` (64^3 cells), `terrain` (the Svoboda terrain of `edit_latency`, 128 x
//! 64 x 128 cells of h = 8/256) or `random` (the property tests' random fields,
//! `rmt_fields::RandomField`, seeds 0 to `fields` - 1, default 200, on 12^3 cells); `chunk` the
//! chunk edge in cells (default 32, for `random` 4); `halos` the halo widths in cells,
//! comma-separated (default `1,2,3,4,6,8`).
//!
//! Body-centred integrated clustering, one thread, in lattice units (cell edge 1, boxes at
//! integer corners, so positions are exact in every box). The whole volume is extracted once
//! with the global rule (no tiles). Then every chunk is extracted from its cells plus a halo of
//! `H` cells (clipped at the volume), again with no tiles, keeping the triangles anchored in its
//! own cells, as the terrain world keeps them. A chunk is *exact* when every triangle it keeps is
//! a triangle of the whole volume; when every chunk is exact and their triangles add up to the
//! whole's, the chunks are the whole volume, bit for bit. Printed per halo: the chunks with a
//! triangle that is not the whole's, those triangles, the chunks' triangles over the whole's,
//! and the median time of one chunk. (Until integrated clustering stopped taking tiles, a first
//! line gave the tile rule with a halo of one cell, for comparison: its chunks reproduced the
//! whole volume only *under the tile rule*, at 1.15-1.50 times the triangles.)
//!
//! A halo that suffices on these fields is not a proof: the repair rounds are not bounded, so
//! a chunk needs a rule (or a certificate) to be exact by construction. This measures how far
//! the global rule is from that in practice. The world's exact seams (`rmt_terrain::Seams`)
//! take the certificate route: a box is trusted inside a band where clustering did nothing.

use std::collections::HashSet;

use glam::Vec3;
use rmt_extract::{CellRange, Clustering, ExtractSettings, Extractor, Grid, Lattice};
use rmt_fields::{
    Asteroid, AsteroidParams, RandomField, ScalarField, SvobodaParams, SvobodaTerrain,
};
use rmt_mesh::Mesh;
use rmt_terrain::canonical_triangles;

/// A field sampled in lattice units: `inner` at `origin + p * h`.
struct Scaled {
    inner: Box<dyn ScalarField>,
    origin: Vec3,
    h: f32,
}

impl ScalarField for Scaled {
    fn sample(&self, p: Vec3) -> f32 {
        self.inner.sample(self.origin + p * self.h)
    }
}

/// The box of cells `lo .. hi`, at its own lattice coordinates.
fn settings(lo: [usize; 3], hi: [usize; 3]) -> ExtractSettings {
    let v = |c: [usize; 3]| Vec3::new(c[0] as f32, c[1] as f32, c[2] as f32);
    ExtractSettings::new(
        Grid::new([0, 1, 2].map(|a| hi[a] - lo[a]), v(lo), v(hi)),
        Lattice::BodyCentred,
        Clustering::Integrated,
    )
}

/// One configuration's outcome over all chunks.
#[derive(Clone, Copy, Default)]
struct Row {
    /// Chunks with a triangle that is not the whole's.
    inexact: usize,
    /// Those triangles.
    wrong: usize,
    /// The chunks' triangles.
    kept: usize,
    /// Chunks.
    chunks: usize,
    /// Median seconds of one chunk's extraction.
    median_s: f64,
}

/// The whole volume's triangle count, and one row per halo width.
fn measure(
    field: &dyn ScalarField,
    cells: [usize; 3],
    chunk: usize,
    runs: &[usize],
) -> Result<(usize, Vec<Row>), Box<dyn std::error::Error>> {
    // The whole volume, with the global rule.
    let mut whole = Extractor::new();
    let mut mesh = Mesh::default();
    whole.extract(field, &settings([0; 3], cells), &mut mesh)?;
    let whole_tris = canonical_triangles(&mesh);
    let whole_set: HashSet<[[u32; 3]; 3]> = whole_tris.iter().copied().collect();
    let samples = whole.samples();
    let counts = cells.map(|c| c.div_ceil(chunk));
    let mut ex = Extractor::new();
    let mut out = Mesh::default();
    let mut rows = Vec::new();
    for &halo in runs {
        let mut row = Row::default();
        let mut times = Vec::new();
        for cz in 0..counts[2] {
            for cy in 0..counts[1] {
                for cx in 0..counts[0] {
                    let c = [cx, cy, cz];
                    let lo = [0, 1, 2].map(|a| c[a] * chunk);
                    let hi = [0, 1, 2].map(|a| (lo[a] + chunk).min(cells[a]));
                    let s0 = [0, 1, 2].map(|a| lo[a].saturating_sub(halo));
                    let s1 = [0, 1, 2].map(|a| (hi[a] + halo).min(cells[a]));
                    let mut st = settings(s0, s1);
                    st.keep_cells = Some(CellRange {
                        lo: [0, 1, 2].map(|a| lo[a] - s0[a]),
                        hi: [0, 1, 2].map(|a| hi[a] - s0[a]),
                    });
                    // The box's values, cut from the whole volume's samples as the terrain
                    // world cuts a chunk's.
                    ex.samples_mut().copy_box(samples, &st, s0)?;
                    let stats = ex.extract_presampled(&st, &mut out)?;
                    times.push(stats.t_total_s);
                    let tris = canonical_triangles(&out);
                    let bad = tris.iter().filter(|t| !whole_set.contains(*t)).count();
                    row.inexact += usize::from(bad > 0);
                    row.wrong += bad;
                    row.kept += tris.len();
                    row.chunks += 1;
                }
            }
        }
        times.sort_by(f64::total_cmp);
        row.median_s = times.get(times.len() / 2).copied().unwrap_or(0.0);
        rows.push(row);
    }
    Ok((whole_tris.len(), rows))
}

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let args: Vec<String> = std::env::args().collect();
    let object = args.get(1).map_or("asteroid", String::as_str);
    let number = |i: usize, what: &str, default: usize| -> Result<usize, String> {
        match args.get(i) {
            Some(s) => s
                .parse()
                .map_err(|_| format!("{what}: a whole number, got {s:?}")),
            None => Ok(default),
        }
    };
    let random = object == "random";
    let chunk = number(2, "chunk", if random { 4 } else { 32 })?;
    let halos: Vec<usize> = match args.get(3) {
        Some(s) => s
            .split(',')
            .map(|h| {
                h.parse()
                    .map_err(|_| format!("halos: whole numbers, got {h:?}"))
            })
            .collect::<Result<_, _>>()?,
        None => vec![1, 2, 3, 4, 6, 8],
    };
    if chunk == 0 {
        return Err("chunk must be at least 1".into());
    }
    // The global rule with each halo.
    let runs = halos;
    if random {
        // The property tests' random fields, `fields` of them from seed 0, on 12^3 cells.
        let fields = number(4, "fields", 200)?;
        let cells = [12; 3];
        let mut failing = vec![0usize; runs.len()];
        let mut totals = vec![Row::default(); runs.len()];
        for seed in 0..fields as u64 {
            let field = Scaled {
                inner: Box::new(RandomField::from_seed(seed)),
                origin: Vec3::splat(-1.0),
                h: 2.0 / 12.0,
            };
            let (_, rows) = measure(&field, cells, chunk, &runs)?;
            for (k, r) in rows.iter().enumerate() {
                failing[k] += usize::from(r.inexact > 0);
                totals[k].inexact += r.inexact;
                totals[k].wrong += r.wrong;
                totals[k].chunks += r.chunks;
            }
        }
        println!(
            "random fields 0..{fields}, {cells:?} cells, chunks of {chunk}^3, BCDL integrated"
        );
        for (k, &halo) in runs.iter().enumerate() {
            let t = totals[k];
            println!(
                "global rule, halo {halo}: {} of {fields} fields with an inexact chunk ({} of {} \
                 chunks, {} triangles)",
                failing[k], t.inexact, t.chunks, t.wrong
            );
        }
        return Ok(());
    }
    let (cells, field) = match object {
        "asteroid" => (
            [64; 3],
            Scaled {
                inner: Box::new(Asteroid::new(Vec3::ZERO, AsteroidParams::default())),
                origin: Vec3::splat(-1.0),
                h: 2.0 / 64.0,
            },
        ),
        "terrain" => {
            let h = 8.0 / 256.0;
            (
                [128, 64, 128],
                Scaled {
                    inner: Box::new(SvobodaTerrain::new(SvobodaParams::default())),
                    origin: Vec3::new(0.0, -32.0 * h, 0.0),
                    h,
                },
            )
        }
        other => return Err(format!("object: asteroid, terrain or random, got {other:?}").into()),
    };
    let (whole, rows) = measure(&field, cells, chunk, &runs)?;
    println!(
        "{object} {cells:?} cells, chunks of {chunk}^3, BCDL integrated, whole volume: {whole} \
         triangles"
    );
    for (r, &halo) in rows.iter().zip(&runs) {
        println!(
            "global rule, halo {halo}: {} of {} chunks with triangles not in the whole ({} \
             triangles); chunks' triangles over the whole's {:.4}; median chunk {:.2} ms",
            r.inexact,
            r.chunks,
            r.wrong,
            r.kept as f64 / whole.max(1) as f64,
            r.median_s * 1e3
        );
    }
    Ok(())
}
