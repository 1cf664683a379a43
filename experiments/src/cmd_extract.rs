//! `experiments extract`: one extraction of one object (options parsed and checked by
//! [`crate::extract_args`]), printed as a summary or as one JSON object (the [`Measurement`]
//! keys, preceded by the configuration keys `object`, `lattice`, `clustering`, `method`,
//! `resolution`, `bounds`, `collapse_threshold`, `iso`, `normals`, `threads`), optionally saved as PLY, OBJ or binary glTF (by the extension of `--out`).
//!
//! ```text
//! experiments extract --object sphere --radius 1.0 --resolution 50 --lattice bcdl \
//!     --clustering integrated --out sphere.ply --json
//! ```

use anyhow::{Context, Result};
use rmt_extract::{BufferPolicy, Extractor, Measurement};
use rmt_mesh::Mesh;
use serde_json::Value;

use crate::config::{self, config_json, measurement_json, Extraction};
use crate::extract_args::{extraction, Args};

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
