//! Load: 200 simulated participants answer all 27 questions concurrently over loopback HTTP
//! (at most 48 requests in flight). Afterwards there are exactly 200 x 27 answers: none lost,
//! none duplicated. Prints the throughput (a benchmark figure, not asserted).
//!
//! `cargo test --release -p rmt-server --test load -- --nocapture`

mod common;

use std::collections::BTreeSet;
use std::sync::{Arc, Condvar, Mutex};
use std::time::Instant;

use common::client::{get, post_json, request};
use common::{fixture, new_session, start};
use serde_json::json;

const PARTICIPANTS: usize = 200;
const IN_FLIGHT: usize = 48;
const ADMIN: &str = "0123456789abcdef0123456789abcdef";

/// A counting semaphore bounding the requests in flight.
struct Slots {
    free: Mutex<usize>,
    cv: Condvar,
}

impl Slots {
    fn with<T>(&self, f: impl FnOnce() -> T) -> T {
        let mut free = self.free.lock().unwrap();
        while *free == 0 {
            free = self.cv.wait(free).unwrap();
        }
        *free -= 1;
        drop(free);
        let out = f();
        *self.free.lock().unwrap() += 1;
        self.cv.notify_one();
        out
    }
}

#[test]
fn two_hundred_participants_answer_everything_concurrently() {
    let dir = tempfile::tempdir().unwrap();
    let run = dir.path().join("run");
    fixture::write_run(&run);
    let db = dir.path().join("load.sqlite");
    let server = start(&run, &db, 0, ADMIN);
    let addr = server.addr;
    let slots = Arc::new(Slots {
        free: Mutex::new(IN_FLIGHT),
        cv: Condvar::new(),
    });
    let started = Instant::now();
    let threads: Vec<_> = (0..PARTICIPANTS)
        .map(|p| {
            let slots = slots.clone();
            std::thread::Builder::new()
                .stack_size(256 * 1024)
                .spawn(move || {
                    let session = slots.with(|| new_session(addr));
                    let token = session["token"].as_str().unwrap().to_string();
                    let total = session["total"].as_u64().unwrap();
                    for item in 1..=total {
                        let answer = ["L", "N", "R"][(p + item as usize) % 3];
                        let r = slots
                            .with(|| {
                                post_json(
                                    addr,
                                    "/api/answer",
                                    Some(&token),
                                    &json!({"item": item, "answer": answer, "ms": 1500}),
                                )
                            })
                            .unwrap();
                        assert_eq!(r.status, 201, "{}", r.text());
                    }
                    let r = slots
                        .with(|| request(addr, "POST", "/api/finish", Some(&token), None))
                        .unwrap();
                    assert_eq!(r.status, 200, "{}", r.text());
                    (token, total)
                })
                .unwrap()
        })
        .collect();
    let mut tokens = BTreeSet::new();
    for t in threads {
        let (token, total) = t.join().expect("participant thread");
        assert_eq!(total, 27);
        tokens.insert(token);
    }
    let elapsed = started.elapsed().as_secs_f64();
    assert_eq!(tokens.len(), PARTICIPANTS, "every token distinct");
    let answers = PARTICIPANTS * 27;
    println!(
        "load: {PARTICIPANTS} participants x 27 answers = {answers} answers in {elapsed:.2} s: \
         {:.0} answers/s ({:.0} requests/s incl. sessions and finishes; {IN_FLIGHT} in flight)",
        answers as f64 / elapsed,
        (answers + 2 * PARTICIPANTS) as f64 / elapsed
    );

    let counts = get(addr, "/admin/counts", Some(ADMIN)).unwrap().json();
    assert_eq!(counts["participants"], PARTICIPANTS);
    assert_eq!(counts["finished"], PARTICIPANTS);
    assert_eq!(counts["answers"], answers);
    for q in counts["per_question"].as_array().unwrap() {
        assert_eq!(q[1], PARTICIPANTS, "{q}");
    }
    let responses = get(addr, "/admin/export/responses.csv", Some(ADMIN))
        .unwrap()
        .text();
    let rows: Vec<&str> = responses.lines().skip(1).collect();
    assert_eq!(rows.len(), answers);
    let distinct: BTreeSet<(&str, &str)> = rows
        .iter()
        .map(|l| {
            let mut f = l.split(',');
            (f.next().unwrap(), f.next().unwrap())
        })
        .collect();
    assert_eq!(distinct.len(), answers, "no (participant, question) twice");

    // Swaps are balanced: every question shown swapped to exactly half of the participants.
    let mut swapped = std::collections::BTreeMap::<&str, usize>::new();
    for l in &rows {
        let f: Vec<&str> = l.split(',').collect();
        *swapped.entry(f[1]).or_default() += usize::from(f[4] == "1");
    }
    assert!(
        swapped.values().all(|&n| n == PARTICIPANTS / 2),
        "{swapped:?}"
    );
    server.stop().unwrap();
    let store = rmt_server::store::Store::open_existing(&db).unwrap();
    assert_eq!(store.integrity_check().unwrap(), "ok");
}
