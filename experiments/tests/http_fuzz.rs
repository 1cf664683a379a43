//! A fuzz campaign over every HTTP route of both servers (the studio with the `experiments`
//! backend, and the survey): seeded random requests with random parameter names and values,
//! numbers at the edges of `f32` and `f64`, long strings, percent-escapes (valid and not), JSON
//! bodies of the wrong shape, random methods and paths. Every reply must be below 500, every
//! error must be `{"error": "<non-empty message>"}` as `application/json`, and `/healthz` must
//! still answer after the run.
//!
//! `RMT_HTTP_FUZZ` sets the number of requests per server (default 300, a few seconds); `.ci/run`
//! runs 20,000 (about 30 s). `RMT_HTTP_FUZZ_SEED` changes the seed. The test prints the count
//! and the replies by status (`-- --nocapture`).

#[path = "../../crates/server/tests/common/client.rs"]
mod client;
#[path = "../../crates/server/tests/common/fixture.rs"]
mod fixture;

use std::collections::BTreeMap;
use std::net::SocketAddr;
use std::sync::Arc;

use client::{request, Reply};
use experiments::studio::StudioBackend;
use rmt_server::studio::Studio;

fn count() -> usize {
    std::env::var("RMT_HTTP_FUZZ")
        .ok()
        .and_then(|s| s.parse().ok())
        .unwrap_or(300)
}

fn seed() -> u64 {
    std::env::var("RMT_HTTP_FUZZ_SEED")
        .ok()
        .and_then(|s| s.parse().ok())
        .unwrap_or(38)
}

/// SplitMix64.
struct Rng(u64);

impl Rng {
    fn next(&mut self) -> u64 {
        self.0 = self.0.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        z ^ (z >> 31)
    }

    fn below(&mut self, n: usize) -> usize {
        (self.next() % n.max(1) as u64) as usize
    }

    fn pick<'a, T>(&mut self, items: &'a [T]) -> &'a T {
        &items[self.below(items.len())]
    }

    fn chance(&mut self, percent: u64) -> bool {
        self.next() % 100 < percent
    }
}

/// Numbers at the edges of f32 and f64, and ordinary ones, as text.
const NUMBERS: &[&str] = &[
    "0",
    "-0",
    "1",
    "-1",
    "0.5",
    "0.6",
    "2",
    "3",
    "8",
    "16",
    "17",
    "1e9",
    "-1e9",
    "NaN",
    "nan",
    "inf",
    "-inf",
    "infinity",
    "+inf",
    "3e38",
    "-3e38",
    "3.4028235e38",
    "3.5e38",
    "-3.5e38",
    "1.7976931348623157e308",
    "-1.7976931348623157e308",
    "1e309",
    "1e30",
    "-1e30",
    "1e-45",
    "-1e-45",
    "1e-38",
    "1.17549435e-38",
    "4.9e-324",
    "2.2250738585072014e-308",
    "0x10",
    "1_000",
    "18446744073709551616",
    "-9223372036854775809",
    "4294967296",
    "65536",
    "1e17",
    "3e17",
    "",
    " 1",
    "1 ",
    "1,2",
    "0.0000001",
    "12345678901234567890123456789",
];

const NAMES: &[&str] = &[
    "object",
    "radius",
    "octaves",
    "amplitude",
    "frequency",
    "seed",
    "margin",
    "band",
    "minor",
    "major",
    "resolution",
    "bounds",
    "lattice",
    "method",
    "clustering",
    "collapse_threshold",
    "collapse-threshold",
    "iso",
    "normals",
    "ratios",
    "format",
    "size",
    "chunk",
    "mesh",
    "out",
    "threads",
    "gif",
    "json",
    "token",
    "item",
    "answer",
    "ms",
    "consent",
    "x",
    "",
    "%00",
    "a b",
    "radius[]",
    "RADIUS",
    "scale",
    "cells",
];

const WORDS: &[&str] = &[
    "sphere",
    "asteroid",
    "gyroid",
    "torus",
    "bunny",
    "terrain",
    "caves",
    "random",
    "teapot",
    "bcdl",
    "simple",
    "hex",
    "mt",
    "mc",
    "none",
    "integrated",
    "integrated-unchecked",
    "postprocessed",
    "meshopt",
    "area",
    "gradient",
    "ply",
    "obj",
    "glb",
    "stl",
    "true",
    "false",
    "null",
    "L",
    "N",
    "R",
    "../../etc/passwd",
    "/etc/passwd",
    "<script>",
    "\u{e9}\u{20ac}",
    "\u{0}",
    "%",
    "%G1",
    "%FF",
    "%2C",
    "%E2%82%AC",
    "%00",
    "+",
    "&",
    "=",
    ";",
];

/// Resolutions small enough to extract in milliseconds, and hostile ones.
const RESOLUTIONS: &[&str] = &[
    "1",
    "2",
    "4",
    "8",
    "12",
    "16",
    "0",
    "-1",
    "8,8,8",
    "4,8,12",
    "1,1,1",
    "100000,1,1",
    "400,400,1",
    "1e9",
    "99999999999999999999",
    "8,8",
    "8,8,8,8",
    "3000",
    "NaN",
    "8.5",
];

fn random_number(rng: &mut Rng) -> String {
    match rng.below(4) {
        0 => (rng.next() as i64).to_string(),
        1 => format!("{:e}", f64::from_bits(rng.next())),
        2 => f32::from_bits(rng.next() as u32).to_string(),
        _ => rng.pick(NUMBERS).to_string(),
    }
}

fn random_value(rng: &mut Rng, name: &str) -> String {
    let k = rng.below(10);
    match name {
        "resolution" if k <= 6 => return rng.pick(RESOLUTIONS).to_string(),
        "bounds" if k <= 5 => {
            return (0..[6, 6, 6, 5, 7][rng.below(5)])
                .map(|_| random_number(rng))
                .collect::<Vec<_>>()
                .join(",")
        }
        "size" | "chunk" if k <= 4 => {
            return rng
                .pick(&["16", "32", "4", "8", "15", "600", "0"])
                .to_string()
        }
        _ => {}
    }
    match (name, k) {
        (_, 0..=3) => random_number(rng),
        (_, 4..=6) => rng.pick(WORDS).to_string(),
        (_, 7) => "x".repeat(rng.below(5000)),
        (_, 8) => (0..rng.below(40))
            .map(|_| format!("%{:02X}", rng.below(256)))
            .collect(),
        _ => (0..rng.below(30))
            .map(|_| char::from_u32(rng.below(0x3000) as u32).unwrap_or('?'))
            .collect(),
    }
}

/// A random value for `name`, encoded for a path segment.
fn segment(rng: &mut Rng, name: &str) -> String {
    let v = random_value(rng, name);
    encode(rng, &v)
}

/// Percent-encodes what a URL cannot carry raw; sometimes leaves the text raw (percent signs
/// and all) to test the server's own decoding.
fn encode(rng: &mut Rng, s: &str) -> String {
    if rng.chance(20) {
        return s
            .chars()
            .filter(|c| c.is_ascii_graphic() && *c != '#' && *c != '?')
            .collect();
    }
    s.bytes()
        .map(|b| {
            if b.is_ascii_alphanumeric() || b"-_.,".contains(&b) {
                (b as char).to_string()
            } else {
                format!("%{b:02X}")
            }
        })
        .collect()
}

fn query(rng: &mut Rng, base: &[(&str, &str)]) -> String {
    let mut pairs: Vec<(String, String)> = base
        .iter()
        .map(|(k, v)| (k.to_string(), v.to_string()))
        .collect();
    for _ in 0..rng.below(6) {
        let name = if rng.chance(85) {
            rng.pick(NAMES).to_string()
        } else {
            random_value(rng, "")
        };
        let value = random_value(rng, &name);
        pairs.push((name, value));
    }
    // Keep extractions small unless the campaign picked a resolution itself.
    if !pairs.iter().any(|(k, _)| k == "resolution") && rng.chance(90) {
        pairs.push(("resolution".into(), rng.pick(&["4", "8", "12"]).to_string()));
    }
    pairs
        .iter()
        .map(|(k, v)| format!("{}={}", encode(rng, k), encode(rng, v)))
        .collect::<Vec<_>>()
        .join("&")
}

/// JSON of the right shape with odd values, or of the wrong shape, or not JSON at all.
fn body(rng: &mut Rng, fields: &[&str]) -> Vec<u8> {
    let value = |rng: &mut Rng| -> serde_json::Value {
        match rng.below(9) {
            0 => serde_json::json!(random_number(rng)),
            1 => serde_json::from_str(&random_number(rng)).unwrap_or(serde_json::Value::Null),
            2 => serde_json::json!(rng.pick(WORDS)),
            3 => serde_json::json!([1e300, -1e300, 0.5]),
            4 => serde_json::json!([random_number(rng), 1, 2]),
            5 => serde_json::json!({"nested": [1, 2, {"x": null}]}),
            6 => serde_json::json!(rng.next() as i64),
            7 => serde_json::json!(true),
            _ => serde_json::Value::Null,
        }
    };
    match rng.below(10) {
        0 => b"{".to_vec(),
        1 => (0..rng.below(3000)).map(|_| rng.next() as u8).collect(),
        2 => serde_json::json!([1, 2, 3]).to_string().into_bytes(),
        3 => b"\"just a string\"".to_vec(),
        _ => {
            let mut m = serde_json::Map::new();
            for f in fields {
                if rng.chance(80) {
                    m.insert(f.to_string(), value(rng));
                }
            }
            if rng.chance(20) {
                m.insert(rng.pick(NAMES).to_string(), value(rng));
            }
            serde_json::Value::Object(m).to_string().into_bytes()
        }
    }
}

/// What one run found.
#[derive(Default)]
struct Tally {
    by_status: BTreeMap<u16, usize>,
    failures: Vec<String>,
    requests: usize,
}

impl Tally {
    fn check(&mut self, method: &str, path: &str, reply: std::io::Result<Reply>) -> Option<Reply> {
        self.requests += 1;
        let shown: String = path.chars().take(300).collect();
        let r = match reply {
            Ok(r) => r,
            Err(e) => {
                self.failures
                    .push(format!("{method} {shown}: no reply ({e})"));
                return None;
            }
        };
        *self.by_status.entry(r.status).or_default() += 1;
        if r.status >= 500 {
            self.failures
                .push(format!("{method} {shown}: {} {}", r.status, r.text()));
        } else if r.status >= 400 {
            let json = r.header("content-type") == Some("application/json");
            let message = serde_json::from_slice::<serde_json::Value>(&r.body)
                .ok()
                .and_then(|v| v["error"].as_str().map(str::to_string))
                .unwrap_or_default();
            if !json || message.is_empty() {
                self.failures.push(format!(
                    "{method} {shown}: {} without a JSON message: {}",
                    r.status,
                    r.text()
                ));
            }
        }
        Some(r)
    }

    fn report(&self, server: &str) {
        eprintln!(
            "http_fuzz {server}: {} requests, replies by status {:?}, {} failures",
            self.requests,
            self.by_status,
            self.failures.len()
        );
        assert!(
            self.failures.is_empty(),
            "{server}: {} failures, first ones:\n{}",
            self.failures.len(),
            self.failures
                .iter()
                .take(20)
                .cloned()
                .collect::<Vec<_>>()
                .join("\n")
        );
    }
}

/// One request (a body only with methods that send one: the client frames bodies for them).
fn send(
    addr: SocketAddr,
    method: &str,
    path: &str,
    token: Option<&str>,
    body: Option<&[u8]>,
) -> std::io::Result<Reply> {
    let body = if method == "GET" { None } else { body };
    request(addr, method, path, token, body)
}

/// Methods for the wrong-method requests (HEAD replies have no body for the client to read).
const METHODS: &[&str] = &["GET", "POST", "PUT", "DELETE", "PATCH", "OPTIONS"];

#[test]
fn the_studio_never_answers_5xx_and_every_error_has_a_message() {
    let studio = Arc::new(Studio::new(StudioBackend::new(2)));
    let server = rmt_server::http::spawn(
        rmt_server::studio::standalone_router(studio),
        "127.0.0.1:0".parse().unwrap(),
    )
    .unwrap();
    let a = server.addr;
    let mut rng = Rng(seed());
    let mut tally = Tally::default();
    let mut sessions: Vec<String> = Vec::new();
    let mut lod_sessions: Vec<String> = Vec::new();
    let brush_fields = ["centre", "mode", "radius_cells", "strength"];
    for _ in 0..count() {
        let (method, path, body): (&str, String, Option<Vec<u8>>) = match rng.below(14) {
            0..=3 => (
                "GET",
                format!("/studio/api/mesh?{}", query(&mut rng, &[])),
                None,
            ),
            4 => (
                "GET",
                format!("/studio/api/export?{}", query(&mut rng, &[])),
                None,
            ),
            5 => {
                let q = query(&mut rng, &[("size", "16"), ("chunk", "8")]);
                ("POST", format!("/studio/api/sculpt?{q}"), None)
            }
            6 | 7 => {
                let id = if !sessions.is_empty() && rng.chance(80) {
                    rng.pick(&sessions).clone()
                } else {
                    segment(&mut rng, "id")
                };
                let action = *rng.pick(&["brush", "brush", "undo", "redo"]);
                let b = (action == "brush").then(|| body(&mut rng, &brush_fields));
                ("POST", format!("/studio/api/sculpt/{id}/{action}"), b)
            }
            8 => {
                let id = match sessions.is_empty() {
                    false if rng.chance(70) => rng.pick(&sessions).clone(),
                    _ => segment(&mut rng, "id"),
                };
                let q = query(&mut rng, &[]);
                ("GET", format!("/studio/api/sculpt/{id}/export?{q}"), None)
            }
            9 => {
                let file = segment(&mut rng, "file");
                ("GET", format!("/studio/assets/{file}"), None)
            }
            10 => ("GET", "/studio/api/schema".to_string(), None),
            // LOD mode: small worlds, then viewer moves, strokes and exports on them.
            11 => {
                let q = query(&mut rng, &[("size", "32"), ("chunk", "4"), ("levels", "1")]);
                // LOD mode refuses a resolution: leave out the one query() adds for extractions.
                let q: Vec<&str> = q
                    .split('&')
                    .filter(|p| !p.starts_with("resolution=") || rng.chance(10))
                    .collect();
                ("POST", format!("/studio/api/lod?{}", q.join("&")), None)
            }
            12 => {
                let id = if !lod_sessions.is_empty() && rng.chance(80) {
                    rng.pick(&lod_sessions).clone()
                } else {
                    segment(&mut rng, "id")
                };
                match rng.below(3) {
                    0 => (
                        "POST",
                        format!("/studio/api/lod/{id}/viewer"),
                        Some(body(&mut rng, &["viewer"])),
                    ),
                    1 => (
                        "POST",
                        format!("/studio/api/lod/{id}/brush"),
                        Some(body(&mut rng, &brush_fields)),
                    ),
                    _ => {
                        let q = query(&mut rng, &[]);
                        ("GET", format!("/studio/api/lod/{id}/export?{q}"), None)
                    }
                }
            }
            _ => {
                let m = *rng.pick(METHODS);
                let p = rng
                    .pick(&[
                        "/studio/api/mesh",
                        "/studio/api/sculpt",
                        "/studio/api/lod",
                        "/studio/",
                        "/healthz",
                        "/",
                        "/studio/api/nope",
                    ])
                    .to_string();
                let b = rng.chance(50).then(|| body(&mut rng, &brush_fields));
                (m, p, b)
            }
        };
        let reply = tally.check(method, &path, send(a, method, &path, None, body.as_deref()));
        if let Some(r) = reply {
            if r.status == 201 && path.starts_with("/studio/api/sculpt?") {
                if let Ok((header, _)) = rmt_server::studio::wire::decode(&r.body) {
                    if let Some(id) = header["session"].as_str() {
                        sessions.push(id.to_string());
                    }
                }
            }
            if r.status == 201 && path.starts_with("/studio/api/lod?") {
                if let Ok((header, _)) = rmt_server::studio::wire::decode(&r.body) {
                    if let Some(id) = header["session"].as_str() {
                        lod_sessions.push(id.to_string());
                    }
                }
            }
        }
    }
    let health = client::get(a, "/healthz", None).expect("/healthz after the run");
    assert_eq!(health.text(), "ok");
    tally.report("studio");
}

#[test]
fn the_survey_never_answers_5xx_and_every_error_has_a_message() {
    let dir = tempfile::tempdir().unwrap();
    let run = dir.path().join("run");
    let names = fixture::write_run(&run);
    let study = rmt_server::study::Study::from_run(
        &run,
        &rmt_server::study::StudyOptions {
            seed: 1,
            controls: 1,
        },
    )
    .unwrap();
    let store = rmt_server::store::Store::open(&dir.path().join("db.sqlite"), &study).unwrap();
    let admin = "f".repeat(32);
    let survey = rmt_server::survey::Survey::new(store, run.join("render"), admin.clone());
    let server = rmt_server::http::spawn(
        rmt_server::survey::router(survey),
        "127.0.0.1:0".parse().unwrap(),
    )
    .unwrap();
    let a = server.addr;
    let mut rng = Rng(seed() ^ 0x5eed);
    let mut tally = Tally::default();
    let mut tokens: Vec<String> = Vec::new();
    for _ in 0..count() {
        let token = if !tokens.is_empty() && rng.chance(60) {
            Some(rng.pick(&tokens).clone())
        } else if rng.chance(30) {
            Some(random_value(&mut rng, "token").replace(['\r', '\n'], ""))
        } else {
            None
        };
        let (method, path, body): (&str, String, Option<Vec<u8>>) = match rng.below(12) {
            0 | 1 => (
                "POST",
                "/api/session".into(),
                Some(body(&mut rng, &["consent"])),
            ),
            2 => ("GET", "/api/session".into(), None),
            3..=5 => (
                "POST",
                "/api/answer".into(),
                Some(body(&mut rng, &["item", "answer", "ms"])),
            ),
            6 => ("POST", "/api/finish".into(), None),
            7 => {
                let name = if rng.chance(50) {
                    rng.pick(&names).clone()
                } else {
                    segment(&mut rng, "name")
                };
                ("GET", format!("/gif/{name}.gif"), None)
            }
            8 => {
                let q = if rng.chance(30) {
                    format!("token={admin}")
                } else {
                    query(&mut rng, &[])
                };
                let p = *rng.pick(&["/admin", "/admin/counts", "/admin/export/responses.csv"]);
                ("GET", format!("{p}?{q}"), None)
            }
            9 => {
                let file = segment(&mut rng, "file");
                ("GET", format!("/admin/export/{file}?token={admin}"), None)
            }
            10 => {
                let p = rng
                    .pick(&["/", "/assets/survey.js", "/assets/survey.css", "/healthz"])
                    .to_string();
                ("GET", p, None)
            }
            _ => {
                let m = *rng.pick(METHODS);
                let p = rng
                    .pick(&[
                        "/api/session",
                        "/api/answer",
                        "/api/finish",
                        "/admin",
                        "/gif/x.gif",
                        "/nope",
                        "/healthz",
                    ])
                    .to_string();
                let b = rng.chance(50).then(|| body(&mut rng, &["consent", "item"]));
                (m, p, b)
            }
        };
        // A few valid participants so that answers reach the store.
        if rng.chance(5) {
            let r = client::post_json(
                a,
                "/api/session",
                None,
                &serde_json::json!({"consent": true}),
            );
            if let Some(r) = tally.check("POST", "/api/session", r) {
                if let Some(t) = r.json()["token"].as_str() {
                    tokens.push(t.to_string());
                }
            }
        }
        tally.check(
            method,
            &path,
            send(a, method, &path, token.as_deref(), body.as_deref()),
        );
    }
    let health = client::get(a, "/healthz", None).expect("/healthz after the run");
    assert_eq!(health.text(), "ok");
    tally.report("survey");
}
