//! Bytes as a .obj file into `rmt_mesh::io::read_obj`: a mesh or an error, never a panic. The
//! reader takes a path, so each input is written to one scratch file in a temporary folder.
#![no_main]

use std::path::PathBuf;
use std::sync::OnceLock;

use libfuzzer_sys::fuzz_target;

fn scratch() -> &'static PathBuf {
    static DIR: OnceLock<(tempfile::TempDir, PathBuf)> = OnceLock::new();
    &DIR.get_or_init(|| {
        let dir = tempfile::tempdir().expect("a temporary folder");
        let path = dir.path().join("input.obj");
        (dir, path)
    })
    .1
}

fuzz_target!(|data: &[u8]| {
    let path = scratch();
    std::fs::write(path, data).expect("write the input");
    if let Ok(mesh) = rmt_mesh::io::read_obj(path) {
        let n = mesh.positions.len();
        assert!(mesh.indices.iter().all(|&i| (i as usize) < n));
    }
});
