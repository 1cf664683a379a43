//! The manifest parser and checks under mutated input (the proptest stand-in for a cargo-fuzz
//! target, which would have to build polars with the experiments crate): the bundled manifests
//! with numbers replaced by edge values (NaN, infinities, +-3e38, 1e309, huge integers,
//! negatives), lines dropped or duplicated, bytes flipped, and truncations. `manifest::parse`
//! and `Manifest::plan` either succeed or return an error; they never panic.
//!
//! Case counts scale with `RMT_CASES` (default 300).

use std::cell::Cell;
use std::path::{Path, PathBuf};

use experiments::manifest::{self, Overrides};
use proptest::prelude::*;
use proptest::test_runner::{FileFailurePersistence, TestRunner};

fn cases(default: u32) -> u32 {
    std::env::var("RMT_CASES")
        .ok()
        .and_then(|s| s.parse().ok())
        .unwrap_or(default)
}

fn manifests() -> Vec<(PathBuf, String)> {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("manifests");
    let mut out: Vec<(PathBuf, String)> = std::fs::read_dir(&dir)
        .expect("experiments/manifests")
        .filter_map(Result::ok)
        .map(|e| e.path())
        .filter(|p| p.extension().is_some_and(|e| e == "toml"))
        .map(|p| {
            let text = std::fs::read_to_string(&p).expect("manifest");
            (p, text)
        })
        .collect();
    out.sort();
    out
}

const EDGES: &[&str] = &[
    "nan",
    "inf",
    "-inf",
    "3e38",
    "-3e38",
    "1e309",
    "-1e309",
    "0",
    "-0",
    "-1",
    "1e-45",
    "18446744073709551616",
    "9223372036854775807",
    "-9223372036854775808",
    "4294967296",
    "1e9",
    "\"x\"",
    "[]",
    "{}",
    "true",
    "0.6",
    "100000",
];

#[derive(Clone, Debug)]
enum Mutation {
    /// Replace the k-th number in the text by an edge value.
    Number(usize, usize),
    /// Drop line k.
    Drop(usize),
    /// Duplicate line k.
    Duplicate(usize),
    /// Flip a bit of byte k.
    Flip(usize, u8),
    /// Cut the text at byte k.
    Truncate(usize),
}

fn mutation() -> impl Strategy<Value = Mutation> {
    prop_oneof![
        4 => (any::<usize>(), 0..EDGES.len()).prop_map(|(k, e)| Mutation::Number(k, e)),
        1 => any::<usize>().prop_map(Mutation::Drop),
        1 => any::<usize>().prop_map(Mutation::Duplicate),
        1 => (any::<usize>(), 0u8..8).prop_map(|(k, b)| Mutation::Flip(k, b)),
        1 => any::<usize>().prop_map(Mutation::Truncate),
    ]
}

fn apply(text: &str, m: &Mutation) -> String {
    match m {
        Mutation::Number(k, e) => {
            // Spans of digits (with sign, dot and exponent) in the text.
            let bytes = text.as_bytes();
            let mut spans = Vec::new();
            let mut i = 0;
            while i < bytes.len() {
                if bytes[i].is_ascii_digit() {
                    let start = i;
                    while i < bytes.len()
                        && (bytes[i].is_ascii_alphanumeric() || b".-+_".contains(&bytes[i]))
                    {
                        i += 1;
                    }
                    spans.push((start, i));
                } else {
                    i += 1;
                }
            }
            match spans.get(k % spans.len().max(1)) {
                Some(&(a, b)) => format!("{}{}{}", &text[..a], EDGES[*e], &text[b..]),
                None => text.to_string(),
            }
        }
        Mutation::Drop(k) | Mutation::Duplicate(k) => {
            let mut lines: Vec<&str> = text.lines().collect();
            if lines.is_empty() {
                return String::new();
            }
            let k = k % lines.len();
            if matches!(m, Mutation::Drop(_)) {
                lines.remove(k);
            } else {
                lines.insert(k, lines[k]);
            }
            lines.join("\n")
        }
        Mutation::Flip(k, bit) => {
            let mut bytes = text.as_bytes().to_vec();
            if !bytes.is_empty() {
                let k = k % bytes.len();
                bytes[k] ^= 1 << bit;
            }
            String::from_utf8_lossy(&bytes).into_owned()
        }
        Mutation::Truncate(k) => {
            let mut k = k % (text.len() + 1);
            while !text.is_char_boundary(k) {
                k -= 1;
            }
            text[..k].to_string()
        }
    }
}

#[test]
fn mutated_manifests_parse_and_plan_or_fail_cleanly() {
    let all = manifests();
    assert!(all.len() >= 5, "the bundled manifests");
    let config = ProptestConfig {
        cases: cases(300),
        failure_persistence: Some(Box::new(FileFailurePersistence::Off)),
        ..ProptestConfig::default()
    };
    let mut runner = TestRunner::new(config);
    let (parsed, planned) = (Cell::new(0usize), Cell::new(0usize));
    let result = runner.run(
        &(0..all.len(), prop::collection::vec(mutation(), 1..4)),
        |(which, mutations)| {
            let (path, text) = &all[which];
            let text = mutations.iter().fold(text.clone(), |t, m| apply(&t, m));
            if let Ok(m) = manifest::parse(&text, path) {
                parsed.set(parsed.get() + 1);
                let base = path.parent().unwrap_or(Path::new("."));
                if m.plan(path, base, &Overrides::default()).is_ok() {
                    planned.set(planned.get() + 1);
                }
            }
            Ok(())
        },
    );
    eprintln!(
        "manifest_fuzz: {} mutated manifests parsed, {} planned",
        parsed.get(),
        planned.get()
    );
    if let Err(e) = result {
        panic!("{e}");
    }
}
