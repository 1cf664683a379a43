//! Shared test helpers: a raw HTTP client, a run-folder fixture, and a survey server started in
//! this process on a loopback port.

#![allow(dead_code)]

pub mod client;
pub mod fixture;

use std::path::Path;

use rmt_server::http::Running;
use rmt_server::store::Store;
use rmt_server::study::{Study, StudyOptions};
use rmt_server::survey::{router, Survey};

/// A server on 127.0.0.1 (free port) over the run folder and database, with this admin token.
pub fn start(run: &Path, db: &Path, controls: usize, admin: &str) -> Running {
    let study = Study::from_run(run, &StudyOptions { seed: 1, controls }).expect("study");
    let store = Store::open(db, &study).expect("store");
    let survey = Survey::new(store, run.join("render"), admin.to_string());
    rmt_server::http::spawn(router(survey), "127.0.0.1:0".parse().unwrap()).expect("server")
}

/// Starts a session (with consent) and returns its view.
pub fn new_session(addr: std::net::SocketAddr) -> serde_json::Value {
    let r = client::post_json(
        addr,
        "/api/session",
        None,
        &serde_json::json!({"consent": true}),
    )
    .expect("request");
    assert_eq!(r.status, 201, "{}", r.text());
    r.json()
}
