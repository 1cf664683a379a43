//! The connection limits of both servers ([`rmt_server::serve`]) and their one error shape, over
//! raw TCP on loopback: idle connections are closed after the header timeout, a body that never
//! arrives gets a 408 after the body timeout, a client that stops reading a large reply is cut
//! off after the write timeout, a 10 GB `Content-Length` is refused at once, a
//! connection cap queues clients instead of dropping them, 200 idle connections do not stop a
//! participant, and every refusal (405, 413, 414, 431, a malformed head, an unknown path) is
//! `{"error": "..."}`. Also: every animation of the survey is served at the same size and still
//! decodes to the same frames.

mod common;

use std::io::{Read, Write};
use std::net::{SocketAddr, TcpStream};
use std::time::{Duration, Instant};

use common::client::{self, get, post_json, request, Reply};
use common::{fixture, new_session, start};
use rmt_server::http::{spawn_with, Limits, Running};
use rmt_server::store::Store;
use rmt_server::study::{Study, StudyOptions};
use rmt_server::survey::{router, Survey};
use serde_json::json;

/// Short timeouts so that the tests wait seconds, not the defaults' half minute.
fn short() -> Limits {
    Limits {
        header_timeout: Duration::from_secs(1),
        body_timeout: Duration::from_secs(1),
        ..Limits::default()
    }
}

fn survey_with(dir: &std::path::Path, limits: Limits) -> Running {
    let run = dir.join("run");
    fixture::write_run(&run);
    let study = Study::from_run(
        &run,
        &StudyOptions {
            seed: 1,
            controls: 0,
        },
    )
    .expect("study");
    let store = Store::open(&dir.join("db.sqlite"), &study).expect("store");
    let survey = Survey::new(store, run.join("render"), "admin".repeat(8));
    spawn_with(router(survey), "127.0.0.1:0".parse().unwrap(), limits).expect("server")
}

fn connect(addr: SocketAddr) -> TcpStream {
    let s = TcpStream::connect(addr).expect("connect");
    s.set_read_timeout(Some(Duration::from_secs(20))).unwrap();
    s
}

/// Sends `bytes` and reads until the server closes (or 20 s pass: then the test fails).
fn raw(addr: SocketAddr, bytes: &[u8]) -> Reply {
    let mut s = connect(addr);
    s.write_all(bytes).expect("write");
    let mut out = Vec::new();
    s.read_to_end(&mut out)
        .expect("the server closes the connection");
    client::parse(&out).unwrap_or_else(|e| panic!("{e}: {}", String::from_utf8_lossy(&out)))
}

/// The reply is an error of `status` in the routes' shape: JSON with a non-empty message.
fn assert_json_error(r: &Reply, status: u16) -> String {
    assert_eq!(r.status, status, "{}", r.text());
    assert_eq!(
        r.header("content-type"),
        Some("application/json"),
        "{status}"
    );
    let message = r.json()["error"].as_str().unwrap_or_default().to_string();
    assert!(!message.is_empty(), "{status}: {}", r.text());
    message
}

/// Waits until the server closes `s` (read gives 0) and returns how long that took.
fn closed_after(mut s: TcpStream) -> Duration {
    let start = Instant::now();
    let mut buf = [0u8; 4096];
    loop {
        match s.read(&mut buf) {
            Ok(0) => return start.elapsed(),
            Ok(_) => continue,
            Err(e) => panic!("the server did not close the idle connection: {e}"),
        }
    }
}

#[test]
fn idle_connections_are_closed_after_the_header_timeout() {
    let dir = tempfile::tempdir().unwrap();
    let server = survey_with(dir.path(), short());
    // Nothing sent at all.
    let silent = connect(server.addr);
    // Half a head.
    let mut partial = connect(server.addr);
    partial
        .write_all(b"GET /healthz HTTP/1.1\r\nHost: x\r\n")
        .unwrap();
    // A kept-alive connection after one request.
    let mut kept = connect(server.addr);
    kept.write_all(b"GET /healthz HTTP/1.1\r\nHost: x\r\n\r\n")
        .unwrap();
    let mut buf = [0u8; 1024];
    let n = kept.read(&mut buf).unwrap();
    assert!(buf[..n].starts_with(b"HTTP/1.1 200"));
    for s in [silent, partial, kept] {
        // The read timeout of `connect` (20 s) fails the test if the server never closes.
        closed_after(s);
    }
}

#[test]
fn a_body_that_never_arrives_gets_408_after_the_body_timeout() {
    let dir = tempfile::tempdir().unwrap();
    let server = survey_with(dir.path(), short());
    let r = raw(
        server.addr,
        b"POST /api/session HTTP/1.1\r\nHost: x\r\nContent-Type: application/json\r\n\
          Content-Length: 100\r\n\r\n{\"consent\": true,   ",
    );
    assert!(assert_json_error(&r, 408).contains("did not arrive"));
    assert_eq!(get(server.addr, "/healthz", None).unwrap().text(), "ok");
}

#[test]
fn a_10_gb_content_length_is_refused_at_once() {
    let dir = tempfile::tempdir().unwrap();
    // Default limits: the refusal must not wait for the body timeout.
    let server = survey_with(dir.path(), Limits::default());
    let mut s = connect(server.addr);
    s.set_read_timeout(Some(Duration::from_secs(10))).unwrap();
    s.write_all(
        b"POST /api/session HTTP/1.1\r\nHost: x\r\nContent-Type: application/json\r\n\
          Content-Length: 10000000000\r\n\r\n{\"consent\": true}   ",
    )
    .unwrap();
    let mut out = Vec::new();
    s.read_to_end(&mut out)
        .expect("answered and closed well before the 30 s body timeout");
    let r = client::parse(&out).unwrap();
    assert!(assert_json_error(&r, 413).contains("too large"));
}

#[test]
fn the_connection_cap_queues_clients_until_idle_ones_time_out() {
    let dir = tempfile::tempdir().unwrap();
    let limits = Limits {
        max_connections: 4,
        ..short()
    };
    let server = survey_with(dir.path(), limits);
    let idle: Vec<TcpStream> = (0..4).map(|_| connect(server.addr)).collect();
    // Give the server time to accept them (the cap counts accepted connections).
    std::thread::sleep(Duration::from_millis(200));
    // A fifth client waits in the backlog and is served once an idle one is closed.
    let r = get(server.addr, "/healthz", None).expect("the fifth client is served");
    assert_eq!(r.text(), "ok");
    // It could only be served after the server closed an idle connection.
    let mut closed = 0;
    for mut s in idle {
        s.set_nonblocking(true).unwrap();
        let mut buf = [0u8; 16];
        if matches!(s.read(&mut buf), Ok(0)) {
            closed += 1;
        }
    }
    assert!(closed >= 1, "served while all 4 idle connections were open");
}

#[test]
fn with_200_idle_connections_open_a_participant_finishes() {
    let dir = tempfile::tempdir().unwrap();
    let run = dir.path().join("run");
    fixture::write_run(&run);
    // The survey as the binary serves it: default limits.
    let server = start(&run, &dir.path().join("db.sqlite"), 0, &"a".repeat(32));
    let idle: Vec<TcpStream> = (0..200).map(|_| connect(server.addr)).collect();
    let session = new_session(server.addr);
    let token = session["token"].as_str().unwrap().to_string();
    let items = session["items"].as_array().unwrap().len();
    for item in 1..=items {
        let r = post_json(
            server.addr,
            "/api/answer",
            Some(&token),
            &json!({"item": item, "answer": "L", "ms": 900}),
        )
        .unwrap();
        assert_eq!(r.status, 201, "{}", r.text());
    }
    let r = request(server.addr, "POST", "/api/finish", Some(&token), None).unwrap();
    assert_eq!(r.status, 200, "{}", r.text());
    assert_eq!(r.json()["finished"], true);
    drop(idle);
}

#[test]
fn every_refusal_is_json_with_a_message() {
    let dir = tempfile::tempdir().unwrap();
    let server = survey_with(dir.path(), short());
    let a = server.addr;
    // 405, with the allowed methods kept.
    let r = request(a, "DELETE", "/api/session", None, None).unwrap();
    assert!(assert_json_error(&r, 405).contains("allowed"));
    assert!(r.header("allow").is_some_and(|v| v.contains("POST")));
    // 414 from the router's limit, and from hyper past 64 KiB.
    for len in [10_000, 70_000] {
        let head = format!("GET /{} HTTP/1.1\r\nHost: x\r\n\r\n", "a".repeat(len));
        let r = raw(a, head.as_bytes());
        assert!(
            matches!(r.status, 414 | 431),
            "{len}: {} {}",
            r.status,
            r.text()
        );
        assert_json_error(&r, r.status);
    }
    let r = raw(
        a,
        format!("GET /{} HTTP/1.1\r\nHost: x\r\n\r\n", "a".repeat(10_000)).as_bytes(),
    );
    assert_json_error(&r, 414);
    // 431: a head over the limit.
    let r = raw(
        a,
        format!(
            "GET / HTTP/1.1\r\nHost: x\r\nX-Big: {}\r\n\r\n",
            "b".repeat(100_000)
        )
        .as_bytes(),
    );
    assert_json_error(&r, 431);
    // 400: not HTTP.
    let r = raw(a, b"HELLO THERE\r\n\r\n");
    assert_json_error(&r, 400);
    // 413: a declared body over the router's limit, and over the servers' limit.
    let body = vec![b' '; 2000];
    let r = request(a, "POST", "/api/session", None, Some(&body)).unwrap();
    assert_json_error(&r, 413);
    // An unknown path and a bad path parameter.
    assert_json_error(&get(a, "/nope", None).unwrap(), 404);
    assert_json_error(&get(a, "/gif/%FF.gif", None).unwrap(), 400);
    assert_eq!(get(a, "/healthz", None).unwrap().text(), "ok");
}

/// A GIF of `w` x `h` pixels with noisy content (so sizes differ).
fn gif_of(w: u16, h: u16, seed: u32) -> Vec<u8> {
    let mut out = Vec::new();
    {
        let mut enc = gif::Encoder::new(&mut out, w, h, &[0, 0, 0, 255, 255, 255]).unwrap();
        let mut x = seed;
        let pixels: Vec<u8> = (0..usize::from(w) * usize::from(h))
            .map(|_| {
                x = x.wrapping_mul(1_103_515_245).wrapping_add(12_345);
                ((x >> 16) & 1) as u8
            })
            .collect();
        let frame = gif::Frame {
            width: w,
            height: h,
            buffer: std::borrow::Cow::Owned(pixels),
            ..gif::Frame::default()
        };
        enc.write_frame(&frame).unwrap();
    }
    out
}

fn frames(bytes: &[u8]) -> Vec<Vec<u8>> {
    let mut options = gif::DecodeOptions::new();
    options.set_color_output(gif::ColorOutput::Indexed);
    let mut d = options.read_info(bytes).expect("a GIF");
    let mut out = Vec::new();
    while let Some(f) = d.read_next_frame().expect("a frame") {
        out.push(f.buffer.to_vec());
    }
    out
}

/// The defect: served sizes differed by configuration (0.88 MB against 1.2 MB), which a
/// participant sees in the developer tools.
#[test]
fn every_animation_is_served_at_one_size_and_decodes_unchanged() {
    let dir = tempfile::tempdir().unwrap();
    let run = dir.path().join("run");
    let names = fixture::write_run(&run);
    let originals: Vec<Vec<u8>> = names
        .iter()
        .enumerate()
        .map(|(k, name)| {
            let side = 8 + 5 * k as u16;
            let g = gif_of(side, side, k as u32);
            std::fs::write(run.join("render").join(format!("{name}.gif")), &g).unwrap();
            g
        })
        .collect();
    let sizes: std::collections::BTreeSet<usize> = originals.iter().map(Vec::len).collect();
    assert!(sizes.len() > 5, "the fixture GIFs differ in size");
    let server = start(&run, &dir.path().join("db.sqlite"), 0, &"a".repeat(32));
    let largest = originals.iter().map(Vec::len).max().unwrap();
    for (name, original) in names.iter().zip(&originals) {
        let r = get(server.addr, &format!("/gif/{name}.gif"), None).unwrap();
        assert_eq!(r.status, 200);
        assert_eq!(
            r.body.len(),
            largest + rmt_server::survey::GIF_PAD_MIN,
            "{name}"
        );
        assert_eq!(frames(&r.body), frames(original), "{name}");
    }
}

/// A client that asks for a large reply and never reads it is cut off after the write timeout,
/// so under a cap of one connection the next client is served instead of waiting forever.
#[test]
fn a_client_that_stops_reading_frees_its_slot_after_the_write_timeout() {
    use axum::routing::get as route;
    let router = axum::Router::new()
        .route("/big", route(|| async { vec![7u8; 64 << 20] }))
        .route("/healthz", route(|| async { "ok" }));
    let limits = Limits {
        max_connections: 1,
        write_timeout: Duration::from_secs(1),
        ..short()
    };
    let server = spawn_with(router, "127.0.0.1:0".parse().unwrap(), limits).expect("server");
    let mut hog = connect(server.addr);
    hog.write_all(b"GET /big HTTP/1.1\r\nHost: x\r\n\r\n")
        .unwrap();
    std::thread::sleep(Duration::from_millis(200));
    // The read timeout of `get` (60 s) fails the test if the hog keeps the only slot.
    let start = Instant::now();
    let r = get(server.addr, "/healthz", None).expect("served once the hog is cut off");
    assert_eq!(r.text(), "ok");
    assert!(
        start.elapsed() >= Duration::from_millis(500),
        "{:?}",
        start.elapsed()
    );
    // The hog's connection was closed: reading it to the end stops short of the 64 MiB.
    hog.set_read_timeout(Some(Duration::from_secs(20))).unwrap();
    let mut got = 0usize;
    let mut buf = vec![0u8; 1 << 20];
    loop {
        match hog.read(&mut buf) {
            Ok(0) | Err(_) => break,
            Ok(n) => got += n,
        }
    }
    assert!(got < 64 << 20, "the whole reply arrived: {got} bytes");
}
