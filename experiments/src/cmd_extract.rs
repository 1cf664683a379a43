//! `experiments extract`: one extraction of one object (options parsed and checked by
//! [`crate::extract_args`]) and its finish steps (`--simplify`, `--vertex-cache`), printed as a
//! summary or as one JSON object (the keys of [`Measured`]: measurement, finish steps, rendering
//! cost; preceded by the configuration keys `object`, `lattice`, `clustering`, `method`,
//! `resolution`, `bounds`, `collapse_threshold`, `iso`, `normals`, `simplify`, `vertex_cache`,
//! `threads`), optionally saved as PLY, OBJ or binary glTF (by the extension of `--out`).
//!
//! ```text
//! experiments extract --object sphere --radius 1.0 --resolution 50 --lattice bcdl \
//!     --clustering integrated --out sphere.ply --json
//! ```

use anyhow::{Context, Result};
use rmt_extract::{BufferPolicy, Extractor, Measurement};
use rmt_mesh::Mesh;
use serde_json::Value;

use crate::config::{self, config_json, Extraction};
use crate::extract_args::{extraction, Args};
use crate::finish::{FinishRecord, Finisher};
use crate::measured::{self, Measured};

/// Runs `extract`.
pub fn run(args: Args) -> Result<()> {
    let (e, threads) = extraction(&args)?;
    if let Some(out) = &args.out {
        // Refuse an unknown format before the (possibly long) extraction.
        config::check_mesh_path(out)?;
    }
    if args.chunks.is_some() && (e.simplify.is_some() || e.vertex_cache) {
        anyhow::bail!(
            "--chunks cannot be combined with --simplify or --vertex-cache (the finish steps work \
             on one whole mesh, not on chunks)"
        );
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
    let mut finish = FinishRecord::default();
    let stats = match args.chunks {
        None => {
            // One extraction: nothing to keep for a next call, so the lowest peak memory.
            let mut extractor = Extractor::new();
            extractor.set_buffer_policy(BufferPolicy::Lean);
            let mut stats = extractor
                .extract(field.as_ref(), &settings, &mut mesh)
                .with_context(|| format!("extracting {}", e.object.kind))?;
            finish = Finisher::new(&e, field.as_ref(), threads)
                .run(&mut mesh, &mut stats)
                .with_context(|| format!("finishing {}", e.object.kind))?;
            stats
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
    let measured = measured::measure(
        &mesh,
        &stats,
        &finish,
        Some(field.as_ref()),
        &settings,
        Some(&mut rmt_render::cost::RenderCostMeter::new()),
    )?;
    let m = &measured.measurement;
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
        map.extend(measured.json()?);
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
        print!("{}", summary(&e, threads, m));
        print!("{}", finish_summary(&e, &measured));
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

/// The finish steps and rendering cost of [`summary`]'s extraction, in readable lines.
pub fn finish_summary(e: &Extraction, m: &Measured) -> String {
    let f = &m.finish;
    let mut out = String::new();
    if let (Some(s), Some(target), Some(before), Some(err)) = (
        &e.simplify,
        f.simplify_target,
        f.simplify_triangles_before,
        f.simplify_error_h,
    ) {
        out += &format!(
            "  simplify: {} from {before} to {} triangles (target {target}), error {err:.4} h, \
             {:.3} ms\n",
            s.name(),
            m.measurement.stats.triangles,
            f.t_simplify_s * 1e3
        );
    }
    if e.vertex_cache {
        out += &format!(
            "  vertex cache: reordered in {:.3} ms\n",
            f.t_vertex_cache_s * 1e3
        );
    }
    if let Some(c) = &m.cost {
        out += &format!(
            "  render:   quad occupancy {:.3} / {:.3} / {:.3} / {:.3} at 1080 / 540 / 270 / 135 px, \
             ACMR {:.3} (cache 16), overdraw {:.3}, {} bytes as .glb ({:.0} ms to measure)\n",
            c.quad_occupancy_1080,
            c.quad_occupancy_540,
            c.quad_occupancy_270,
            c.quad_occupancy_135,
            c.acmr_16,
            c.overdraw,
            c.glb_bytes,
            m.t_cost_s * 1e3
        );
    }
    out
}
