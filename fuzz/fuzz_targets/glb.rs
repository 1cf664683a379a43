//! Binary glTF bytes into `rmt_mesh::glb::from_glb`: a mesh or an error, never a panic.
#![no_main]

use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    if let Ok(mesh) = rmt_mesh::glb::from_glb(data) {
        // What the reader promises: indices in range.
        let n = mesh.positions.len();
        assert!(mesh.indices.iter().all(|&i| (i as usize) < n));
    }
});
