//! The survey's request bodies: the first byte picks a route (`POST /api/session`,
//! `/api/answer`, `/api/finish`) and whether to send a valid participant token, the rest is the
//! body, sent through the survey's router in process. Never a 5xx, every 4xx is JSON with a
//! message.
#![no_main]

#[path = "../../crates/server/tests/common/fixture.rs"]
mod fixture;

use std::sync::OnceLock;

use axum::body::Body;
use axum::http::{header, Request};
use axum::Router;
use libfuzzer_sys::fuzz_target;
use tower::ServiceExt;

struct Setup {
    _dir: tempfile::TempDir,
    runtime: tokio::runtime::Runtime,
    router: Router,
    token: String,
}

fn setup() -> &'static Setup {
    static SETUP: OnceLock<Setup> = OnceLock::new();
    SETUP.get_or_init(|| {
        let dir = tempfile::tempdir_in("/dev/shm")
            .or_else(|_| tempfile::tempdir())
            .expect("a temporary folder");
        let run = dir.path().join("run");
        fixture::write_run(&run);
        let study = rmt_server::study::Study::from_run(
            &run,
            &rmt_server::study::StudyOptions {
                seed: 1,
                controls: 1,
            },
        )
        .expect("study");
        let store = rmt_server::store::Store::open(&dir.path().join("db.sqlite"), &study)
            .expect("store");
        let survey = rmt_server::survey::Survey::new(store, run.join("render"), "f".repeat(32));
        let router = rmt_server::survey::router(survey);
        let runtime = tokio::runtime::Builder::new_current_thread()
            .build()
            .expect("runtime");
        let token = {
            let r = runtime.block_on(send(&router, "/api/session", None, b"{\"consent\": true}"));
            let (_, body) = r;
            let v: serde_json::Value = serde_json::from_slice(&body).expect("session JSON");
            v["token"].as_str().expect("token").to_string()
        };
        Setup {
            _dir: dir,
            runtime,
            router,
            token,
        }
    })
}

async fn send(router: &Router, path: &str, token: Option<&str>, body: &[u8]) -> (u16, Vec<u8>) {
    let mut request = Request::post(path).header(header::CONTENT_TYPE, "application/json");
    if let Some(t) = token {
        request = request.header(header::AUTHORIZATION, format!("Bearer {t}"));
    }
    let request = request
        .body(Body::from(body.to_vec()))
        .expect("a request");
    let response = router.clone().oneshot(request).await.expect("infallible");
    let status = response.status().as_u16();
    let bytes = axum::body::to_bytes(response.into_body(), usize::MAX)
        .await
        .expect("the body");
    (status, bytes.to_vec())
}

fuzz_target!(|data: &[u8]| {
    let Some((&selector, body)) = data.split_first() else {
        return;
    };
    let s = setup();
    let path = ["/api/session", "/api/answer", "/api/finish"][usize::from(selector % 3)];
    let token = (selector & 4 != 0).then_some(s.token.as_str());
    let (status, reply) = s.runtime.block_on(send(&s.router, path, token, body));
    assert!(status < 500, "{path}: {status} {}", String::from_utf8_lossy(&reply));
    if status >= 400 {
        let v: serde_json::Value = serde_json::from_slice(&reply).expect("a JSON error");
        assert!(v["error"].as_str().is_some_and(|m| !m.is_empty()));
    }
});
