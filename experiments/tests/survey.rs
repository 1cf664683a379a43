//! `experiments survey`: the real binary serves a run folder; the crash test kills it with
//! SIGKILL in the middle of a load and restarts it on the same database: every answer that was
//! acknowledged with 2xx is there, and `PRAGMA integrity_check` says ok. Then the participants
//! finish on the restarted server and `survey export` + `analyse` read the result.

#[path = "../../crates/server/tests/common/client.rs"]
mod client;
#[path = "../../crates/server/tests/common/fixture.rs"]
mod fixture;

use std::collections::BTreeMap;
use std::io::{BufRead, BufReader};
use std::net::SocketAddr;
use std::path::Path;
use std::process::{Child, Command, Stdio};
use std::sync::atomic::{AtomicUsize, Ordering};
use std::sync::{Arc, Mutex};

use serde_json::json;

const PARTICIPANTS: usize = 40;

fn experiments() -> Command {
    Command::new(env!("CARGO_BIN_EXE_experiments"))
}

/// Starts `survey serve` on a free loopback port and returns the child and its address.
fn serve(run: &Path, db: &Path) -> (Child, SocketAddr) {
    let mut child = experiments()
        .args(["survey", "serve"])
        .arg(run)
        .args(["--addr", "127.0.0.1:0", "--db"])
        .arg(db)
        .stdout(Stdio::piped())
        .stderr(Stdio::inherit())
        .spawn()
        .expect("spawn experiments survey serve");
    let stdout = child.stdout.take().unwrap();
    let mut lines = BufReader::new(stdout).lines();
    let addr = loop {
        let line = lines
            .next()
            .expect("server exited before listening")
            .unwrap();
        if let Some(rest) = line.strip_prefix("Listening on http://") {
            let addr = rest.split('/').next().unwrap();
            break addr.parse::<SocketAddr>().unwrap();
        }
    };
    // Keep draining stdout so the child never blocks on a full pipe.
    std::thread::spawn(move || for _ in lines {});
    (child, addr)
}

type Acked = Arc<Mutex<BTreeMap<String, BTreeMap<u64, String>>>>;

#[test]
fn sigkill_mid_load_loses_no_acknowledged_answer() {
    let dir = tempfile::tempdir().unwrap();
    let run = dir.path().join("run");
    fixture::write_run(&run);
    let db = dir.path().join("survey.sqlite");
    let (mut child, addr) = serve(&run, &db);

    // Participants answer concurrently; every 201 is recorded as acknowledged.
    let acked: Acked = Arc::default();
    let total_acks = Arc::new(AtomicUsize::new(0));
    let threads: Vec<_> = (0..PARTICIPANTS)
        .map(|p| {
            let acked = acked.clone();
            let total_acks = total_acks.clone();
            std::thread::spawn(move || {
                let Ok(r) =
                    client::post_json(addr, "/api/session", None, &json!({"consent": true}))
                else {
                    return;
                };
                if r.status != 201 {
                    return;
                }
                let token = r.json()["token"].as_str().unwrap().to_string();
                acked.lock().unwrap().insert(token.clone(), BTreeMap::new());
                for item in 1..=27u64 {
                    let answer = ["L", "N", "R"][(p + item as usize) % 3];
                    match client::post_json(
                        addr,
                        "/api/answer",
                        Some(&token),
                        &json!({"item": item, "answer": answer, "ms": 700}),
                    ) {
                        Ok(r) if r.status == 201 => {
                            acked
                                .lock()
                                .unwrap()
                                .get_mut(&token)
                                .unwrap()
                                .insert(item, answer.to_string());
                            total_acks.fetch_add(1, Ordering::SeqCst);
                        }
                        Ok(r) => panic!("unexpected {}: {}", r.status, r.text()),
                        Err(_) => return, // the server is gone
                    }
                }
            })
        })
        .collect();
    // Kill in the middle: after a third of all answers were acknowledged.
    let target = PARTICIPANTS * 27 / 3;
    let deadline = std::time::Instant::now() + std::time::Duration::from_secs(120);
    while total_acks.load(Ordering::SeqCst) < target && std::time::Instant::now() < deadline {
        std::thread::sleep(std::time::Duration::from_millis(2));
    }
    child.kill().expect("SIGKILL"); // Child::kill sends SIGKILL on Unix
    child.wait().unwrap();
    for t in threads {
        t.join().expect("participant thread");
    }
    let acked = Arc::try_unwrap(acked).unwrap().into_inner().unwrap();
    let n_acked: usize = acked.values().map(BTreeMap::len).sum();
    assert!(n_acked >= target, "only {n_acked} answers before the kill");
    assert!(
        n_acked < PARTICIPANTS * 27,
        "the kill came after the load ended"
    );

    // The database is sound, and holds every acknowledged answer.
    let store = rmt_server::store::Store::open_existing(&db).unwrap();
    assert_eq!(store.integrity_check().unwrap(), "ok");
    drop(store);
    let (mut child, addr) = serve(&run, &db);
    let mut stored_total = 0;
    for (token, answers) in &acked {
        let r = client::get(addr, "/api/session", Some(token)).unwrap();
        assert_eq!(r.status, 200, "{}", r.text());
        let view = r.json();
        let stored: BTreeMap<u64, String> = view["answers"]
            .as_array()
            .unwrap()
            .iter()
            .map(|a| {
                (
                    a["item"].as_u64().unwrap(),
                    a["answer"].as_str().unwrap().to_string(),
                )
            })
            .collect();
        for (item, answer) in answers {
            assert_eq!(
                stored.get(item),
                Some(answer),
                "acknowledged answer {item} of {token} lost"
            );
        }
        // At most the one answer in flight at the kill was stored without its acknowledgement.
        assert!(stored.len() <= answers.len() + 1);
        stored_total += stored.len();
        // Finish the session on the restarted server.
        for item in 1..=27u64 {
            if stored.contains_key(&item) {
                continue;
            }
            let r = client::post_json(
                addr,
                "/api/answer",
                Some(token),
                &json!({"item": item, "answer": "N", "ms": 800}),
            )
            .unwrap();
            assert_eq!(r.status, 201, "{}", r.text());
        }
        let r = client::request(addr, "POST", "/api/finish", Some(token), None).unwrap();
        assert_eq!(r.status, 200, "{}", r.text());
    }
    println!(
        "crash: {n_acked} answers acknowledged before SIGKILL, {stored_total} stored, all \
         acknowledged ones present"
    );
    child.kill().unwrap();
    child.wait().unwrap();

    // Export and analyse the survey.
    let out = dir.path().join("export");
    let status = experiments()
        .args(["survey", "export"])
        .arg(&db)
        .arg("--out")
        .arg(&out)
        .status()
        .unwrap();
    assert!(status.success());
    let responses = std::fs::read_to_string(out.join("responses.csv")).unwrap();
    assert_eq!(responses.lines().count(), 1 + acked.len() * 27);
    let analysis = dir.path().join("analysis");
    let output = experiments()
        .arg("analyse")
        .arg("--responses")
        .arg(&db)
        .arg("--out")
        .arg(&analysis)
        .args(["--resamples", "0"])
        .output()
        .unwrap();
    assert!(
        output.status.success(),
        "{}",
        String::from_utf8_lossy(&output.stderr)
    );
    assert!(analysis.join("summary.csv").exists());
}

#[test]
fn serve_names_what_is_missing() {
    let dir = tempfile::tempdir().unwrap();
    let output = experiments()
        .args(["survey", "serve"])
        .arg(dir.path())
        .args(["--addr", "127.0.0.1:0"])
        .output()
        .unwrap();
    assert!(!output.status.success());
    let err = String::from_utf8_lossy(&output.stderr);
    assert!(err.contains("configurations.csv"), "{err}");
    let output = experiments()
        .args(["survey", "export"])
        .arg(dir.path().join("none.sqlite"))
        .output()
        .unwrap();
    assert!(!output.status.success());
    let err = String::from_utf8_lossy(&output.stderr);
    assert!(
        err.contains("none.sqlite") && err.contains("no such file"),
        "{err}"
    );
}
