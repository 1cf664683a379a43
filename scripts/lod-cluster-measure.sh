#!/usr/bin/env bash
# Clustering at every level (issue 40, part 2): what the tile rule at chunk faces and plain
# marching tetrahedra in the transition layer cost in triangles, on viewer maps of cave worlds.
#
#   scripts/lod-cluster-measure.sh [OUT_DIR]
#
# 1. `lod_cluster` (rmt-terrain example) meshes each viewer map with plain MT, classes every
#    chunk (uniform: its tets are exactly its level's body-centred lattice; transition; boundary:
#    near the world's x or z faces) and writes per level a job listing the uniform chunks.
# 2. Integrated clustering takes no tiles since commit 0af9409 (the extractor refuses them and
#    lost the tile checks of its quotient test, lone crossings and sliver passes), so the jobs
#    run on the extractor of the commit before it, built in a temporary directory: per uniform
#    chunk, plain MT (the chunk plus one cell of halo), integrated clustering over the level's
#    whole lattice without tiles, and with tiles = chunks. Values are sampled at the lattice
#    points' world positions exactly as the multiresolution mesh samples them (lattice units,
#    exact), so the plain counts must equal the multiresolution mesh's chunk for chunk; the
#    chunks on the world's bottom face, where its domain stops half a coarsest cell short,
#    differ and are counted as boundary.
# 3. A summary per world: measured counts, and a projection to the whole map with the uniform
#    chunks' ratios applied to the boundary chunks (lattice chunks like them).
#
# Results with the multiresolution mesh of commit 84f6b95 (three viewer maps per world):
# - integrated clustering keeps 0.209-0.219 of plain MT's triangles in uniform chunks, at every
#   level; with tiles = chunks 0.41-0.44 for chunks of 8^3 cells (1.86-2.05x untiled; 0.68 at
#   level 2 of `big`, 18 chunks) and 0.33 for 16^3 at level 0 (1.52x; 0.47 at level 1, 18 chunks);
# - transition chunks hold 16% (ci), 43% (big) and 24% (big16) of the plain world's triangles;
# - projected over the maps (triangles over plain MT): tiles = chunks with a plain transition
#   layer 0.51 / 0.67 / 0.50; untiled per level with a plain transition layer 0.35 / 0.55 / 0.41;
#   everything clustered 0.22.
# (The message of the commit that added this script quoted projections taken with an earlier
# working-tree state of the mesh code; these replace them. The uniform chunks' ratios agree.)
set -euo pipefail
root=$(cd "$(dirname "$0")/.." && pwd)
out=${1:-lod-cluster}
mkdir -p "$out"
out=$(cd "$out" && pwd)
cd "$root"
cargo build --release -p rmt-terrain --example lod_cluster
for w in ci big big16; do
  rm -rf "${out:?}/$w"
  target/release/examples/lod_cluster "$out/$w" "$w"
done

old=$(mktemp -d)
trap 'rm -rf "$old"' EXIT
git archive 0af9409^ Cargo.toml Cargo.lock crates/extract crates/fields crates/mesh | tar -x -C "$old"
sed -i 's|members = \["crates/\*", "experiments"\]|members = ["crates/extract", "crates/fields", "crates/mesh", "oldlod"]|' "$old/Cargo.toml"
mkdir -p "$old/oldlod/src"
cat > "$old/oldlod/Cargo.toml" <<'TOML'
[package]
name = "oldlod"
version.workspace = true
edition.workspace = true
license.workspace = true

[dependencies]
glam.workspace = true
rmt-extract = { path = "../crates/extract" }
rmt-fields.workspace = true
rmt-mesh.workspace = true
TOML
cat > "$old/oldlod/src/main.rs" <<'RUST'
//! Counts, per chunk of one level's uniform region, the triangles of plain MT, integrated
//! clustering without tiles and integrated clustering under the tile rule with tiles = chunks,
//! with the last extractor that accepted tiles for integrated clustering.
use glam::{DVec3, Vec3};
use rmt_extract::{Clustering, ExtractSettings, Extractor, Grid, Lattice, Tiling};
use rmt_fields::{CaveParams, CaveTerrain, ScalarField};

struct Scaled {
    field: CaveTerrain,
    s: f64,
    origin: DVec3,
    h: f64,
}

impl ScalarField for Scaled {
    fn sample(&self, p: Vec3) -> f32 {
        let u = (p.as_dvec3() * self.s).round();
        self.field.sample((self.origin + u * (self.h * 0.5)).as_vec3())
    }
}

fn main() {
    let path = std::env::args().nth(1).expect("job file");
    let text = std::fs::read_to_string(&path).expect("read");
    let mut lines = text.lines();
    let head: Vec<f64> = lines.next().unwrap().split_whitespace().map(|x| x.parse().unwrap()).collect();
    // s nx ny nz ox oy oz h chunk
    let s = head[0];
    let cells = [head[1] as usize, head[2] as usize, head[3] as usize];
    let origin = DVec3::new(head[4], head[5], head[6]);
    let h = head[7];
    let chunk = head[8] as usize;
    let chunks: Vec<[usize; 3]> = lines
        .filter(|l| !l.trim().is_empty())
        .map(|l| {
            let v: Vec<usize> = l.split_whitespace().map(|x| x.parse().unwrap()).collect();
            [v[0], v[1], v[2]]
        })
        .collect();
    let field = Scaled { field: CaveTerrain::new(CaveParams::default()), s, origin, h };
    let grid = Grid::new(cells, Vec3::ZERO, Vec3::new(cells[0] as f32, cells[1] as f32, cells[2] as f32));
    let mut counts = vec![[0usize; 3]; chunks.len()];
    let index: std::collections::HashMap<[usize; 3], usize> =
        chunks.iter().enumerate().map(|(i, c)| (*c, i)).collect();
    for (k, (clustering, tiles)) in [
        (Clustering::Integrated, false),
        (Clustering::Integrated, true),
    ]
    .into_iter()
    .enumerate()
    {
        let k = k + 1;
        let mut st = ExtractSettings::new(grid, Lattice::BodyCentred, clustering);
        st.threads = 2;
        if tiles {
            st.tiles = Some(Tiling::new([chunk; 3], [0; 3]));
        }
        let mut ex = Extractor::new();
        ex.set_recording(true);
        let mut mesh = rmt_mesh::Mesh::default();
        ex.extract(&field, &st, &mut mesh).expect("extract");
        for &c in ex.triangle_cells() {
            let c = c as usize;
            let cell = [c % cells[0], (c / cells[0]) % cells[1], c / (cells[0] * cells[1])];
            let key = cell.map(|v| v / chunk);
            if let Some(&i) = index.get(&key) {
                counts[i][k] += 1;
            }
        }
    }
    // Plain MT is local: each chunk with one cell of halo (clipped at the world), kept cells
    // the chunk's (recording is for clustering only).
    for (i, c) in chunks.iter().enumerate() {
        let lo: [usize; 3] = std::array::from_fn(|a| (c[a] * chunk).saturating_sub(1));
        let hi: [usize; 3] = std::array::from_fn(|a| ((c[a] + 1) * chunk + 1).min(cells[a]));
        let n: [usize; 3] = std::array::from_fn(|a| hi[a] - lo[a]);
        let v = |x: [usize; 3]| Vec3::new(x[0] as f32, x[1] as f32, x[2] as f32);
        let mut st = ExtractSettings::new(Grid::new(n, v(lo), v(hi)), Lattice::BodyCentred, Clustering::None);
        st.keep_cells = Some(rmt_extract::CellRange {
            lo: std::array::from_fn(|a| c[a] * chunk - lo[a]),
            hi: std::array::from_fn(|a| ((c[a] + 1) * chunk).min(cells[a]) - lo[a]),
        });
        let mut ex = Extractor::new();
        let mut mesh = rmt_mesh::Mesh::default();
        ex.extract(&field, &st, &mut mesh).expect("extract plain");
        counts[i][0] = mesh.triangle_count();
    }
    for (c, n) in chunks.iter().zip(&counts) {
        println!("{} {} {} {} {} {}", c[0], c[1], c[2], n[0], n[1], n[2]);
    }
}
RUST
(cd "$old" && CARGO_TARGET_DIR="$old/target" cargo build --release -p oldlod)
for w in ci big big16; do
  for j in "$out/$w"/job-*.txt; do
    "$old/target/release/oldlod" "$j" > "${j%.txt}.out"
  done
done
python3 - "$out" <<'PY'
import csv, glob, collections
import sys, os
os.chdir(sys.argv[1])
for w in ['ci', 'big', 'big16']:
    rows = list(csv.DictReader(open(f'{w}/chunks.csv')))
    lod = {(int(r['map']), int(r['level']), int(r['x']), int(r['y']), int(r['z'])): (r['class'], int(r['triangles'])) for r in rows}
    ext = {}
    for f in glob.glob(f'{w}/job-*.out'):
        m, l = map(int, f.split('job-')[1].split('.')[0].split('-'))
        for line in open(f):
            x, y, z, p, u, t = map(int, line.split())
            ext[(m, l, x, y, z)] = (p, u, t)
    # uniform chunks whose plain count differs from the extractor's (bottom face) -> boundary
    cls = {}
    bad = 0
    for k, (c, n) in lod.items():
        if c == 'uniform' and ext[k][0] != n:
            c = 'boundary'; bad += 1
        cls[k] = c
    print(f'== {w}  (uniform chunks moved to boundary, plain counts differ at the bottom face: {bad}; all others equal)')
    print('| map | chunks U/T/B | none | U plain / untiled / tiles | T plain | B plain | tiles=chunks | untiled region | + transition clustered (est.) |')
    for m in sorted({k[0] for k in lod}) + ['all']:
        keys = [k for k in lod if m == 'all' or k[0] == m]
        none = sum(lod[k][1] for k in keys)
        U = [k for k in keys if cls[k] == 'uniform']
        T = [k for k in keys if cls[k] == 'transition']
        B = [k for k in keys if cls[k] == 'boundary']
        up = sum(ext[k][0] for k in U); uu = sum(ext[k][1] for k in U); ut = sum(ext[k][2] for k in U)
        tp = sum(lod[k][1] for k in T); bp = sum(lod[k][1] for k in B)
        r = uu / up if up else 0
        tiles = tp + bp + ut; untiled = tp + bp + uu; est = tp * r + bp + uu
        print(f'| {m} | {len(U)}/{len(T)}/{len(B)} | {none} | {up} / {uu} / {ut} | {tp} | {bp} | {tiles} ({tiles/none:.3f}) | {untiled} ({untiled/none:.3f}) | {est:.0f} ({est/none:.3f}) |')
    per = collections.defaultdict(lambda: [0,0,0,0])
    for k in lod:
        if cls[k] == 'uniform':
            a = per[k[1]]; a[0] += 1; a[1] += ext[k][0]; a[2] += ext[k][1]; a[3] += ext[k][2]
    for l in sorted(per):
        a = per[l]
        print(f'  level {l}: uniform chunks {a[0]}, plain {a[1]}, untiled {a[2]} ({a[2]/a[1]:.3f} of plain), tiles=chunks {a[3]} ({a[3]/a[1]:.3f}; {a[3]/a[2]:.2f}x untiled)')
    # Projection over all maps: boundary chunks clustered like uniform ones.
    none = sum(n for _, n in lod.values())
    U = [k for k in lod if cls[k] == 'uniform']
    up = sum(ext[k][0] for k in U); uu = sum(ext[k][1] for k in U); ut = sum(ext[k][2] for k in U)
    tp = sum(lod[k][1] for k in lod if cls[k] == 'transition')
    lat = none - tp
    ru, rt = uu / up, ut / up
    print(f'  projection over all maps (triangles over plain MT): transition layer {tp / none:.3f} of the plain world;')
    print(f'    tiles = chunks, transition plain {(rt * lat + tp) / none:.3f}; untiled per level, transition plain {(ru * lat + tp) / none:.3f}; everything clustered {ru:.3f}')
PY
