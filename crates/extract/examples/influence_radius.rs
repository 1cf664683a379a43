//! How far one changed sample value can change the mesh, per clustering mode: the empirical
//! radius that a chunk's halo must cover for chunked output to equal the whole volume's (issue
//! 18's bounded-radius rule).
//!
//! ```text
//! cargo run --release -p rmt-extract --example influence_radius -- [n] [perturbations] [seed] [random]
//! ```
//!
//! The asteroid on `n^3` body-centred cells of `[-1, 1]^3` (default 32) is extracted once per
//! mode; then, `perturbations` times (default 200), one sample point near the surface (value
//! within one cell of the isovalue) gets its value moved by up to one cell's worth, and the
//! mesh is extracted again. With `random`, every perturbation has its own field of the property
//! tests' families (`RandomField::from_seed`: blobs, waves, thin shells and tubes, a quarter of
//! them quantised so that samples sit exactly on the threshold; and, for a third of the fields,
//! thin sheets and stairs; use `n` about 10), and the
//! moved point (among the fifth of points nearest the threshold) gets its value scaled by -1,
//! -1/2, 0 or 1/2: its side may flip, and it may land exactly on the threshold. Triangles are compared by their vertex positions (bit for bit, up to
//! rotation); the radius of a perturbation is the largest distance, in cells, from the moved
//! point to the centroid of a triangle that appeared or disappeared. Prints per mode the median,
//! 99th percentile and largest radius, and how many perturbations changed nothing.
use std::collections::HashSet;

use glam::Vec3;
use rmt_extract::{Clustering, ExtractSettings, Extractor, Grid, Lattice, NormalMode, Samples};
use rmt_fields::{Asteroid, AsteroidParams, RandomFamily, RandomField, ScalarField};
use rmt_mesh::Mesh;

/// The asteroid with the value at one position moved by `delta` (sampled densely: no range).
struct Moved<'a> {
    inner: &'a dyn ScalarField,
    at: Vec3,
    delta: f32,
}

impl ScalarField for Moved<'_> {
    fn sample(&self, p: Vec3) -> f32 {
        let v = self.inner.sample(p);
        if p == self.at {
            v + self.delta
        } else {
            v
        }
    }
}

/// A triangle as its three vertex positions' bits, rotated so that the smallest comes first
/// (orientation kept).
type Key = [[u32; 3]; 3];

fn triangles(mesh: &Mesh) -> HashSet<Key> {
    mesh.indices
        .chunks_exact(3)
        .map(|t| {
            let k: Key = [0, 1, 2].map(|i| mesh.positions[t[i] as usize].map(f32::to_bits));
            let first = (0..3).min_by_key(|&i| k[i]).unwrap_or(0);
            [0, 1, 2].map(|i| k[(first + i) % 3])
        })
        .collect()
}

fn centroid(k: &Key) -> Vec3 {
    k.iter()
        .map(|v| Vec3::from(v.map(f32::from_bits)))
        .sum::<Vec3>()
        / 3.0
}

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let args: Vec<String> = std::env::args().collect();
    let parse = |i: usize, default: u64| -> Result<u64, String> {
        args.get(i).map_or(Ok(default), |s| {
            s.parse()
                .map_err(|_| format!("argument {i}: expected a whole number, got {s:?}"))
        })
    };
    let n = parse(1, 32)? as usize;
    let count = parse(2, 200)? as usize;
    let mut seed = parse(3, 1)? | 1;
    let random = match args.get(4).map(String::as_str) {
        None => false,
        Some("random") => true,
        Some(other) => return Err(format!("argument 4: expected `random`, got {other:?}").into()),
    };
    if !(4..=256).contains(&n) || count == 0 {
        return Err("n must be in 4..=256 and perturbations at least 1".into());
    }
    let mut next = move || {
        seed ^= seed << 13;
        seed ^= seed >> 7;
        seed ^= seed << 17;
        seed
    };
    let asteroid = Asteroid::new(Vec3::ZERO, AsteroidParams::default());
    let grid = Grid::cube(n, 1.0);
    let h = 2.0 / n as f32;
    let settings_for = |clustering| {
        let mut s = ExtractSettings::new(grid, Lattice::BodyCentred, clustering);
        s.threads = 1;
        s.normals = NormalMode::Skip;
        s
    };
    let mut layout = Samples::default();
    layout.prepare(&settings_for(Clustering::None));
    // Every lattice point's position (corners, then centres; ghosts are on the box faces).
    let points: Vec<Vec3> = (0..2)
        .flat_map(|odd: i32| {
            let m = n as i32 + 1 - odd;
            (0..m * m * m).map(move |i| [i % m, i / m % m, i / (m * m)].map(|c| 2 * c + odd))
        })
        .map(|p| layout.bcdl_position(p))
        .collect();
    // The perturbations: a field (index into `fields`), a point near its surface, and how far
    // its value moves.
    let mut fields: Vec<Box<dyn ScalarField>> = Vec::new();
    if !random {
        fields.push(Box::new(asteroid));
    }
    let mut moves: Vec<(usize, Vec3, f32)> = Vec::with_capacity(count);
    // A random field of `family`, unquantised, on `[-1, 1]^3`.
    let unquantised = |family| RandomField {
        family,
        quantum: 0.0,
        centre: Vec3::ZERO,
        half: 1.0,
    };
    while moves.len() < count {
        let pick = |r: u64| points[(r % points.len() as u64) as usize];
        if random {
            // A third of the fields are the property tests' cascade makers: thin sheets, and
            // stairs (whole layers of points exactly on the threshold).
            let (which, field_seed) = (next() % 6, next());
            let mut unit = || (next() % 2001) as f32 / 1000.0 - 1.0;
            let field = match which {
                0 => unquantised(RandomFamily::Sheet(
                    Vec3::new(unit(), unit(), unit()),
                    0.5 * unit(),
                    h * (0.55 + 0.45 * unit()),
                )),
                1 => unquantised(RandomFamily::Stairs(
                    Vec3::new(unit(), unit(), unit()) * (2.0 / h),
                    0.5 * unit(),
                )),
                _ => RandomField::from_seed(field_seed),
            };
            let mut near: Vec<f32> = points.iter().map(|&p| field.sample(p).abs()).collect();
            near.sort_by(f32::total_cmp);
            let limit = near[near.len() / 5];
            let at = (0..1000)
                .map(|_| pick(next()))
                .find(|&p| field.sample(p).abs() <= limit);
            if let Some(at) = at {
                let f = field.sample(at);
                let scale = (next() % 4) as f32 / 2.0 - 1.0;
                moves.push((fields.len(), at, f * scale - f));
                fields.push(Box::new(field));
            }
        } else {
            let at = pick(next());
            if fields[0].sample(at).abs() < h {
                let delta = h * ((next() % 2001) as f32 / 1000.0 - 1.0);
                moves.push((0, at, delta));
            }
        }
    }
    println!(
        "{} {n}^3 bcdl, {count} moved values near the surface: radius (cells) from the moved \
         point to the farthest changed triangle",
        if random { "random fields" } else { "asteroid" }
    );
    for clustering in [
        Clustering::None,
        Clustering::IntegratedUnchecked,
        Clustering::Integrated,
    ] {
        let settings = settings_for(clustering);
        let mut extractor = Extractor::new();
        let mut mesh = Mesh::default();
        let mut radii = Vec::with_capacity(count);
        let mut unchanged = 0;
        let (mut base, mut base_of) = (HashSet::new(), None);
        for &(fi, at, delta) in &moves {
            let field = fields[fi].as_ref();
            if base_of != Some(fi) {
                extractor.extract(field, &settings, &mut mesh)?;
                base = triangles(&mesh);
                base_of = Some(fi);
            }
            let moved = Moved {
                inner: field,
                at,
                delta,
            };
            extractor.extract(&moved, &settings, &mut mesh)?;
            let now = triangles(&mesh);
            let radius = base
                .symmetric_difference(&now)
                .map(|k| centroid(k).distance(at) / h)
                .fold(None, |m: Option<f32>, r| Some(m.map_or(r, |m| m.max(r))));
            match radius {
                Some(r) => radii.push(r),
                None => unchanged += 1,
            }
        }
        radii.sort_by(f32::total_cmp);
        let at = |q: f64| {
            radii
                .get(((radii.len() as f64 - 1.0) * q).round() as usize)
                .copied()
                .unwrap_or(0.0)
        };
        println!(
            "{:<22} median {:5.2}  p99 {:5.2}  max {:5.2}  unchanged {unchanged}/{count}",
            format!("{clustering:?}"),
            at(0.5),
            at(0.99),
            at(1.0)
        );
    }
    Ok(())
}
