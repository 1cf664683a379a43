//! The studio's LOD mode over HTTP on loopback: a multiresolution world meshed for a viewer
//! (every chunk with its level), viewer moves that send only what changed (and equal a fresh
//! session at the new position, byte for byte), strokes far from the viewer re-meshing coarse
//! chunks, export, and bad requests (4xx with a message, never a 500; the server keeps serving).

#[path = "../../crates/server/tests/common/client.rs"]
mod client;

use std::collections::BTreeMap;
use std::net::SocketAddr;
use std::sync::Arc;

use client::{get, request, Reply};
use experiments::studio::StudioBackend;
use rmt_mesh::Mesh;
use rmt_server::studio::{wire, Studio};

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
    wire::decode(&reply.body).unwrap()
}

fn error_of(reply: &Reply, status: u16) -> String {
    assert_eq!(reply.status, status, "{}", reply.text());
    reply.json()["error"].as_str().unwrap().to_string()
}

/// What the page keeps: part id -> (level, chunk index, mesh).
type Shown = BTreeMap<u32, (u64, [i64; 3], Mesh)>;

/// Applies a reply to `shown` as the page does: drop, then replace or add.
fn apply(shown: &mut Shown, h: &serde_json::Value, parts: Vec<wire::Part>) {
    for d in h["dropped"].as_array().unwrap() {
        assert!(
            shown.remove(&(d.as_u64().unwrap() as u32)).is_some(),
            "dropped an id never shown"
        );
    }
    let chunks = h["chunks"].as_array().unwrap();
    assert_eq!(chunks.len(), parts.len(), "one chunk entry per part");
    for (c, p) in chunks.iter().zip(parts) {
        assert_eq!(c["id"].as_u64().unwrap() as u32, p.id);
        let at: Vec<i64> = c["at"]
            .as_array()
            .unwrap()
            .iter()
            .map(|v| v.as_i64().unwrap())
            .collect();
        shown.insert(
            p.id,
            (c["level"].as_u64().unwrap(), [at[0], at[1], at[2]], p.mesh),
        );
    }
    assert_eq!(shown.len() as u64, h["chunk_count"].as_u64().unwrap());
    let triangles: usize = shown.values().map(|(_, _, m)| m.triangle_count()).sum();
    assert_eq!(triangles as u64, h["triangles"].as_u64().unwrap());
}

/// The shown chunks by (level, index), for comparing sessions whose ids differ.
fn by_key(shown: &Shown) -> BTreeMap<(u64, [i64; 3]), Mesh> {
    shown
        .values()
        .map(|(l, at, m)| ((*l, *at), m.clone()))
        .collect()
}

/// A small world: 64 x 16 x 64 cells of 1/8, chunks of 4 cells, levels 0-2.
const WORLD: &str = "/studio/api/lod?object=terrain&size=64&chunk=4&levels=2&ratio=1";

#[test]
fn a_lod_session_shows_every_chunk_with_its_level_and_a_move_sends_only_what_changed() {
    let server = start();
    let a = server.addr;
    let created = post(a, &format!("{WORLD}&viewer=-3,0.5,-3"), None);
    assert_eq!(created.status, 201, "{}", created.text());
    let (h, parts) = decode(&created);
    let id = h["session"].as_str().unwrap().to_string();
    assert_eq!(h["world"]["cells"], serde_json::json!([64, 16, 64]));
    assert_eq!(h["world"]["levels"], 2);
    assert_eq!(h["viewer"], serde_json::json!([-3.0, 0.5, -3.0]));
    assert_eq!(h["dropped"].as_array().unwrap().len(), 0);
    let mut shown = Shown::new();
    apply(&mut shown, &h, parts);
    // Levels near and far: the finest around the viewer, the coarsest away from it.
    let per_level: Vec<u64> = h["chunks_per_level"]
        .as_array()
        .unwrap()
        .iter()
        .map(|v| v.as_u64().unwrap())
        .collect();
    assert_eq!(per_level.len(), 3);
    assert!(per_level.iter().all(|&n| n > 0), "{per_level:?}");
    let near = |shown: &Shown, level: u64, x: f32, z: f32| {
        shown.values().any(|(l, _, m)| {
            *l == level
                && m.positions
                    .iter()
                    .any(|p| (p[0] - x).abs() < 0.5 && (p[2] - z).abs() < 0.5)
        })
    };
    assert!(near(&shown, 0, -3.0, -3.0), "no finest chunk at the viewer");
    assert!(near(&shown, 2, 3.5, 3.5), "no coarsest chunk far away");
    assert!(!near(&shown, 0, 3.5, 3.5), "a finest chunk far away");

    // Fly to the far corner: only the changed chunks come back, dropped ones are named.
    let moved = post(
        a,
        &format!("/studio/api/lod/{id}/viewer"),
        Some(r#"{"viewer": [3, 0.5, 3]}"#),
    );
    let (h2, parts2) = decode(&moved);
    let sent = parts2.len();
    assert!(sent > 0 && sent < h2["chunk_count"].as_u64().unwrap() as usize);
    assert!(!h2["dropped"].as_array().unwrap().is_empty());
    apply(&mut shown, &h2, parts2);
    assert!(near(&shown, 0, 3.0, 3.0));
    assert!(!near(&shown, 0, -3.5, -3.5));

    // The same position again: nothing to re-mesh.
    let (h3, parts3) = decode(&post(
        a,
        &format!("/studio/api/lod/{id}/viewer"),
        Some(r#"{"viewer": [3, 0.5, 3]}"#),
    ));
    assert!(parts3.is_empty() && h3["dropped"].as_array().unwrap().is_empty());

    // What the page holds equals a fresh session at the new position, byte for byte.
    let (hf, partsf) = decode(&post(a, &format!("{WORLD}&viewer=3,0.5,3"), None));
    let mut fresh = Shown::new();
    apply(&mut fresh, &hf, partsf);
    assert!(by_key(&shown) == by_key(&fresh), "incremental != fresh");

    // Export: the welded world, closed where it is inside the box.
    let ply = get(a, &format!("/studio/api/lod/{id}/export?format=ply"), None).unwrap();
    assert_eq!(ply.status, 200);
    assert!(ply.body.starts_with(b"ply\n"));
    let obj = get(a, &format!("/studio/api/lod/{id}/export?format=obj"), None).unwrap();
    let faces = obj.text().lines().filter(|l| l.starts_with("f ")).count();
    assert_eq!(faces as u64, h2["triangles"].as_u64().unwrap());
}

#[test]
fn a_stroke_far_from_the_viewer_remeshes_the_coarse_chunks_that_see_it() {
    let server = start();
    let a = server.addr;
    let (h, parts) = decode(&post(a, &format!("{WORLD}&viewer=-3,0.5,-3"), None));
    let id = h["session"].as_str().unwrap().to_string();
    let mut shown = Shown::new();
    apply(&mut shown, &h, parts);
    // The ground far away, where the map is coarse: the highest vertex near (3, 3).
    let ground = shown
        .values()
        .flat_map(|(_, _, m)| m.positions.iter())
        .filter(|p| (p[0] - 3.0).abs() < 0.3 && (p[2] - 3.0).abs() < 0.3)
        .map(|p| p[1])
        .fold(f32::NEG_INFINITY, f32::max);
    assert!(ground.is_finite());
    let before = by_key(&shown);
    let body = format!(
        r#"{{"centre": [3, {ground}, 3], "mode": "add", "radius_cells": 16, "strength": 20}}"#
    );
    let (h2, parts2) = decode(&post(
        a,
        &format!("/studio/api/lod/{id}/brush"),
        Some(&body),
    ));
    assert!(h2["marked"].as_u64().unwrap() > 0);
    assert_eq!(h2["strokes"], 1);
    let levels: Vec<u64> = h2["chunks"]
        .as_array()
        .unwrap()
        .iter()
        .map(|c| c["level"].as_u64().unwrap())
        .collect();
    assert!(!levels.is_empty());
    assert!(
        levels.iter().all(|&l| l >= 1),
        "a stroke far away re-meshed a finest chunk: {levels:?}"
    );
    apply(&mut shown, &h2, parts2);
    let after = by_key(&shown);
    let changed = after
        .iter()
        .filter(|(k, m)| before.get(k).is_none_or(|b| b != *m))
        .count();
    assert!(changed > 0, "the stroke changed no surface");
    // Near the viewer nothing moved.
    for (k, m) in &after {
        if k.0 == 0 {
            assert!(before.get(k) == Some(m), "finest chunk {k:?} changed");
        }
    }
}

/// Clustering at every level from the page: the same world with fewer triangles, closed.
#[test]
fn a_clustered_lod_session_has_fewer_triangles() {
    let server = start();
    let a = server.addr;
    let mut triangles = Vec::new();
    for clustering in ["none", "integrated"] {
        let created = post(
            a,
            &format!("{WORLD}&viewer=-3,0.5,-3&clustering={clustering}"),
            None,
        );
        assert_eq!(created.status, 201, "{}", created.text());
        let (h, parts) = decode(&created);
        assert_eq!(h["world"]["clustering"], clustering);
        let mut shown = Shown::new();
        apply(&mut shown, &h, parts);
        let id = h["session"].as_str().unwrap().to_string();
        let obj = get(a, &format!("/studio/api/lod/{id}/export?format=obj"), None).unwrap();
        let faces = obj.text().lines().filter(|l| l.starts_with("f ")).count();
        assert_eq!(faces as u64, h["triangles"].as_u64().unwrap());
        triangles.push(faces);
    }
    assert!(
        triangles[1] * 10 < triangles[0] * 8,
        "clustered {} of plain {}",
        triangles[1],
        triangles[0]
    );
}

#[test]
fn bad_lod_requests_get_4xx_with_a_message_and_the_server_keeps_serving() {
    let server = start();
    let a = server.addr;
    for (query, needle) in [
        ("size=60", "multiple of chunk"),
        ("size=64&chunk=8&levels=2", "multiple of chunk"),
        ("size=1000", "size must be 16 to 256"),
        ("chunk=2", "chunk must be 4 to 32"),
        ("levels=9", "levels must be 0 to 4"),
        ("levels=-1", "levels must be a whole number"),
        ("ratio=abc", "ratio"),
        ("ratio=10", "ratio"),
        ("object=sphere", "terrain or caves"),
        ("method=mc", "fixed in LOD mode"),
        ("clustering=integrated-unchecked", "integrated or none"),
        ("resolution=64", "fixed in LOD mode"),
        ("out=%2Ftmp%2Fx", "cannot be set"),
        ("bogus=1", "unknown parameter"),
        ("viewer=1,2", "viewer"),
        ("viewer=1,NaN,2", "viewer"),
        ("x=%ZZ", "percent"),
    ] {
        let r = post(a, &format!("/studio/api/lod?{query}"), None);
        let message = error_of(&r, 400);
        assert!(message.contains(needle), "{query}: {message}");
    }
    let small = "/studio/api/lod?size=32&chunk=4&levels=1";
    let (h, _) = decode(&post(a, small, None));
    let id = h["session"].as_str().unwrap().to_string();
    let viewer = format!("/studio/api/lod/{id}/viewer");
    for (body, needle) in [
        ("", "invalid JSON"),
        ("{", "invalid JSON"),
        (r#"{"viewer": [1, 2]}"#, "invalid JSON"),
        (r#"{"viewer": [1, 2, 3], "x": 1}"#, "unknown field"),
        (r#"{"viewer": [1e39, 0, 0]}"#, "viewer"),
    ] {
        let message = error_of(&post(a, &viewer, Some(body)), 400);
        assert!(message.contains(needle), "{body}: {message}");
    }
    let brush = format!("/studio/api/lod/{id}/brush");
    for (body, needle) in [
        (
            r#"{"centre": [0, 0, 0], "mode": "add", "radius_cells": 100}"#,
            "radius",
        ),
        (r#"{"centre": [0, 0, 0], "mode": "smear"}"#, "smear"),
        (r#"{"centre": [0, 0]}"#, "invalid JSON"),
    ] {
        let message = error_of(&post(a, &brush, Some(body)), 400);
        assert!(message.contains(needle), "{body}: {message}");
    }
    let big = format!(
        r#"{{"viewer": [0, 0, 0], "pad": "{}"}}"#,
        "x".repeat(20_000)
    );
    assert_eq!(post(a, &viewer, Some(&big)).status, 413);
    let r = get(a, &format!("/studio/api/lod/{id}/export?format=stl"), None).unwrap();
    assert!(error_of(&r, 400).contains("stl"));
    let r = get(a, &format!("/studio/api/lod/{id}/export?x=1"), None).unwrap();
    assert!(error_of(&r, 400).contains("unknown parameter"));
    let none = "/studio/api/lod/0123456789abcdef0123456789abcdef";
    let r = post(
        a,
        &format!("{none}/viewer"),
        Some(r#"{"viewer": [0, 0, 0]}"#),
    );
    assert!(error_of(&r, 404).contains("session"));
    assert_eq!(get(a, &format!("{none}/export"), None).unwrap().status, 404);
    // A viewer outside the box is allowed (the map coarsens everywhere); the session still
    // answers.
    let (h2, _) = decode(&post(a, &viewer, Some(r#"{"viewer": [100, 100, 100]}"#)));
    assert!(h2["chunk_count"].as_u64().unwrap() > 0);
    // The schema, the page and its script offer the mode.
    let schema = get(a, "/studio/api/schema", None).unwrap().json();
    assert_eq!(schema["lod"]["defaults"]["levels"], "2");
    let page = get(a, "/studio/", None).unwrap().text();
    assert!(page.contains(r#"data-mode="lod""#) && page.contains(r#"id="lod-colour""#));
    let script = get(a, "/studio/assets/studio.js", None).unwrap().text();
    assert!(script.contains("/studio/api/lod/${lodSession}/viewer"));
}
