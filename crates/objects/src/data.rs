//! Finding data files (meshes) named by relative paths.

use std::path::{Path, PathBuf};

use crate::kind::ObjectError;

/// The workspace root as seen at build time (two folders above this package,
/// `crates/objects`).
pub fn workspace_root() -> PathBuf {
    let here = Path::new(env!("CARGO_MANIFEST_DIR"));
    here.ancestors()
        .nth(2)
        .map(Path::to_path_buf)
        .unwrap_or_else(|| here.to_path_buf())
}

/// Finds a data file: `path` itself when absolute; else the first existing of the current folder,
/// each folder of `search` and their ancestors, and the workspace root.
pub fn resolve_data_path(path: &Path, search: &[PathBuf]) -> Result<PathBuf, ObjectError> {
    if path.is_absolute() {
        return if path.is_file() {
            Ok(path.to_path_buf())
        } else {
            Err(ObjectError::MissingMesh {
                path: path.to_path_buf(),
                tried: vec![path.into()],
            })
        };
    }
    let mut tried = vec![path.to_path_buf()];
    for folder in search {
        for ancestor in folder.ancestors() {
            if !ancestor.as_os_str().is_empty() {
                tried.push(ancestor.join(path));
            }
        }
    }
    tried.push(workspace_root().join(path));
    let mut seen = Vec::new();
    tried.retain(|p| {
        let new = !seen.contains(p);
        seen.push(p.clone());
        new
    });
    match tried.iter().find(|p| p.is_file()) {
        Some(p) => Ok(p.clone()),
        None => Err(ObjectError::MissingMesh {
            path: path.to_path_buf(),
            tried,
        }),
    }
}
