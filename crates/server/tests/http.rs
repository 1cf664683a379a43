//! Every route of the survey over real HTTP on a loopback port: the participant's whole session,
//! resume, idempotent finish, admin counts and exports, blinding on the wire, and bad input
//! (4xx with a clear message, nothing stored).

mod common;

use std::collections::BTreeSet;

use common::client::{get, post_json, request, Reply};
use common::{fixture, new_session, start};
use rmt_server::store::Store;
use serde_json::json;

const ADMIN: &str = "0123456789abcdef0123456789abcdef";

fn error_of(r: &Reply) -> String {
    r.json()["error"].as_str().unwrap_or_default().to_string()
}

/// Words that would reveal a configuration: ids and variable values of the fixture.
fn secrets() -> Vec<String> {
    let mut s = fixture::ids();
    s.extend(
        [
            "sphere",
            "asteroid",
            "bunny",
            "bcdl",
            "integrated",
            "postprocessed",
            "lattice",
            "clustering",
            "key.csv",
            "configurations",
        ]
        .map(String::from),
    );
    s
}

fn assert_blind(what: &str, body: &[u8]) {
    let text = String::from_utf8_lossy(body).to_ascii_lowercase();
    for secret in secrets() {
        assert!(
            !text.contains(&secret.to_ascii_lowercase()),
            "{what} reveals `{secret}`: {text}"
        );
    }
}

#[test]
fn a_participant_session_end_to_end_over_every_route() {
    let dir = tempfile::tempdir().unwrap();
    let run = dir.path().join("run");
    let names = fixture::write_run(&run);
    let db = dir.path().join("survey.sqlite");
    let server = start(&run, &db, 2, ADMIN);
    let addr = server.addr;
    let mut bodies: Vec<(String, Vec<u8>)> = Vec::new();

    // Static page, script, style, health.
    let page = get(addr, "/", None).unwrap();
    assert_eq!(page.status, 200);
    assert!(page
        .header("content-type")
        .unwrap()
        .starts_with("text/html"));
    assert!(page.text().contains("id=\"consent-check\""));
    assert!(page.header("content-security-policy").is_some());
    for (path, kind) in [
        ("/assets/survey.js", "text/javascript"),
        ("/assets/survey.css", "text/css"),
    ] {
        let r = get(addr, path, None).unwrap();
        assert_eq!(r.status, 200, "{path}");
        assert!(r.header("content-type").unwrap().starts_with(kind));
        bodies.push((path.into(), r.body));
    }
    assert!(String::from_utf8_lossy(&bodies[1].1).contains("image-rendering: pixelated"));
    bodies.push(("/".into(), page.body));
    assert_eq!(get(addr, "/healthz", None).unwrap().text(), "ok");

    // Consent -> a session with 27 questions + 2 controls, names only.
    let session = new_session(addr);
    bodies.push(("POST /api/session".into(), session.to_string().into_bytes()));
    let token = session["token"].as_str().unwrap().to_string();
    assert_eq!(session["total"], 29);
    let items = session["items"].as_array().unwrap();
    assert_eq!(items.len(), 29);
    let shown: BTreeSet<&str> = items
        .iter()
        .flat_map(|i| [i["left"].as_str().unwrap(), i["right"].as_str().unwrap()])
        .collect();
    assert!(shown.iter().all(|n| names.iter().any(|m| m == n)));
    assert_eq!(
        items.iter().filter(|i| i["left"] == i["right"]).count(),
        2,
        "two controls"
    );

    // Every animation the session names is served, as a GIF, cacheable.
    for name in &shown {
        let r = get(addr, &format!("/gif/{name}.gif"), None).unwrap();
        assert_eq!(r.status, 200);
        assert_eq!(r.header("content-type"), Some("image/gif"));
        // Padded to the study's common size with a comment before the trailer.
        let mut padded = fixture::TINY_GIF.to_vec();
        assert!(rmt_server::survey::pad_gif(
            &mut padded,
            fixture::TINY_GIF.len() + rmt_server::survey::GIF_PAD_MIN
        ));
        assert_eq!(r.body, padded);
        assert!(r.header("cache-control").unwrap().contains("max-age"));
    }

    // Finishing early is refused.
    let r = request(addr, "POST", "/api/finish", Some(&token), None).unwrap();
    assert_eq!(r.status, 409);
    assert!(error_of(&r).contains("29 of 29 questions are not answered"));

    // Answer half, then "reload": the session lists them and resumes.
    let answer_code = |k: usize| ["L", "N", "R"][k % 3];
    for k in 1..=14usize {
        let r = post_json(
            addr,
            "/api/answer",
            Some(&token),
            &json!({"item": k, "answer": answer_code(k), "ms": 1000 + k}),
        )
        .unwrap();
        assert_eq!(r.status, 201, "{}", r.text());
        assert_eq!(r.json()["answered"], k);
        bodies.push((format!("answer {k}"), r.body));
    }
    let resumed = get(addr, "/api/session", Some(&token)).unwrap();
    assert_eq!(resumed.status, 200);
    assert_eq!(resumed.header("cache-control"), Some("no-store"));
    let view = resumed.json();
    assert_eq!(view["answers"].as_array().unwrap().len(), 14);
    assert_eq!(view["items"], session["items"], "same order and sides");
    assert_eq!(view["finished"], false);
    bodies.push(("GET /api/session".into(), resumed.body));
    for k in 15..=29usize {
        let r = post_json(
            addr,
            "/api/answer",
            Some(&token),
            &json!({"item": k, "answer": answer_code(k), "ms": 900}),
        )
        .unwrap();
        assert_eq!(r.status, 201, "{}", r.text());
    }

    // Finish, twice: same result.
    let first = request(addr, "POST", "/api/finish", Some(&token), None).unwrap();
    assert_eq!(first.status, 200, "{}", first.text());
    assert_eq!(first.json()["finished"], true);
    let again = request(addr, "POST", "/api/finish", Some(&token), None).unwrap();
    assert_eq!(again.status, 200);
    assert_eq!(again.json(), first.json());
    bodies.push(("finish".into(), first.body));
    // After finishing, no answer is taken.
    let r = post_json(
        addr,
        "/api/answer",
        Some(&token),
        &json!({"item": 1, "answer": "L"}),
    )
    .unwrap();
    assert_eq!(r.status, 409);

    // Blinding: nothing the participant received names a configuration.
    for (what, body) in &bodies {
        assert_blind(what, body);
    }

    // Admin: counts (JSON and HTML) and every export file, with the token as header or query.
    let counts = get(addr, "/admin/counts", Some(ADMIN)).unwrap();
    assert_eq!(counts.status, 200);
    let counts = counts.json();
    assert_eq!(counts["participants"], 1);
    assert_eq!(counts["finished"], 1);
    assert_eq!(counts["answers"], 27);
    assert_eq!(counts["control_answers"], 2);
    let page = get(addr, &format!("/admin?token={ADMIN}"), None).unwrap();
    assert_eq!(page.status, 200);
    assert!(
        page.text().contains("1 started, 1 finished"),
        "{}",
        page.text()
    );
    for file in rmt_server::export::EXPORT_FILES {
        let r = get(addr, &format!("/admin/export/{file}"), Some(ADMIN)).unwrap();
        assert_eq!(r.status, 200, "{file}");
        assert!(!r.body.is_empty());
    }
    let responses = get(addr, "/admin/export/responses.csv", Some(ADMIN))
        .unwrap()
        .text();
    assert_eq!(responses.lines().count(), 28, "{responses}");
    assert!(responses.starts_with("participant,question,response,order,swapped,seconds\n"));

    // The export maps each answer back to the canonical sides: L clicked on a swapped question
    // is R for the question's canonical left/right.
    let participants = get(addr, "/admin/export/participants.csv", Some(ADMIN))
        .unwrap()
        .text();
    let row: Vec<&str> = participants.lines().nth(1).unwrap().split(',').collect();
    assert_eq!(row[0], "P001");
    assert_eq!(row[1], token);
    assert_eq!(row[6], "1");
    let order: Vec<&str> = row[7].split(' ').collect();
    let swaps: Vec<char> = row[8].chars().collect();
    assert_eq!(order.len(), 29);
    assert!(swaps.contains(&'1') && swaps.contains(&'0'));
    for line in responses.lines().skip(1) {
        let f: Vec<&str> = line.split(',').collect();
        let position: usize = f[3].parse().unwrap();
        assert_eq!(order[position - 1], f[1]);
        assert_eq!(f[4], if swaps[position - 1] == '1' { "1" } else { "0" });
        let clicked = answer_code(position);
        let expected = match (clicked, f[4]) {
            ("L", "1") => "R",
            ("R", "1") => "L",
            (c, _) => c,
        };
        assert_eq!(f[2], expected, "{line}");
        let seconds: f64 = f[5].parse().unwrap();
        assert!(seconds > 0.8 && seconds < 1.1, "{line}");
    }
    let controls = get(addr, "/admin/export/controls.csv", Some(ADMIN))
        .unwrap()
        .text();
    assert_eq!(controls.lines().count(), 3);
    server.stop().unwrap();

    let store = Store::open_existing(&db).unwrap();
    assert_eq!(store.integrity_check().unwrap(), "ok");
}

#[test]
fn bad_input_gets_a_4xx_with_a_clear_message_and_stores_nothing() {
    let dir = tempfile::tempdir().unwrap();
    let run = dir.path().join("run");
    fixture::write_run(&run);
    let server = start(&run, &dir.path().join("a.sqlite"), 0, ADMIN);
    let addr = server.addr;
    // A second server with its own database: its tokens are foreign to the first.
    let other = start(&run, &dir.path().join("b.sqlite"), 0, ADMIN);
    let foreign = new_session(other.addr)["token"]
        .as_str()
        .unwrap()
        .to_string();

    let token = new_session(addr)["token"].as_str().unwrap().to_string();
    let answer = |token: Option<&str>, body: serde_json::Value| {
        post_json(addr, "/api/answer", token, &body).unwrap()
    };
    let cases: Vec<(&str, Reply, u16, &str)> = vec![
        (
            "unknown question",
            answer(Some(&token), json!({"item": 28, "answer": "L"})),
            400,
            "unknown question 28: this session has questions 1 to 27",
        ),
        (
            "question zero",
            answer(Some(&token), json!({"item": 0, "answer": "L"})),
            400,
            "unknown question 0",
        ),
        (
            "unknown answer value",
            answer(Some(&token), json!({"item": 1, "answer": "left please"})),
            400,
            "unknown answer `left please` (expected L, N or R)",
        ),
        (
            "forged token",
            answer(
                Some("ffffffffffffffffffffffffffffffff"),
                json!({"item": 1, "answer": "L"}),
            ),
            401,
            "unknown participant token",
        ),
        (
            "malformed token",
            answer(Some("../../etc/passwd"), json!({"item": 1, "answer": "L"})),
            401,
            "unknown participant token",
        ),
        (
            "foreign token",
            answer(Some(&foreign), json!({"item": 1, "answer": "L"})),
            401,
            "unknown participant token",
        ),
        (
            "admin token as participant",
            answer(Some(ADMIN), json!({"item": 1, "answer": "L"})),
            401,
            "unknown participant token",
        ),
        (
            "no token",
            answer(None, json!({"item": 1, "answer": "L"})),
            401,
            "missing participant token",
        ),
        (
            "unknown field",
            answer(Some(&token), json!({"item": 1, "answer": "L", "who": "x"})),
            400,
            "invalid JSON body",
        ),
        (
            "not JSON",
            request(addr, "POST", "/api/answer", Some(&token), Some(b"item=1")).unwrap(),
            400,
            "invalid JSON body",
        ),
        (
            "answer time out of range",
            answer(
                Some(&token),
                json!({"item": 1, "answer": "L", "ms": 100_000_000u64}),
            ),
            400,
            "out of range",
        ),
        (
            "oversized body",
            request(
                addr,
                "POST",
                "/api/answer",
                Some(&token),
                Some(
                    format!(
                        r#"{{"item": 1, "answer": "L", "pad": "{}"}}"#,
                        "x".repeat(4096)
                    )
                    .as_bytes(),
                ),
            )
            .unwrap(),
            413,
            "request body too large (at most 1024 bytes)",
        ),
        (
            "session without consent",
            post_json(addr, "/api/session", None, &json!({"consent": false})).unwrap(),
            400,
            "consent is required",
        ),
        (
            "session of a forged token",
            get(
                addr,
                "/api/session",
                Some("00000000000000000000000000000000"),
            )
            .unwrap(),
            401,
            "unknown participant token",
        ),
        (
            "finish with a foreign token",
            request(addr, "POST", "/api/finish", Some(&foreign), None).unwrap(),
            401,
            "unknown participant token",
        ),
        (
            "animation outside the study",
            get(addr, "/gif/settings.json", None).unwrap(),
            404,
            "no such animation",
        ),
        (
            "path outside render/",
            get(addr, "/gif/..%2Fkey.csv", None).unwrap(),
            404,
            "no such animation",
        ),
        (
            "key file",
            get(addr, "/key.csv", None).unwrap(),
            404,
            "no such page: /key.csv",
        ),
        (
            "admin page without token",
            get(addr, "/admin", None).unwrap(),
            401,
            "admin token required",
        ),
        (
            "admin counts with a participant token",
            get(addr, "/admin/counts", Some(&token)).unwrap(),
            401,
            "wrong admin token",
        ),
        (
            "admin export without token",
            get(addr, "/admin/export/responses.csv", None).unwrap(),
            401,
            "admin token required",
        ),
        (
            "admin export with a wrong query token",
            get(addr, "/admin/export/responses.csv?token=abc", None).unwrap(),
            401,
            "wrong admin token",
        ),
        (
            "admin export of an unknown file",
            get(addr, "/admin/export/key.csv", Some(ADMIN)).unwrap(),
            404,
            "no such export file",
        ),
    ];
    for (what, reply, status, message) in &cases {
        assert_eq!(reply.status, *status, "{what}: {}", reply.text());
        assert!(
            error_of(reply).contains(message),
            "{what}: `{}` lacks `{message}`",
            reply.text()
        );
    }
    let counts = get(addr, "/admin/counts", Some(ADMIN)).unwrap().json();
    assert_eq!(counts["answers"], 0, "nothing stored by bad requests");
    assert_eq!(counts["participants"], 1, "no session without consent");

    // A second answer to the same question is rejected and the first one stands.
    let first = answer(Some(&token), json!({"item": 3, "answer": "R", "ms": 500}));
    assert_eq!(first.status, 201);
    let second = answer(Some(&token), json!({"item": 3, "answer": "L", "ms": 600}));
    assert_eq!(second.status, 409);
    assert_eq!(
        error_of(&second),
        "question 3 was already answered (R); answers are final"
    );
    let view = get(addr, "/api/session", Some(&token)).unwrap().json();
    assert_eq!(view["answers"], json!([{"item": 3, "answer": "R"}]));
    let counts = get(addr, "/admin/counts", Some(ADMIN)).unwrap().json();
    assert_eq!(counts["answers"], 1);
    // The foreign server got nothing either.
    let counts = get(other.addr, "/admin/counts", Some(ADMIN))
        .unwrap()
        .json();
    assert_eq!(counts["answers"], 0);
}

#[test]
fn a_restart_resumes_the_database_and_another_study_is_refused() {
    let dir = tempfile::tempdir().unwrap();
    let run = dir.path().join("run");
    fixture::write_run(&run);
    let db = dir.path().join("s.sqlite");
    let server = start(&run, &db, 0, ADMIN);
    let token = new_session(server.addr)["token"]
        .as_str()
        .unwrap()
        .to_string();
    let r = post_json(
        server.addr,
        "/api/answer",
        Some(&token),
        &json!({"item": 1, "answer": "N"}),
    )
    .unwrap();
    assert_eq!(r.status, 201);
    server.stop().unwrap();

    let server = start(&run, &db, 0, ADMIN);
    let view = get(server.addr, "/api/session", Some(&token))
        .unwrap()
        .json();
    assert_eq!(view["answers"], json!([{"item": 1, "answer": "N"}]));
    server.stop().unwrap();

    let study = rmt_server::study::Study::from_run(
        &run,
        &rmt_server::study::StudyOptions {
            seed: 1,
            controls: 3,
        },
    )
    .unwrap();
    let err = Store::open(&db, &study).err().expect("another study");
    assert!(err.to_string().contains("another study"), "{err}");
}

#[test]
fn a_run_without_render_says_what_to_run() {
    let dir = tempfile::tempdir().unwrap();
    let run = dir.path();
    fixture::write_run(run);
    std::fs::remove_file(run.join("key.csv")).unwrap();
    let err = rmt_server::study::Study::from_run(run, &Default::default()).unwrap_err();
    assert!(err.to_string().contains("experiments render"), "{err}");
    fixture::write_run(run);
    let name = std::fs::read_dir(run.join("render"))
        .unwrap()
        .map(|e| e.unwrap().path())
        .find(|p| p.extension().is_some_and(|e| e == "gif"))
        .unwrap();
    std::fs::remove_file(&name).unwrap();
    let err = rmt_server::study::Study::from_run(run, &Default::default()).unwrap_err();
    assert!(err.to_string().contains(".gif is missing"), "{err}");
}
