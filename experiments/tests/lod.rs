//! The `lod` workload end to end: a small multiresolution cave world flown over, its files and
//! columns, and the manifest's refusals.

use std::fs;
use std::path::Path;

use experiments::manifest::{self, Overrides};
use experiments::run_record::Status;
use experiments::runner::{self, RunOptions};
use rmt_runfolder::schema::{LOD_LEVELS, LOD_MAP, LOD_STEPS, LOD_SUMMARY};
use rmt_runfolder::Table;

const WORLD: &str = r#"
name = "lod-test"
workload = "lod"
threads = 2
save_meshes = true

[[objects]]
name = "caves"
resolution = [32, 16, 32]
bounds = [-1.0, -0.5, -1.0, 1.0, 0.5, 1.0]

[matrix]
methods = ["mt"]
lattices = ["bcdl"]
clustering = ["none"]

[lod]
levels = 2
chunk = 4
ratio = 1.0
steps = 4
path = [[-0.9, 0.2, -0.9], [0.9, 0.2, 0.9]]
"#;

fn write(dir: &Path, name: &str, text: &str) -> std::path::PathBuf {
    let p = dir.join(name);
    fs::write(&p, text).unwrap();
    p
}

/// Runs the manifest `text` (written as `NAME.toml` in `dir`) into the folder `dir/NAME`, which
/// it returns, and asserts the run finished.
fn fly(dir: &Path, name: &str, text: &str) -> std::path::PathBuf {
    let manifest = write(dir, &format!("{name}.toml"), text);
    let folder = dir.join(name);
    let opts = RunOptions {
        quiet: true,
        stop_after: None,
    };
    let report = runner::start(&manifest, &Overrides::default(), Some(&folder), &opts).unwrap();
    assert_eq!(report.status, Status::Finished);
    folder
}

#[test]
fn a_flight_writes_one_row_per_step_a_closed_world_and_a_summary() {
    let dir = tempfile::tempdir().unwrap();
    let folder = fly(dir.path(), "lod", WORLD);
    let steps = Table::read(&folder.join("lod.csv")).unwrap();
    assert_eq!(steps.header, LOD_STEPS);
    assert_eq!(steps.rows.len(), 5, "step 0 and 4 viewer steps");
    for r in 0..5 {
        // Every step validated (validate_every defaults to 1): closed inside the domain,
        // manifold, oriented.
        for col in ["open_edges", "non_manifold_edges", "orientation_errors"] {
            assert_eq!(steps.get(r, col), Some("0"), "step {r} {col}");
        }
        let seam: f64 = steps
            .get(r, "normal_seam_max_deg")
            .unwrap()
            .parse()
            .unwrap();
        assert!(seam < 5.0, "step {r}: seam {seam}");
    }
    // The viewer crosses the world, so some chunk changes level and its pop is measured.
    assert!((1..5).any(|r| !steps.get(r, "pop_max_cells").unwrap().is_empty()));
    let summary = Table::read(&folder.join("summary.csv")).unwrap();
    assert_eq!(summary.header, LOD_SUMMARY);
    assert_eq!(summary.rows.len(), 1);
    assert_eq!(summary.get(0, "steps"), Some("4"));
    assert_eq!(summary.get(0, "validated_steps"), Some("5"));
    assert_eq!(summary.get(0, "open_edges"), Some("0"));
    assert_eq!(summary.get(0, "finest_source"), Some("exact"));
    let over: f64 = summary
        .get(0, "triangles_over_finest")
        .unwrap()
        .parse()
        .unwrap();
    assert!(over > 0.0 && over < 1.5, "{over}");
    let p50: f64 = summary.get(0, "remesh_p50_ms").unwrap().parse().unwrap();
    let p99: f64 = summary.get(0, "remesh_p99_ms").unwrap().parse().unwrap();
    assert!(p50 >= 0.0 && p50 <= p99);
    assert!(folder.join("meshes/cs_bu.ply").is_file());
    assert!(!folder.join("raw.csv").exists());
}

/// `lod_levels.csv` splits every step's chunks and triangles by level; `lod_map.csv` is the
/// last step's map, whose boxes tile the world, with that step's triangles; both are the same on
/// 1 and 2 threads.
#[test]
fn levels_and_the_last_map_add_up_to_the_steps() {
    let dir = tempfile::tempdir().unwrap();
    let manifest = write(
        dir.path(),
        "lod.toml",
        &WORLD.replace("save_meshes = true", ""),
    );
    let opts = RunOptions {
        quiet: true,
        stop_after: None,
    };
    let mut files = Vec::new();
    for threads in [1, 2] {
        let folder = dir.path().join(format!("t{threads}"));
        let overrides = Overrides {
            threads: Some(threads),
            ..Overrides::default()
        };
        runner::start(&manifest, &overrides, Some(&folder), &opts).unwrap();
        let steps = Table::read(&folder.join("lod.csv")).unwrap();
        let levels = Table::read(&folder.join("lod_levels.csv")).unwrap();
        let map = Table::read(&folder.join("lod_map.csv")).unwrap();
        assert_eq!(levels.header, LOD_LEVELS);
        assert_eq!(map.header, LOD_MAP);
        let num = |t: &Table, r: usize, c: &str| -> f64 { t.get(r, c).unwrap().parse().unwrap() };
        // Levels 0..=2 at each of the 5 steps.
        assert_eq!(levels.rows.len(), 5 * 3);
        for r in 0..5 {
            let of_step: Vec<usize> = (0..levels.rows.len())
                .filter(|&i| num(&levels, i, "step") as usize == r)
                .collect();
            let lv: Vec<f64> = of_step.iter().map(|&i| num(&levels, i, "level")).collect();
            assert_eq!(lv, [0.0, 1.0, 2.0]);
            let sum = |c: &str| of_step.iter().map(|&i| num(&levels, i, c)).sum::<f64>();
            assert_eq!(sum("chunks"), num(&steps, r, "chunks"), "step {r}");
            assert_eq!(sum("triangles"), num(&steps, r, "triangles"), "step {r}");
        }
        // The viewer is near the ground: the finest level is in use at the end.
        let finest_last = (0..levels.rows.len())
            .find(|&i| num(&levels, i, "step") == 4.0 && num(&levels, i, "level") == 0.0)
            .unwrap();
        assert!(num(&levels, finest_last, "chunks") > 0.0);
        assert_eq!(map.rows.len() as f64, num(&steps, 4, "chunks"));
        let mut volume = 0.0;
        let mut triangles = 0.0;
        for r in 0..map.rows.len() {
            assert_eq!(map.get(r, "step"), Some("4"));
            let level = num(&map, r, "level");
            let edge = num(&map, r, "x_max") - num(&map, r, "x_min");
            // Chunks of 4 cells of 2 / 32 at level l: 0.25 * 2^l world units.
            assert!(
                (edge - 0.25 * 2f64.powf(level)).abs() < 1e-6,
                "row {r}: {edge}"
            );
            volume += (0..3)
                .map(|a| {
                    let ax = ["x", "y", "z"][a];
                    num(&map, r, &format!("{ax}_max")) - num(&map, r, &format!("{ax}_min"))
                })
                .product::<f64>();
            triangles += num(&map, r, "triangles");
        }
        assert!(
            (volume - 4.0).abs() < 1e-6,
            "the map's boxes fill {volume} of 4"
        );
        assert_eq!(triangles, num(&steps, 4, "triangles"));
        files.push((
            fs::read(folder.join("lod_levels.csv")).unwrap(),
            fs::read(folder.join("lod_map.csv")).unwrap(),
        ));
    }
    assert!(files[0] == files[1], "1 and 2 threads differ");
}

/// The same flight on 1 and 2 threads, and without the chunk-tets cache, gives the same
/// `lod.csv` outside the time and memory columns (the world's bytes depend on its hash tables'
/// history, like a time on the machine).
#[test]
fn a_flight_is_deterministic_outside_times() {
    let dir = tempfile::tempdir().unwrap();
    let manifest = write(
        dir.path(),
        "lod.toml",
        &WORLD.replace("threads = 2", "threads = 1"),
    );
    let uncached = write(
        dir.path(),
        "uncached.toml",
        &format!("{WORLD}tet_cache_mb = 0\n"),
    );
    let opts = RunOptions {
        quiet: true,
        stop_after: None,
    };
    let mut tables = Vec::new();
    for (name, threads, manifest) in [
        ("a", 1, &manifest),
        ("b", 2, &manifest),
        ("c", 2, &uncached),
    ] {
        let folder = dir.path().join(name);
        let overrides = Overrides {
            threads: Some(threads),
            ..Overrides::default()
        };
        runner::start(manifest, &overrides, Some(&folder), &opts).unwrap();
        let t = Table::read(&folder.join("lod.csv")).unwrap();
        let keep: Vec<usize> = (0..t.header.len())
            .filter(|&i| !matches!(t.header[i].as_str(), "remesh_s" | "memory_bytes"))
            .collect();
        tables.push(
            t.rows
                .iter()
                .map(|r| keep.iter().map(|&i| r[i].clone()).collect::<Vec<_>>())
                .collect::<Vec<_>>(),
        );
    }
    assert_eq!(tables[0], tables[1], "1 and 2 threads differ");
    assert_eq!(
        tables[1], tables[2],
        "with and without the tets cache differ"
    );
}

/// Clustering at every level: the world that clusters stays closed, manifold and oriented at
/// every step, with fewer triangles than the plain one, and its finest level is clustered too.
#[test]
fn a_clustered_flight_is_closed_and_has_fewer_triangles() {
    let dir = tempfile::tempdir().unwrap();
    let text = WORLD
        .replace(
            "clustering = [\"none\"]",
            "clustering = [\"none\", \"integrated\"]",
        )
        .replace("chunk = 4", "chunk = 8")
        .replace("resolution = [32, 16, 32]", "resolution = [64, 32, 64]");
    let folder = fly(dir.path(), "lod", &text);
    let summary = Table::read(&folder.join("summary.csv")).unwrap();
    assert_eq!(summary.rows.len(), 2);
    let row = |c: &str| {
        (0..2)
            .find(|&r| summary.get(r, "clustering") == Some(c))
            .unwrap()
    };
    let (plain, clustered) = (row("none"), row("integrated"));
    let num = |r: usize, col: &str| -> f64 { summary.get(r, col).unwrap().parse().unwrap() };
    for col in ["open_edges", "non_manifold_edges", "orientation_errors"] {
        assert_eq!(summary.get(clustered, col), Some("0"), "{col}");
    }
    assert_eq!(summary.get(clustered, "validated_steps"), Some("5"));
    assert!(num(clustered, "normal_seam_max_deg") < 5.0);
    assert!(num(clustered, "triangles_max") < 0.8 * num(plain, "triangles_max"));
    assert!(num(clustered, "finest_triangles") < 0.8 * num(plain, "finest_triangles"));
}

#[test]
fn the_lod_workload_refuses_what_it_cannot_mesh() {
    let dir = tempfile::tempdir().unwrap();
    let err = |name: &str, text: &str| {
        let p = write(dir.path(), name, text);
        manifest::load(&p, &Overrides::default())
            .err()
            .map(|e| e.to_string())
            .unwrap_or_default()
    };
    let unchecked = err(
        "unchecked.toml",
        &WORLD.replace(
            "clustering = [\"none\"]",
            "clustering = [\"integrated-unchecked\"]",
        ),
    );
    assert!(unchecked.contains("(integrated)"), "{unchecked}");
    let uneven = err(
        "uneven.toml",
        &WORLD.replace("resolution = [32, 16, 32]", "resolution = [40, 16, 32]"),
    );
    assert!(uneven.contains("40") && uneven.contains("16"), "{uneven}");
    let path = err(
        "path.toml",
        &WORLD.replace(
            "path = [[-0.9, 0.2, -0.9], [0.9, 0.2, 0.9]]",
            "path = [[0.0, 0.0, 0.0]]",
        ),
    );
    assert!(path.contains("lod.path"), "{path}");
    let stray = err(
        "stray.toml",
        &WORLD.replace("workload = \"lod\"", "workload = \"extract\""),
    );
    assert!(stray.contains("[lod]"), "{stray}");
    let simple = err(
        "simple.toml",
        &WORLD.replace("lattices = [\"bcdl\"]", "lattices = [\"simple\"]"),
    );
    assert!(simple.contains("bcdl"), "{simple}");
    let cache = err("cache.toml", &format!("{WORLD}tet_cache_mb = 2000000\n"));
    assert!(cache.contains("lod.tet_cache_mb"), "{cache}");
    for bad in ["1.5", "-0.5", "nan"] {
        let morph = err("morph.toml", &format!("{WORLD}morph = {bad}\n"));
        assert!(morph.contains("lod.morph"), "{bad}: {morph}");
    }
    let still = err(
        "still.toml",
        &format!("{WORLD}morph = 0.5\n").replace("ratio = 1.0", "ratio = 0.0"),
    );
    assert!(
        still.contains("lod.morph") && still.contains("ratio"),
        "{still}"
    );
}

/// The same flight with a morph: the surface stays closed, the pop (the change of tets at one
/// viewer) shrinks to rounding where without the morph it jumps, and the morph's own motion per
/// step is measured; without a morph its columns are empty.
#[test]
fn a_morphed_flight_does_not_pop() {
    let dir = tempfile::tempdir().unwrap();
    // Short steps (about a finest cell each) so the viewer moves less than a band per step.
    let slow = WORLD
        .replace("steps = 4", "steps = 12")
        .replace(
            "path = [[-0.9, 0.2, -0.9], [0.9, 0.2, 0.9]]",
            "path = [[-0.3, 0.0, -0.3], [0.2, 0.0, 0.2]]",
        )
        .replace("save_meshes = true", "");
    let mut pops = Vec::new();
    for (name, text) in [
        ("plain", slow.clone()),
        ("morph", format!("{slow}morph = 1.0\n")),
    ] {
        let folder = fly(dir.path(), name, &text);
        let steps = Table::read(&folder.join("lod.csv")).unwrap();
        let summary = Table::read(&folder.join("summary.csv")).unwrap();
        for r in 0..steps.rows.len() {
            for col in ["open_edges", "non_manifold_edges", "orientation_errors"] {
                assert_eq!(steps.get(r, col), Some("0"), "{name} step {r} {col}");
            }
        }
        let cell = |c: &str| summary.get(0, c).unwrap().to_string();
        if name == "plain" {
            assert_eq!(cell("morph"), "0");
            assert_eq!(cell("morph_max_cells"), "");
            assert!((0..steps.rows.len()).all(|r| steps.get(r, "morph_max_cells") == Some("")));
        } else {
            assert_eq!(cell("morph"), "1");
            let moved: f64 = cell("morph_max_cells").parse().unwrap();
            assert!(moved > 0.0, "the morph moved nothing");
        }
        let changed = (1..steps.rows.len())
            .filter(|&r| !steps.get(r, "pop_max_cells").unwrap().is_empty())
            .count();
        assert!(changed > 2, "{name}: {changed} steps changed a level");
        pops.push(cell("pop_max_cells").parse::<f64>().unwrap());
    }
    assert!(pops[0] > 0.1, "no pop without the morph: {pops:?}");
    assert!(pops[1] < 0.25 * pops[0], "the morph left the pop: {pops:?}");
}

/// A stroke far from the viewer (where the world is coarse) at step 2 of `WORLD`'s flight (the
/// viewer at the centre, the stroke in a corner off its path, whose level-1 chunks keep their
/// level from step 0 to 2): removing ground in a ball of radius 0.15.
const FAR_STROKE: &str = "edits = [{ step = 2, at = [0.85, 0.0, -0.85], radius = 0.15, \
                          mode = \"subtract\", strength = 3.0, frames = 10 }]\n";

/// The welded last world of the flight of the manifest at `path`, configuration `id`, and the
/// session.
fn session_of(path: &Path, id: &str, keep_mesh: bool) -> experiments::lod::LodSession {
    let loaded = manifest::load(path, &Overrides::default()).unwrap();
    let plan = &loaded.plan;
    let c = plan.configurations.iter().find(|c| c.id == id).unwrap();
    let field = loaded.fields.get(&c.field_key()).unwrap();
    experiments::lod::run_lod_session(
        field,
        &c.extraction,
        plan.lod.as_ref().unwrap(),
        plan.threads,
        keep_mesh,
    )
    .unwrap()
}

/// Issue 40, part 5, in the runner: a brush stroke far from the viewer marks chunks of a
/// coarse level only, which are re-meshed at that step; the surface stays closed, manifold and
/// oriented; the triangles change inside the stroke's ball and nowhere far from it; the steps
/// before the stroke are those of the same flight without it.
#[test]
fn a_stroke_far_from_the_viewer_remeshes_coarse_chunks_and_stays_closed() {
    let dir = tempfile::tempdir().unwrap();
    let plain_text = WORLD.replace("save_meshes = true", "");
    let edited_text = format!("{plain_text}{FAR_STROKE}");
    let plain = fly(dir.path(), "plain", &plain_text);
    let edited = fly(dir.path(), "edited", &edited_text);
    let read = |f: &Path, name: &str| Table::read(&f.join(name)).unwrap();
    let (p_steps, e_steps) = (read(&plain, "lod.csv"), read(&edited, "lod.csv"));
    let num = |t: &Table, r: usize, c: &str| -> f64 { t.get(r, c).unwrap().parse().unwrap() };
    for r in 0..5 {
        for col in ["open_edges", "non_manifold_edges", "orientation_errors"] {
            assert_eq!(e_steps.get(r, col), Some("0"), "step {r} {col}");
        }
        assert_eq!(p_steps.get(r, "edit_chunks"), Some("0"), "step {r}");
        if r != 2 {
            assert_eq!(e_steps.get(r, "edit_chunks"), Some("0"), "step {r}");
        }
    }
    // Steps 0 and 1 are the same flight; at step 2 the stroke's chunks are re-meshed on top
    // of the level changes, and the triangles differ.
    let same = |r: usize| {
        (0..e_steps.header.len())
            .filter(|&i| !matches!(e_steps.header[i].as_str(), "remesh_s" | "memory_bytes"))
            .all(|i| e_steps.rows[r][i] == p_steps.rows[r][i])
    };
    assert!(same(0) && same(1), "a step before the stroke differs");
    let marked = num(&e_steps, 2, "edit_chunks");
    assert!(marked > 0.0, "the stroke marked no chunk");
    assert!(
        num(&e_steps, 2, "chunks_remeshed") >= num(&p_steps, 2, "chunks_remeshed") + 1.0,
        "the stroke's chunks were not re-meshed"
    );
    assert_ne!(e_steps.get(2, "triangles"), p_steps.get(2, "triangles"));
    // The marked chunks by level: none at level 0 (the stroke is far from the viewer).
    let levels = read(&edited, "lod_levels.csv");
    let at_step: Vec<(f64, f64)> = (0..levels.rows.len())
        .filter(|&i| num(&levels, i, "step") == 2.0)
        .map(|i| (num(&levels, i, "level"), num(&levels, i, "edit_chunks")))
        .collect();
    assert_eq!(at_step.iter().map(|l| l.1).sum::<f64>(), marked);
    assert_eq!(at_step[0], (0.0, 0.0), "a level-0 chunk saw the far stroke");
    let summary = read(&edited, "summary.csv");
    assert_eq!(summary.get(0, "edits_applied"), Some("1"));
    assert_eq!(
        summary.get(0, "edit_chunks_total").unwrap(),
        marked.to_string()
    );
    assert_eq!(summary.get(0, "open_edges"), Some("0"));
    let p_summary = read(&plain, "summary.csv");
    assert_eq!(p_summary.get(0, "edits_applied"), Some("0"));
    // Where the triangles changed: the last worlds' vertices inside the ball differ, and far
    // from it (beyond the radius and a coarse edge) they are the same bits.
    let worlds: Vec<Vec<[u32; 3]>> = [&plain_text, &edited_text]
        .iter()
        .enumerate()
        .map(|(i, text)| {
            let path = write(dir.path(), &format!("m{i}.toml"), text);
            let mesh = session_of(&path, "cs_bu", true).mesh.unwrap();
            mesh.positions.iter().map(|p| p.map(f32::to_bits)).collect()
        })
        .collect();
    let centre = glam::Vec3::new(0.85, 0.0, -0.85);
    let near = |p: &[u32; 3], lo: f32, hi: f32| {
        let d = glam::Vec3::from(p.map(f32::from_bits)).distance(centre);
        lo <= d && d < hi
    };
    let part = |w: &[[u32; 3]], lo: f32, hi: f32| {
        let mut v: Vec<[u32; 3]> = w.iter().filter(|p| near(p, lo, hi)).copied().collect();
        v.sort_unstable();
        v
    };
    assert_ne!(
        part(&worlds[0], 0.0, 0.15),
        part(&worlds[1], 0.0, 0.15),
        "nothing changed inside the stroke"
    );
    let far = (0.15 + 0.25, f32::INFINITY);
    assert!(!part(&worlds[0], far.0, far.1).is_empty());
    assert_eq!(
        part(&worlds[0], far.0, far.1),
        part(&worlds[1], far.0, far.1),
        "the stroke changed the world far from it"
    );
}

/// The incrementally updated world of a flight with strokes (one far, at a coarse level; one
/// near the viewer, adding ground; one before the first meshing) equals a from-scratch meshing
/// of the last step's level map over the field with the same strokes, byte for byte, plain
/// and clustered.
#[test]
fn a_flight_with_strokes_equals_meshing_its_last_map_from_scratch() {
    use experiments::lod::{lod_brushes, lod_settings, viewer_path};
    use rmt_terrain::lod::{cluster_chunk, mesh_chunks, thread_pool, weld, EditedField, LodWorld};
    let dir = tempfile::tempdir().unwrap();
    let text = format!(
        "{}{}",
        WORLD.replace("save_meshes = true", "").replace(
            "clustering = [\"none\"]",
            "clustering = [\"none\", \"integrated\"]"
        ),
        "edits = [{ step = 1, at = [0.7, 0.0, 0.7], radius = 0.3, mode = \"subtract\", \
         strength = 3.0, frames = 10 },\n\
         { step = 3, at = [0.45, 0.0, 0.45], radius = 0.2, mode = \"add\", strength = 2.0, \
         frames = 4 },\n\
         { step = 0, at = [-0.5, -0.1, 0.5], radius = 0.25, mode = \"subtract\" }]\n"
    );
    let path = write(dir.path(), "strokes.toml", &text);
    let loaded = manifest::load(&path, &Overrides::default()).unwrap();
    let plan = &loaded.plan;
    let lod = plan.lod.as_ref().unwrap();
    assert_eq!(lod.edits.len(), 3);
    for c in &plan.configurations {
        let session = session_of(&path, &c.id, true);
        let incremental = session.mesh.unwrap();
        let field = loaded.fields.get(&c.field_key()).unwrap();
        let settings = lod_settings(&c.extraction, lod, 1).unwrap();
        let frame = settings.frame;
        // The strokes in the flight's order, on a world never meshed: only its map and overlay
        // are used.
        let mut fresh = LodWorld::new(field, settings).unwrap();
        let path = viewer_path(&c.extraction, lod);
        for k in 0..path.len() {
            for (brush, dt) in lod_brushes(lod, k, frame.h) {
                fresh.edit(&brush, dt).unwrap();
            }
        }
        assert_eq!(fresh.edits().strokes().len(), 10 + 4 + 1);
        fresh.set_viewer(*path.last().unwrap());
        let edited = EditedField::new(&field, fresh.edits());
        let pool = thread_pool(1).unwrap();
        let mut chunks = mesh_chunks(fresh.pending_map(), &edited, &frame, &pool).unwrap();
        if settings.cluster {
            chunks = chunks.iter().map(|m| cluster_chunk(m, &frame).0).collect();
        }
        let (scratch, _) = weld(&chunks);
        let bits =
            |v: &[[f32; 3]]| -> Vec<[u32; 3]> { v.iter().map(|p| p.map(f32::to_bits)).collect() };
        assert!(!scratch.indices.is_empty());
        assert_eq!(incremental.indices, scratch.indices, "{}: indices", c.id);
        assert!(
            bits(&incremental.positions) == bits(&scratch.positions),
            "{}: positions",
            c.id
        );
        assert!(
            bits(&incremental.normals) == bits(&scratch.normals),
            "{}: normals",
            c.id
        );
    }
}

#[test]
fn a_bad_stroke_is_refused_with_its_entry_and_reason() {
    let dir = tempfile::tempdir().unwrap();
    let err = |name: &str, edits: &str| {
        let p = write(dir.path(), name, &format!("{WORLD}edits = [{edits}]\n"));
        manifest::load(&p, &Overrides::default())
            .err()
            .map(|e| e.to_string())
            .unwrap_or_default()
    };
    let ok = "{ step = 1, at = [0.0, 0.0, 0.0], radius = 0.1, mode = \"add\" }";
    let cases = [
        (
            "{ step = 1, at = [0.0, 0.6, 0.0], radius = 0.1, mode = \"add\" }",
            "lod.edits[1].at: [0.0, 0.6, 0.0] is outside the box of configuration cs_bu",
        ),
        (
            "{ step = 1, at = [0.0, 0.0, 0.0], radius = -0.1, mode = \"add\" }",
            "lod.edits[1].radius: must be finite and > 0",
        ),
        (
            "{ step = 9, at = [0.0, 0.0, 0.0], radius = 0.1, mode = \"add\" }",
            "lod.edits[1].step: step 9 is after the flight's last step (lod.steps = 4)",
        ),
        (
            "{ step = 1, at = [0.0, inf, 0.0], radius = 0.1, mode = \"add\" }",
            "lod.edits[1].at: the centre must be finite",
        ),
        (
            "{ step = 1, at = [0.0, 0.0, 0.0], radius = 0.1, mode = \"add\", strength = nan }",
            "lod.edits[1].strength: must be finite and >= 0",
        ),
        (
            "{ step = 1, at = [0.0, 0.0, 0.0], radius = 0.1, mode = \"add\", frames = 20000 }",
            "lod.edits[1].frames: must be 1 to 10000",
        ),
        (
            "{ step = 1, at = [0.0, 0.0, 0.0], radius = 0.1, mode = \"dig\" }",
            "unknown variant `dig`, expected `add` or `subtract`",
        ),
        (
            "{ step = 1, at = [0.0, 0.0, 0.0], radius = 0.1 }",
            "missing field `mode`",
        ),
    ];
    for (i, (bad, expect)) in cases.iter().enumerate() {
        let e = err(&format!("bad{i}.toml"), &format!("{ok}, {bad}"));
        assert!(e.contains(expect), "{bad}: {e}");
    }
    // Good strokes pass, with their defaults.
    let p = write(dir.path(), "good.toml", &format!("{WORLD}edits = [{ok}]\n"));
    let plan = manifest::load(&p, &Overrides::default()).unwrap().plan;
    let e = plan.lod.unwrap().edits;
    assert_eq!((e.len(), e[0].frames, e[0].strength), (1, 1, 1.0));
}

/// The shape of the world's triangles (radius ratio R / 2r, `rmt_mesh::quality`) on every
/// validated step, plain and clustered: the last step's is the welded world's own (as the
/// extractor measures its meshes), the summary's mean lies within the steps' and its median,
/// p99 and max are the steps' largest.
#[test]
fn the_world_triangles_shape_is_measured_on_validated_steps() {
    let dir = tempfile::tempdir().unwrap();
    let text = WORLD
        .replace("save_meshes = true", "")
        .replace(
            "clustering = [\"none\"]",
            "clustering = [\"none\", \"integrated\"]",
        )
        .replace("steps = 4", "steps = 4\nvalidate_every = 2");
    let path = write(dir.path(), "shape.toml", &text);
    let folder = fly(dir.path(), "shape", &text);
    let steps = Table::read(&folder.join("lod.csv")).unwrap();
    let summary = Table::read(&folder.join("summary.csv")).unwrap();
    let num = |t: &Table, r: usize, c: &str| -> f64 { t.get(r, c).unwrap().parse().unwrap() };
    for id in ["cs_bu", "cs_bi"] {
        let rows: Vec<usize> = (0..steps.rows.len())
            .filter(|&r| steps.get(r, "id") == Some(id))
            .collect();
        assert_eq!(rows.len(), 5);
        // Steps 0, 2 and 4 are validated (every 2nd, the first and the last).
        for (k, &r) in rows.iter().enumerate() {
            let cell = steps.get(r, "ar_mean").unwrap();
            assert_eq!(cell.is_empty(), k % 2 == 1, "{id} step {k}: {cell:?}");
        }
        let validated: Vec<usize> = rows.iter().copied().step_by(2).collect();
        for &r in &validated {
            let (median, mean, p99, max) = (
                num(&steps, r, "ar_median"),
                num(&steps, r, "ar_mean"),
                num(&steps, r, "ar_p99"),
                num(&steps, r, "ar_max"),
            );
            assert!(
                1.0 <= mean && 1.0 <= median && median <= p99 && p99 <= max,
                "{id}: {mean} {median} {p99} {max}"
            );
        }
        // The last step's shape is the welded world's, measured by the extractor's quality.
        let mesh = session_of(&path, id, true).mesh.unwrap();
        let q = rmt_mesh::quality(&mesh);
        let last = *validated.last().unwrap();
        assert_eq!(
            steps.get(last, "ar_mean").unwrap(),
            format!("{:.4}", q.ar_mean)
        );
        assert_eq!(
            steps.get(last, "ar_median").unwrap(),
            format!("{:.4}", q.ar_median)
        );
        assert_eq!(
            steps.get(last, "ar_max").unwrap(),
            format!("{:.4}", q.ar_max)
        );
        assert_eq!(
            steps.get(last, "zero_area_triangles").unwrap(),
            q.zero_area_triangles.to_string()
        );
        let s = (0..2).find(|&r| summary.get(r, "id") == Some(id)).unwrap();
        let of_steps =
            |c: &str| -> Vec<f64> { validated.iter().map(|&r| num(&steps, r, c)).collect() };
        let lo = of_steps("ar_mean")
            .into_iter()
            .fold(f64::INFINITY, f64::min);
        let hi = of_steps("ar_mean").into_iter().fold(0.0, f64::max);
        let mean = num(&summary, s, "ar_mean");
        assert!(
            lo - 1e-4 <= mean && mean <= hi + 1e-4,
            "{id}: {mean} not in [{lo}, {hi}]"
        );
        for c in ["ar_median", "ar_p99", "ar_max"] {
            assert_eq!(
                num(&summary, s, c),
                of_steps(c).into_iter().fold(0.0, f64::max),
                "{id} {c}"
            );
        }
    }
}
