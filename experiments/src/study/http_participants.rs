//! Simulated participants who answer through the survey server's HTTP API, as browsers do:
//! `POST /api/session` (consent), one `POST /api/answer` per item in the order the session
//! lists them (the screen side clicked and the time taken), `POST /api/finish`. What they see
//! is only the anonymous names of the two animations; they answer from the planted model by
//! looking the names up in the run's `key.csv` and `study_key.csv` (which participants never
//! see), with the left-side bias and the fatigue drift of [`PlantedModel`] applied to the
//! screen sides and positions the server chose.

use std::collections::BTreeMap;
use std::io::{Read, Write};
use std::net::{SocketAddr, TcpStream};
use std::path::Path;
use std::time::Duration;

use anyhow::{bail, Context, Result};
use rmt_analysis::bradley_terry_position::probabilities;
use rmt_analysis::stats::SplitMix64;
use rmt_analysis::study::simulate::{draw, uniform, PlantedModel};
use rmt_analysis::study::StudyItems;
use serde_json::{json, Value};

/// One HTTP/1.1 request with `Connection: close`; returns the status and the body.
fn request(
    addr: SocketAddr,
    method: &str,
    path: &str,
    token: Option<&str>,
    body: Option<&Value>,
) -> Result<(u16, Vec<u8>)> {
    let mut stream = TcpStream::connect_timeout(&addr, Duration::from_secs(10))
        .with_context(|| format!("connecting to {addr}"))?;
    stream.set_read_timeout(Some(Duration::from_secs(60)))?;
    let body = body.map(|v| v.to_string()).unwrap_or_default();
    let mut head = format!("{method} {path} HTTP/1.1\r\nHost: {addr}\r\nConnection: close\r\n");
    if let Some(t) = token {
        head.push_str(&format!("Authorization: Bearer {t}\r\n"));
    }
    if method != "GET" {
        head.push_str(&format!(
            "Content-Type: application/json\r\nContent-Length: {}\r\n",
            body.len()
        ));
    }
    head.push_str("\r\n");
    stream.write_all(head.as_bytes())?;
    stream.write_all(body.as_bytes())?;
    let mut raw = Vec::new();
    stream.read_to_end(&mut raw)?;
    let split = raw
        .windows(4)
        .position(|w| w == b"\r\n\r\n")
        .context("a reply without a head")?;
    let head = String::from_utf8_lossy(&raw[..split]).to_ascii_lowercase();
    let status: u16 = head
        .split_whitespace()
        .nth(1)
        .and_then(|s| s.parse().ok())
        .context("a reply without a status")?;
    let mut payload = raw[split + 4..].to_vec();
    if head.contains("transfer-encoding: chunked") {
        let mut out = Vec::new();
        let mut rest = &payload[..];
        loop {
            let line_end = rest
                .windows(2)
                .position(|w| w == b"\r\n")
                .context("a broken chunk")?;
            let size = usize::from_str_radix(String::from_utf8_lossy(&rest[..line_end]).trim(), 16)
                .context("a broken chunk size")?;
            if size == 0 {
                break;
            }
            let start = line_end + 2;
            out.extend_from_slice(rest.get(start..start + size).context("a short chunk")?);
            rest = rest.get(start + size + 2..).unwrap_or(&[]);
        }
        payload = out;
    }
    Ok((status, payload))
}

fn json_of(status: u16, body: &[u8], what: &str) -> Result<Value> {
    if !(200..300).contains(&status) {
        bail!("{what}: HTTP {status}: {}", String::from_utf8_lossy(body));
    }
    serde_json::from_slice(body).with_context(|| format!("{what}: not JSON"))
}

/// Reads `key.csv` (name -> id) and `study_key.csv` (id -> object, method, shading) of a run
/// folder: each anonymous name's study configuration.
pub fn names_to_items(run: &Path, items: &StudyItems) -> Result<BTreeMap<String, usize>> {
    let read = |file: &str| -> Result<Vec<BTreeMap<String, String>>> {
        let path = run.join(file);
        let mut reader =
            csv::Reader::from_path(&path).with_context(|| format!("reading {}", path.display()))?;
        let header = reader.headers()?.clone();
        reader
            .records()
            .map(|r| {
                let r = r.with_context(|| format!("reading {}", path.display()))?;
                Ok(header
                    .iter()
                    .zip(r.iter())
                    .map(|(h, v)| (h.to_string(), v.to_string()))
                    .collect())
            })
            .collect()
    };
    let mut item_of_id = BTreeMap::new();
    for row in read("study_key.csv")? {
        let find = |list: &[String], key: &str| {
            list.iter()
                .position(|x| Some(x) == row.get(key))
                .with_context(|| {
                    format!("study_key.csv: {key} {:?} is not the study's", row.get(key))
                })
        };
        let item = items.item(
            find(&items.objects, "object")?,
            find(&items.methods, "method")?,
            find(&items.shadings, "shading")?,
        );
        item_of_id.insert(row.get("id").cloned().unwrap_or_default(), item);
    }
    let mut out = BTreeMap::new();
    for row in read("key.csv")? {
        let (Some(name), Some(id)) = (row.get("name"), row.get("id")) else {
            bail!("key.csv: no name or id column");
        };
        if let Some(&item) = item_of_id.get(id) {
            out.insert(name.clone(), item);
        }
    }
    Ok(out)
}

/// `participants` simulated participants answer the survey served at `addr` from `model`
/// (seeded); returns the answers sent.
pub fn answer_over_http(
    addr: SocketAddr,
    names: &BTreeMap<String, usize>,
    model: &PlantedModel,
    participants: usize,
    seed: u64,
) -> Result<usize> {
    let mut rng = SplitMix64::new(seed ^ 0x4854_5450);
    let a = model.left_bias.ln();
    let mut sent = 0;
    for p in 0..participants {
        let (status, body) = request(
            addr,
            "POST",
            "/api/session",
            None,
            Some(&json!({"consent": true})),
        )?;
        let session = json_of(status, &body, "starting a session")?;
        let token = session["token"]
            .as_str()
            .context("the session has no token")?
            .to_string();
        let list = session["items"]
            .as_array()
            .context("the session has no items")?;
        let last = list.len().saturating_sub(1).max(1) as f64;
        for (k, it) in list.iter().enumerate() {
            let side = |s: &str| -> Result<usize> {
                let name = it[s].as_str().context("an item without names")?;
                names
                    .get(name)
                    .copied()
                    .with_context(|| format!("animation `{name}` is in no study configuration"))
            };
            let (left, right) = (side("left")?, side("right")?);
            let probs = probabilities(
                model.log_strengths[left],
                model.log_strengths[right],
                a,
                model.tie_log(k as f64 / last),
            );
            let answer = draw(probs, &mut rng).code();
            let ms = (4000.0 + 8000.0 * uniform(&mut rng)).round() as u64;
            let item = it["item"].as_u64().context("an item without a number")?;
            let (status, body) = request(
                addr,
                "POST",
                "/api/answer",
                Some(&token),
                Some(&json!({"item": item, "answer": answer, "ms": ms})),
            )?;
            if status != 201 {
                bail!(
                    "participant {}: answer {item}: HTTP {status}: {}",
                    p + 1,
                    String::from_utf8_lossy(&body)
                );
            }
            sent += 1;
        }
        let (status, body) = request(addr, "POST", "/api/finish", Some(&token), None)?;
        if !(200..300).contains(&status) {
            bail!(
                "participant {}: finishing: HTTP {status}: {}",
                p + 1,
                String::from_utf8_lossy(&body)
            );
        }
    }
    Ok(sent)
}
