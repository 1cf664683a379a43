//! File helpers of the runner: new run folders, JSON written atomically, rows appended and
//! synced. The atomic write itself is the workspace's one ([`rmt_runfolder::write_atomic`]).

use std::fs::OpenOptions;
use std::io::Write;
use std::path::{Path, PathBuf};

use anyhow::{bail, Context, Result};
use rmt_runfolder::write_atomic;
use serde::Serialize;

use crate::provenance;

/// A new folder `<parent>/<name>-<UTC stamp>` (with `-2`, `-3`, ... if taken).
pub(crate) fn new_folder(parent: &Path, name: &str) -> Result<PathBuf> {
    let base = format!("{name}-{}", provenance::stamp(provenance::unix_now()));
    for n in 1..1000 {
        let candidate = if n == 1 {
            parent.join(&base)
        } else {
            parent.join(format!("{base}-{n}"))
        };
        if !candidate.exists() {
            return Ok(candidate);
        }
    }
    bail!("no free run folder name under {}", parent.display())
}

/// `p` made absolute and canonical when it exists, else as given.
pub(crate) fn absolute(p: &Path) -> PathBuf {
    p.canonicalize().unwrap_or_else(|_| p.to_path_buf())
}

/// Writes `value` as pretty JSON with a final newline, atomically.
pub(crate) fn write_json<T: Serialize>(path: &Path, value: &T) -> Result<()> {
    let mut bytes = serde_json::to_vec_pretty(value)?;
    bytes.push(b'\n');
    Ok(write_atomic(path, &bytes)?)
}

/// Appends `bytes` to `path` in one write and syncs it; returns the new length.
pub(crate) fn append_synced(path: &Path, bytes: &[u8]) -> Result<u64> {
    let mut f = OpenOptions::new()
        .append(true)
        .open(path)
        .with_context(|| format!("opening {}", path.display()))?;
    f.write_all(bytes)
        .with_context(|| format!("appending to {}", path.display()))?;
    f.sync_data()
        .with_context(|| format!("syncing {}", path.display()))?;
    Ok(f.metadata()
        .with_context(|| format!("reading {}", path.display()))?
        .len())
}

/// Cuts `path` back to `len` bytes and syncs it.
pub(crate) fn truncate_synced(path: &Path, len: u64) -> Result<()> {
    let file = OpenOptions::new()
        .write(true)
        .open(path)
        .with_context(|| format!("opening {}", path.display()))?;
    file.set_len(len)
        .with_context(|| format!("truncating {}", path.display()))?;
    file.sync_all()
        .with_context(|| format!("syncing {}", path.display()))
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::fs;

    #[test]
    fn appends_are_synced_and_truncation_cuts_them_back() {
        let dir = tempfile::tempdir().unwrap();
        let p = dir.path().join("raw.csv");
        write_atomic(&p, b"header\n").unwrap();
        assert_eq!(append_synced(&p, b"row 1\n").unwrap(), 13);
        assert_eq!(append_synced(&p, b"torn").unwrap(), 17);
        truncate_synced(&p, 13).unwrap();
        assert_eq!(fs::read(&p).unwrap(), b"header\nrow 1\n");
    }

    #[test]
    fn json_ends_with_a_newline() {
        let dir = tempfile::tempdir().unwrap();
        let p = dir.path().join("a.json");
        write_json(&p, &serde_json::json!({"a": 1})).unwrap();
        assert_eq!(fs::read_to_string(&p).unwrap(), "{\n  \"a\": 1\n}\n");
    }
}
