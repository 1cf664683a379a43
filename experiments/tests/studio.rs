//! The studio over HTTP on loopback, every route: the page and its assets, the schema, a mesh
//! request against `experiments extract` (same triangles), export files, sculpt sessions
//! (a stroke re-meshes and sends only the chunks it should; undo and redo), and bad requests
//! (4xx with a message, the server keeps serving).

#[path = "../../crates/server/tests/common/client.rs"]
mod client;

use std::net::SocketAddr;
use std::sync::Arc;

use client::{get, request, Reply};
use experiments::studio::StudioBackend;
use rmt_mesh::Mesh;
use rmt_server::studio::{wire, Studio};
use rmt_terrain::canonical_triangles;

fn start() -> rmt_server::http::Running {
    let studio = Arc::new(Studio::new(StudioBackend::new(2)));
    rmt_server::http::spawn(
        rmt_server::studio::standalone_router(studio),
        "127.0.0.1:0".parse().unwrap(),
    )
    .unwrap()
}

fn post(addr: SocketAddr, path: &str, body: Option<&str>) -> Reply {
    request(addr, "POST", path, None, body.map(str::as_bytes)).unwrap()
}

fn decode(reply: &Reply) -> (serde_json::Value, Vec<wire::Part>) {
    assert!(
        reply.status < 300,
        "status {}: {}",
        reply.status,
        reply.text()
    );
    assert_eq!(
        reply.header("content-type"),
        Some("application/octet-stream")
    );
    wire::decode(&reply.body).unwrap()
}

fn error_of(reply: &Reply, status: u16) -> String {
    assert_eq!(reply.status, status, "{}", reply.text());
    reply.json()["error"].as_str().unwrap().to_string()
}

#[test]
fn page_assets_and_schema_are_served() {
    let server = start();
    let a = server.addr;
    let page = get(a, "/studio/", None).unwrap();
    assert_eq!(page.status, 200);
    assert!(page.text().contains("/studio/assets/studio.js"));
    assert!(page.header("content-security-policy").is_some());
    for (file, needle) in [
        ("studio.js", "OrbitControls"),
        ("studio.css", "#panel"),
        ("three.module.min.js", "three.core.min.js"),
        ("three.core.min.js", "WebGL"),
        ("OrbitControls.js", "./three.module.min.js"),
    ] {
        let r = get(a, &format!("/studio/assets/{file}"), None).unwrap();
        assert_eq!(r.status, 200, "{file}");
        assert!(r.text().contains(needle), "{file} lacks {needle}");
        assert!(r.header("content-type").unwrap().starts_with("text/"));
    }
    assert_eq!(
        get(a, "/studio/assets/secret.rs", None).unwrap().status,
        404
    );
    assert_eq!(get(a, "/", None).unwrap().status, 307);
    assert_eq!(get(a, "/studio", None).unwrap().status, 308);
    let schema = get(a, "/studio/api/schema", None).unwrap().json();
    assert_eq!(schema["defaults"]["object"], "sphere");
    assert!(schema["sculpt"]["objects"].as_array().unwrap().len() == 2);
}

#[test]
fn a_mesh_request_returns_the_triangles_of_experiments_extract() {
    let server = start();
    let dir = tempfile::tempdir().unwrap();
    for (query, line) in [
        (
            "object=torus&resolution=24&clustering=integrated",
            vec!["--object", "torus", "--resolution", "24"],
        ),
        (
            "object=gyroid&resolution=20&lattice=simple&clustering=postprocessed&iso=-0.05",
            vec![
                "--object",
                "gyroid",
                "--resolution",
                "20",
                "--lattice",
                "simple",
                "--clustering",
                "postprocessed",
                "--iso",
                "-0.05",
            ],
        ),
        (
            "object=asteroid&resolution=16&method=mc&clustering=none&normals=gradient",
            vec![
                "--object",
                "asteroid",
                "--resolution",
                "16",
                "--method",
                "mc",
                "--clustering",
                "none",
                "--normals",
                "gradient",
            ],
        ),
        // Marching cubes alone: clustering none, as on the command line.
        (
            "object=sphere&resolution=16&method=mc",
            vec!["--object", "sphere", "--resolution", "16", "--method", "mc"],
        ),
    ] {
        let reply = get(
            server.addr,
            &format!("/studio/api/mesh?{query}&ratios=1"),
            None,
        )
        .unwrap();
        let (header, parts) = decode(&reply);
        assert_eq!(parts.len(), 1);
        let part = &parts[0];
        assert_eq!(part.ratios.len(), part.mesh.triangle_count());
        assert_eq!(
            header["studio"]["triangles"].as_u64().unwrap() as usize,
            part.mesh.triangle_count()
        );
        assert!(header["studio"]["ar_p95"].as_f64().unwrap() >= 1.0);
        let ply = dir.path().join("cli.ply");
        let out = std::process::Command::new(env!("CARGO_BIN_EXE_experiments"))
            .arg("extract")
            .args(&line)
            .arg("--out")
            .arg(&ply)
            .output()
            .unwrap();
        assert!(
            out.status.success(),
            "{}",
            String::from_utf8_lossy(&out.stderr)
        );
        let cli: Mesh = rmt_mesh::io::read_mesh(&ply).unwrap();
        assert_eq!(cli.triangle_count(), part.mesh.triangle_count(), "{query}");
        // Same triangles, bit for bit, in the same order.
        assert_eq!(cli.positions, part.mesh.positions, "{query}");
        assert_eq!(cli.indices, part.mesh.indices, "{query}");
        assert_eq!(
            canonical_triangles(&cli),
            canonical_triangles(&part.mesh),
            "{query}"
        );
    }
}

#[test]
fn exports_are_files_of_the_shown_mesh() {
    let server = start();
    let q = "object=sphere&resolution=12";
    let (_, parts) = decode(&get(server.addr, &format!("/studio/api/mesh?{q}"), None).unwrap());
    let shown = &parts[0].mesh;
    let dir = tempfile::tempdir().unwrap();
    for format in ["ply", "obj", "glb"] {
        let r = get(
            server.addr,
            &format!("/studio/api/export?format={format}&{q}"),
            None,
        )
        .unwrap();
        assert_eq!(r.status, 200, "{format}: {}", r.text());
        assert!(r
            .header("content-disposition")
            .unwrap()
            .contains(&format!("sphere.{format}")));
        let path = dir.path().join(format!("m.{format}"));
        std::fs::write(&path, &r.body).unwrap();
        let back = rmt_mesh::io::read_mesh(&path).unwrap();
        assert_eq!(back.triangle_count(), shown.triangle_count(), "{format}");
        if format == "obj" {
            // OBJ readers number vertices in order of first use: compare oriented triangles by
            // their corners' positions, f32 for f32.
            assert_eq!(corners(&back), corners(shown), "{format}");
        } else {
            assert_eq!(back.indices, shown.indices, "{format}");
        }
    }
    let bad = get(
        server.addr,
        &format!("/studio/api/export?format=stl&{q}"),
        None,
    )
    .unwrap();
    assert!(error_of(&bad, 400).contains("stl"));
}

/// The mesh's triangles as sorted lists of corner positions (bits), each rotated to start at its
/// smallest corner so that orientation is kept.
fn corners(m: &rmt_mesh::Mesh) -> Vec<[[u32; 3]; 3]> {
    let mut t: Vec<[[u32; 3]; 3]> = m
        .triangles()
        .map(|t| {
            let c = t.map(|i| m.positions[i as usize].map(f32::to_bits));
            let first = (0..3).min_by_key(|&k| c[k]).unwrap_or(0);
            [c[first], c[(first + 1) % 3], c[(first + 2) % 3]]
        })
        .collect();
    t.sort_unstable();
    t
}

#[test]
fn bad_parameters_get_4xx_with_the_command_lines_message() {
    let server = start();
    let a = server.addr;
    for (query, needle) in [
        ("object=teapot", "teapot"),
        ("object=gyroid&radius=2", "radius"),
        ("resolution=0", "resolution"),
        ("resolution=abc", "resolution"),
        ("lattice=hex", "hex"),
        ("method=mc&clustering=integrated", "marching cubes"),
        ("resolution=20000", "too large"),
        ("iso=NaN", "iso"),
        ("out=%2Ftmp%2Fx.ply", "cannot be set"),
        ("mesh=%2Fetc%2Fpasswd&object=bunny", "cannot be set"),
        ("threads=64", "cannot be set"),
        ("ratios=2", "ratios"),
        ("bogus=1", "unknown parameter"),
        ("x=%ZZ", "percent"),
    ] {
        let r = get(a, &format!("/studio/api/mesh?{query}"), None).unwrap();
        let message = error_of(&r, 400);
        assert!(
            message.to_lowercase().contains(&needle.to_lowercase()),
            "{query}: {message}"
        );
    }
    // Sculpt: bad world parameters, unknown sessions, bad strokes, nothing to undo.
    for (query, needle) in [
        ("size=10", "size"),
        ("size=130", "multiple of 4"),
        ("chunk=0", "chunk"),
        ("object=sphere", "terrain or caves"),
        ("resolution=64", "fixed"),
        ("clustering=meshopt", "meshopt"),
    ] {
        let r = post(a, &format!("/studio/api/sculpt?{query}"), None);
        assert!(error_of(&r, 400).contains(needle), "{query}");
    }
    let none = "/studio/api/sculpt/0123456789abcdef0123456789abcdef";
    let r = post(a, &format!("{none}/undo"), None);
    assert!(error_of(&r, 404).contains("session"));
    let r = get(a, &format!("{none}/export?format=ply"), None).unwrap();
    assert_eq!(r.status, 404);
    // The server still works after all that.
    let (_, parts) = decode(&get(a, "/studio/api/mesh?resolution=8", None).unwrap());
    assert!(parts[0].mesh.triangle_count() > 0);
}

#[test]
fn a_brush_stroke_remeshes_and_sends_only_the_chunks_it_should_and_undo_redo_restore() {
    let server = start();
    let a = server.addr;
    // A small edit-workload terrain: 32 x 8 x 32 cells of 1/4, chunks of 8 cells: 4 x 1 x 4.
    let created = post(a, "/studio/api/sculpt?size=32&chunk=8", None);
    assert_eq!(created.status, 201, "{}", created.text());
    let (h, parts) = decode(&created);
    let id = h["session"].as_str().unwrap().to_string();
    assert_eq!(h["chunk_count"], 16);
    assert_eq!(parts.len(), 16);
    let mut chunks: Vec<Mesh> = parts.iter().map(|p| p.mesh.clone()).collect();
    let initial = chunks.clone();
    let welded = |chunks: &[Mesh]| canonical_triangles(&rmt_terrain::weld(chunks.iter()));

    // Where the ground is near world (x, z): the y of the nearest chunk vertex.
    let ground = |chunks: &[Mesh], x: f32, z: f32| -> f32 {
        chunks
            .iter()
            .flat_map(|m| m.positions.iter())
            .min_by(|p, q| {
                let d = |p: &[f32; 3]| (p[0] - x).powi(2) + (p[2] - z).powi(2);
                d(p).total_cmp(&d(q))
            })
            .unwrap()[1]
    };
    let centre = [-3.0, ground(&chunks, -3.0, -3.0), -3.0];
    let body = format!(
        r#"{{"centre": [{}, {}, {}], "mode": "add", "radius_cells": 2, "strength": 3}}"#,
        centre[0], centre[1], centre[2]
    );
    let r = post(a, &format!("/studio/api/sculpt/{id}/brush"), Some(&body));
    let (h, parts) = decode(&r);
    let sent: Vec<u32> = parts.iter().map(|p| p.id).collect();
    assert_eq!(h["chunks_remeshed"].as_u64().unwrap() as usize, sent.len());
    assert!(h["changed_values"].as_u64().unwrap() > 0);
    // A brush of radius 0.5 at (-3, -3) lies inside chunk 0 (x, z in -4 .. -2) and its halo
    // reaches no other chunk: exactly chunk 0 comes back.
    assert_eq!(sent, vec![0]);
    for p in &parts {
        chunks[p.id as usize] = p.mesh.clone();
    }
    assert_ne!(chunks[0].positions, initial[0].positions);
    // What the page holds now equals the server's whole sculpted terrain (its export).
    let exported = get(
        a,
        &format!("/studio/api/sculpt/{id}/export?format=ply"),
        None,
    )
    .unwrap();
    assert_eq!(exported.status, 200);
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("t.ply");
    std::fs::write(&path, &exported.body).unwrap();
    let server_mesh = rmt_mesh::io::read_mesh(&path).unwrap();
    assert_eq!(
        server_mesh.triangle_count(),
        rmt_terrain::weld(chunks.iter()).triangle_count()
    );
    assert_eq!(
        h["triangles"].as_u64().unwrap() as usize,
        chunks.iter().map(Mesh::triangle_count).sum::<usize>()
    );

    // A stroke on the seam of four chunks changes those four.
    let body = format!(
        r#"{{"centre": [-2.0, {}, -2.0], "mode": "subtract", "radius_cells": 2, "strength": 3}}"#,
        ground(&chunks, -2.0, -2.0)
    );
    let (_, parts) = decode(&post(
        a,
        &format!("/studio/api/sculpt/{id}/brush"),
        Some(&body),
    ));
    let mut sent: Vec<u32> = parts.iter().map(|p| p.id).collect();
    sent.sort();
    assert_eq!(sent, vec![0, 1, 4, 5]);
    let after_two = {
        let mut c = chunks.clone();
        for p in &parts {
            c[p.id as usize] = p.mesh.clone();
        }
        c
    };

    // Undo both: the initial terrain comes back; redo: the first stroke again.
    let (h, parts) = decode(&post(a, &format!("/studio/api/sculpt/{id}/undo"), None));
    assert_eq!((h["undo"].as_u64(), h["redo"].as_u64()), (Some(1), Some(1)));
    let mut c = after_two.clone();
    for p in &parts {
        c[p.id as usize] = p.mesh.clone();
    }
    assert_eq!(welded(&c), welded(&chunks));
    let (_, parts) = decode(&post(a, &format!("/studio/api/sculpt/{id}/undo"), None));
    for p in &parts {
        c[p.id as usize] = p.mesh.clone();
    }
    assert_eq!(welded(&c), welded(&initial));
    let r = post(a, &format!("/studio/api/sculpt/{id}/undo"), None);
    assert!(error_of(&r, 409).contains("nothing to undo"));
    let (h, parts) = decode(&post(a, &format!("/studio/api/sculpt/{id}/redo"), None));
    assert_eq!(parts.iter().map(|p| p.id).collect::<Vec<_>>(), vec![0]);
    for p in &parts {
        c[p.id as usize] = p.mesh.clone();
    }
    assert_eq!(welded(&c), welded(&chunks));
    assert_eq!(h["redo"], 1);

    // A new stroke clears the redo history.
    let (h, _) = decode(&post(
        a,
        &format!("/studio/api/sculpt/{id}/brush"),
        Some(&body),
    ));
    assert_eq!(h["redo"], 0);

    // Bad strokes: 400, the world untouched.
    for (body, needle) in [
        (r#"{"centre": [0, 0, 0], "mode": "smear"}"#, "smear"),
        (
            r#"{"centre": [0, 0, 0], "mode": "add", "radius_cells": 1000}"#,
            "radius",
        ),
        (r#"{"centre": [0, 0], "mode": "add"}"#, "JSON"),
        (
            r#"{"centre": [0, 0, 0], "mode": "add", "colour": 1}"#,
            "colour",
        ),
        ("not json", "JSON"),
    ] {
        let r = post(a, &format!("/studio/api/sculpt/{id}/brush"), Some(body));
        assert!(error_of(&r, 400).contains(needle), "{body}");
    }
    let big = format!(r#"{{"pad": "{}"}}"#, "x".repeat(40_000));
    let r = post(a, &format!("/studio/api/sculpt/{id}/brush"), Some(&big));
    assert_eq!(r.status, 413);
}

/// Defect: invalid object parameters and extreme finite bounds were 500s on both extraction
/// routes; the command line refuses them, so the page gets a 400 with the same message.
#[test]
fn invalid_object_parameters_and_extreme_bounds_are_400s() {
    let server = start();
    let a = server.addr;
    let cases = [
        ("object=sphere&radius=-1", "radius"),
        ("object=sphere&radius=NaN", "radius"),
        ("object=asteroid&octaves=0", "octaves"),
        ("object=asteroid&octaves=1000000000", "octaves"),
        ("object=asteroid&amplitude=NaN", "amplitude"),
        ("object=asteroid&frequency=-2", "frequency"),
        ("object=torus&minor=-0.1", "minor"),
        ("object=bunny&margin=0.6", "margin"),
        ("bounds=-1e30,-1e30,-1e30,1e30,1e30,1e30", "finite"),
        ("bounds=-3e38,-3e38,-3e38,3e38,3e38,3e38", "finite"),
    ];
    for (query, needle) in cases {
        for route in ["mesh", "export"] {
            let r = get(
                a,
                &format!("/studio/api/{route}?{query}&resolution=8"),
                None,
            )
            .unwrap();
            assert!(r.status < 500, "{route}?{query}: {} {}", r.status, r.text());
            let message = error_of(&r, 400);
            assert!(
                message.to_lowercase().contains(needle),
                "{route}?{query}: {message}"
            );
        }
    }
    assert_eq!(get(a, "/healthz", None).unwrap().text(), "ok");
}

/// Defect: `resolution=100000,1,1` took about 14 s (and blocked every other extraction);
/// flat cells are over the studio's per-request budget and get a 400 at once.
#[test]
fn extractions_over_the_budget_are_refused_with_a_400() {
    let server = start();
    let a = server.addr;
    for resolution in ["100000,1,1", "400,400,1", "400"] {
        let r = get(
            a,
            &format!("/studio/api/mesh?resolution={resolution}"),
            None,
        )
        .unwrap();
        let message = error_of(&r, 400);
        assert!(message.contains("budget"), "{resolution}: {message}");
    }
    // Thin boxes with cubic cells are cheap and stay allowed.
    let r = get(
        a,
        "/studio/api/mesh?resolution=64,64,2&bounds=-1,-1,-0.03125,1,1,0.03125&object=gyroid",
        None,
    )
    .unwrap();
    assert_eq!(r.status, 200, "{}", r.text());
}

/// Defect: extractions ran one at a time, so one slow request stalled everyone. A small
/// extraction on another connection now completes while a large one is still running.
#[test]
fn a_small_extraction_is_not_stuck_behind_a_large_one() {
    use std::sync::atomic::{AtomicBool, Ordering};
    let server = start();
    let a = server.addr;
    let big_done = Arc::new(AtomicBool::new(false));
    let big = {
        let big_done = big_done.clone();
        std::thread::spawn(move || {
            let start = std::time::Instant::now();
            let r = get(a, "/studio/api/mesh?object=gyroid&resolution=200", None).unwrap();
            big_done.store(true, Ordering::SeqCst);
            (r.status, start.elapsed())
        })
    };
    // Let the large request reach its extraction.
    std::thread::sleep(std::time::Duration::from_millis(500));
    let start = std::time::Instant::now();
    let small = get(a, "/studio/api/mesh?resolution=64", None).unwrap();
    let small_time = start.elapsed();
    let big_was_running = !big_done.load(Ordering::SeqCst);
    assert_eq!(small.status, 200, "{}", small.text());
    let (status, big_time) = big.join().unwrap();
    assert_eq!(status, 200);
    eprintln!("64^3 beside a running 200^3 gyroid: {small_time:?} (the 200^3: {big_time:?})");
    assert!(
        big_was_running,
        "the 64^3 request finished only after the 200^3 one ({small_time:?}, {big_time:?})"
    );
}

/// Where the ground of a sculpt world is near world (x, z): the y of the nearest vertex of its
/// chunk meshes.
fn ground_of(parts: &[wire::Part], x: f32, z: f32) -> f32 {
    parts
        .iter()
        .flat_map(|p| p.mesh.positions.iter())
        .min_by(|p, q| {
            let d = |p: &[f32; 3]| (p[0] - x).powi(2) + (p[2] - z).powi(2);
            d(p).total_cmp(&d(q))
        })
        .unwrap()[1]
}

/// Defect: one lock covered every sculpt session, so a stroke waited for strokes on other
/// sessions. Session A is a caves world of 192 x 48 x 192 cells in chunks of 96 cells with
/// postprocessed clustering (tile seams: a stroke re-meshes every chunk it touches), and a stroke
/// on the corner of its four chunks re-meshes all of them (one to two seconds). A stroke on
/// session B, sent while that one runs, has come back whole before the first byte of A's reply
/// arrives. (With the sessions' lock held through the stroke, as before, B's reply came after.)
#[test]
fn a_stroke_on_one_session_is_not_stuck_behind_a_long_one_on_another() {
    use std::io::{Read, Write};
    const LARGE: &str = "object=caves&size=192&chunk=96&clustering=postprocessed";
    const SMALL: &str = "size=32&chunk=8";
    let server = start();
    let a = server.addr;
    let create = |query: &str| {
        let (h, parts) = decode(&post(a, &format!("/studio/api/sculpt?{query}"), None));
        (h["session"].as_str().unwrap().to_string(), parts)
    };
    let (small, small_parts) = create(SMALL);
    let (large, large_parts) = create(LARGE);
    let body = |centre: [f32; 3], radius: f32, strength: f32| {
        serde_json::json!({
            "centre": centre, "mode": "add", "radius_cells": radius, "strength": strength
        })
        .to_string()
    };

    // A's stroke on a connection of its own, whose reply is read only after B's.
    let long = body([0.0, ground_of(&large_parts, 0.0, 0.0), 0.0], 32.0, 20.0);
    let mut stream = std::net::TcpStream::connect(a).unwrap();
    stream
        .set_read_timeout(Some(std::time::Duration::from_secs(60)))
        .unwrap();
    write!(
        stream,
        "POST /studio/api/sculpt/{large}/brush HTTP/1.1\r\nHost: {a}\r\nConnection: close\r\n\
         Content-Type: application/json\r\nContent-Length: {}\r\n\r\n{long}",
        long.len()
    )
    .unwrap();
    // Let the long stroke reach its session.
    std::thread::sleep(std::time::Duration::from_millis(300));
    let start = std::time::Instant::now();
    let centre = [0.0, ground_of(&small_parts, 0.0, 0.0), 0.0];
    let r = post(
        a,
        &format!("/studio/api/sculpt/{small}/brush"),
        Some(&body(centre, 4.0, 3.0)),
    );
    let small_time = start.elapsed();
    // Has any of A's reply arrived yet?
    stream.set_nonblocking(true).unwrap();
    let long_was_running = matches!(
        stream.peek(&mut [0u8; 1]),
        Err(e) if e.kind() == std::io::ErrorKind::WouldBlock
    );
    stream.set_nonblocking(false).unwrap();
    let (h, parts) = decode(&r);
    assert!(h["changed_values"].as_u64().unwrap() > 0);
    assert_eq!(parts.len(), 4, "B's stroke on its four chunks' corner");
    let mut raw = Vec::new();
    stream.read_to_end(&mut raw).unwrap();
    let long_time = start.elapsed();
    let (h, parts) = decode(&client::parse(&raw).unwrap());
    assert!(h["changed_values"].as_u64().unwrap() > 0);
    assert_eq!(h["chunk_count"], 4);
    assert_eq!(parts.len(), 4, "the long stroke re-meshes all four chunks");
    eprintln!(
        "a stroke on session B beside a running stroke on A ({LARGE}): {small_time:?} \
         (A's reply read {long_time:?} after B's stroke was sent)"
    );
    assert!(
        long_was_running,
        "A's reply had begun when B's stroke came back: B waited for A \
         ({small_time:?}, {long_time:?})"
    );
}
