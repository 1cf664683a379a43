//! The slivers of edge collapse (post-processed clustering) on the paper manifest's objects, and
//! why they are left: per configuration (sphere, asteroid, bunny at the paper's resolutions and
//! boxes, both lattices, threshold 0.5 h) the triangles and radius ratio (mean, p95, max) of plain
//! MT and of post-processed clustering, the triangles with a (near) zero-length edge and the caps,
//! and for every sliver left what edge collapse did with its short edges (from
//! [`Extractor::collapse_log`]).
//!
//! `cargo run --release -p rmt-extract --example collapse_slivers [-- --list]` (`--list` prints
//! every sliver left). The bunny needs `data/bunny.obj` (run from the workspace root, or set
//! `RMT_BUNNY`).
//!
//! Names follow the paper manifest: `ss`/`as`/`bs` (sphere, asteroid, bunny), then `_b`/`_s`
//! (lattice) and `p` (post-processed). A *sliver* has a radius ratio above 10 (or zero area); a
//! *zero-length edge* is shorter than 1e-4 h; a *cap* is a sliver with no edge shorter than the
//! collapse threshold.
use std::collections::HashMap;

use glam::Vec3;
use rmt_extract::{
    Clustering, CollapseOutcome, ExtractSettings, Extractor, Grid, Lattice, NormalMode,
};
use rmt_fields::{Asteroid, AsteroidParams, MeshSdf, ScalarField, Sphere};
use rmt_mesh::Mesh;

/// Radius ratio above which a triangle counts as a sliver.
const SLIVER: f64 = 10.0;
/// Edges shorter than this many grid spacings count as zero-length.
const ZERO: f64 = 1e-4;

struct Shape {
    lengths: [f64; 3],
    ratio: f64,
}

fn shape(mesh: &Mesh, t: [u32; 3]) -> Shape {
    let p = t.map(|i| glam::DVec3::from(mesh.positions[i as usize].map(f64::from)));
    // Edge e joins corners e and e + 1.
    let lengths = [0, 1, 2].map(|e| (p[(e + 1) % 3] - p[e]).length());
    let double_area = (p[1] - p[0]).cross(p[2] - p[0]).length();
    let [a, b, c] = lengths;
    let s = 0.5 * (a + b + c);
    let area = 0.5 * double_area;
    let ratio = if area > 0.0 {
        a * b * c * s / (8.0 * area * area)
    } else {
        f64::INFINITY
    };
    Shape { lengths, ratio }
}

#[derive(Default)]
struct Row {
    triangles: usize,
    mean: f64,
    p95: f64,
    max: f64,
    zero_area: usize,
    zero_edge: usize,
    short_slivers: usize,
    caps: usize,
    closed: bool,
    euler: i64,
}

fn row(mesh: &Mesh, grid: &Grid, threshold: f64) -> Row {
    let q = rmt_mesh::quality(mesh);
    let v = rmt_mesh::validate(mesh, &|p| rmt_extract::measure::on_box_boundary(grid, p));
    let h = f64::from(grid.h());
    let mut r = Row {
        triangles: mesh.triangle_count(),
        mean: q.ar_mean,
        p95: q.ar_p95,
        max: q.ar_max,
        zero_area: q.zero_area_triangles,
        closed: v.is_watertight_manifold(),
        euler: v.euler,
        ..Row::default()
    };
    for t in mesh.triangles() {
        let s = shape(mesh, t);
        let shortest = s.lengths.iter().copied().fold(f64::INFINITY, f64::min);
        if shortest < ZERO * h {
            r.zero_edge += 1;
        }
        if s.ratio > SLIVER {
            if shortest < threshold * h {
                r.short_slivers += 1;
            } else {
                r.caps += 1;
            }
        }
    }
    r
}

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let list = std::env::args().any(|a| a == "--list");
    let bunny_path = std::env::var("RMT_BUNNY").unwrap_or_else(|_| "data/bunny.obj".into());
    let cube = Grid::cube(50, 1.0);
    let bunny_grid = Grid::new(
        [75, 40, 56],
        Vec3::new(-4.96, -0.01, -3.73),
        Vec3::new(4.95, 9.66, 3.81),
    );
    let bunny_mesh = rmt_mesh::io::read_mesh(&bunny_path)
        .map_err(|e| format!("{bunny_path}: {e} (run from the workspace root or set RMT_BUNNY)"))?;
    let band = 2.0 * bunny_grid.spacing().max_element();
    let bunny = MeshSdf::fit(&bunny_mesh, bunny_grid.min, bunny_grid.max, 0.09)?.with_band(band);
    let objects: Vec<(&str, Box<dyn ScalarField>, Grid)> = vec![
        ("ss", Box::new(Sphere::new(Vec3::ZERO, 1.0)), cube),
        (
            "as",
            Box::new(Asteroid::new(Vec3::ZERO, AsteroidParams::default())),
            cube,
        ),
        ("bs", Box::new(bunny), bunny_grid),
    ];
    println!(
        "{:5} {:>7} {:>7} | {:>7} {:>7} {:>7} {:>10} {:>5} {:>5} {:>5} {:>4} {:>6} {:>5} | \
         short-edge slivers: refused (disc/cone/flip) / skipped (moved apart/tile) / no candidate",
        "conf",
        "MT tri",
        "MT mean",
        "tri",
        "mean",
        "p95",
        "max",
        "zarea",
        "zedge",
        "short",
        "caps",
        "closed",
        "euler"
    );
    for (code, field, grid) in &objects {
        for lattice in [Lattice::BodyCentred, Lattice::Simple] {
            let name = format!(
                "{code}_{}p",
                if lattice == Lattice::BodyCentred {
                    "b"
                } else {
                    "s"
                }
            );
            let mut ex = Extractor::new();
            ex.set_recording(true);
            let mut s = ExtractSettings::new(*grid, lattice, Clustering::None);
            s.normals = NormalMode::Skip;
            let threshold = f64::from(s.collapse_threshold);
            let mut plain = Mesh::default();
            ex.extract(field.as_ref(), &s, &mut plain)?;
            s.clustering = Clustering::Postprocessed;
            let mut post = Mesh::default();
            let stats = ex.extract(field.as_ref(), &s, &mut post)?;
            let before = row(&plain, grid, threshold);
            let after = row(&post, grid, threshold);
            // What edge collapse did with each output edge's candidates.
            let mut outcomes: HashMap<[u32; 2], Vec<CollapseOutcome>> = HashMap::new();
            for a in ex.collapse_log() {
                let [x, y] = a.ends;
                outcomes
                    .entry([x.min(y), x.max(y)])
                    .or_default()
                    .push(a.outcome);
            }
            let h = f64::from(grid.h());
            // Per short edge of a sliver: refused (by reason), skipped, never a candidate.
            let (mut disc, mut cone, mut flip, mut apart, mut tile, mut none) = (0, 0, 0, 0, 0, 0);
            for t in post.triangles() {
                let sh = shape(&post, t);
                if sh.ratio <= SLIVER {
                    continue;
                }
                let longest = sh.lengths.iter().copied().fold(0.0, f64::max);
                for e in 0..3 {
                    if sh.lengths[e] >= threshold * h {
                        continue;
                    }
                    let (x, y) = (t[e], t[(e + 1) % 3]);
                    let seen = outcomes.get(&[x.min(y), x.max(y)]);
                    let last = seen.and_then(|o| o.last().copied());
                    match last {
                        Some(CollapseOutcome::NotADisc) => disc += 1,
                        Some(CollapseOutcome::NotACone) => cone += 1,
                        Some(CollapseOutcome::Flip) => flip += 1,
                        Some(CollapseOutcome::MovedApart) => apart += 1,
                        Some(CollapseOutcome::OtherTile) => tile += 1,
                        _ => none += 1,
                    }
                    if list {
                        let ring = |v: u32| -> std::collections::BTreeSet<u32> {
                            post.triangles()
                                .filter(|t| t.contains(&v))
                                .flatten()
                                .filter(|&u| u != v)
                                .collect()
                        };
                        let common = ring(x).intersection(&ring(y)).count();
                        let both = post
                            .triangles()
                            .filter(|t| t.contains(&x) && t.contains(&y))
                            .count();
                        println!(
                            "  {name}   common neighbours {common}, triangles on the edge {both}"
                        );
                        println!(
                            "  {name} sliver ratio {:.1}: edge {x}-{y} {:.2e} h (longest {:.2} h) \
                             at {:?}: {:?}",
                            sh.ratio,
                            sh.lengths[e] / h,
                            longest / h,
                            post.positions[x as usize],
                            seen
                        );
                    }
                }
                if list && sh.lengths.iter().all(|&l| l >= threshold * h) {
                    println!(
                        "  {name} cap ratio {:.1}: edges {:.2} {:.2} {:.2} h",
                        sh.ratio,
                        sh.lengths[0] / h,
                        sh.lengths[1] / h,
                        sh.lengths[2] / h
                    );
                }
            }
            println!(
                "{name:5} {:7} {:7.3} | {:7} {:7.3} {:7.3} {:10.1} {:5} {:5} {:5} {:4} {:>6} {:5} | \
                 {disc}/{cone}/{flip} / {apart}/{tile} / {none} | {} collapses, geometry {:.1} ms",
                before.triangles,
                before.mean,
                after.triangles,
                after.mean,
                after.p95,
                after.max,
                after.zero_area,
                after.zero_edge,
                after.short_slivers,
                after.caps,
                after.closed,
                after.euler,
                stats.collapses,
                stats.t_geometry_s * 1e3,
            );
        }
    }
    Ok(())
}
