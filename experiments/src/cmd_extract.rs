//! `experiments extract`: one extraction of one object, printed as a summary or as one JSON
//! object (the [`Measurement`] keys, preceded by the configuration keys `object`, `lattice`,
//! `clustering`, `method`, `resolution`, `bounds`, `collapse_threshold`, `iso`, `normals`,
//! `threads`), optionally saved as PLY, OBJ or binary glTF (by the extension of `--out`).
//!
//! ```text
//! experiments extract --object sphere --radius 1.0 --resolution 50 --lattice bcdl \
//!     --clustering integrated --out sphere.ply --json
//! ```

use std::path::PathBuf;

use anyhow::{Context, Result};
use rmt_extract::{BufferPolicy, Clustering, Extractor, Lattice, Measurement, Method};
use rmt_mesh::Mesh;
use serde_json::{Map, Value};

use crate::config::{self, Extraction, Normals};
use crate::objects::{Bounds, ObjectKind, ObjectParams, ObjectSpec, Resolution};

/// Arguments of `extract`.
#[derive(clap::Args, Debug)]
pub struct Args {
    /// Object: sphere, asteroid, gyroid, torus or bunny.
    #[arg(long, default_value = "sphere")]
    pub object: String,
    /// Object parameters (each object takes only its own).
    #[command(flatten)]
    pub params: ObjectParams,
    /// Cells per axis: N or NX,NY,NZ.
    #[arg(long, default_value = "50")]
    pub resolution: Resolution,
    /// Sampled box xmin,ymin,zmin,xmax,ymax,zmax (default -1,-1,-1,1,1,1).
    #[arg(long, allow_hyphen_values = true)]
    pub bounds: Option<Bounds>,
    /// Lattice: bcdl or simple (ignored by marching cubes).
    #[arg(long, default_value = "bcdl", value_parser = config::parse_lattice)]
    pub lattice: Lattice,
    /// Clustering: none, integrated, integrated-unchecked, postprocessed or meshopt (default:
    /// integrated for marching tetrahedra, none for marching cubes).
    #[arg(long, value_parser = config::parse_clustering)]
    pub clustering: Option<Clustering>,
    /// Method: mt (marching tetrahedra) or mc (marching cubes).
    #[arg(long, default_value = "mt", value_parser = config::parse_method)]
    pub method: Method,
    /// Edge-collapse threshold (post-processed) or error bound (meshopt), in grid spacings.
    #[arg(long)]
    pub collapse_threshold: Option<f32>,
    /// Isovalue.
    #[arg(long, default_value_t = 0.0, allow_hyphen_values = true)]
    pub iso: f32,
    /// Normals: area, gradient or none.
    #[arg(long, default_value = "area", value_parser = config::parse_normals)]
    pub normals: Normals,
    /// Worker threads (default: all cores).
    #[arg(long)]
    pub threads: Option<usize>,
    /// Write the mesh to this file, in the format its extension names: .ply (binary unless
    /// --ascii), .obj or .glb (binary glTF).
    #[arg(long)]
    pub out: Option<PathBuf>,
    /// Write ASCII PLY instead of binary (with a .ply --out).
    #[arg(long)]
    pub ascii: bool,
    /// Render a turntable GIF of the mesh (default turntable settings) to this file.
    #[arg(long)]
    pub gif: Option<PathBuf>,
    /// Print one JSON object instead of a summary.
    #[arg(long)]
    pub json: bool,
    /// Extract in chunks of C^3 cells, weld the chunks and compare with the whole volume
    /// extracted at once. Integrated clustering of marching tetrahedra, checked or not, has
    /// exact seams (the chunks are the whole volume's own mesh, cut by anchor cell); the other
    /// modes mesh each chunk on its own, in parallel, under the tile rule (collapses never cross
    /// a chunk face).
    /// Needs cubic cells; adds the keys `chunk_size`, `chunks`, `t_chunked_s`, `t_whole_s`,
    /// `whole_triangles`, `chunked_equals_whole`.
    #[arg(long, value_name = "C")]
    pub chunks: Option<usize>,
}

/// Threads to use when not told: every core the process may use.
pub fn default_threads() -> usize {
    std::thread::available_parallelism()
        .map(|n| n.get())
        .unwrap_or(1)
}

/// The extraction that `args` describe (checked, field not built yet).
pub fn extraction(args: &Args) -> Result<(Extraction, usize)> {
    let kind: ObjectKind = args.object.parse()?;
    let object = ObjectSpec::new(kind, args.params.clone())?;
    let threads = args.threads.unwrap_or_else(default_threads);
    let e = Extraction {
        object,
        bounds: args.bounds.unwrap_or_default(),
        resolution: args.resolution,
        method: args.method,
        lattice: args.lattice,
        clustering: args
            .clustering
            .unwrap_or_else(|| config::default_clustering(args.method)),
        collapse_threshold: args
            .collapse_threshold
            .unwrap_or_else(config::default_collapse_threshold),
        iso: args.iso,
        normals: args.normals,
    };
    e.check(threads).map_err(anyhow::Error::msg)?;
    Ok((e, threads))
}

/// The configuration keys that precede the measurement in JSON output.
pub fn config_json(e: &Extraction, threads: usize) -> Map<String, Value> {
    let mut m = Map::new();
    m.insert("object".into(), e.object.kind.name().into());
    m.insert(
        "lattice".into(),
        config::lattice_name(e.method, e.lattice).into(),
    );
    m.insert("clustering".into(), e.clustering.name().into());
    m.insert("method".into(), config::method_name(e.method).into());
    m.insert("resolution".into(), serde_json::json!(e.resolution.cells()));
    m.insert(
        "bounds".into(),
        serde_json::json!(<[f32; 6]>::from(e.bounds)),
    );
    m.insert(
        "collapse_threshold".into(),
        serde_json::json!(e.collapse_threshold),
    );
    m.insert("iso".into(), serde_json::json!(e.iso));
    m.insert("normals".into(), e.normals.name().into());
    m.insert("threads".into(), threads.into());
    m
}

/// The measurement as an ordered JSON map (its serde keys, flattened).
pub fn measurement_json(m: &Measurement) -> Result<Map<String, Value>> {
    match serde_json::to_value(m).context("serialising the measurement")? {
        Value::Object(map) => Ok(map),
        other => anyhow::bail!("the measurement serialised to {other}, not an object"),
    }
}

/// Runs `extract`.
pub fn run(args: Args) -> Result<()> {
    let (e, threads) = extraction(&args)?;
    if let Some(out) = &args.out {
        // Refuse an unknown format before the (possibly long) extraction.
        config::check_mesh_path(out)?;
    }
    let field = e
        .object
        .build_for_spacing(
            &e.bounds,
            Some(e.settings(1).grid.spacing().max_element()),
            &[],
        )
        .with_context(|| format!("building object {}", e.object.kind))?;
    let settings = e.settings(threads);
    let mut mesh = Mesh::default();
    let mut chunked = None;
    let stats = match args.chunks {
        None => {
            // One extraction: nothing to keep for a next call, so the lowest peak memory.
            let mut extractor = Extractor::new();
            extractor.set_buffer_policy(BufferPolicy::Lean);
            extractor
                .extract(field.as_ref(), &settings, &mut mesh)
                .with_context(|| format!("extracting {}", e.object.kind))?
        }
        Some(c) => {
            let (_, mut result) = crate::edit::extract_chunked(field.as_ref(), &e, c, threads)
                .with_context(|| format!("extracting {} in chunks of {c}", e.object.kind))?;
            mesh = std::mem::take(&mut result.mesh);
            let stats = rmt_extract::Stats {
                vertices: mesh.vertex_count(),
                triangles: mesh.triangle_count(),
                t_total_s: result.t_chunked_s,
                ..Default::default()
            };
            chunked = Some((c, result));
            stats
        }
    };
    let m = rmt_extract::measure(&mesh, &stats, Some(field.as_ref()), &settings);
    if let Some(out) = &args.out {
        rmt_mesh::io::save_mesh(out, &mesh, args.ascii)
            .with_context(|| format!("saving the mesh to {}", out.display()))?;
    }
    if let Some(gif) = &args.gif {
        rmt_render::render_turntable_gif(&mesh, &rmt_render::TurntableSettings::default(), gif)
            .with_context(|| format!("rendering the turntable to {}", gif.display()))?;
    }
    if args.json {
        let mut map = config_json(&e, threads);
        map.extend(measurement_json(&m)?);
        if let Some((c, r)) = &chunked {
            map.insert("chunk_size".into(), (*c).into());
            map.insert("chunks".into(), r.chunks.into());
            map.insert("t_chunked_s".into(), serde_json::json!(r.t_chunked_s));
            map.insert("t_whole_s".into(), serde_json::json!(r.t_whole_s));
            map.insert("whole_triangles".into(), r.whole_triangles.into());
            map.insert("chunked_equals_whole".into(), r.identical.into());
        }
        println!("{}", serde_json::to_string_pretty(&Value::Object(map))?);
    } else {
        print!("{}", summary(&e, threads, &m));
        if let Some((c, r)) = &chunked {
            println!(
                "  chunks:   {} chunks of {c}^3 cells in {:.3} ms; the whole volume at once {:.3} ms, \
                 {} triangles: {}",
                r.chunks,
                r.t_chunked_s * 1e3,
                r.t_whole_s * 1e3,
                r.whole_triangles,
                if r.identical { "identical" } else { "DIFFERENT" }
            );
        }
        if let Some(out) = &args.out {
            println!("mesh saved to {}", out.display());
        }
    }
    Ok(())
}

/// A readable summary of one extraction.
pub fn summary(e: &Extraction, threads: usize, m: &Measurement) -> String {
    let s = &m.stats;
    let v = &m.validation;
    let q = &m.quality;
    let ms = |t: f64| t * 1e3;
    let [nx, ny, nz] = e.resolution.cells();
    let mut out = String::new();
    out += &format!(
        "{} ({}, {}, {}) at {nx}x{ny}x{nz} cells, {threads} thread(s)\n",
        e.object.kind,
        config::method_name(e.method),
        config::lattice_name(e.method, e.lattice),
        e.clustering.name(),
    );
    out += &format!(
        "  mesh:     {} vertices, {} triangles ({} discarded), {} crossings\n",
        s.vertices, s.triangles, s.discarded, s.crossings
    );
    out += &format!(
        "  clusters: {} proposed, {} committed, {} rejected; {} collapses\n",
        s.clusters_proposed, s.clusters_committed, s.clusters_rejected, s.collapses
    );
    out += &format!(
        "  time:     {:.3} ms total = sampling {:.3} + vertex {:.3} + geometry {:.3} + normals {:.3} \
         (allocation {:.3})\n",
        ms(s.t_total_s),
        ms(s.t_sampling_s),
        ms(s.t_vertex_s),
        ms(s.t_geometry_s),
        ms(s.t_normals_s),
        ms(s.t_allocation_s),
    );
    out += &format!(
        "  sampling: field evaluated at {} of {} points ({:.1}%), {} of {} blocks skipped\n",
        s.points_sampled,
        s.sample_points,
        100.0 * s.points_sampled as f64 / s.sample_points.max(1) as f64,
        s.blocks_skipped,
        s.blocks,
    );
    if s.t_tests_s > 0.0 {
        out += &format!(
            "  merging:  of the vertex pass, {} ms\n",
            rmt_extract::Stats::merge_steps_text(s.merge_steps().map(ms), 3)
        );
    }
    out +=
        &format!(
        "  topology: {} (holes {}, non-manifold edges {} / vertices {}, orientation errors {}), \
         Euler {}, {} component(s)\n",
        if v.is_watertight_manifold() { "closed and manifold" } else { "DEFECTS" },
        v.boundary_edges_interior,
        v.non_manifold_edges,
        v.non_manifold_vertices,
        v.orientation_errors,
        v.euler,
        v.components,
    );
    out += &format!(
        "  quality:  radius ratio mean {:.3} (max {:.3}), min angle {:.2} deg\n",
        q.ar_mean, q.ar_max, q.min_angle_deg_min
    );
    if let (Some(mean), Some(max)) = (m.fidelity_mean_h, m.fidelity_max_h) {
        out += &format!("  fidelity: mean {mean:.4} h, max {max:.4} h from the true surface\n");
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;
    use clap::Parser;

    #[derive(Parser)]
    struct Cli {
        #[command(flatten)]
        args: Args,
    }

    fn parse(line: &[&str]) -> Result<Args, clap::Error> {
        Cli::try_parse_from(std::iter::once("extract").chain(line.iter().copied())).map(|c| c.args)
    }

    #[test]
    fn command_line_builds_the_described_extraction() {
        let args = parse(&[
            "--object",
            "sphere",
            "--radius",
            "0.5",
            "--resolution",
            "8,9,10",
            "--bounds",
            "-1,-2,-3,1,2,3",
            "--lattice",
            "simple",
            "--clustering",
            "postprocessed",
            "--collapse-threshold",
            "0.3",
            "--iso",
            "-0.1",
            "--threads",
            "2",
        ])
        .unwrap();
        let (e, threads) = extraction(&args).unwrap();
        let s = e.settings(threads);
        assert_eq!(s.grid.cells, [8, 9, 10]);
        assert_eq!(s.grid.min, glam::Vec3::new(-1.0, -2.0, -3.0));
        assert_eq!(s.lattice, Lattice::Simple);
        assert_eq!(s.clustering, Clustering::Postprocessed);
        assert_eq!(s.collapse_threshold, 0.3);
        assert_eq!(s.iso, -0.1);
        assert_eq!(s.threads, 2);
        let keys: Vec<String> = config_json(&e, threads).keys().cloned().collect();
        assert_eq!(
            &keys[..5],
            ["object", "lattice", "clustering", "method", "resolution"]
        );
    }

    #[test]
    fn bad_command_lines_give_errors_not_panics() {
        assert!(parse(&["--resolution", "0"]).is_err());
        assert!(parse(&["--bounds", "NaN,0,0,1,1,1"]).is_err());
        assert!(parse(&["--lattice", "hex"]).is_err());
        let unknown = parse(&["--object", "teapot"]).unwrap();
        assert!(extraction(&unknown)
            .unwrap_err()
            .to_string()
            .contains("teapot"));
        let wrong_param = parse(&["--object", "gyroid", "--radius", "2"]).unwrap();
        assert!(extraction(&wrong_param)
            .unwrap_err()
            .to_string()
            .contains("radius"));
        let mc = parse(&["--method", "mc", "--clustering", "integrated"]).unwrap();
        assert!(extraction(&mc)
            .unwrap_err()
            .to_string()
            .contains("marching cubes"));
        let mc_unchecked = parse(&["--method", "mc", "--clustering", "none"]).unwrap();
        assert!(extraction(&mc_unchecked).is_ok());
        let threads = parse(&["--threads", "0"]).unwrap();
        assert!(extraction(&threads)
            .unwrap_err()
            .to_string()
            .contains("threads"));
    }

    #[test]
    fn the_default_clustering_follows_the_method() {
        let (mc, _) = extraction(&parse(&["--method", "mc"]).unwrap()).unwrap();
        assert_eq!(mc.clustering, Clustering::None);
        let (mt, _) = extraction(&parse(&[]).unwrap()).unwrap();
        assert_eq!(mt.clustering, Clustering::Integrated);
    }

    #[test]
    fn measurement_keys_follow_the_stats_fields_in_order() {
        let keys: Vec<String> = measurement_json(&Measurement::default())
            .unwrap()
            .keys()
            .cloned()
            .collect();
        assert_eq!(keys[0], "vertices");
        assert!(keys.iter().any(|k| k == "t_total_s"));
        assert!(keys.iter().any(|k| k == "fidelity_mean_h"));
    }
}
