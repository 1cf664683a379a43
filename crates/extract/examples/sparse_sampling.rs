//! Sparse against dense sampling: median sampling and total times, points evaluated and blocks
//! skipped, per object, with the same meshes checked.
//!
//! ```text
//! cargo run --release -p rmt-extract --example sparse_sampling -- [n] [reps] [threads] [clustering]
//! cargo run --release -p rmt-extract --example sparse_sampling -- growth [threads] [reps] [max_n]
//! ```
//!
//! The first form extracts the sphere, asteroid, torus, gyroid and terrains at `n^3` (default
//! 128, body-centred lattice, clustering `none` or `integrated`) with both samplings and prints
//! the median sampling and total times, their ratio and the share of points evaluated. `growth`
//! times the whole extraction (sparse sampling, integrated clustering, body-centred) of the
//! sphere and the asteroid from 64^3 to `max_n`^3 (default 512) and fits `t = a N^b`.
use noise::{Fbm, MultiFractal, NoiseFn, Perlin};
use rmt_extract::{Clustering, ExtractSettings, Extractor, Grid, Lattice, NormalMode, Sampling};
use rmt_fields::{
    Asteroid, AsteroidParams, CaveParams, CaveTerrain, Gyroid, ScalarField, Sphere, SvobodaParams,
    SvobodaTerrain, Torus,
};
use rmt_mesh::Mesh;

fn median(mut v: Vec<f64>) -> f64 {
    v.sort_by(f64::total_cmp);
    v[v.len() / 2]
}

fn arg<T: std::str::FromStr>(args: &[String], i: usize, default: T) -> Result<T, String> {
    match args.get(i) {
        None => Ok(default),
        Some(s) => s
            .parse()
            .map_err(|_| format!("argument {i}: cannot parse {s:?}")),
    }
}

fn clustering(name: &str) -> Result<Clustering, String> {
    match name {
        "none" => Ok(Clustering::None),
        "integrated" => Ok(Clustering::Integrated),
        other => Err(format!("clustering: none or integrated, got {other:?}")),
    }
}

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let args: Vec<String> = std::env::args().skip(1).collect();
    if args.first().map(String::as_str) == Some("growth") {
        return growth(arg(&args, 1, 2)?, arg(&args, 2, 3)?, arg(&args, 3, 512)?);
    }
    let n: usize = arg(&args, 0, 128)?;
    let reps: usize = arg(&args, 1, 5)?;
    let threads: usize = arg(&args, 2, 1)?;
    let clustering = clustering(args.get(3).map_or("none", String::as_str))?;
    if n == 0 || reps == 0 || threads == 0 {
        return Err("n, reps and threads must be at least 1".into());
    }
    let fields: Vec<(&str, Box<dyn ScalarField>)> = vec![
        ("sphere", Box::new(Sphere::new(glam::Vec3::ZERO, 0.8))),
        (
            "asteroid",
            Box::new(Asteroid::new(glam::Vec3::ZERO, AsteroidParams::default())),
        ),
        (
            "torus",
            Box::new(Torus {
                centre: glam::Vec3::ZERO,
                major: 0.6,
                minor: 0.25,
            }),
        ),
        (
            "gyroid",
            Box::new(Gyroid {
                frequency: 1.5,
                thickness: 0.3,
            }),
        ),
        (
            "terrain",
            Box::new(SvobodaTerrain::new(SvobodaParams::default())),
        ),
        ("caves", Box::new(CaveTerrain::new(CaveParams::default()))),
    ];
    println!(
        "{n}^3 bcdl {}, {threads} thread(s), median of {reps}: sampling dense / sparse ms, ratio; total dense / sparse ms; points evaluated; blocks skipped",
        clustering.name()
    );
    // Before this work: the asteroid sampled at every point through the noise crate, one point
    // at a time (a closure field has no range and no batch evaluation).
    let params = AsteroidParams::default();
    let fbm = Fbm::<Perlin>::new(params.seed)
        .set_octaves(params.octaves)
        .set_frequency(params.frequency);
    // `Asteroid::sample` as it was: the crate's `f64` noise at the `f32` point.
    let before = rmt_fields::FnField(|p: glam::Vec3| {
        let n = fbm.get([p.x, p.y, p.z].map(f64::from)) as f32;
        p.length() - params.radius + params.amplitude * n
    });
    {
        let mut s = ExtractSettings::new(Grid::cube(n, 1.0), Lattice::BodyCentred, clustering);
        s.threads = threads;
        s.normals = NormalMode::Skip;
        let mut ex = Extractor::new();
        let mut mesh = Mesh::default();
        ex.extract(&before, &s, &mut mesh)?;
        let (mut ts, mut tt) = (Vec::new(), Vec::new());
        for _ in 0..reps {
            let st = ex.extract(&before, &s, &mut mesh)?;
            ts.push(st.t_sampling_s * 1e3);
            tt.push(st.t_total_s * 1e3);
        }
        println!(
            "asteroid before (noise crate, every point): sampling {:8.2} ms, total {:8.2} ms",
            median(ts),
            median(tt)
        );
    }
    for (name, field) in &fields {
        let mut s = ExtractSettings::new(Grid::cube(n, 1.0), Lattice::BodyCentred, clustering);
        s.threads = threads;
        s.normals = NormalMode::Skip;
        let mut row = Vec::new();
        let mut meshes = Vec::new();
        for sampling in [Sampling::Dense, Sampling::Sparse] {
            let mut ex = Extractor::new();
            ex.set_sampling(sampling);
            let mut mesh = Mesh::default();
            let first = ex.extract(field.as_ref(), &s, &mut mesh)?;
            let (mut ts, mut tt) = (Vec::new(), Vec::new());
            for _ in 0..reps {
                let st = ex.extract(field.as_ref(), &s, &mut mesh)?;
                ts.push(st.t_sampling_s * 1e3);
                tt.push(st.t_total_s * 1e3);
            }
            row.push((median(ts), median(tt), first));
            meshes.push((mesh.positions, mesh.indices));
        }
        let same = meshes[0] == meshes[1];
        let (ds, dt, _) = &row[0];
        let (ss, st, stats) = &row[1];
        println!(
            "{name:9} sampling {ds:8.2} / {ss:8.2} ms = {:.3}; total {dt:8.2} / {st:8.2} ms = {:.3}; points {:5.1}%; blocks skipped {}/{} ({:.1}%); same mesh: {same}",
            ss / ds,
            st / dt,
            100.0 * stats.points_sampled as f64 / stats.sample_points as f64,
            stats.blocks_skipped,
            stats.blocks,
            100.0 * stats.blocks_skipped as f64 / stats.blocks.max(1) as f64,
        );
        if !same {
            return Err(format!("{name}: sparse and dense meshes differ").into());
        }
    }
    Ok(())
}

/// Whole-extraction time against resolution, sparse sampling, integrated clustering.
fn growth(threads: usize, reps: usize, max_n: usize) -> Result<(), Box<dyn std::error::Error>> {
    let fields: Vec<(&str, Box<dyn ScalarField>)> = vec![
        ("sphere", Box::new(Sphere::new(glam::Vec3::ZERO, 0.8))),
        (
            "asteroid",
            Box::new(Asteroid::new(glam::Vec3::ZERO, AsteroidParams::default())),
        ),
    ];
    println!("bcdl integrated, sparse sampling, {threads} thread(s), median of {reps}");
    for (name, field) in &fields {
        let mut points = Vec::new();
        let mut n = 64;
        while n <= max_n {
            let mut s = ExtractSettings::new(
                Grid::cube(n, 1.0),
                Lattice::BodyCentred,
                Clustering::Integrated,
            );
            s.threads = threads;
            let mut ex = Extractor::new();
            ex.set_buffer_policy(rmt_extract::BufferPolicy::Lean);
            let mut mesh = Mesh::default();
            let mut t = Vec::new();
            let mut last = None;
            for _ in 0..reps {
                let st = ex.extract(field.as_ref(), &s, &mut mesh)?;
                t.push(st.t_total_s);
                last = Some(st);
            }
            let t = median(t);
            let st = last.ok_or("no repetition")?;
            println!(
                "{name:9} {n:4}^3: total {:9.1} ms (sampling {:8.1}, vertex {:8.1}, geometry {:8.1}); points evaluated {:.1}%; {} triangles",
                t * 1e3,
                st.t_sampling_s * 1e3,
                st.t_vertex_s * 1e3,
                st.t_geometry_s * 1e3,
                100.0 * st.points_sampled as f64 / st.sample_points as f64,
                st.triangles
            );
            points.push(((n as f64).ln(), t.ln()));
            n *= 2;
        }
        let k = points.len() as f64;
        let mx = points.iter().map(|p| p.0).sum::<f64>() / k;
        let my = points.iter().map(|p| p.1).sum::<f64>() / k;
        let sxy: f64 = points.iter().map(|p| (p.0 - mx) * (p.1 - my)).sum();
        let sxx: f64 = points.iter().map(|p| (p.0 - mx).powi(2)).sum();
        println!("{name:9} growth exponent b of t = a N^b: {:.2}", sxy / sxx);
    }
    Ok(())
}
