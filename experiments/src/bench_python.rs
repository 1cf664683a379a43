//! The Python peers of `experiments bench`: VTK's Flying Edges and scikit-image's
//! `marching_cubes`, timed by `scripts/peer_bench.py` on the very values our methods read, in the
//! same run.
//!
//! ```text
//!   bench (Rust)                           DIR (--dump, or a temporary folder)
//!   sample FIELD at n^3  --dump_values-->  FIELD_N.f32   (n+1)^3 little-endian f32, x fastest
//!                                          FIELD_N.json  header, format "rmt-values-1"
//!                                          peer_bench.py the script, as compiled into the binary
//!   our first half of the repetitions
//!   PY peer_bench.py DIR --only FIELD_N  --> CSV rows: field,n,method,threads,median_ms,...
//!   our second half of the repetitions
//! ```
//!
//! Rules:
//! - the values are the corner grid of the simple cubic lattice, sampled densely: exactly what
//!   our marching cubes, fast-surface-nets and isomesh read;
//! - the script is the one compiled into this binary (`include_str!`), written into DIR beside
//!   the values, so a dump folder records what timed it and the binary needs no checkout;
//! - our repetitions are split in two halves around the peers' run of the same field and size,
//!   so a drift of the machine's load reaches both sides alike;
//! - a row from the script is checked (known method, the field and size asked for, numbers
//!   finite and positive) before it enters the results; anything else is an error naming the row.

use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};

use rmt_extract::Samples;

/// The script, as it is in this checkout's `scripts/peer_bench.py`.
pub const PEER_BENCH_PY: &str = include_str!("../../scripts/peer_bench.py");

/// The values format written by [`dump_values`] and read by the script.
pub const VALUES_FORMAT: &str = "rmt-values-1";

/// Why the Python peers could not be timed.
#[derive(Debug, thiserror::Error)]
pub enum PythonPeerError {
    /// Writing the dump folder failed.
    #[error("writing {path}: {source}")]
    Write {
        /// The file or folder.
        path: PathBuf,
        /// The I/O error.
        source: std::io::Error,
    },
    /// The samples are not a corner grid of `(n + 1)^3` values.
    #[error("{name}: the samples hold {len} values, not a corner grid of {dims:?}")]
    NotAGrid {
        /// The volume's name.
        name: String,
        /// Stored values.
        len: usize,
        /// Points per axis.
        dims: [usize; 3],
    },
    /// The interpreter could not be started.
    #[error("starting {python} {script}: {source} (is --python the path of a Python 3 with numpy, vtk and scikit-image?)")]
    Spawn {
        /// The interpreter asked for.
        python: String,
        /// The script path.
        script: PathBuf,
        /// The I/O error.
        source: std::io::Error,
    },
    /// The script exited with an error.
    #[error("{python} peer_bench.py on {name} failed ({status}); its stderr: {stderr}")]
    Failed {
        /// The interpreter.
        python: String,
        /// The volume's name.
        name: String,
        /// The exit status.
        status: String,
        /// The last lines of its standard error.
        stderr: String,
    },
    /// A row of the script's output that cannot be used.
    #[error("peer_bench.py row {row:?}: {message}")]
    BadRow {
        /// The row as printed.
        row: String,
        /// What is wrong with it.
        message: String,
    },
}

/// The peers the script times, by the names it prints.
pub const PYTHON_PEERS: [&str; 2] = ["vtk_flying_edges", "skimage_mc"];

/// One peer's timing of one volume, from the script.
#[derive(Clone, Debug, PartialEq)]
pub struct PeerTiming {
    /// The peer's name, one of [`PYTHON_PEERS`].
    pub method: &'static str,
    /// Median seconds of one call.
    pub median_s: f64,
    /// Fastest call, seconds.
    pub min_s: f64,
    /// Timed repetitions.
    pub reps: usize,
    /// Output triangles.
    pub triangles: usize,
}

/// The name of the volume of `field` at `n` cells (`sphere_64`): the stem of its two files.
pub fn volume_name(field: &str, n: usize) -> String {
    format!("{field}_{n}")
}

/// Writes `DIR/NAME.f32` and `DIR/NAME.json` ([`VALUES_FORMAT`]) for the corner grid `samples`
/// of `field` at `n` cells, and `DIR/peer_bench.py`; returns the volume's name.
pub fn dump_values(
    dir: &Path,
    field: &str,
    n: usize,
    samples: &Samples,
) -> Result<String, PythonPeerError> {
    let name = volume_name(field, n);
    let dims = samples.dims;
    if samples.values.len() != dims[0] * dims[1] * dims[2] {
        return Err(PythonPeerError::NotAGrid {
            name,
            len: samples.values.len(),
            dims,
        });
    }
    let write = |path: PathBuf, bytes: &[u8]| {
        std::fs::write(&path, bytes).map_err(|source| PythonPeerError::Write { path, source })
    };
    std::fs::create_dir_all(dir).map_err(|source| PythonPeerError::Write {
        path: dir.to_path_buf(),
        source,
    })?;
    let mut bytes = Vec::with_capacity(4 * samples.values.len());
    for v in &samples.values {
        bytes.extend_from_slice(&v.to_le_bytes());
    }
    let values = format!("{name}.f32");
    write(dir.join(&values), &bytes)?;
    let header = serde_json::json!({
        "format": VALUES_FORMAT,
        "field": field,
        "cells": n,
        "dims": dims,
        "origin": samples.min.to_array(),
        "spacing": samples.spacing.to_array(),
        "level": 0.0,
        "values": values,
    });
    write(
        dir.join(format!("{name}.json")),
        format!("{header:#}\n").as_bytes(),
    )?;
    write(dir.join("peer_bench.py"), PEER_BENCH_PY.as_bytes())?;
    Ok(name)
}

/// Runs `python DIR/peer_bench.py DIR --only NAME --reps REPS` on a volume written by
/// [`dump_values`] and returns one timing per peer, checked against `field` and `n`.
pub fn time_peers(
    python: &str,
    dir: &Path,
    field: &str,
    n: usize,
    reps: usize,
) -> Result<Vec<PeerTiming>, PythonPeerError> {
    let name = volume_name(field, n);
    let script = dir.join("peer_bench.py");
    let out = Command::new(python)
        .arg(&script)
        .arg(dir)
        .args(["--only", &name, "--reps", &reps.to_string()])
        .stdin(Stdio::null())
        .output()
        .map_err(|source| PythonPeerError::Spawn {
            python: python.to_string(),
            script: script.clone(),
            source,
        })?;
    if !out.status.success() {
        let text = String::from_utf8_lossy(&out.stderr);
        let lines: Vec<&str> = text.lines().collect();
        return Err(PythonPeerError::Failed {
            python: python.to_string(),
            name,
            status: out.status.to_string(),
            stderr: lines[lines.len().saturating_sub(5)..].join("\n"),
        });
    }
    let text = String::from_utf8_lossy(&out.stdout);
    parse_rows(&text, field, n)
}

/// The script's CSV (header row first) as timings of `field` at `n`; every peer of
/// [`PYTHON_PEERS`] must appear exactly once.
pub fn parse_rows(text: &str, field: &str, n: usize) -> Result<Vec<PeerTiming>, PythonPeerError> {
    let mut lines = text.lines().filter(|l| !l.trim().is_empty());
    let header = lines.next().unwrap_or_default();
    if header.trim() != "field,n,method,threads,median_ms,min_ms,reps,triangles" {
        return Err(PythonPeerError::BadRow {
            row: header.to_string(),
            message: "expected the header field,n,method,threads,median_ms,min_ms,reps,triangles"
                .into(),
        });
    }
    let mut out: Vec<PeerTiming> = Vec::new();
    for line in lines {
        let bad = |message: String| PythonPeerError::BadRow {
            row: line.to_string(),
            message,
        };
        let c: Vec<&str> = line.split(',').map(str::trim).collect();
        if c.len() != 8 {
            return Err(bad(format!("{} columns, expected 8", c.len())));
        }
        let method = PYTHON_PEERS
            .into_iter()
            .find(|m| *m == c[2])
            .ok_or_else(|| bad(format!("unknown method, expected one of {PYTHON_PEERS:?}")))?;
        if c[0] != field || c[1] != n.to_string() {
            return Err(bad(format!("expected field {field} at n = {n}")));
        }
        let ms = |s: &str| -> Result<f64, PythonPeerError> {
            match s.parse::<f64>() {
                Ok(v) if v.is_finite() && v > 0.0 => Ok(v / 1e3),
                _ => Err(bad(format!("{s:?} is not a positive time in ms"))),
            }
        };
        let count = |s: &str| s.parse::<usize>().map_err(|e| bad(format!("{s:?}: {e}")));
        let timing = PeerTiming {
            method,
            median_s: ms(c[4])?,
            min_s: ms(c[5])?,
            reps: count(c[6])?,
            triangles: count(c[7])?,
        };
        if out.iter().any(|t| t.method == method) {
            return Err(bad("a second row for this method".into()));
        }
        out.push(timing);
    }
    if let Some(missing) = PYTHON_PEERS
        .into_iter()
        .find(|m| !out.iter().any(|t| t.method == *m))
    {
        return Err(PythonPeerError::BadRow {
            row: String::new(),
            message: format!("no row for {missing}"),
        });
    }
    out.sort_by_key(|t| PYTHON_PEERS.iter().position(|m| *m == t.method));
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;

    const GOOD: &str = "field,n,method,threads,median_ms,min_ms,reps,triangles\n\
                        sphere,16,skimage_mc,1,2.000,1.500,3,900\n\
                        sphere,16,vtk_flying_edges,1,0.500,0.400,3,900\n";

    #[test]
    fn rows_parse_into_seconds_in_peer_order() {
        let t = parse_rows(GOOD, "sphere", 16).unwrap();
        assert_eq!(t.len(), 2);
        assert_eq!(t[0].method, "vtk_flying_edges");
        assert!((t[0].median_s - 0.0005).abs() < 1e-12);
        assert_eq!(
            (t[1].method, t[1].reps, t[1].triangles),
            ("skimage_mc", 3, 900)
        );
    }

    #[test]
    fn bad_rows_are_named() {
        let cases = [
            (GOOD.replace("skimage_mc", "pymcubes"), "unknown method"),
            (GOOD.replace("2.000", "nan"), "positive time"),
            (GOOD.replace("0.500", "-1"), "positive time"),
            (GOOD.replace(",900\nsphere", ",x\nsphere"), "\"x\""),
            (
                GOOD.replace("sphere,16,vtk", "asteroid,16,vtk"),
                "expected field",
            ),
            (GOOD.replace(",3,900\n", ",3\n"), "columns"),
            (
                GOOD.lines().take(2).collect::<Vec<_>>().join("\n"),
                "no row for vtk_flying_edges",
            ),
            (GOOD.replace("field,n", "f,n"), "header"),
            (
                format!("{GOOD}sphere,16,skimage_mc,1,2,1,3,900\n"),
                "second row",
            ),
        ];
        for (text, needle) in cases {
            let err = parse_rows(&text, "sphere", 16).unwrap_err().to_string();
            assert!(err.contains(needle), "{needle}: {err}");
        }
    }

    #[test]
    fn a_dump_is_the_grid_its_header_describes() {
        let dir = tempfile::tempdir().unwrap();
        let mut samples = Samples {
            dims: [3, 2, 2],
            values: (0..12).map(|i| i as f32 - 5.5).collect::<Vec<f32>>().into(),
            ..Samples::default()
        };
        let name = dump_values(dir.path(), "sphere", 2, &samples).unwrap();
        assert_eq!(name, "sphere_2");
        let header: serde_json::Value = serde_json::from_str(
            &std::fs::read_to_string(dir.path().join("sphere_2.json")).unwrap(),
        )
        .unwrap();
        assert_eq!(header["format"], VALUES_FORMAT);
        assert_eq!(header["dims"], serde_json::json!([3, 2, 2]));
        let bytes = std::fs::read(dir.path().join("sphere_2.f32")).unwrap();
        let back: Vec<f32> = bytes
            .chunks_exact(4)
            .map(|b| f32::from_le_bytes([b[0], b[1], b[2], b[3]]))
            .collect();
        assert_eq!(back[..], samples.values[..]);
        let script = std::fs::read_to_string(dir.path().join("peer_bench.py")).unwrap();
        assert_eq!(script, PEER_BENCH_PY);
        // A sample array that is not a grid is refused, not written.
        samples.values = back[..11].to_vec().into();
        let err = dump_values(dir.path(), "asteroid", 2, &samples).unwrap_err();
        assert!(err.to_string().contains("not a corner grid"), "{err}");
        assert!(!dir.path().join("asteroid_2.json").exists());
    }

    #[test]
    fn a_missing_interpreter_is_a_clear_error() {
        let dir = tempfile::tempdir().unwrap();
        let err = time_peers("/nonexistent/python3", dir.path(), "sphere", 16, 1)
            .unwrap_err()
            .to_string();
        assert!(
            err.contains("/nonexistent/python3") && err.contains("--python"),
            "{err}"
        );
    }
}
